"""The fast evaluation path of TaylorModel: same values and same radius decisions as before.

References: the monomials against a direct product of powers; the values against
``jets.evaluate`` (coefficient by coefficient); the warning decision against the per-sample
estimate of ``error_estimate`` (which the screen must reproduce exactly: it only skips the
per-sample estimate when an upper bound of it meets the tolerance).
"""

import warnings

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex import jets
from pinflex.erls import FlexibleModel
from pinflex.exceptions import TaylorRadiusExceeded, TaylorRadiusWarning
from pinflex.parametric import expand

Q0 = np.array([1.817, 5.312])
Y0 = np.array([0.125, 0.125])


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(TWO_LINK, planar=True)


@pytest.mark.parametrize("nvars,order", [(1, 0), (1, 5), (2, 4), (3, 3), (7, 4), (4, 6)])
def test_monomials_equal_products_of_powers(nvars, order):
    """The row-slice monomials equal the products of powers, one sample and many."""
    space = jets.JetSpace(nvars, order)
    dx = np.random.default_rng(nvars * 10 + order).normal(size=(11, nvars))
    ref = np.prod(dx[:, None, :] ** space.multi_indices[None], axis=2)
    np.testing.assert_allclose(jets.monomials(space, dx), ref, rtol=1e-14, atol=0)
    np.testing.assert_allclose(jets.monomials(space, dx[3]), ref[3], rtol=1e-14, atol=0)


def _warned(tm, Q, Y=None, **kw):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        tm.evaluate(Q, Y, **kw)
    return any(issubclass(r.category, TaylorRadiusWarning) for r in rec)


@pytest.mark.parametrize("order", [1, 2, 4])
def test_values_and_decisions_match_the_per_sample_estimate(arm, order):
    """Values and warning decisions equal the per-sample estimate's.

    Joints only (direct path) and joints + design (general path); tolerances that straddle
    the worst estimate of each sample set decide exactly as the per-sample estimate.
    """
    rng = np.random.default_rng(order)
    cases = [
        (expand(arm, Q0, Y0, order=order, modes=(1, 2), design=[]), None),
        (expand(arm, Q0, Y0, order=order, modes=(1, 2, 3)), "design"),
    ]
    for tm, kind in cases:
        for scale in (0.05, 0.3, 1.0):
            Q = Q0 + scale * rng.uniform(-1, 1, size=(40, 2))
            Y = None if kind is None else Y0 + 0.05 * scale * rng.uniform(-1, 1, size=(40, 2))
            dx = tm.offsets(Q, Y, warn=False)
            for quantity in ("eigval", "freq_hz"):
                ref = jets.evaluate(tm.space, tm.jet(quantity), dx)
                got = tm.evaluate(Q, Y, quantity=quantity, warn=False)
                np.testing.assert_allclose(got, ref, rtol=1e-13, atol=0)
                est, _ = tm.error_estimate(dx, quantity=quantity)
                worst = float(np.max(est))
                for tol in (0.5 * worst, 0.999 * worst, 1.001 * worst, 2.0 * worst):
                    if not np.isfinite(tol) or tol == 0:
                        continue
                    assert _warned(tm, Q, Y, quantity=quantity, tol=tol) == (worst > tol)
                checked = tm.evaluate(Q, Y, quantity=quantity, tol=np.inf)
                np.testing.assert_allclose(checked, ref, rtol=1e-13, atol=0)


def test_screen_bound_is_above_every_sample_estimate(arm):
    """The screen's bound (from column extremes) is ≥ the worst per-sample estimate."""
    tm = expand(arm, Q0, Y0, order=4, modes=(1, 2, 3), design=[])
    plan = tm._evaluation_plan
    rng = np.random.default_rng(7)
    finite = 0
    for scale in (0.02, 0.1, 0.2, 0.6):
        Q = Q0 + scale * rng.uniform(-1, 1, size=(60, 2))
        dx = tm.offsets(Q, warn=False)
        worst = float(np.max(tm.error_estimate(dx, quantity="freq_hz")[0]))
        mon = jets.monomials(tm.space, dx)
        rows = plan.checked["freq_hz", False] @ mon.T
        colmax = np.abs(rows[plan.k:]).max(axis=1).tolist()
        if not np.isfinite(worst):  # beyond the radius somewhere: no tolerance passes
            assert not plan.screen_passes(colmax, 1e300)
            continue
        assert plan.screen_passes(colmax, worst * 1.01)
        # a tolerance below the worst sample never passes the screen
        assert not plan.screen_passes(colmax, worst * 0.99)
        finite += 1
    assert finite >= 2


def test_strict_raises_and_warning_points_at_the_caller(arm):
    """Beyond the radius: strict raises; the warning names the caller's line."""
    tm = expand(arm, Q0, Y0, order=2, modes=(1, 2, 3))
    q = (Q0 + np.array([2.0, 0.0]))[None]
    with pytest.raises(TaylorRadiusExceeded):
        tm.evaluate(q, quantity="freq_hz", strict=True)
    with pytest.warns(TaylorRadiusWarning) as rec:
        tm.evaluate(q, quantity="freq_hz")
    assert rec[0].filename == __file__


def test_concurrent_evaluations_do_not_share_rows(arm):
    """Threads evaluating one model at once (same sample count) get their own values."""
    from concurrent.futures import ThreadPoolExecutor

    tm = expand(arm, Q0, Y0, order=4, modes=(1, 2), design=[])
    rng = np.random.default_rng(11)
    batches = [Q0 + 0.3 * rng.uniform(-1, 1, size=(64, 2)) for _ in range(8)]
    expected = [jets.evaluate(tm.space, tm.jet("freq_hz"), tm.offsets(Q, warn=False))
                for Q in batches]

    def run(i):
        return [tm.evaluate(batches[i], quantity="freq_hz", warn=False) for _ in range(300)]

    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(run, range(8)))
    for got, ref in zip(results, expected):
        for g in got:
            np.testing.assert_allclose(g, ref, rtol=1e-13, atol=0)


@pytest.mark.parametrize("order,modes", [(2, (1,)), (4, (1, 2, 3)), (7, (2,))])
def test_two_joint_grid_values_equal_the_coefficient_sum(arm, order, modes):
    """The factored two-joint path equals Σ_α c_α δx^α (C- and F-ordered samples)."""
    tm = expand(arm, Q0, Y0, order=order, modes=modes, design=[])
    assert tm._evaluation_plan.grid is not None
    assert expand(arm, Q0, Y0, order=order, modes=modes)._evaluation_plan.grid is None
    rng = np.random.default_rng(order)
    Q = Q0 + 0.4 * rng.uniform(-1, 1, size=(33, 2))
    dx = tm.offsets(Q, warn=False)
    for quantity in ("eigval", "freq_hz"):
        ref = jets.evaluate(tm.space, tm.jet(quantity), dx)
        for samples in (np.ascontiguousarray(Q), np.asfortranarray(Q), Q[::-1][::-1]):
            for lin in (False, True):
                got = tm.evaluate(samples, quantity=quantity, linear_in_design=lin, warn=False)
                assert got.shape == (33, len(modes))
                np.testing.assert_allclose(got, ref, rtol=1e-13, atol=0)
                np.testing.assert_allclose(tm.evaluate(samples, quantity=quantity, tol=np.inf),
                                           ref, rtol=1e-13, atol=0)
    # one sample, and none
    np.testing.assert_allclose(tm.evaluate(Q[:1], quantity="freq_hz", tol=np.inf), ref[:1],
                               rtol=1e-13)
    assert tm.evaluate(Q[:0], quantity="freq_hz").shape == (0, len(modes))
    tmd = expand(arm, Q0, Y0, order=order, modes=modes)
    assert tmd.evaluate(Q[:0], quantity="freq_hz").shape == (0, len(modes))


def test_first_screen_bounds_every_check_row(arm):
    """|row_r(dx)| ≤ K_r τ^{d_r} with τ² = dxᵀ A dx, for every check row, at any offset.

    The check rows are evaluated from the coefficients at random offsets of all sizes and
    directions, including the whole-arm rotation (the direction in which benchmark A's
    eigenvalues do not change, where A is thin).
    """
    rng = np.random.default_rng(3)
    for modes in ((1,), (1, 2, 3)):
        tm = expand(arm, Q0, Y0, order=4, modes=modes, design=[])
        grid, plan = tm._evaluation_plan.grid, tm._evaluation_plan
        dirs = np.vstack([rng.normal(size=(4000, 2)), [[1.0, 1.0], [1.0, -1.0], [1.0, 0.0]]])
        dx = dirs * rng.uniform(0.01, 3.0, size=(dirs.shape[0], 1))
        mon = jets.monomials(tm.space, dx)
        for key, rows in plan.checked.items():
            vals = np.abs(mon @ rows[plan.k:].T)  # (n, ncheck)
            a01, a00, a11 = grid.form[0] / 2, grid.form[1], grid.form[2]
            tau = np.sqrt(a00 * dx[:, 0] ** 2 + 2 * a01 * dx[:, 0] * dx[:, 1] + a11 * dx[:, 1] ** 2)
            K, deg = (np.array(v) for v in grid.bounds[key])
            assert np.all(np.isfinite(K))
            bound = K[None, :] * tau[:, None] ** deg[None, :]
            assert np.all(vals <= bound * (1 + 1e-12) + 1e-300)
            # and not loose by much where the rows are largest (K is a maximum, not a guess)
            assert np.all(np.max(vals / np.maximum(bound, 1e-300), axis=0)[K > 0] > 0.95)


def test_first_screen_never_passes_a_tolerance_some_sample_misses(arm):
    """Screen 1 passes only when every sample's estimate meets tol, and passes near q0."""
    tm = expand(arm, Q0, Y0, order=4, modes=(1, 2), design=[])
    grid, plan = tm._evaluation_plan.grid, tm._evaluation_plan
    rng = np.random.default_rng(5)
    passed = 0
    for scale in (0.01, 0.05, 0.2, 0.5, 1.0):
        Q = Q0 + scale * rng.uniform(-1, 1, size=(80, 2))
        dx = tm.offsets(Q, warn=False)
        t2 = float(np.max(grid.form @ np.stack([dx[:, 0] * dx[:, 1], dx[:, 0] ** 2,
                                                 dx[:, 1] ** 2])))
        worst = float(np.max(tm.error_estimate(dx, quantity="freq_hz")[0]))
        for tol in (1e-2, 1e-4):
            limit = grid.limit(("freq_hz", False), tol, plan.screen_passes)
            if t2 <= limit:
                assert worst <= tol
                passed += 1
        if np.isfinite(worst) and worst > 0:
            assert t2 > grid.limit(("freq_hz", False), 0.99 * worst, plan.screen_passes)
    assert passed >= 3  # the cheap screen does decide the common case
