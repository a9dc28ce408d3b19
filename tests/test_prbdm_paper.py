"""Paper 001's definitions, determinacy, classic PRBMs and the epsilon-constraint front."""

import numpy as np
import pytest
import scipy.optimize

from pinflex.prbdm.beams import equivalent_bending_stiffness, random_beam, uniform_beam
from pinflex.prbdm.chain import build_chain, chain_frequencies, solve_tip_statics
from pinflex.prbdm.classic import HOWELL_1R, SU_3R, SU_3R_FORCE, SU_3R_MOMENT
from pinflex.prbdm.mapping import fit_prbdm
from pinflex.prbdm.paper import eq14_reference, paper_losses, paper_problem
from pinflex.prbdm.pareto import epsilon_constraint_front, hypervolume_2d, nondominated
from pinflex.prbdm.problem import (
    build_problem,
    compute_truth,
    evaluate,
    paper_poses,
    reference_stiffness,
)


@pytest.fixture(scope="module")
def small():
    """A five-section random beam with 3 modes and two load levels."""
    beam = random_beam(5, n_sections=5)
    return beam, compute_truth(beam, 3, alphas=(1.0, 4.0))


def test_eq14_width_drops_out():
    """sqrt(E I_j / m_j) equals sqrt(E t^2 / (12 rho L_j)) on any planform of uniform t."""
    beam = random_beam(2)
    truth = compute_truth(beam, 3, alphas=())
    problem = build_problem(beam, 3, 3, "paper", "paper", truth)
    gamma = np.array([0.1, 0.45, 0.15, 0.3])
    np.testing.assert_allclose(reference_stiffness(problem, gamma),
                               eq14_reference(beam, gamma[1:] * beam.length_m), rtol=1e-12)


def test_paper_losses_are_the_papers_formulas(small):
    """Eq. 15a is the sum over the eps = 0.1 poses of eq. 16, computed here by hand."""
    beam, truth = small
    problem = build_problem(beam, 2, 2, "straight", "segment", truth)
    gamma = np.array([0.2, 0.5, 0.3])
    k = np.array([3e6, 1e6])
    x = np.concatenate([gamma, np.log(k / reference_stiffness(problem, gamma))])
    losses = paper_losses(problem, x)
    chain = build_chain(beam, gamma, k)
    poses = paper_poses(2, 0.05, 0.1)
    f_truth = truth.modes.freq_hz[:2]
    eq16 = [np.linalg.norm(chain_frequencies(chain, q) - f_truth) / np.linalg.norm(f_truth)
            for q in poses]
    assert losses.n_poses == len(poses) == 8
    assert losses.eq15a_sum == pytest.approx(sum(eq16), rel=1e-10)
    assert losses.eq15a_mean == pytest.approx(np.mean(eq16), rel=1e-10)
    eq19 = [np.linalg.norm(solve_tip_statics(chain, f, load_steps=4).tip_m - t) / np.linalg.norm(t)
            for f, t in zip(truth.forces_n, truth.tips_m)]
    assert losses.eq19_rms == pytest.approx(np.sqrt(np.mean(np.square(eq19))), rel=1e-8)
    assert losses.eq27_sum == pytest.approx(np.hypot(sum(eq16), losses.eq19_rms), rel=1e-12)


def test_pareto_sweep_uses_eps_001(small):
    """The Pareto sweep of eq. 11 has eps = 0.01: about ten times the single-objective poses."""
    beam, truth = small
    assert paper_problem(beam, 3, truth, epsilon=0.01).poses.shape[0] == 48
    assert paper_problem(beam, 3, truth).poses.shape[0] == 5


def test_eigen_only_fit_is_reported_exactly_determined(small):
    """N modes at one pose with 2n free parameters: 'exactly determined', not a loss."""
    beam, truth = small
    eig = fit_prbdm(beam, 2, 2, "eigen", n_starts=2, truth=truth)
    assert eig.exactly_determined and (eig.n_free_parameters, eig.n_matched) == (4, 2)
    comb = fit_prbdm(beam, 2, 2, truth=truth, n_starts=2)
    assert comb.objective == "combined" and not comb.exactly_determined
    assert (comb.n_free_parameters, comb.n_matched) == (4, 6)


def test_su_3r_linear_compliance_is_its_closed_form():
    """Su's 3R tip compliance is sum(arm_i^2 / k_i) L^3/EI = 0.3407 (1/3 exact): 2.2 % soft."""
    beam = uniform_beam()
    ei = equivalent_bending_stiffness(beam)
    arms = np.array([0.9, 0.55, 0.15])
    expected = np.sum(arms**2 / np.array([3.51, 2.99, 2.58]))
    tip = solve_tip_statics(SU_3R.chain(beam), np.array([0.0, -1e-6 * ei])).tip_m
    assert -tip[1] / 1e-6 == pytest.approx(expected, rel=1e-5)
    assert HOWELL_1R.chain(beam).stiffness_nm_rad[0] == pytest.approx(0.85 * 2.65 * ei)


def _su_fit(targets, torques_of):
    """Least-squares k_i of Su's 3R following the tip states (x, y, angle) / L, one per row.

    Each state is met exactly by inverse kinematics (continued from the previous one), the
    joint torques come from the load, and k_i = sum(tau_i theta_i) / sum(theta_i^2).
    """
    g = np.array([0.10, 0.35, 0.40, 0.15])

    def tip(t):
        q = np.cumsum(t)
        return np.array([g[0] + g[1:] @ np.cos(q), g[1:] @ np.sin(q), q[-1]])

    theta, tau, guess = [], [], np.full(3, targets[0][2] / 3)
    for target in targets:
        guess = scipy.optimize.least_squares(lambda t: tip(t) - target, guess, xtol=1e-15,
                                             ftol=1e-15, gtol=1e-15).x
        assert np.linalg.norm(tip(guess) - target) < 1e-10
        theta.append(guess)
        tau.append(torques_of(guess, g))
    theta, tau = np.array(theta), np.array(tau)
    return np.sum(tau * theta, axis=0) / np.sum(theta**2, axis=0)


def test_su_3r_end_moment_set_is_the_circular_arc_fit():
    """The published end-moment set is the least-squares fit to circular arcs up to 1.5 pi.

    Under an end moment the beam is a circular arc (tip angle theta0 = ML/EI) and every joint
    carries the moment: k_i theta_i = theta0. Sampling theta0 uniformly on (0, 1.5 pi]
    reproduces Su's numbers to 1e-3; the load-independent Table-1 set is not this fit.
    """
    th0 = np.linspace(1e-3, 1.5 * np.pi, 300)
    arcs = np.column_stack([np.sin(th0) / th0, (1 - np.cos(th0)) / th0, th0])
    k = _su_fit(arcs, lambda t, g: np.full(3, np.sum(t)))
    assert k == pytest.approx(SU_3R_MOMENT.stiffness_coefficients, rel=1e-3)
    assert np.max(np.abs(k / np.array(SU_3R.stiffness_coefficients) - 1)) > 0.06


def test_su_3r_end_force_set_is_a_small_angle_force_fit():
    """The published end-force set is the fit to a transverse end force at moderate angles.

    Tip states of a uniform cantilever under a transverse end force from the elastica's first
    integral, theta' = c sqrt(sin theta0 - sin theta) with c^2 = 2 F L^2/EI (quadrature here,
    tip angle theta0 <= 0.5 rad); the joint torques are J^T F. The fit agrees with Su's set to
    1 % (the set depends on the fitted range: up to 1.2 rad its third coefficient is 8 % lower).
    """
    from scipy.integrate import quad

    def elastica(theta0):
        """Tip (x, y, angle) / L and F L^2/EI of the end-force cantilever (L = 1)."""
        def integral(weight):
            # theta = theta0 - w^2 removes the endpoint's inverse square root.
            return quad(lambda w: 2 * w * weight(theta0 - w * w)
                        / np.sqrt(np.sin(theta0) - np.sin(theta0 - w * w)),
                        0.0, np.sqrt(theta0), epsabs=1e-13, epsrel=1e-13)[0]
        c = integral(lambda t: 1.0)
        return (2 * np.sqrt(np.sin(theta0)) / c, integral(np.sin) / c, theta0), c * c / 2

    pairs = [elastica(t0) for t0 in np.linspace(0.005, 0.5, 100)]
    forces = iter([f for _, f in pairs])

    def torques(t, g):
        q, f = np.cumsum(t), next(forces)
        return np.array([f * (g[1 + j:] @ np.cos(q[j:])) for j in range(3)])

    k = _su_fit(np.array([state for state, _ in pairs]), torques)
    assert k == pytest.approx(SU_3R_FORCE.stiffness_coefficients, rel=1e-2)


def test_hypervolume_of_a_staircase():
    """Two points dominate an L-shaped area up to the reference point."""
    assert hypervolume_2d(np.array([[1.0, 3.0], [2.0, 1.0]]), (4.0, 4.0)) == pytest.approx(7.0)
    assert hypervolume_2d(np.array([[5.0, 1.0]]), (4.0, 4.0)) == 0.0
    mask = nondominated(np.array([[1.0, 3.0], [2.0, 1.0], [2.5, 3.5]]))
    assert mask.tolist() == [True, True, False]


def test_epsilon_constraint_points_meet_their_bounds(small):
    """Each epsilon-constraint design satisfies its deflection bound and is not dominated."""
    beam, truth = small
    problem = build_problem(beam, 2, 2, "straight", "segment", truth)
    fit = fit_prbdm(beam, 2, 2, "combined", n_starts=2, truth=truth)
    x = np.concatenate([fit.link_fractions, np.log(fit.correction_factors)])
    base = evaluate(problem, x)
    bounds = base.deflection_error * np.array([0.8, 1.5])
    front = epsilon_constraint_front(problem, [x], bounds)
    assert front
    for design, ev in front:
        assert ev.deflection_error <= bounds.max() * (1 + 1e-6)
        assert evaluate(problem, design).eigen_error == pytest.approx(ev.eigen_error, rel=1e-8)
