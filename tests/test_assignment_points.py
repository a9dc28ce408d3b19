"""Expansion points by tolerance for the assignment: estimate against the exact model."""

import json
import warnings

import crossing_arm as arm_ref
import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex import Target
from pinflex.assignment.driver import assign_frequencies, build_assignment
from pinflex.assignment.points import points_for_tolerance
from pinflex.cases.benchmark_a import benchmark_trajectory
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError, TaylorRadiusWarning

ROOT = TWO_LINK.parents[1]


@pytest.fixture(scope="module")
def arm():
    """Benchmark A's planar two-link arm (shipped)."""
    return FlexibleModel(TWO_LINK, planar=True)


def _exact_error(arm, pt, Q, y0):
    """Relative error of the piecewise polynomial at y0 (δy = 0) against the exact model."""
    l0, _ = pt.linear_parts(Q, quantity="freq_hz")
    exact = arm.frequencies(Q, y0, n_modes=1)[:, 0]
    return float(np.max(np.abs(l0[:, 0] / exact - 1)))


@pytest.mark.parametrize("tol", [1e-3, 1e-4])
def test_points_at_order_two_cover_benchmark_a_within_tol(arm, tol):
    """Order 2 only: several points; the estimate meets tol and is within 1.5x of the truth."""
    Q = benchmark_trajectory(arm).q
    pt = points_for_tolerance(arm, Q, arm.y0, tol=tol, modes=(1,), orders=(2,))
    c = pt.points_choice
    assert len(c["points"]) >= 2 and c["order"] == 2
    assert [a for a, _ in pt.segments][0] == 0 and pt.segments[-1][1] == Q.shape[0]
    assert all(b == a2 for (_, b), (a2, _) in zip(pt.segments[:-1], pt.segments[1:]))
    actual = _exact_error(arm, pt, Q, arm.y0)
    assert c["exact_error"] == pytest.approx(actual, rel=1e-9)
    assert c["estimate"] <= tol and actual <= tol
    assert 1 / 1.5 < c["estimate"] / actual < 1.5
    # one point of the same order misses tol: the points are needed
    one = points_for_tolerance(arm, Q, arm.y0, tol=1.0, modes=(1,), orders=(2,))
    assert len(one.points_choice["points"]) == 1 and _exact_error(arm, one, Q, arm.y0) > tol


def test_all_orders_pick_one_point_and_say_how_far_the_estimate_is(arm):
    """Orders 1-8 at tol 1e-3 and 1e-4: one point; estimate within 2x of the exact error."""
    Q = benchmark_trajectory(arm).q
    for tol in (1e-3, 1e-4):
        with warnings.catch_warnings():
            warnings.simplefilter("error", TaylorRadiusWarning)  # the estimate holds here
            pt = points_for_tolerance(arm, Q, arm.y0, tol=tol, modes=(1,))
        c = pt.points_choice
        actual = _exact_error(arm, pt, Q, arm.y0)
        assert len(c["points"]) == 1 and c["estimate"] <= tol and actual <= tol
        assert 0.5 < c["estimate"] / actual < 2
        assert c["candidates"][c["order"]] == 1
        assert all(c["candidates"][p] > 1 for p in range(1, c["order"]))


def test_an_optimistic_estimate_is_reported_with_the_exact_error(arm):
    """Mode 1 of the crossing arm at order 2: the estimate misses by a little, and says so."""
    model = FlexibleModel(parse(arm_ref.urdf()))
    el = np.linspace(0.0, 0.6, 61)
    Q = np.column_stack([np.full_like(el, 0.3), el])
    with pytest.warns(TaylorRadiusWarning, match="exact relative error"):
        pt = points_for_tolerance(model, Q, model.y0, tol=1e-3, modes=(1,), orders=(2,))
    c = pt.points_choice
    exact = model.frequencies(Q, model.y0, n_modes=1)[:, 0]
    actual = float(np.max(np.abs(pt.linear_parts(Q, quantity="freq_hz")[0][:, 0] / exact - 1)))
    assert c["estimate"] <= 1e-3 < actual == pytest.approx(c["exact_error"], rel=1e-9)


def test_points_that_number_crossing_modes_differently_are_refused():
    """Modes 2/3 cross along the elbow sweep: points on both sides would mix the branches."""
    model = FlexibleModel(parse(arm_ref.urdf()))
    el = np.linspace(0.0, 0.6, 61)
    Q = np.column_stack([np.full_like(el, 0.3), el])
    with pytest.raises(ConfigurationError, match="differently"):
        points_for_tolerance(model, Q, model.y0, tol=1e-3, modes=(2, 3), orders=(2,))


def test_assignment_with_points_uses_each_segment_model(arm):
    """QP rows: sample i's l0, L are those of its segment's model; the assignment improves."""
    traj = benchmark_trajectory(arm)
    Q = traj.q
    targets = [Target(1, 190.0)]
    problem, pt = build_assignment(arm, traj, targets, y0=arm.y0, points_tol=1e-3)
    l0, L = pt.linear_parts(Q, quantity="freq_hz")
    for tm, (a, b) in zip(pt.models, pt.segments):
        la, La = tm.linear_parts(Q[a:b], quantity="freq_hz")
        np.testing.assert_array_equal(l0[a:b], la)
        np.testing.assert_array_equal(L[a:b], La)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = assign_frequencies(arm, traj, targets, y0=arm.y0, points_tol=1e-3)
    assert res.taylor.points_choice["tol"] == 1e-3
    assert res.max_error_after < 0.02 < res.max_error_before
    with pytest.raises(ConfigurationError, match="not both"):
        build_assignment(arm, traj, targets, points_tol=1e-3, taylor_tol=1e-3)


def test_cli_points_tol_reports_points_order_and_estimate(capsys):
    """``pinflex assign --points-tol`` prints and returns the choice; bad flags are named."""
    from pinflex.cli import main

    study = str(ROOT / "examples" / "benchmark_a.toml")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["assign", study, "--points-tol", "1e-3", "--json", "--no-progress"]) == 0
    out = json.loads(capsys.readouterr().out)
    c = out["taylor_points_choice"]
    assert c["tol"] == 1e-3 and len(c["points"]) == len(c["segments"]) >= 1
    assert out["taylor_order"] == c["order"] and c["estimate"] <= 1e-3
    assert c["exact_error"] <= 1e-3 and out["taylor_order_choice"] is None
    for bad, says in ((["--points-tol", "0"], "positive"),
                      (["--points-tol", "1e-3", "--tol", "1e-3"], "not both")):
        assert main(["assign", study, *bad, "--no-progress"]) != 0
        assert says in capsys.readouterr().err
