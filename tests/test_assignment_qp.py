"""Tests of pinflex.assignment: the assignment QP (paper 000, eq. 10–14) and its solvers."""

from __future__ import annotations

import numpy as np
import pytest

from pinflex.assignment import (
    AssignmentQP,
    build_assignment_qp,
    solve_assignment_qp,
    solve_assignment_qp_scipy,
)
from pinflex.exceptions import AssignmentInfeasible, InvalidAssignmentProblem


def grid(ns, seed=0):
    """A non-uniform time grid [s] and its trapezoidal weights, computed here by hand."""
    rng = np.random.default_rng(seed)
    t = np.concatenate([[0.0], np.cumsum(rng.uniform(0.005, 0.015, ns - 1))])
    w = np.zeros(ns)
    w[:-1] += 0.5 * np.diff(t)
    w[1:] += 0.5 * np.diff(t)
    return t, w


def random_modes(nm, ns, ny, seed=0, scale=1.0):
    """Smooth random l0 (nm, ns), L (nm, ns, ny) and targets (nm, ns) along a grid."""
    rng = np.random.default_rng(seed)
    t, w = grid(ns, seed)
    basis = np.stack([np.ones_like(t), np.sin(5 * t), np.cos(3 * t), t], axis=-1)
    l0 = scale * (1.0 + 0.2 * basis @ rng.normal(size=(4, nm))).T
    L = scale * np.einsum("kb,bmj->mkj", basis, rng.normal(size=(4, nm, ny)))
    targets = scale * (1.0 + 0.1 * rng.normal(size=(nm, 1))) * np.ones((nm, ns))
    return l0, L, targets, w


def direct_cost(l0, L, targets, w, dy, mode_weights=None):
    """½ Σ_i w_i Σ_k ω_k (l0 + L dy − target)², evaluated sample by sample."""
    mode_weights = np.ones(len(l0)) if mode_weights is None else mode_weights
    total = 0.0
    for i in range(len(l0)):
        for k in range(len(w)):
            total += 0.5 * mode_weights[i] * w[k] * (l0[i, k] + L[i, k] @ dy - targets[i, k]) ** 2
    return total


def test_cost_is_exact_including_the_constant():
    """AssignmentQP.cost equals the quadrature of the squared mismatch at any δy."""
    l0, L, d, w = random_modes(2, 40, 3, seed=1)
    mw = np.array([1.0, 0.3])
    qp = build_assignment_qp(l0, L, d, w, lower=-1.0, upper=1.0, mode_weights=mw)
    for dy in np.random.default_rng(2).normal(size=(4, 3)):
        assert qp.cost(dy) == pytest.approx(direct_cost(l0, L, d, w, dy, mw), rel=1e-12)


def test_multi_mode_cost_is_the_sum_of_single_mode_costs():
    """R, h, c and the cost of a two-mode problem are the sums of the single-mode ones."""
    l0, L, d, w = random_modes(2, 30, 2, seed=3)
    both = build_assignment_qp(l0, L, d, w, lower=-1.0, upper=1.0)
    single = [build_assignment_qp(l0[i], L[i], d[i], w, lower=-1.0, upper=1.0) for i in (0, 1)]
    np.testing.assert_allclose(both.R, single[0].R + single[1].R, rtol=1e-13)
    np.testing.assert_allclose(both.h, single[0].h + single[1].h, rtol=1e-13)
    assert both.c == pytest.approx(single[0].c + single[1].c, rel=1e-13)
    dy = np.array([0.3, -0.7])
    assert both.cost(dy) == pytest.approx(single[0].cost(dy) + single[1].cost(dy), rel=1e-13)


def test_unconstrained_optimum_is_the_weighted_least_squares_solution():
    """Without active constraints, ProxQP returns numpy's lstsq of the √ω-weighted system."""
    l0, L, d, w = random_modes(2, 60, 3, seed=4)
    mw = np.array([2.0, 0.5])
    sqrt_w = np.sqrt(mw[:, None] * w[None, :]).ravel()
    reference = np.linalg.lstsq(
        sqrt_w[:, None] * L.reshape(-1, 3), sqrt_w * (d - l0).ravel(), rcond=None
    )[0]
    qp = build_assignment_qp(l0, L, d, w, lower=-np.inf, upper=np.inf, mode_weights=mw)
    sol = solve_assignment_qp(qp)
    assert sol.found and sol.status == "PROXQP_SOLVED"
    np.testing.assert_allclose(sol.dy, reference, rtol=1e-7, atol=1e-9)
    # the same with a box far from the optimum: the bounds stay inactive
    boxed = build_assignment_qp(l0, L, d, w, lower=-1e3, upper=1e3, mode_weights=mw)
    np.testing.assert_allclose(solve_assignment_qp(boxed).dy, reference, rtol=1e-7, atol=1e-9)


def test_eigenvalue_sized_data_solve_to_the_least_squares_solution():
    """Data of eigenvalue size (≈1.4e6 rad²/s², Hessian ≈1e12) solve as well as unit data."""
    l0, L, d, w = random_modes(1, 152, 2, seed=5, scale=(2 * np.pi * 190) ** 2)
    reference = np.linalg.lstsq(np.sqrt(w)[:, None] * L[0], np.sqrt(w) * (d - l0)[0],
                                rcond=None)[0]
    sol = solve_assignment_qp(build_assignment_qp(l0, L, d, w, lower=-10.0, upper=10.0))
    np.testing.assert_allclose(sol.dy, reference, rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("seed", range(6))
def test_proxsuite_matches_scipy_with_active_box_bounds(seed):
    """On random problems whose box bounds bind, ProxQP and the SciPy solver agree to 1e-6."""
    l0, L, d, w = random_modes(2, 50, 4, seed=10 + seed)
    free = build_assignment_qp(l0, L, d, w, lower=-np.inf, upper=np.inf)
    optimum = solve_assignment_qp(free).dy
    bound = 0.5 * np.max(np.abs(optimum))  # cuts the free optimum: at least one bound binds
    qp = build_assignment_qp(l0, L, d, w, lower=-bound, upper=bound)
    sol, ref = solve_assignment_qp(qp), solve_assignment_qp_scipy(qp)
    assert np.any(np.isclose(np.abs(sol.dy), bound, rtol=0, atol=1e-9))
    np.testing.assert_allclose(sol.dy, ref.dy, atol=1e-6)
    raw = solve_assignment_qp(qp, polish=False)  # ProxQP's own iterate, before polishing
    np.testing.assert_allclose(raw.dy, ref.dy, atol=1e-6)
    assert sol.objective == pytest.approx(ref.objective, rel=1e-9)
    assert sol.max_violation <= 1e-9


def test_mass_budget_binds():
    """A total-mass budget below the unconstrained optimum's total is met with equality."""
    l0, L, d, w = random_modes(1, 80, 3, seed=20)
    free = solve_assignment_qp(build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0)).dy
    budget = free.sum() - 0.3
    qp = build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0,
                             A_ineq=np.ones((1, 3)), b_ineq=[budget])
    sol, ref = solve_assignment_qp(qp), solve_assignment_qp_scipy(qp)
    assert sol.dy.sum() == pytest.approx(budget, abs=1e-9)
    assert sol.dual_in[0] > 0.0  # the budget's multiplier: the constraint is active
    np.testing.assert_allclose(sol.dy, ref.dy, atol=1e-6)
    # independent check: minimise on the plane Σ δy = budget by eliminating one variable
    Z = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, -1.0]])
    y0 = np.array([0.0, 0.0, budget])
    sw = np.sqrt(w)
    z = np.linalg.lstsq(sw[:, None] * (L[0] @ Z), sw * (d - l0 - L @ y0)[0], rcond=None)[0]
    np.testing.assert_allclose(sol.dy, y0 + Z @ z, atol=1e-7)


def test_frequency_floor_is_active():
    """A floor above the unconstrained prediction somewhere is met exactly at its worst sample."""
    l0, L, d, w = random_modes(1, 60, 2, seed=30)
    free_qp = build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0)
    free = solve_assignment_qp(free_qp).dy
    predicted = l0[0] + L[0] @ free
    floor = np.min(predicted) + 0.3 * (np.max(predicted) - np.min(predicted))
    qp = build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0, floors=floor)
    assert qp.C.shape == (60, 2) and set(qp.constraint_groups) == {"floor"}
    sol, ref = solve_assignment_qp(qp), solve_assignment_qp_scipy(qp)
    margin = l0[0] + L[0] @ sol.dy - floor
    assert margin.min() == pytest.approx(0.0, abs=1e-8)
    assert sol.objective > free_qp.cost(free)
    np.testing.assert_allclose(sol.dy, ref.dy, atol=1e-6)


def test_bands_keep_each_sample_on_its_side():
    """Band rows keep samples above (below) the band where they start above (below) its middle."""
    ns = 40
    t, w = grid(ns, 7)
    l0 = np.where(np.arange(ns) % 2 == 0, 0.6, 1.4) + 0.1 * t  # both sides of the band (0.9, 1.1)
    L = np.column_stack([np.ones(ns), t])
    qp = build_assignment_qp(l0, L, 1.6, w, lower=-1.0, upper=1.0, bands=[(0, 0.9, 1.1)])
    np.testing.assert_array_equal(qp.band_sides[0], np.where(l0 >= 1.0, 1, -1))
    free = solve_assignment_qp(build_assignment_qp(l0, L, 1.6, w, lower=-1.0, upper=1.0)).dy
    assert np.any((l0 + L @ free > 0.9) & (qp.band_sides[0] < 0))  # the target pulls into the band
    sol = solve_assignment_qp(qp)
    value = l0 + L @ sol.dy
    below = qp.band_sides[0] < 0
    assert np.all(value[below] <= 0.9 + 1e-9) and np.all(value[~below] >= 1.1 - 1e-9)
    assert np.max(value[below]) == pytest.approx(0.9, abs=1e-9)  # the band edge binds
    np.testing.assert_allclose(sol.dy, solve_assignment_qp_scipy(qp).dy, atol=1e-6)


def test_equality_constraint_holds():
    """An equality row is satisfied to the solver tolerance."""
    l0, L, d, w = random_modes(1, 30, 3, seed=40)
    qp = build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0,
                             A_eq=[[1.0, -2.0, 0.5]], b_eq=[0.25])
    sol = solve_assignment_qp(qp)
    assert sol.dy @ [1.0, -2.0, 0.5] == pytest.approx(0.25, abs=1e-9)
    np.testing.assert_allclose(sol.dy, solve_assignment_qp_scipy(qp).dy, atol=1e-6)


@pytest.mark.parametrize(
    "kwargs, group",
    [
        ({"A_ineq": [[1.0, 1.0]], "b_ineq": [-3.0]}, "mass budget"),
        ({"floors": 1e3}, "floors"),
        ({"lower": [0.0, 1.0], "upper": [1.0, 0.5]}, "lower 1 > upper 0.5"),
    ],
)
def test_infeasible_problem_raises_and_names_the_conflict(kwargs, group):
    """Budget, floors or box that cannot be met raise AssignmentInfeasible naming the culprit."""
    l0, L, d, w = random_modes(1, 20, 2, seed=50)
    args = {"lower": -1.0, "upper": 1.0, **kwargs}
    qp = build_assignment_qp(l0, L, d, w, **args)
    with pytest.raises(AssignmentInfeasible) as info:
        solve_assignment_qp(qp)
    assert group in str(info.value)
    assert isinstance(info.value.problem, AssignmentQP)
    if info.value.result is not None:
        assert not info.value.result.found
    with pytest.raises(AssignmentInfeasible):
        solve_assignment_qp_scipy(qp)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"L": np.zeros((19, 2))},
        {"weights_t": np.ones(19)},
        {"targets": np.ones(7)},
        {"A_ineq": [[1.0, 1.0]]},
        {"bands": [(0, 2.0, 1.0)]},
        {"l0": np.full(20, np.nan)},
    ],
)
def test_inconsistent_inputs_raise(kwargs):
    """Mismatched shapes, half-given constraints, inverted bands and NaNs raise a named error."""
    l0, L, d, w = random_modes(1, 20, 2, seed=60)
    args = {"l0": l0[0], "L": L[0], "targets": d[0], "weights_t": w, **kwargs}
    with pytest.raises(InvalidAssignmentProblem):
        build_assignment_qp(args.pop("l0"), args.pop("L"), args.pop("targets"),
                            args.pop("weights_t"), lower=-1.0, upper=1.0, **args)


def test_solver_stopping_early_raises_with_its_result():
    """A feasible problem that ProxQP cannot finish in max_iter raises, carrying ProxQP's result."""
    l0, L, d, w = random_modes(1, 40, 3, seed=70)
    free = solve_assignment_qp(build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0)).dy
    qp = build_assignment_qp(l0, L, d, w, lower=-5.0, upper=5.0,
                             A_ineq=np.ones((1, 3)), b_ineq=[free.sum() - 0.3])
    with pytest.raises(AssignmentInfeasible) as info:
        solve_assignment_qp(qp, max_iter=1)
    assert "max_iter" in str(info.value)
    assert info.value.result is not None and not info.value.result.found
