"""Assignment options checked against independent computations (benchmark A arm).

Each test solves the same problem a second way that shares no code with the QP path: a bounded
least-squares solve (SciPy's lsq_linear) of the Taylor polynomial's weighted residuals, the
exact model's frequencies summed with trapezoid weights, or an equivalent constraint.
"""

import numpy as np
import pytest
from conftest import TWO_LINK
from scipy.optimize import lsq_linear

from pinflex.assignment import Target, assign_frequencies, brute_force, build_assignment
from pinflex.assignment.study import user_trajectory
from pinflex.erls import FlexibleModel

Q0 = np.array([1.817, 5.312])
TARGET = [Target(1, 190.0)]


@pytest.fixture(scope="module")
def arm():
    """Benchmark A model and trajectory (absolute coordinates)."""
    model = FlexibleModel(TWO_LINK, planar=True)
    return model, user_trajectory(model, "benchmark_a")


def _lsq_design(model, traj, taylor, quantity):
    """Bounded weighted least squares of the partially linear polynomial of mode 1."""
    l0, L = taylor.linear_parts(traj.q, quantity=quantity)
    target = 190.0 if quantity == "freq_hz" else (2 * np.pi * 190.0) ** 2
    w = np.sqrt(traj.trapezoid_weights())
    y0 = taylor.y0
    lo = np.array([d.lower for d in model.design]) - y0
    hi = np.array([d.upper for d in model.design]) - y0
    sol = lsq_linear(w[:, None] * L[:, 0, :], -w * (l0[:, 0] - target), bounds=(lo, hi),
                     tol=1e-14, lsmr_tol="auto", max_iter=1000)
    return y0 + sol.x


@pytest.mark.parametrize("quantity", ["freq_hz", "eigval"])
def test_design_equals_bounded_least_squares_of_the_polynomial(arm, quantity):
    """The QP's design is the bounded weighted least-squares optimum, for Hz and for λ."""
    model, traj = arm
    r = assign_frequencies(model, traj, TARGET, q0=Q0, quantity=quantity)
    np.testing.assert_allclose(r.y, _lsq_design(model, traj, r.taylor, quantity), atol=1e-7)
    f = model.frequencies(traj.q, r.y, n_modes=1)[:, 0]
    assert r.max_error_after == pytest.approx(np.max(np.abs(f / 190 - 1)), rel=1e-12)


def test_eigval_and_freq_designs_differ_as_their_costs_do(arm):
    """Expanding λ instead of f changes the optimum (another cost), both between the bounds."""
    model, traj = arm
    a = assign_frequencies(model, traj, TARGET, q0=Q0, quantity="freq_hz").y
    b = assign_frequencies(model, traj, TARGET, q0=Q0, quantity="eigval").y
    assert np.all((b >= 0.0) & (b <= 0.25))
    assert abs(a[0] - b[0]) > 1e-4


def test_q0_none_expands_at_the_middle_sample(arm):
    """Without q0 the expansion pose is the trajectory's middle sample."""
    model, traj = arm
    _, taylor = build_assignment(model, traj, TARGET)
    np.testing.assert_array_equal(taylor.q0, traj.q[len(traj.q) // 2])


def test_a_ineq_row_equals_the_mass_budget(arm):
    """A_ineq (y - y0) <= b with a row of ones is the mass budget: same design, constraint met."""
    model, traj = arm
    budget = 0.15
    by_budget = assign_frequencies(model, traj, TARGET, q0=Q0, mass_budget_kg=budget)
    y0 = model.y0
    by_rows = assign_frequencies(model, traj, TARGET, q0=Q0, A_ineq=[[1.0, 1.0]],
                                 b_ineq=[budget - y0.sum()])
    assert by_rows.y.sum() <= budget + 1e-9
    np.testing.assert_allclose(by_rows.y, by_budget.y, atol=1e-8)
    free = assign_frequencies(model, traj, TARGET, q0=Q0)
    assert free.y.sum() > budget  # the row binds


def test_refinement_converges_to_the_exact_least_squares_design(arm):
    """refine=True re-expands while the exact cost (10) falls: it ends at the optimum of the
    exact cost (bounded SciPy minimisation of the exact trapezoid sum), not above plain's."""
    from scipy.optimize import minimize

    model, traj = arm
    plain = assign_frequencies(model, traj, TARGET, q0=Q0)
    refined = assign_frequencies(model, traj, TARGET, q0=Q0, refine=True, max_refinements=4)
    w = traj.trapezoid_weights()

    def cost(y):
        f = model.frequencies(traj.q, np.clip(y, 0.0, 0.25), n_modes=1)[:, 0]
        return 0.5 * float(np.sum(w * (f - 190.0) ** 2))

    ref = minimize(cost, plain.y, method="L-BFGS-B", bounds=[(0.0, 0.25)] * 2,
                   options={"ftol": 1e-14, "gtol": 1e-10})
    assert cost(refined.y) <= cost(plain.y) + 1e-12
    assert cost(refined.y) == pytest.approx(ref.fun, rel=1e-6)
    np.testing.assert_allclose(refined.y, ref.x, atol=2e-4)
    assert refined.status == "met" and refined.refinements >= 1
    f = model.frequencies(traj.q, refined.y, n_modes=1)[:, 0]
    assert refined.max_error_after == pytest.approx(np.max(np.abs(f / 190 - 1)), rel=1e-12)
    assert not np.allclose(refined.taylor.y0, plain.taylor.y0)


def test_brute_force_cost_is_the_exact_trapezoid_sum(arm):
    """The grid search's best cost is ½ Σ w_k (f1 - 190)² of the exact model at its design."""
    model, traj = arm
    bf = brute_force(model, traj, TARGET, points=5, zoom_levels=1)
    w = traj.trapezoid_weights()

    def cost(y):
        f = model.frequencies(traj.q, y, n_modes=1)[:, 0]
        return 0.5 * float(np.sum(w * (f - 190.0) ** 2))

    assert bf.best_cost == pytest.approx(cost(bf.y_best_cost), rel=1e-10)
    for y in ([0.0, 0.0], [0.25, 0.25], [0.125, 0.0], [0.25, 0.0]):  # points of its first grid
        assert bf.best_cost <= cost(np.array(y)) * (1 + 1e-9)  # two eigensolvers: round-off
    assert bf.evaluations == 2 * 25
