"""Solver-coordinate design terms, solver tracking and Taylor evaluation on further arms.

The arms: a 3-D arm built from an upstream URDF (the Franka Panda of example-robot-data, two
beams in series), a three-joint spatial arm, benchmark A's two-link arm.

References: the exact model's frequencies (no jets), the nodal-coordinate jets (a second
formulation of the pencil), the polynomial summed monomial by monomial from its coefficients,
and the per-sample radius estimate of :meth:`TaylorModel.error_estimate`.
"""

import warnings

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import TWO_LINK

from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.erls.tracking import track_modes
from pinflex.exceptions import (
    ConfigurationError,
    PinflexWarning,
    TaylorRadiusExceeded,
    TaylorRadiusWarning,
)
from pinflex.parametric import expand, matrix_jets
from pinflex.parametric.eigen import eigen_jets

PANDA = """<?xml version="1.0"?>
<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" name="panda_designed"
                 base="example-robot-data:panda_description/urdf/panda.urdf">
  <pinflex:parameter name="D2" value="0.08" lower="0.05" upper="0.12" design="true"/>
  <pinflex:parameter name="E4" value="70e9" lower="50e9" upper="90e9" design="true"/>
  <pinflex:parameter name="w4" value="0.05" lower="0.03" upper="0.08" design="true"/>
  <pinflex:parameter name="k2" value="5e4" lower="1e4" upper="1e6" design="true"/>
  <pinflex:flexible link="panda_link2" elements="4">
    <pinflex:material E="70e9" density="2700"/>
    <pinflex:section shape="hollow_circle" outer_diameter="{D2}" wall="0.005"/>
  </pinflex:flexible>
  <pinflex:flexible link="panda_link4" elements="4">
    <pinflex:material E="{E4}" density="2700"/>
    <pinflex:section shape="rectangle" width="{w4}" height="0.03"/>
  </pinflex:flexible>
  <pinflex:point_mass name="tool" link="panda_hand" xyz="0 0 0.1" mass="0.5" design="true"
                      lower="0" upper="2"/>
  <pinflex:joint name="panda_joint2" stiffness="{k2}"/>
  <pinflex:joint name="panda_joint4" stiffness="3e4"/>
  <pinflex:joint name="panda_joint6" locked="true"/>
</pinflex:overlay>"""

Q_PANDA = np.array([0.3, -0.4, 0.2, -1.8, 0.1, 1.5, 0.6, 0.01, 0.01])


@pytest.fixture(scope="module")
def panda(tmp_path_factory):
    """The Panda with design sections, material, springs and a locked joint.

    A tube on link 2 (outer diameter D2, not the last beam), a bar on link 4 (modulus E4,
    width w4: a rational torsion constant), a design spring on joint 2, a fixed spring on
    joint 4 and joint 6 locked.
    """
    path = tmp_path_factory.mktemp("panda") / "panda_designed.xml"
    path.write_text(PANDA)
    return FlexibleModel(path, joints="annotated")


def _lam(model, q, y, n):
    return (2 * np.pi * model.frequencies(q, y, n_modes=n)) ** 2


def test_panda_sections_springs_and_lock_converge_like_h_to_the_p_plus_one(panda):
    """Order 3 at a non-nominal design, against the exact model and the nodal route.

    The error against the exact model falls like h⁴, the coefficients equal the nodal
    route's and the first design derivatives the exact model's central differences.
    """
    model = panda
    assert model.joint_labels()["panda_joint6"] == "locked"
    y = model.y0 * np.array([1.1, 0.9, 1.1, 1.5, 1.3])  # tool, D2, E4, w4, k2
    joints = ["panda_joint2", "panda_joint4", "panda_joint6"]
    tm = expand(model, Q_PANDA, y, order=3, modes=(1, 2, 3), joints=joints)
    assert len(tm.design_idx) == 5
    space, M, K, _, _ = matrix_jets(model, Q_PANDA, y, order=3, joints=joints)
    w, V = sla.eigh(K[0], M[0])
    ref = eigen_jets(space, M, K, [model.n_rigid + k for k in range(3)], eigvals0=w,
                     eigvecs0=V)[0]
    for d in range(4):
        s = space.degree_slice(d)
        assert np.max(np.abs(tm.eigval_jets[s] - ref[s]) / np.abs(ref[s]).max(axis=0)) < 1e-9
    lam0 = _lam(model, Q_PANDA, y, 3)
    np.testing.assert_allclose(tm.eigval_jets[0], lam0, rtol=1e-9)
    names = list(model.design_names)
    for name in ("D2", "E4", "w4", "k2", "tool"):  # first derivatives by central differences
        j = names.index(name)
        h = 1e-4 * y[j]
        up, down = y.copy(), y.copy()
        up[j] += h
        down[j] -= h
        fd = (_lam(model, Q_PANDA, up, 3) - _lam(model, Q_PANDA, down, 3)) / (2 * h)
        alpha = [0] * space.nvars
        alpha[len(joints) + j] = 1
        coef = tm.eigval_jets[space.index[tuple(alpha)]]
        np.testing.assert_allclose(coef, fd, rtol=3e-4, atol=1e-6 * lam0.max() / y[j])
    rng = np.random.default_rng(1)
    dq, dy = 0.3 * rng.normal(size=3), 0.1 * y * rng.normal(size=5)
    cols = [list(model.joint_names).index(n) for n in joints]
    errs = []
    for h in (0.1, 0.05):
        q = Q_PANDA.copy()
        q[cols] += h * dq
        errs.append(np.max(np.abs(tm.evaluate(q[None], y + h * dy, warn=False)[0]
                                  / _lam(model, q, y + h * dy, 3) - 1)))
    assert errs[0] < 1e-6
    assert 10 < errs[0] / errs[1] < 25, errs  # 2⁴ = 16


def test_panda_solver_tracking_equals_nodal_through_a_crossing(tmp_path):
    """The shipped flexible Panda, tubes alone: solver and nodal tracking agree through a
    crossing.

    A nine-joint motion with a tool mass changing per sample: same permutations, events and
    MACs in both coordinates; sorted modes 3 and 4 exchange along it (with the URDF's motors
    kept on the tube links, the default, they do not cross along this motion).
    """
    from conftest import ROOT

    text = (ROOT / "urdf" / "panda_flexible.xml").read_text()
    assert "<pinflex:flexible " in text
    path = tmp_path / "panda_tubes_alone.xml"
    path.write_text(text.replace("<pinflex:flexible ", '<pinflex:flexible inertia="beam-only" '))
    model = FlexibleModel(path)
    assert not model.description.bodies
    t = np.linspace(0.0, 1.0, 25)[:, None]
    Q = Q_PANDA + t * np.array([1.0, 1.2, -0.8, 1.5, 2.0, -1.0, 1.0, 0.02, 0.0])
    Y = np.linspace(0.1, 1.9, 25)[:, None]
    a = track_modes(model, Q, Y, modes=(1, 2, 3, 4, 5, 6), coordinates="solver")
    b = track_modes(model, Q, Y, modes=(1, 2, 3, 4, 5, 6), coordinates="nodal")
    np.testing.assert_array_equal(a.permutation, b.permutation)
    assert [(e.kind, e.sample, e.modes) for e in a.events] == \
        [(e.kind, e.sample, e.modes) for e in b.events]
    assert any(e.kind == "crossing" and e.modes == (3, 4) for e in a.events)
    assert set(a.order[:, 2]) == {3, 4}
    np.testing.assert_allclose(a.mac_step, b.mac_step, atol=1e-8)
    np.testing.assert_allclose(a.mac_reference, b.mac_reference, atol=1e-8)
    np.testing.assert_allclose(a.eigvals, b.eigvals, rtol=1e-8)


THREE = """<robot name="three" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="link3"/>
  <link name="tool"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <joint name="q2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <joint name="q3" type="revolute"><parent link="link2"/><child link="link3"/>
    <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="link3"/><child link="tool"/>
    <origin xyz="0.3 0 0"/></joint>
  <pinflex:flexible link="link1" elements="3" normal="0 0 1">
    <pinflex:material E="69e9" density="2687"/>
    <pinflex:section shape="hollow_circle" outer_diameter="0.04" wall="0.003"/>
  </pinflex:flexible>
  <pinflex:flexible link="link2" elements="3" normal="0 0 1">
    <pinflex:material E="69e9" density="2687"/>
    <pinflex:section shape="rectangle" width="0.03" height="0.02"/>
  </pinflex:flexible>
  <pinflex:flexible link="link3" elements="2" normal="0 0 1">
    <pinflex:material E="69e9" density="2687"/>
    <pinflex:section shape="solid_circle" diameter="0.02"/>
  </pinflex:flexible>
  <pinflex:point_mass name="mt" link="tool" xyz="0 0 0" mass="0.2" design="true" lower="0"
                      upper="1"/>
</robot>"""


def _by_monomials(tm, Q, Y, quantity, linear):
    """The polynomial summed monomial by monomial, and the offsets."""
    C = tm.coefficients(quantity, linear_in_design=linear)
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    j = list(tm.joint_idx)
    dx = np.zeros((Q.shape[0], tm.space.nvars))
    dx[:, : len(j)] = Q[:, j] - tm.q0[j]
    if tm.design_idx and Y is not None:
        d = list(tm.design_idx)
        dx[:, len(j):] = np.broadcast_to(Y, (Q.shape[0], tm.y0.size))[:, d] - tm.y0[d]
    out = np.zeros((Q.shape[0], C.shape[1]))
    for alpha, c in zip(tm.space.multi_indices, C):
        out += np.prod(dx**alpha, axis=1)[:, None] * c[None]
    return out, dx


def _same_as_reference(tm, Qs, Ys=(None,)):
    """Values to round-off and the radius decisions of the per-sample estimate."""
    warned = set()
    for Q in Qs:
        for Y in Ys:
            for quantity in ("eigval", "freq_hz"):
                for linear in (False, True):
                    ref, dx = _by_monomials(tm, Q, Y, quantity, linear)
                    est, _ = tm.error_estimate(dx, quantity=quantity)
                    expect = bool(np.max(est) > 1e-2)
                    warned.add(expect)
                    for warn in (False, True):
                        with warnings.catch_warnings(record=True) as w:
                            warnings.simplefilter("always")
                            v = tm.evaluate(Q, Y, quantity=quantity, warn=warn,
                                            linear_in_design=linear)
                        got = any(issubclass(x.category, TaylorRadiusWarning) for x in w)
                        assert got == (warn and expect)
                        assert np.max(np.abs(v - ref) / np.abs(ref).max(axis=0)) < 1e-13
                    if expect:
                        with pytest.raises(TaylorRadiusExceeded):
                            tm.evaluate(Q, Y, quantity=quantity, strict=True,
                                        linear_in_design=linear)
    assert warned == {False, True}  # both decisions were exercised


@pytest.mark.parametrize("order", [2, 5])
def test_two_joint_factored_evaluation_equals_the_monomial_sum(order):
    """Benchmark A, both joints, no design (the factored path), 1 and 3 modes."""
    model = FlexibleModel(TWO_LINK, planar=True)
    q0 = np.array([1.817, 5.312])
    rng = np.random.default_rng(order)
    for modes in ((1,), (1, 2, 3)):
        tm = expand(model, q0, order=order, modes=modes, design=[])
        assert tm._evaluation_plan.grid is not None
        Qs = [q0 + s * rng.normal(size=(n, 2)) for s in (1e-3, 0.1, 0.5, 2.0) for n in (1, 7)]
        _same_as_reference(tm, Qs + [np.asfortranarray(Qs[-1]), Qs[-1][::2]])


def test_three_and_one_joint_evaluation_equals_the_monomial_sum():
    """A three-joint spatial arm (all joints; a subset; with its design mass) and a rod."""
    model = FlexibleModel(parse(THREE))
    q0 = np.array([0.2, 0.7, -0.9])
    rng = np.random.default_rng(2)
    Qs = [q0 + s * rng.normal(size=(6, 3)) for s in (1e-3, 0.1, 0.4, 1.5)]
    tm = expand(model, q0, order=3, modes=(1, 2, 3), design=[])
    assert tm._evaluation_plan.q0_col is not None
    _same_as_reference(tm, Qs + [q0 + 1.5 * rng.normal(size=(1, 3))])
    tm = expand(model, q0, order=2, modes=(1, 2))
    _same_as_reference(tm, Qs, (None, model.y0 + rng.uniform(-0.1, 0.1, size=(6, 1))))
    sub = [np.column_stack([np.full(6, q0[0]), q0[1:] + s * rng.normal(size=(6, 2))])
           for s in (0.01, 0.3, 1.0)]
    _same_as_reference(expand(model, q0, order=3, modes=(1, 2), joints=["q2", "q3"],
                              design=[]), sub)


def test_evaluate_refuses_design_values_the_model_does_not_depend_on():
    """A design variable that is not expanded must stay at y0; bad design values are named.

    Moving it changes the exact frequency, so a value "at" it would silently be the value at
    y0.
    """
    model = FlexibleModel(TWO_LINK, planar=True)
    q0 = np.array([1.817, 5.312])
    Y = np.array([0.125, 0.25])  # m2 doubled
    assert abs(_lam(model, q0, Y, 1)[0] / _lam(model, q0, None, 1)[0] - 1) > 1e-2
    tm = expand(model, q0, order=3, modes=(1,), design=["m1"])
    with pytest.raises(ConfigurationError, match="not expanded"):
        tm.evaluate(q0[None], Y)
    with pytest.raises(ConfigurationError, match="not expanded"):
        expand(model, q0, order=3, modes=(1,), design=[]).evaluate(q0[None], Y)
    ok = tm.evaluate(q0[None], [0.2, 0.125])  # m2 at y0: fine
    np.testing.assert_allclose(ok[0], _lam(model, q0, [0.2, 0.125], 1), rtol=1e-3)
    tm = expand(model, q0, order=2, modes=(1,))
    Q2 = np.tile(q0, (2, 1))
    for bad in ([0.1], [0.1, 0.2, 0.3], np.full((3, 2), 0.1), "ab", [np.nan, 0.1]):
        with pytest.raises(ConfigurationError):
            tm.evaluate(Q2, bad)
    np.testing.assert_array_equal(tm.evaluate(Q2, [[0.1, 0.1]]), tm.evaluate(Q2, [0.1, 0.1]))


def test_a_near_rigid_spring_expands_on_the_nodal_pencil():
    """A spring 1e12 N·m/rad on the Panda's joint 4 (about 1e6 times its stiffest element).

    The solver-coordinate pencil refuses it (its bordered matrix fails the condition check,
    reported as a cluster of modes 25 % apart); the nodal pencil resolves it to the digits
    the stiffness leaves (~1e-6): the expansion agrees with the exact model to that level
    at the point and at small offsets, and with the locked joint's limit. Tubes alone (with
    the URDF's motors kept the offsets' agreement is 1.3e-5).
    """
    from arms import tubes_alone
    from conftest import ROOT

    path = tubes_alone(ROOT / "urdf" / "panda_flexible.xml")
    with pytest.warns(PinflexWarning, match="digits"):  # the model says so
        model = FlexibleModel(path, joints={"panda_joint4": 1e12})
    joints = ["panda_joint2", "panda_joint4"]
    tm = expand(model, Q_PANDA, order=3, modes=(1, 2, 3), joints=joints)
    lam0 = _lam(model, Q_PANDA, None, 3)
    np.testing.assert_allclose(tm.eigval_jets[0], lam0, rtol=1e-6)
    locked = FlexibleModel(path, joints={"panda_joint4": "locked"})
    np.testing.assert_allclose(lam0, _lam(locked, Q_PANDA, None, 3), rtol=3e-6)
    q = Q_PANDA.copy()
    q[[1, 3]] += [0.02, -0.03]
    np.testing.assert_allclose(tm.evaluate(q[None], warn=False)[0], _lam(model, q, None, 3),
                               rtol=5e-6)


def test_points_tolerance_reports_the_exact_error_of_its_cover():
    """A wide elbow sweep (0.3 → 2.8 rad) of benchmark A needs two expansion points at 1e-3.

    The segments tile the samples, each centre lies in its segment, and the reported exact
    error equals each segment's model against the exact frequencies, recomputed here.
    """
    from pinflex.assignment.points import points_for_tolerance

    model = FlexibleModel(TWO_LINK, planar=True)
    t = np.linspace(0.0, 1.0, 60)
    Q = np.column_stack([1.0 + 0.5 * t, 1.3 + 3.0 * t])  # absolute angles
    exact = model.frequencies(Q, model.y0, n_modes=1)[:, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("error", TaylorRadiusWarning)  # the cover meets the tolerance
        pw = points_for_tolerance(model, Q, model.y0, tol=1e-3, modes=(1,))
    assert len(pw.centres) == 2
    assert pw.segments[0][0] == 0 and pw.segments[-1][1] == Q.shape[0]
    assert all(a[1] == b[0] for a, b in zip(pw.segments, pw.segments[1:]))
    assert all(a <= c < b for c, (a, b) in zip(pw.centres, pw.segments))
    err = max(float(np.max(np.abs(tm.evaluate(Q[a:b], quantity="freq_hz", warn=False)[:, 0]
                                  / exact[a:b] - 1)))
              for tm, (a, b) in zip(pw.models, pw.segments))
    assert err < 1e-3
    assert abs(pw.points_choice["exact_error"] / err - 1) < 1e-9
    assert pw.points_choice["estimate"] < 1e-3


def test_points_tolerance_judges_its_cover_against_the_tracked_modes():
    """Across an exact crossing, one point's polynomial follows its own branch.

    The edge-bar arm of ``crossing_arm`` along its elbow sweep: sorted modes 2 and 3 exchange
    near 0.15 rad. At tol 1e-4 for mode 3 one expansion point past the crossing covers the
    sweep; its exact error is that against the mode family it follows (the independent global
    FE, families told apart by where the motion lives), not against sorted mode 3 (which jumps
    to the other family before the crossing: 5.8 %).
    """
    import crossing_arm as arm_ref

    from pinflex.assignment.points import points_for_tolerance

    model = FlexibleModel(parse(arm_ref.urdf()))
    el = np.linspace(0.0, 0.6, 31)
    Q = np.column_stack([np.full_like(el, 0.3), el])
    with warnings.catch_warnings():
        warnings.simplefilter("error", TaylorRadiusWarning)
        pw = points_for_tolerance(model, Q, model.y0, tol=1e-4, modes=(3,))
    assert len(pw.models) == 1
    fams = [arm_ref.reference_families(q, 0.125, 0.125) for q in Q]
    inp = np.array([f[0][0] for f in fams])  # first in-plane mode
    out = np.array([f[1][1] for f in fams])  # second out-of-plane mode
    c = pw.centres[0]
    f_c = model.frequencies(Q[c], n_modes=3)[2]
    family = inp if abs(f_c / inp[c] - 1) < abs(f_c / out[c] - 1) else out
    v = pw.models[0].evaluate(Q, quantity="freq_hz", warn=False)[:, 0]
    err = float(np.max(np.abs(v / family - 1)))
    assert err < 1e-4
    assert abs(pw.points_choice["exact_error"] / err - 1) < 1e-6
    sorted3 = model.frequencies(Q, n_modes=3)[:, 2]
    assert np.max(np.abs(v / sorted3 - 1)) > 1e-2  # the sorted numbers change branch


@pytest.mark.parametrize("condition", ["4e4", "locked"])
def test_prismatic_joint_between_beams_on_the_solver_route(condition):
    """The three-joint arm with its middle joint prismatic (axis oblique to the beams).

    A spring or a lock on it, the tip mass as design variable at 1.2 × nominal: order 3 in
    the last two joints and the mass, error against the exact model falls like h⁴; free, the
    solver-coordinate tracking along a three-joint motion equals the nodal one.
    """
    text = THREE.replace('<joint name="q2" type="revolute">', '<joint name="q2" type="prismatic">')
    text = text.replace('<axis xyz="0 1 0"/>\n    <limit lower="-7"',
                        '<axis xyz="0 0.6 0.8"/>\n    <limit lower="-7"', 1)
    free = FlexibleModel(parse(text))
    q0 = np.array([0.2, 0.1, -0.9])
    Q = q0 + np.linspace(0.0, 1.0, 30)[:, None] * np.array([1.5, 0.4, 2.5])
    a = track_modes(free, Q, modes=(1, 2, 3, 4), coordinates="solver")
    b = track_modes(free, Q, modes=(1, 2, 3, 4), coordinates="nodal")
    np.testing.assert_array_equal(a.permutation, b.permutation)
    np.testing.assert_allclose(a.mac_step, b.mac_step, atol=1e-9)
    joint = (f'<pinflex:joint name="q2" stiffness="{condition}"/>' if condition != "locked"
             else '<pinflex:joint name="q2" locked="true"/>')
    model = FlexibleModel(parse(text.replace("</robot>", joint + "</robot>")),
                          joints="annotated")
    y = model.y0 * 1.2
    tm = expand(model, q0, y, order=3, modes=(1, 2, 3), joints=["q2", "q3"])
    errs = []
    for h in (0.1, 0.05):
        q, yy = q0 + h * np.array([0.0, 0.2, -0.3]), y + h * 0.05
        errs.append(np.max(np.abs(tm.evaluate(q[None], yy, warn=False)[0]
                                  / _lam(model, q, yy, 3) - 1)))
    assert errs[0] < 1e-4
    assert 12 < errs[0] / errs[1] < 22, errs  # 2⁴ = 16
