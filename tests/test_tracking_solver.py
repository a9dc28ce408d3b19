"""Tracking in solver coordinates: shapes moved between poses give the nodal MACs exactly."""

import crossing_arm as arm_ref
import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.checks import check_y
from pinflex.description import parse
from pinflex.erls import FlexibleModel, eigensolve, kinematics, solve
from pinflex.erls.eigenpairs import PoseMap
from pinflex.erls.tracking import mac_matrix, track, track_modes
from pinflex.exceptions import ConfigurationError

Q0_A = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def crossing_arm():
    """The edge-bar arm of ``crossing_arm`` (modes that cross along the elbow sweep)."""
    return FlexibleModel(parse(arm_ref.urdf()))


@pytest.fixture(scope="module")
def two_link():
    """Benchmark A's planar two-link arm."""
    return FlexibleModel(TWO_LINK, planar=True)


def _elbow_sweep(n):
    el = np.linspace(0.0, 0.6, n)
    return np.column_stack([np.full_like(el, 0.3), el])


def test_a_moved_shape_is_the_same_nodal_shape(crossing_arm):
    """T(q_t) move(φ, s, t) = T(q_s) φ, with T the solver-to-nodal map of eigensolve.to_nodal."""
    model = crossing_arm
    Q = np.array([[0.3, 0.0], [-0.4, 0.5], [1.1, -0.7]])
    terms = kinematics.pose_terms(model, Q)
    pm = PoseMap(model, terms, 3)
    plan = solve.solve_plan(model)
    twist = solve.root_twists(model, plan, terms, 3)
    rng = np.random.default_rng(3)
    phi = rng.standard_normal((3, model.nx, 4))

    def nodal(i, x):  # T(q_i) x on the elastic coordinates
        tw = {k: None if v is None else v[i : i + 1] for k, v in twist.items()}
        full = np.zeros((model.ndof, x.shape[1]))
        full[: model.nx] = x
        return eigensolve.to_nodal(model, tw, full)[: model.nx]

    moved = pm.move(phi, np.array([0, 1, 2]), np.array([2, 0, 1]))
    for s, t in ((0, 2), (1, 0), (2, 1)):
        ref = nodal(s, phi[s])
        np.testing.assert_allclose(nodal(t, moved[s]), ref, atol=1e-12 * np.abs(ref).max())
        # and the pose really changes the coordinates (the map is not the identity)
        assert np.abs(moved[s] - phi[s]).max() > 1e-3 * np.abs(phi[s]).max()


@pytest.mark.parametrize("case", ["crossing", "veering", "reference point"])
def test_solver_and_nodal_tracking_agree(crossing_arm, case):
    """Same permutations and events; MACs and eigenvalues agree to solver round-off."""
    if case == "veering":
        model, Q, y, kw = (FlexibleModel(parse(arm_ref.urdf(tilt=0.1))), _elbow_sweep(61),
                           None, {"modes": (1, 2, 3, 4), "reference": 30})
    elif case == "crossing":
        model, Q, y, kw = crossing_arm, _elbow_sweep(31), None, {"modes": (1, 2, 3, 4),
                                                                 "reference": 15}
    else:
        model, Q, y = crossing_arm, _elbow_sweep(16)[:6], [0.0, 0.25]
        kw = {"modes": (2, 3), "reference": (np.array([0.3, 0.3]), np.array([0.125, 0.125]))}
    a = track_modes(model, Q, y, coordinates="nodal", **kw)
    b = track_modes(model, Q, y, coordinates="solver", **kw)
    assert a.events, "each case has a crossing or a veering"
    np.testing.assert_array_equal(a.permutation, b.permutation)
    assert [(e.kind, e.sample, e.modes) for e in a.events] == \
        [(e.kind, e.sample, e.modes) for e in b.events]
    np.testing.assert_allclose([e.mac for e in b.events], [e.mac for e in a.events], atol=1e-9)
    np.testing.assert_allclose(b.mac_step, a.mac_step, atol=1e-9)
    np.testing.assert_allclose(b.mac_reference, a.mac_reference, atol=1e-9)
    np.testing.assert_allclose(b.sorted_eigvals, a.sorted_eigvals, rtol=1e-9)


def test_a_crossing_in_solver_coordinates_is_caught_not_matched_by_order(crossing_arm):
    """The swap of modes 2/3 is reported, and the tracked branches are not the sorted ones."""
    Q = _elbow_sweep(31)
    tr = track_modes(crossing_arm, Q, modes=(2, 3), reference=15, coordinates="solver")
    ref = [arm_ref.reference_families(q, 0.125, 0.125) for q in Q]
    out2 = np.array([r[1][1] for r in ref])
    in1 = np.array([r[0][0] for r in ref])
    np.testing.assert_allclose(tr.freq_hz[:, 0], out2, rtol=1e-9)
    np.testing.assert_allclose(tr.freq_hz[:, 1], in1, rtol=1e-9)
    (ev,) = tr.crossings(2)
    swap = int(np.flatnonzero(np.diff(np.sign(out2 - in1)))[0]) + 1
    assert ev.sample == swap and ev.modes == (2, 3)
    assert np.abs(tr.sorted_hz[:, 1] - tr.freq_hz[:, 0]).max() > 1.0  # sorted ≠ tracked


def test_benchmark_a_step_macs_need_the_pose_map(two_link):
    """Unmoved solver shapes give another MAC between poses; moved ones give the nodal one."""
    from pinflex.cases.benchmark_a import benchmark_trajectory
    from pinflex.erls.eigenpairs import solver_eigenpairs

    Q = benchmark_trajectory(two_link).q[::8]
    y = check_y(two_link, np.array([0.2, 0.05]))
    lam, phi, B, pm = solver_eigenpairs(two_link, Q, y, n_modes=4)
    raw = track(lam, phi, B, modes=(1, 2, 3, 4))
    mapped = track(lam, phi, B, modes=(1, 2, 3, 4), pose_map=pm)
    nodal = track_modes(two_link, Q, y, modes=(1, 2, 3, 4), coordinates="nodal")
    np.testing.assert_allclose(mapped.mac_step, nodal.mac_step, atol=1e-10)
    assert np.abs(raw.mac_step - nodal.mac_step).max() > 1e-3
    # the stand-alone MAC of one step, by hand: moved shape against the later sample's shapes
    C = mac_matrix(pm.move(phi[3], 3, 4), phi[4], B[4])
    np.testing.assert_allclose(np.diag(C), mapped.mac_step[4], atol=1e-12)


def test_design_only_lead_in_and_named_errors(two_link):
    """A reference on a sample with another design walks the design at one pose."""
    from pinflex.cases.benchmark_a import benchmark_trajectory

    Q = benchmark_trajectory(two_link).q
    kw = {"modes": (1, 2), "reference": (Q0_A, two_link.y0)}
    a = track_modes(two_link, Q, [0.25, 0.0], coordinates="nodal", **kw)
    b = track_modes(two_link, Q, [0.25, 0.0], coordinates="solver", **kw)
    np.testing.assert_array_equal(a.permutation, b.permutation)
    np.testing.assert_allclose(b.mac_reference, a.mac_reference, atol=1e-10)
    with pytest.raises(ConfigurationError):
        track_modes(two_link, Q[:3], coordinates="modal")


def test_models_the_conditioned_solve_lacks_are_tracked_on_the_nodal_pencil():
    """Joint springs: 'auto' falls back to the nodal pencil, 'solver' says it cannot."""
    from reference_fe import planar_two_link_frequencies

    model = FlexibleModel(TWO_LINK, planar=True, joints={"q1": 4.0e3, "q2": 1.5e3})
    assert not solve.supported(model)
    Q = Q0_A + np.linspace(0.0, 0.3, 5)[:, None] * np.array([0.0, 1.0])
    tr = track_modes(model, Q, modes=(1, 2))
    for q, f in zip(Q, tr.freq_hz):
        _, f_ref = planar_two_link_frequencies(q, 0.125, 0.125, joints=[4.0e3, 1.5e3])
        np.testing.assert_allclose(f, f_ref[:2], rtol=1e-9)
    with pytest.raises(ConfigurationError, match="conditioned solve"):
        track_modes(model, Q, modes=(1, 2), coordinates="solver")


def test_flexible_ur5_tracking_agrees_in_both_coordinates():
    """Six joints in 3-D (two tubes alone, rigid links between, a still base pan): same
    tracking through the events of this motion (with the URDF's motors kept it has none)."""
    from arms import tubes_alone

    ur5 = FlexibleModel(tubes_alone(TWO_LINK.parent / "ur5_flexible.xml"))
    q0 = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
    Q = q0 + np.linspace(0.0, 1.0, 40)[:, None] * np.array([0.5, 0.8, -1.0, 0.7, 1.2, 0.9])
    kw = {"modes": (1, 2, 3, 4, 5, 6), "reference": (q0 + 0.05, None)}
    a = track_modes(ur5, Q, coordinates="nodal", **kw)
    b = track_modes(ur5, Q, coordinates="solver", **kw)
    assert a.events
    np.testing.assert_array_equal(a.permutation, b.permutation)
    assert [(e.kind, e.sample, e.modes) for e in a.events] == \
        [(e.kind, e.sample, e.modes) for e in b.events]
    np.testing.assert_allclose(b.mac_step, a.mac_step, atol=1e-9)
    np.testing.assert_allclose(b.mac_reference, a.mac_reference, atol=1e-9)
    np.testing.assert_allclose(b.eigvals, a.eigvals, rtol=1e-9)
