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
    plan = tm.evaluation_plan
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
