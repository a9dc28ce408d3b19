"""Tests of pinflex.prbdm.chain: the nR chain as a Pinocchio model, statics and URDF."""

import numpy as np
import pinocchio as pin
import pytest

from pinflex.exceptions import ConfigurationError, InvalidChain, NewtonDivergence
from pinflex.prbdm.beams import chain_segments, random_beam, uniform_beam
from pinflex.prbdm.chain import (
    _statics_terms,
    build_chain,
    chain_frequencies,
    mass_matrix,
    mass_matrix_condition,
    solve_tip_statics,
    tip_jacobian,
    tip_position,
    to_urdf,
)
from pinflex.prbdm.truth import beam_frequencies, elastica_tip

EI_UNIFORM = 205e9 * 0.3624 * 0.040532**3 / 12


def _planar_mass_matrix(beam, gamma, theta):
    """Independent Lagrangian mass matrix of a planar chain from segment properties."""
    lengths = np.asarray(gamma) * beam.length_m
    starts = np.cumsum(lengths)[:-1]
    segs = chain_segments(beam, np.concatenate([starts, [beam.length_m]]))
    n = theta.size
    q = np.cumsum(theta)
    origins = [np.array([lengths[0], 0.0])]
    for j in range(1, n):
        origins.append(origins[-1] + lengths[j] * np.array([np.cos(q[j - 1]), -np.sin(q[j - 1])]))
    m = np.zeros((n, n))
    for k, seg in enumerate(segs):
        d = seg.com_m - starts[k]
        com = origins[k] + d * np.array([np.cos(q[k]), -np.sin(q[k])])
        jac = np.zeros((2, n))
        for i in range(k + 1):
            arm = com - origins[i]
            jac[:, i] = [arm[1], -arm[0]]  # rotation about +Y: d(x, z) = (z, -x) dtheta
        m[: k + 1, : k + 1] += seg.mass_kg * (jac.T @ jac)[: k + 1, : k + 1]
        m[: k + 1, : k + 1] += seg.inertia_com_kg_m2[1]
    return m


def test_crba_matches_planar_lagrangian():
    """Pinocchio's CRBA equals an independent planar Lagrangian mass matrix at a random pose."""
    beam = random_beam(1)
    gamma = np.array([0.12, 0.3, 0.08, 0.25, 0.25])
    chain = build_chain(beam, gamma, np.ones(4))
    theta = np.array([0.3, -0.2, 0.5, 0.1])
    assert np.allclose(mass_matrix(chain, theta), _planar_mass_matrix(beam, gamma, theta),
                       rtol=1e-12, atol=1e-12)


def test_one_joint_frequency_is_spring_over_inertia():
    """A 1R chain oscillates at sqrt(K / I_joint) / 2 pi with I_joint = I_com + m d^2."""
    beam = uniform_beam()
    chain = build_chain(beam, np.array([0.15, 0.85]), np.array([1e6]))
    seg = chain_segments(beam, np.array([0.15, 1.0]))[0]
    inertia = seg.inertia_com_kg_m2[1] + seg.mass_kg * (seg.com_m - 0.15) ** 2
    assert chain_frequencies(chain)[0] == pytest.approx(np.sqrt(1e6 / inertia) / (2 * np.pi),
                                                        rel=1e-12)


def _discretised_chain(beam, n):
    """Chain with half links at both ends and springs EI / l: a finite-difference beam."""
    gamma = np.full(n + 1, 1.0 / n)
    gamma[0] = gamma[-1] = 0.5 / n
    return build_chain(beam, gamma, np.full(n, EI_UNIFORM * n))


def test_many_link_chain_converges_to_elastica():
    """A 64R finite-difference chain reproduces the elastica tip under large loads to 1e-4 L."""
    beam = uniform_beam()
    chain = _discretised_chain(beam, 64)
    for alpha in (1.0, 5.0):
        force = np.array([0.0, -alpha * EI_UNIFORM])
        tip = solve_tip_statics(chain, force, load_steps=4).tip_m
        assert np.linalg.norm(tip - elastica_tip(beam, force).tip_m) < 1e-4


def test_many_link_chain_frequencies_approach_beam():
    """The 64R chain's first three frequencies are within 0.5 % of the converged beam's."""
    beam = uniform_beam()
    chain = _discretised_chain(beam, 64)
    assert np.allclose(chain_frequencies(chain)[:3], beam_frequencies(beam, 3).freq_hz,
                       rtol=5e-3)


def test_tangent_stiffness_matches_finite_differences():
    """The Newton tangent equals central differences of the statics residual."""
    chain = build_chain(random_beam(2), np.array([0.1, 0.2, 0.3, 0.2, 0.2]),
                        np.array([3e5, 2e5, 1e5, 5e4]))
    data = chain.model.createData()
    theta = np.array([0.1, 0.4, -0.2, 0.3])
    force = np.array([2e5, -6e5])
    _, tangent, _ = _statics_terms(chain, data, theta, force)
    fd = np.zeros((4, 4))
    for i in range(4):
        step = np.zeros(4)
        step[i] = 1e-6
        fd[:, i] = (_statics_terms(chain, data, theta + step, force)[0]
                    - _statics_terms(chain, data, theta - step, force)[0]) / 2e-6
    assert np.allclose(tangent, fd, rtol=1e-7, atol=1e-7 * np.abs(tangent).max())


def test_tip_jacobian_matches_finite_differences():
    """The Pinocchio tip Jacobian equals central differences of forward kinematics."""
    chain = build_chain(random_beam(2), np.array([0.1, 0.3, 0.3, 0.3]), np.ones(3))
    theta = np.array([0.2, -0.4, 0.7])
    fd = np.column_stack([(tip_position(chain, theta + e) - tip_position(chain, theta - e)) / 2e-7
                          for e in np.eye(3) * 1e-7])
    assert np.allclose(tip_jacobian(chain, theta), fd, atol=1e-8)


@pytest.mark.parametrize("alpha", [0.5, 1.0, 2.0, 3.0, 5.0])
def test_howell_1r_tip_stays_on_elastica_path(alpha):
    """Howell's 1R (gamma = 0.85) circle passes within 0.25 % of L of the elastica tip."""
    beam = uniform_beam()
    tip = elastica_tip(beam, np.array([0.0, -alpha * EI_UNIFORM])).tip_m
    assert abs(np.hypot(tip[0] - 0.15, tip[1]) - 0.85) < 2.5e-3


@pytest.mark.parametrize("alpha, w_ref, u_ref", [(1.0, 0.30172, 0.05643), (2.0, 0.49346, 0.16064)])
def test_howell_1r_load_deflection_matches_mattiasson(alpha, w_ref, u_ref):
    """With K = gamma K_Theta EI / L (K_Theta = 2.65) the 1R tip is within 1 % of L of the table."""
    chain = build_chain(uniform_beam(), np.array([0.15, 0.85]),
                        np.array([0.85 * 2.65 * EI_UNIFORM]))
    tip = solve_tip_statics(chain, np.array([0.0, -alpha * EI_UNIFORM])).tip_m
    assert np.hypot(-tip[1] - w_ref, 1.0 - tip[0] - u_ref) < 1e-2


def test_extreme_load_raises_newton_divergence():
    """A 5R chain under alpha = 1000 in one load step raises NewtonDivergence, not a number."""
    chain = build_chain(uniform_beam(), np.array([0.1, 0.2, 0.2, 0.2, 0.2, 0.1]),
                        np.full(5, 5 * EI_UNIFORM))
    with pytest.raises(NewtonDivergence, match="increase load_steps"):
        solve_tip_statics(chain, np.array([0.0, -1000.0 * EI_UNIFORM]))


def test_newton_never_returns_a_wrong_branch():
    """Across loads, one-step Newton either raises or returns the continuation solution."""
    chain = build_chain(uniform_beam(), np.array([0.15, 0.85]),
                        np.array([0.85 * 2.65 * EI_UNIFORM]))
    outcomes = []
    for alpha in np.logspace(-1, 4, 30):
        force = np.array([0.0, -alpha * EI_UNIFORM])
        try:
            theta = solve_tip_statics(chain, force).theta
        except NewtonDivergence:
            outcomes.append("raised")
            continue
        reference = solve_tip_statics(chain, force, load_steps=400).theta
        assert theta == pytest.approx(reference, abs=1e-9)
        outcomes.append("ok")
    assert "raised" in outcomes and "ok" in outcomes


def test_mass_matrix_regular_at_straight_pose():
    """M(0) is positive definite and well conditioned; the tip Jacobian has rank 1 there."""
    chain = build_chain(uniform_beam(), np.full(6, 1 / 6), np.full(5, EI_UNIFORM))
    np.linalg.cholesky(mass_matrix(chain, np.zeros(5)))
    cond = mass_matrix_condition(chain, np.linspace(0, 0.3, 4)[:, None] * np.ones(5))
    assert np.all(cond < 1e4)
    sv = np.linalg.svd(tip_jacobian(chain, np.zeros(5)), compute_uv=False)
    assert sv[1] < 1e-12 * sv[0]


def test_urdf_export_loads_in_pinocchio_with_same_dynamics():
    """The exported URDF loads in plain Pinocchio and gives the same CRBA and tip position."""
    beam = random_beam(3)
    chain = build_chain(beam, np.array([0.1, 0.3, 0.2, 0.4]), np.array([1e5, 2e5, 3e5]))
    text = to_urdf(chain)
    assert "pinflex_spring" in text
    model = pin.buildModelFromXML(text)
    data = model.createData()
    theta = np.array([0.3, -0.1, 0.6])
    assert np.allclose(pin.crba(model, data, theta), mass_matrix(chain, theta), rtol=1e-12,
                       atol=1e-14)
    pin.framesForwardKinematics(model, data, theta)
    tip = data.oMf[model.getFrameId("tip")].translation[[0, 2]]
    assert np.allclose(tip, tip_position(chain, theta), atol=1e-14)


def test_gamma_off_simplex_raises():
    """Link fractions that do not sum to 1 raise InvalidChain."""
    with pytest.raises(InvalidChain, match="sum"):
        build_chain(uniform_beam(), np.array([0.2, 0.2]), np.ones(1))


def test_non_positive_spring_raises():
    """A non-positive spring stiffness raises InvalidChain."""
    with pytest.raises(InvalidChain, match="positive"):
        build_chain(uniform_beam(), np.array([0.5, 0.5]), np.array([-1.0]))


def test_wrong_pose_shape_raises():
    """Joint angles of the wrong length raise ConfigurationError."""
    chain = build_chain(uniform_beam(), np.array([0.5, 0.5]), np.ones(1))
    with pytest.raises(ConfigurationError):
        chain_frequencies(chain, np.zeros(3))
