"""ERLS modal analysis against closed forms and second formulations."""

import re

import numpy as np
import pinocchio as pin
import pytest
from conftest import TWO_LINK, UR5, single_link_urdf

from pinflex.description import load, parse
from pinflex.erls import FlexibleModel

CANTILEVER = np.array([1.875104069, 4.694091133, 7.854757438])
PINNED_FREE = np.array([3.926602312, 7.068582745, 10.210176124])


def _beta_l(freq_hz, EI, rhoA, L=1.0):
    return np.sqrt(2 * np.pi * np.asarray(freq_hz) * np.sqrt(rhoA / EI)) * L


def test_benchmark_a_has_23_dof_and_2_rigid_modes(two_link_planar):
    """Benchmark A in planar mode has 21 elastic + 2 rigid dof."""
    r = two_link_planar.modes([1.817, 5.312])
    assert r.ndof == 23 and two_link_planar.nx == 21
    assert r.rigid_modes == 2 and r.freq_hz.size == 21


@pytest.mark.parametrize("planar", [True, False])
def test_revolute_base_gives_pinned_free_roots(planar):
    """One bar on a free revolute joint has the pinned-free βL roots (in-plane) within 0.01 %."""
    m = FlexibleModel(parse(single_link_urdf("revolute", elements=60)), planar=planar)
    EIz, rhoA = 2e11 * 1e-9, 7800 * 1e-4
    bl = _beta_l(m.frequencies([0.3]), EIz, rhoA)
    found = [bl[np.argmin(abs(bl - r))] for r in PINNED_FREE]
    np.testing.assert_allclose(found, PINNED_FREE, rtol=1e-4)
    assert m.nv == 1


@pytest.mark.parametrize("planar", [True, False])
def test_fixed_joint_gives_cantilever_roots(planar):
    """One bar on a fixed joint has the cantilever βL roots within 0.01 %."""
    m = FlexibleModel(parse(single_link_urdf("fixed", elements=60)), planar=planar)
    bl = _beta_l(m.frequencies(np.zeros(0)), 2e11 * 1e-9, 7800 * 1e-4)
    found = [bl[np.argmin(abs(bl - r))] for r in CANTILEVER]
    np.testing.assert_allclose(found, CANTILEVER, rtol=1e-4)
    assert m.nv == 0


def test_spatial_out_of_plane_bending_torsion_and_axial_closed_forms():
    """A clamped spatial bar shows x–z bending with Iy, torsion and axial modes in closed form."""
    L, E, G, rho, A, Iy, Iz, J = 1.0, 2e11, 8e10, 7800.0, 1e-4, 2e-9, 1e-9, 1.5e-9
    m = FlexibleModel(parse(single_link_urdf("fixed", elements=80)))
    f = m.frequencies(np.zeros(0))
    bend_y = CANTILEVER**2 / (2 * np.pi * L**2) * np.sqrt(E * Iy / (rho * A))
    # linear torsion elements converge as O(h²), so only the first torsion mode is checked
    torsion = np.array([1.0]) / (4 * L) * np.sqrt(G * J / (rho * (Iy + Iz)))
    axial = np.array([1.0]) / (4 * L) * np.sqrt(E / rho)
    for ref in np.concatenate([bend_y, torsion, axial]):
        assert np.min(np.abs(f / ref - 1)) < 1e-4, ref


def test_revolute_base_out_of_plane_is_clamped():
    """Out of plane, a revolute base about z clamps the bar: cantilever roots with Iy."""
    m = FlexibleModel(parse(single_link_urdf("revolute", elements=60)))
    bl = _beta_l(m.frequencies([1.0]), 2e11 * 2e-9, 7800 * 1e-4)
    for r in CANTILEVER:
        assert np.min(np.abs(bl / r - 1)) < 1e-4


def test_spatial_in_plane_modes_equal_planar_modes():
    """Each planar eigenfrequency of benchmark A appears in the spatial model to 1e-9."""
    planar = FlexibleModel(TWO_LINK, planar=True)
    spatial = FlexibleModel(TWO_LINK)
    rng = np.random.default_rng(3)
    for q in rng.uniform(-np.pi, np.pi, size=(5, 2)):
        fp = planar.frequencies(q)
        fs = spatial.frequencies(q)
        for f in fp:
            assert np.min(np.abs(fs / f - 1)) < 1e-9


def test_rigid_model_mass_matrix_equals_pinocchio_crba():
    """With no flexible link, the ERLS mass matrix of the UR5 is Pinocchio's CRBA matrix."""
    desc = load(UR5)
    xml = re.sub(r"<pinflex:flexible .*?</pinflex:flexible>", "", desc.urdf_xml, flags=re.S)
    rigid = FlexibleModel(parse(xml))
    assert rigid.nx == 0
    rng = np.random.default_rng(0)
    for q in rng.uniform(-3, 3, size=(4, rigid.nv)):
        M, _ = rigid.matrices(q, check_bounds=False)
        Mc = pin.crba(rigid.model, rigid.model.createData(), rigid.pin_configuration(q))
        Mc = np.triu(Mc) + np.triu(Mc, 1).T
        # the design payload is in M through the point-mass path, not in the URDF inertia
        payload = rigid.design[0].nominal
        Mp = payload * _point_mass_matrix(rigid, q)
        np.testing.assert_allclose(M, Mc + Mp, atol=1e-12 * np.abs(Mc).max())


def _point_mass_matrix(model, q):
    """Mass matrix of a unit point mass at the end-effector frame, from Pinocchio."""
    fid = model.model.getFrameId("ee_link")
    data = model.model.createData()
    pin.computeJointJacobians(model.model, data, model.pin_configuration(q))
    J = pin.getFrameJacobian(model.model, data, fid, pin.LOCAL_WORLD_ALIGNED)[:3]
    return J.T @ J


def test_frequencies_do_not_depend_on_base_rotation_about_gravity_free_axis():
    """Turning the UR5's first joint about the vertical does not change any frequency."""
    m = FlexibleModel(UR5)
    q = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
    q2 = q.copy()
    q2[0] = 2.1
    np.testing.assert_allclose(m.frequencies(q2), m.frequencies(q), rtol=1e-8)


def test_mode_shapes_are_mass_normalised_and_solve_the_full_problem(two_link_planar):
    """Returned shapes satisfy K φ = λ M φ on the full 23-dof pair and φᵀMφ = I."""
    q, y = np.array([1.2, 4.0]), np.array([0.1, 0.2])
    r = two_link_planar.modes(q, y, n_modes=5)
    M, K = two_link_planar.matrices(q, y)
    np.testing.assert_allclose(r.shapes.T @ M @ r.shapes, np.eye(5), atol=1e-10)
    res = K @ r.shapes - M @ r.shapes * r.eigvals
    assert np.abs(res).max() < 1e-9 * r.eigvals.max()


def test_batched_frequencies_equal_single_pose_modes(two_link_planar):
    """The batched eigenvalue path equals scipy's eigh of each pose."""
    rng = np.random.default_rng(1)
    Q = rng.uniform(0, 2 * np.pi, size=(6, 2))
    fb = two_link_planar.frequencies(Q)
    for q, f in zip(Q, fb):
        np.testing.assert_allclose(f, two_link_planar.modes(q).freq_hz, rtol=1e-11)


def test_node_motion_of_a_mode_matches_its_elastic_coordinates(two_link_planar):
    """World nodal motion of node k of link 2 equals the rotated elastic dofs plus ERLS motion."""
    q = np.array([0.4, 1.9])
    r = two_link_planar.modes(q, n_modes=2)
    tip = r.node_positions["link2"][-1]
    L1, L2 = 0.6, 0.45
    np.testing.assert_allclose(
        tip, [L1 * np.cos(0.4) + L2 * np.cos(1.9), L1 * np.sin(0.4) + L2 * np.sin(1.9), 0],
        atol=1e-14,
    )
    # elastic motion is orthogonal to nothing in particular, but the planar model moves in-plane
    assert np.abs(r.node_motion["link1"][..., 2]).max() < 1e-14
    assert np.abs(r.node_motion["link1"][..., 3:5]).max() < 1e-14
    # link 1 hangs from the ground: node k moves by its own elastic dofs (beam axes turned by
    # q1 into the world) plus the rigid rotation phi_q1 about z through the base
    model = two_link_planar
    names = list(model.x_names)
    R = _rot_z(q[0]) @ model.plan.beams["link1"].spec.rotation
    for m in range(2):
        phi = r.shapes[:, m]
        dq1 = phi[model.nx]
        for k in range(1, model.plan.beams["link1"].spec.elements + 1):
            u = np.array([phi[names.index(f"link1.n{k}.u{a}")] for a in "xy"] + [0.0])
            p = r.node_positions["link1"][k]
            expected = R @ u + dq1 * np.array([-p[1], p[0], 0.0])
            np.testing.assert_allclose(r.node_motion["link1"][m, k, :3], expected, atol=1e-12)
            rz = phi[names.index(f"link1.n{k}.rz")]
            assert r.node_motion["link1"][m, k, 5] == pytest.approx(rz + dq1, abs=1e-12)


def _rot_z(angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def test_panda_overlay_loads_and_is_invariant_about_the_vertical():
    """The flexible Panda overlay has 9 rigid modes and frequencies independent of joint 1."""
    from conftest import ROOT

    m = FlexibleModel(ROOT / "urdf" / "panda_flexible.xml")
    assert m.nv == 9 and m.nx == 60
    q = np.array([0.1, -0.5, 0.3, -2.0, 0.2, 1.5, 0.7, 0.01, 0.01])
    q2 = q.copy()
    q2[0] += 1.3
    np.testing.assert_allclose(m.frequencies(q2), m.frequencies(q), rtol=1e-8)
