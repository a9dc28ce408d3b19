"""One pose per call: the one-pose assembly and the shape fields against the general paths."""

import numpy as np
import pytest
from arms import PRISMATIC
from conftest import TWO_LINK, UR5, single_link_urdf

from pinflex.checks import check_q
from pinflex.description import parse
from pinflex.erls import FlexibleModel, eigensolve, kinematics, modal, one_pose, solve
from pinflex.exceptions import ConfigurationError, DesignVariableOutOfBounds

# a beam carrying a rigid link with an inertia and a (non-design) point mass, behind a
# continuous joint (configuration (cos, sin)) and with a rigid link before the beam
MIXED = """<robot name="mixed" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/>
  <link name="hub"><inertial><origin xyz="0 0 0.02"/><mass value="1.5"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.012" iyz="0" izz="0.008"/></inertial></link>
  <link name="beam"/>
  <link name="hand"><inertial><origin xyz="0.03 0.01 0"/><mass value="0.4"/>
    <inertia ixx="2e-4" ixy="0" ixz="0" iyy="3e-4" iyz="0" izz="2.5e-4"/></inertial></link>
  <joint name="yaw" type="continuous"><parent link="base"/><child link="hub"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="pitch" type="revolute"><parent link="hub"/><child link="beam"/>
    <origin xyz="0 0 0.05" rpy="0.1 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="wrist" type="revolute"><parent link="beam"/><child link="hand"/>
    <origin xyz="0.6 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="beam" elements="4" tip="0.6 0 0" normal="0 0 1">
    <pinflex:material E="7e10" density="2700"/>
    <pinflex:section shape="hollow_circle" outer_diameter="0.04" inner_diameter="0.03"/>
  </pinflex:flexible>
  <pinflex:point_mass name="tool" link="hand" xyz="0.08 0 0.01" mass="0.2"/>
  <pinflex:point_mass name="sensor" link="beam" xyz="0.3 0 0.02" mass="0.05"
     design="true" lower="0" upper="0.2"/>
</robot>"""


def _models():
    return [
        ("benchmark A planar", FlexibleModel(TWO_LINK, planar=True), np.array([0.4, -0.9])),
        ("benchmark A spatial", FlexibleModel(TWO_LINK), np.array([0.4, -0.9])),
        ("flexible UR5", FlexibleModel(UR5), np.array([0.3, -0.8, 1.1, 0.2, -0.4, 0.7])),
        ("prismatic", FlexibleModel(parse(PRISMATIC)), np.array([0.2, 0.7, -0.5])),
        ("mixed", FlexibleModel(parse(MIXED)), np.array([2.9, -0.6, 0.8])),
        ("one bar, one joint", FlexibleModel(parse(single_link_urdf(elements=6))), np.array([0.3])),
    ]


@pytest.fixture(scope="module")
def models():
    """The models of this file with one pose each."""
    return _models()


def test_one_pose_mass_equals_the_block_assembly(models):
    """``S^T W S`` equals the structured block assembly of :func:`solve.mass` (round-off)."""
    for name, model, q in models:
        terms = kinematics.pose_terms(model, check_q(model, q)[None])
        plan = solve.solve_plan(model)
        twist = solve.root_twists(model, plan, terms, 1)
        layout = one_pose.one_pose_layout(model)
        assert layout is not None, name
        ys = [model.y0] + ([np.linspace(0.03, 0.2, model.ny)] if model.ny else [])
        for y in ys:
            ref = solve.mass(model, terms, y, 1)[0]
            got, S = one_pose.mass_one(model, layout, terms, twist, y)
            rows = layout.S0.shape[0] if layout.keep is None else layout.keep.size
            assert S.shape == (rows, model.nx + model.nv)
            assert np.abs(got - ref).max() <= 1e-14 * np.abs(ref).max(), name


def _general_modes(model, q, n_modes):
    """Modes by the general path: nodal shapes, then node fields from the nodal root twists."""
    q = check_q(model, q)
    terms = kinematics.pose_terms(model, q[None])
    plan = solve.solve_plan(model)
    twist = solve.root_twists(model, plan, terms, 1)
    M = solve.mass(model, terms, model.y0, 1)[0]
    lam, sw, sx = eigensolve.eigvecs(model, M, n_modes)
    shapes = np.concatenate([eigensolve.to_nodal(model, twist, sw), sx], axis=1)
    phix = shapes[: model.nx]
    idx = np.argmax(np.abs(phix), axis=0)
    shapes *= np.where(phix[idx, np.arange(lam.size)] < 0, -1.0, 1.0)[None, :]
    return lam, shapes, *modal.node_fields(model, q, shapes, terms)


def test_modes_fields_equal_the_general_path(models):
    """``modes()`` fields through the layout equal the general path's.

    Shapes over [x; q], node positions, nodal and elastic motion (the general path goes
    through the nodal shapes and the nodal root twists).
    """
    for name, model, q in models:
        res = model.modes(q, n_modes=4)
        lam, shapes, pos, motion, elastic = _general_modes(model, q, 4)
        np.testing.assert_allclose(res.eigvals, lam, rtol=1e-12, err_msg=name)
        np.testing.assert_allclose(res.shapes, shapes, rtol=0, atol=1e-10 * np.abs(shapes).max(),
                                   err_msg=name)
        assert list(res.node_motion) == list(motion)
        for link in motion:
            scale = np.abs(motion[link]).max()
            np.testing.assert_allclose(res.node_positions[link], pos[link], atol=1e-14)
            np.testing.assert_allclose(res.node_motion[link], motion[link], atol=1e-10 * scale)
            np.testing.assert_allclose(res.node_elastic[link], elastic[link],
                                       atol=1e-10 * scale)


def test_large_layouts_fall_back_to_the_block_assembly(models, monkeypatch):
    """Above the row limit no layout is built and modes()/frequencies() give the same modes."""
    name, model, q = models[3]
    before = model.modes(q, n_modes=3)
    f_before = model.frequencies(q, n_modes=3)
    fresh = FlexibleModel(parse(PRISMATIC))
    monkeypatch.setattr(one_pose, "ONE_POSE_MAX_ROWS", 10)
    assert one_pose.one_pose_layout(fresh) is None
    after = fresh.modes(q, n_modes=3)
    np.testing.assert_allclose(after.eigvals, before.eigvals, rtol=1e-12)
    np.testing.assert_allclose(after.shapes, before.shapes,
                               atol=1e-10 * np.abs(before.shapes).max())
    np.testing.assert_allclose(fresh.frequencies(q, n_modes=3), f_before, rtol=1e-12)


def test_one_pose_inputs_are_still_checked(models):
    """The one-pose paths refuse bad poses, designs and mode counts with named errors."""
    _, model, q = models[0]
    for f in (model.modes, model.frequencies):
        with pytest.raises(ConfigurationError):
            f(np.array([np.nan, 0.0]))
        with pytest.raises(ConfigurationError):
            f(np.zeros(3))
        with pytest.raises(ConfigurationError):
            f(q, n_modes=0)
        with pytest.raises(DesignVariableOutOfBounds):
            f(q, {"m1": 0.5})


def test_small_requests_skip_the_available_memory_but_not_the_limit(monkeypatch):
    """Small requests skip the available memory, not an explicit limit.

    Below the always-allowed size the available memory is not read; above it, it is; an
    explicit PINFLEX_MAX_MEMORY_GB still bounds small requests.
    """
    from pinflex import resources
    from pinflex.exceptions import ResourceLimitExceeded

    calls = []

    def tiny_limit():
        calls.append(1)
        return 1024  # bytes: every real request is above it

    monkeypatch.delenv("PINFLEX_MAX_MEMORY_GB", raising=False)
    monkeypatch.setattr(resources, "memory_limit_bytes", tiny_limit)
    resources.check_modal(23)  # 25 kB: below ALWAYS_ALLOWED_BYTES, not read
    assert calls == []
    big = int(np.sqrt(resources.ALWAYS_ALLOWED_BYTES / 48)) + 1  # 6 n^2 doubles above it
    with pytest.raises(ResourceLimitExceeded):
        resources.check_modal(big)
    assert calls == [1]
    monkeypatch.setenv("PINFLEX_MAX_MEMORY_GB", "1e-9")  # about one byte
    with pytest.raises(ResourceLimitExceeded):
        resources.check_modal(23)


def test_one_kinematics_pass_equals_pose_terms_and_node_placements(models):
    """One kinematics pass gives the batched pose terms and the node placements.

    Jacobians, joint rotations, slides and node placements from one Pinocchio pass equal
    ``pose_terms`` and a separate forward kinematics (``node_placements``).
    """
    for name, model, q in models:
        q = check_q(model, q)
        terms, placements = kinematics.pose_terms_and_placements(model, q)
        ref, ref_placements = kinematics.pose_terms(model, q[None]), model.node_placements(q)
        for got, want in ((terms.jac, ref.jac), (terms.rot, ref.rot), (terms.slide, ref.slide)):
            assert list(got) == list(want), name
            for key in want:
                assert got[key].shape == want[key].shape
                np.testing.assert_allclose(got[key], want[key], rtol=0, atol=1e-15)
        for link, p in ref_placements.items():
            np.testing.assert_allclose(placements[link].positions_m, p.positions_m, atol=1e-15)
            np.testing.assert_allclose(placements[link].rotation, p.rotation, atol=1e-15)


def test_one_pose_frequencies_equal_the_batched_solve(models):
    """``frequencies(q)`` (one-pose layout, NumPy only) equals the batched block assembly."""
    for name, model, q in models:
        batched = model.frequencies(np.stack([q, q]), n_modes=6)
        np.testing.assert_allclose(model.frequencies(q, n_modes=6), batched[0], rtol=1e-12,
                                   err_msg=name)
        np.testing.assert_allclose(model.frequencies(q)[:6], batched[1], rtol=1e-12)


def test_one_pose_root_twists_equal_the_batched_ones(models):
    """The one-pose root-twist recursion equals the batched one link by link (round-off).

    It covers every link the one-pose solve reads (beams, rigid inertias, point masses) and
    their ancestors, and skips the others (benchmark A's tool frame).
    """
    for name, model, q in models:
        terms = kinematics.pose_terms_one(model, check_q(model, q))
        plan = solve.solve_plan(model)
        ref = solve.root_twists(model, plan, terms, 1)
        got = one_pose.root_twists_one(model, plan, terms)
        read = set(plan.cores) | set(model.plan.inertias) | {
            pm.link for pm in model.plan.point_masses}
        assert read <= set(got) <= set(ref), name
        if name.startswith("benchmark A"):
            assert set(ref) - set(got) == {"tool"}
        for link, e in ref.items():
            if link not in got:
                continue
            if e is None:
                assert got[link] is None, (name, link)
            else:
                np.testing.assert_allclose(got[link], e, rtol=0, atol=1e-15 * np.abs(e).max())


def test_planar_rows_left_out_are_zero_at_every_pose():
    """The rows a planar model leaves out of the one-pose products are zero at any pose.

    They are the out-of-plane components (link axes) of the root twists and frame Jacobians;
    the model decides them from its plane and link axes, this checks them at random poses
    and design values (and that spatial models leave nothing out).
    """
    planar = FlexibleModel(TWO_LINK, planar=True)
    layout = one_pose.one_pose_layout(planar)
    dropped = np.setdiff1d(np.arange(layout.S0.shape[0]), layout.keep)
    assert dropped.size == 12  # 3 components x (root, frame) x 2 links
    rng = np.random.default_rng(4)
    plan = solve.solve_plan(planar)
    nx = planar.nx
    for _ in range(20):
        q = rng.uniform(-3, 3, size=2)
        terms = kinematics.pose_terms_one(planar, q)
        twist = one_pose.root_twists_one(planar, plan, terms)
        S = layout.S0.copy()  # the fill of mass_one, before the rows are gathered
        for link, re, rj in layout.beams:
            if twist[link] is not None:
                S[re : re + 6, :nx] = twist[link][0]
            S[rj : rj + 6, nx:] = terms.jac[link][0]
        scale = np.abs(S).max()
        assert np.abs(S[dropped]).max() <= 1e-14 * scale
        assert np.abs(S[layout.keep]).max() > 0.1 * scale
    for spatial in (FlexibleModel(TWO_LINK), FlexibleModel(UR5)):
        assert one_pose.one_pose_layout(spatial).keep is None
