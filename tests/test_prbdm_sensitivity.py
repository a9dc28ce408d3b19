"""Exact Jacobians of the PRBDM losses against central finite differences and a second path."""

from dataclasses import replace

import numpy as np
import pytest

from pinflex.prbdm.beams import random_beam
from pinflex.prbdm.chain import build_chain, mass_matrix, solve_tip_statics
from pinflex.prbdm.massmatrix import (
    ChainWorkspace,
    link_moments,
    mass_structure,
    pose_mass_matrix,
)
from pinflex.prbdm.planar import planar_statics
from pinflex.prbdm.problem import build_problem, compute_truth, evaluate, reference_stiffness
from pinflex.prbdm.sensitivity import evaluate_with_jacobian, residuals_and_jacobian
from pinflex.prbdm.warmstarts import WarmStarts


@pytest.fixture(scope="module")
def beam_truth():
    """A six-section random beam with its truth at three load levels."""
    beam = random_beam(3, n_sections=6)
    return beam, compute_truth(beam, 4, alphas=(0.5, 2.0, 5.0))


def _design(problem, seed):
    rng = np.random.default_rng(seed)
    gamma = 0.03 + 0.85 * rng.dirichlet(np.ones(problem.n_joints + 1))
    base = 0.0
    if problem.stiffness_law == "paper":
        # Eq. 14's scale sqrt(E I / m) is not a stiffness; put the springs near physical ones.
        physical = reference_stiffness(replace(problem, stiffness_law="segment"), gamma)
        base = float(np.log(np.median(physical / reference_stiffness(problem, gamma))))
    return np.concatenate([gamma, base + rng.normal(0, 0.3, problem.n_stiffness_params)])


def _central(fun, x, h=1e-6):
    cols = []
    for i in range(x.size):
        e = np.zeros_like(x)
        e[i] = h * max(1.0, abs(x[i]))
        cols.append((fun(x + e) - fun(x - e)) / (2 * e[i]))
    return np.column_stack(cols)


@pytest.mark.parametrize("law, poses", [("segment", "straight"), ("paper", "paper"),
                                        ("segment", "paper")])
def test_jacobian_matches_finite_differences_of_reference_path(beam_truth, law, poses):
    """Residuals equal the rebuild-per-design path; the exact Jacobian equals its differences."""
    beam, truth = beam_truth
    problem = build_problem(beam, 3, 3, poses, law, truth)
    x = _design(problem, 1)
    fast = evaluate_with_jacobian(problem, x, ChainWorkspace(beam, 3))
    ref = evaluate(problem, x)
    assert fast.evaluation.failed_loads == 0
    np.testing.assert_allclose(fast.evaluation.residuals, ref.residuals, rtol=0, atol=1e-12)
    fd = _central(lambda y: evaluate(problem, y).residuals, x)
    scale = np.abs(fd).max()
    assert np.abs(fast.jacobian - fd).max() < 1e-6 * scale


def test_closed_form_mass_matrix_and_its_derivative(beam_truth):
    """S^T (C o G) S equals Pinocchio's CRBA; dG/ds equals differences of CRBA matrices."""
    beam, _ = beam_truth
    ws = ChainWorkspace(beam, 4)
    gamma = np.array([0.2, 0.15, 0.3, 0.25, 0.1])
    theta = np.array([0.3, -0.2, 0.5, 0.1])
    s, lengths, links = ws.update(gamma)
    mu, dmu = link_moments(beam, s, links)
    g, dg = mass_structure(lengths[1:], mu, dmu)
    crba = mass_matrix(build_chain(beam, gamma, np.ones(4)), theta)
    np.testing.assert_allclose(pose_mass_matrix(g, theta)[0], crba, rtol=0, atol=1e-13)
    np.testing.assert_allclose(ws.mass_matrix(theta), crba, rtol=0, atol=1e-13)
    for j in range(4):
        h = 1e-6
        plus, minus = gamma.copy(), gamma.copy()
        # Moving joint j+1 by h: link j grows by h / L, link j+1 shrinks by it.
        plus[j] += h
        plus[j + 1] -= h
        minus[j] -= h
        minus[j + 1] += h
        diff = (mass_matrix(build_chain(beam, plus, np.ones(4)), theta)
                - mass_matrix(build_chain(beam, minus, np.ones(4)), theta)) / (2 * h)
        q = np.cumsum(theta)
        tri = np.tril(np.ones((4, 4)))
        exact = tri.T @ (np.cos(q[:, None] - q[None, :]) * dg[:, :, j]) @ tri
        np.testing.assert_allclose(exact, diff, rtol=0, atol=1e-6 * np.abs(crba).max())


def test_batched_planar_newton_equals_pinocchio_newton(beam_truth):
    """planar_statics gives solve_tip_statics' angles on every load, and refuses the same."""
    beam, truth = beam_truth
    gamma = np.array([0.1, 0.3, 0.35, 0.25])
    stiff = np.array([4e6, 2e6, 1e6])
    chain = build_chain(beam, gamma, stiff)
    theta, ok = planar_statics(stiff, chain.link_lengths_m[1:], truth.forces_n,
                               np.zeros((3, 3)), 4)
    assert ok.all()
    for i, force in enumerate(truth.forces_n):
        ref = solve_tip_statics(chain, force, load_steps=4)
        np.testing.assert_allclose(theta[i], ref.theta, rtol=0, atol=1e-10)
    # A huge load in one step fails both ways (no silent wrong branch).
    big = np.array([[0.0, -1e3 * truth.forces_n[-1, 1]]])
    _, ok_big = planar_statics(stiff, chain.link_lengths_m[1:], -big, np.zeros((1, 3)), 1)
    assert not ok_big[0]


def test_warm_starts_are_explicit_and_do_not_change_answers(beam_truth):
    """A search's warm starts live in a WarmStarts object; cold and warm answers agree."""
    beam, truth = beam_truth
    problem = build_problem(beam, 3, 3, "straight", "segment", truth)
    assert not any(name.startswith("_") for name in vars(problem))
    x = _design(problem, 2)
    warm = WarmStarts()
    ws = ChainWorkspace(beam, 3)
    first = evaluate_with_jacobian(problem, x, ws, warm)
    assert sorted(warm.angles) == [0, 1, 2]
    again = evaluate_with_jacobian(problem, x * 1.0001, ws, warm)
    cold = evaluate_with_jacobian(problem, x * 1.0001, ChainWorkspace(beam, 3))
    # Equal to the Newton tolerance (1e-10 relative residual).
    np.testing.assert_allclose(again.evaluation.residuals, cold.evaluation.residuals,
                               rtol=0, atol=1e-9)
    assert first.evaluation.failed_loads == 0


@pytest.mark.parametrize("law, poses", [("segment", "straight"), ("paper", "paper")])
def test_lazy_jacobian_equals_the_full_evaluation(beam_truth, law, poses):
    """The fit's inner loop (residuals now, Jacobian on demand) is the full evaluation."""
    beam, truth = beam_truth
    problem = build_problem(beam, 3, 3, poses, law, truth)
    x = _design(problem, 5)
    full = evaluate_with_jacobian(problem, x, ChainWorkspace(beam, 3))
    res, jacobian = residuals_and_jacobian(problem, x, ChainWorkspace(beam, 3))
    np.testing.assert_allclose(res, full.evaluation.residuals, rtol=0, atol=1e-13)
    np.testing.assert_allclose(jacobian(), full.jacobian, rtol=1e-10, atol=1e-12)


def test_warm_start_prediction_is_second_order(beam_truth):
    """The predicted start base + slopes dx misses the converged angles by O(|dx|^2)."""
    beam, truth = beam_truth
    problem = build_problem(beam, 3, 3, "straight", "segment", truth)
    x = _design(problem, 7)
    warm = WarmStarts()
    _, jacobian = residuals_and_jacobian(problem, x, ChainWorkspace(beam, 3), warm)
    jacobian()                                       # keeps the base angles and slopes
    direction = np.random.default_rng(1).normal(size=x.size)
    misses = []
    for h in (1e-2, 5e-3):
        x_new = x + h * direction
        predicted = np.array([warm.start(k, x_new) for k in range(3)])
        together, have = warm.starts(x_new, 3, 3)        # the fits' form: all loads at once
        assert have.all()
        np.testing.assert_allclose(together, predicted, rtol=0, atol=1e-14)
        cold = WarmStarts()
        residuals_and_jacobian(problem, x_new, ChainWorkspace(beam, 3), cold)
        exact = np.array([cold.angles[k] for k in range(3)])
        misses.append(np.max(np.abs(predicted - exact)))
        base = np.array([warm.base[k] for k in range(3)])
        assert misses[-1] < 0.1 * np.max(np.abs(exact - base))  # far better than no prediction
    assert 3.0 < misses[0] / misses[1] < 5.0             # halving the step quarters the miss
