"""The Taylor model's error estimate fires where the error is large and stays quiet inside.

Actual errors are measured against the independent global planar frame of benchmark A
(``reference_fe``), not against pinflex's own exact model.
"""

import warnings

import numpy as np
import pytest
from conftest import TWO_LINK
from reference_fe import planar_two_link_frequencies

from pinflex.cases.benchmark_a_path import benchmark_a_trajectory
from pinflex.erls import FlexibleModel
from pinflex.exceptions import TaylorRadiusExceeded, TaylorRadiusWarning
from pinflex.parametric import expand

Q0 = np.array([1.817, 5.312])
Y0 = np.array([0.125, 0.125])


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(TWO_LINK, planar=True)


def _fe_eigvals(q_abs, y, n=3):
    _, f = planar_two_link_frequencies(q_abs, *y)
    return (2 * np.pi * f[:n]) ** 2


def test_order_two_two_radians_off_warns_and_is_indeed_far_off(arm):
    """Order 2, base angle 2 rad off (elbow −2 rad): +46 % / +60 % on modes 2, 3: warned."""
    tm = expand(arm, Q0, Y0, order=2, modes=(1, 2, 3))
    q = Q0 + np.array([2.0, 0.0])
    with pytest.warns(TaylorRadiusWarning, match="mode"):
        f = tm.evaluate(q[None], quantity="freq_hz")[0]
    _, ref = planar_two_link_frequencies(q, *Y0)
    err = f / ref[:3] - 1
    assert err[1] > 0.4 and err[2] > 0.5
    with pytest.raises(TaylorRadiusExceeded):
        tm.evaluate(q[None], quantity="freq_hz", strict=True)


def test_the_warning_fires_wherever_the_error_is_large_along_the_elbow(arm):
    """Orders 1–4, elbow offsets ±(0.05..2) rad: every error above 3 % is warned about."""
    ts = np.concatenate([-np.geomspace(0.05, 2.0, 12), np.geomspace(0.05, 2.0, 12)])
    Q = Q0 + np.column_stack([np.zeros_like(ts), ts])
    ref = np.array([_fe_eigvals(q, Y0) for q in Q])
    for p in (1, 2, 3, 4):
        tm = expand(arm, Q0, Y0, order=p, modes=(1, 2, 3), design=[])
        approx = tm.evaluate(Q, warn=False)
        actual = np.abs(approx / ref - 1)
        est, _ = tm.error_estimate(tm.offsets(Q, warn=False))
        large = actual > 0.03
        assert large.any()
        assert np.all(est[large] > 0.01), f"order {p}: a large error went unflagged"
        for i in np.flatnonzero(large.any(axis=1))[:3]:
            with pytest.warns(TaylorRadiusWarning):
                tm.evaluate(Q[i : i + 1])


def test_quiet_inside_the_radius_and_along_benchmark_a_at_order_four(arm):
    """P = 4 along the 152-sample path and p = 2 within 0.05 rad: no warning, small errors."""
    tr = benchmark_a_trajectory()
    Q = np.linalg.solve(arm.coord_map, tr.q.T).T
    tm = expand(arm, Q0, Y0, order=4, modes=(1, 2, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error", TaylorRadiusWarning)
        approx = tm.evaluate(Q)
        near = expand(arm, Q0, Y0, order=2, modes=(1, 2, 3)).evaluate(
            Q0 + np.array([[0.05, 0.0], [0.0, -0.05], [0.03, 0.04]]))
        tm.evaluate(Q, quantity="freq_hz", strict=True)
    ref = np.array([_fe_eigvals(q, Y0) for q in Q[::8]])
    assert np.max(np.abs(approx[::8] / ref - 1)) < 0.005  # the quiet answer is good
    ref_near = np.array([_fe_eigvals(q, Y0) for q in Q0 + np.array(
        [[0.05, 0.0], [0.0, -0.05], [0.03, 0.04]])])
    assert np.max(np.abs(near / ref_near - 1)) < 0.001
    est, ratio = tm.error_estimate(tm.offsets(Q, warn=False))
    assert est.max() < 0.01 and ratio.max() < 1


def test_turning_the_whole_arm_changes_nothing_and_is_not_flagged(arm):
    """Equal absolute-angle offsets are a rigid rotation: exact invariance, no warning."""
    tm = expand(arm, Q0, Y0, order=8, modes=(1, 2, 3))
    with warnings.catch_warnings():
        warnings.simplefilter("error", TaylorRadiusWarning)
        v = tm.evaluate(Q0 + np.array([[2.0, 2.0], [-1.0, -1.0]]))
    # round-off of an order-8 sum at distance 2.8 (terms cancel): 1e-8
    np.testing.assert_allclose(v, tm.eigval_jets[0][None].repeat(2, axis=0), rtol=1e-7)
