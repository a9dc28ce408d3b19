"""Taylor models, expansions along a trajectory and piecewise QP models survive pickling."""

import pickle

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.cases.benchmark_a import benchmark_trajectory
from pinflex.erls import FlexibleModel
from pinflex.parametric import expand, expand_along

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def arm():
    """Benchmark A's planar two-link arm."""
    return FlexibleModel(TWO_LINK, planar=True)


def test_a_taylor_model_round_trip_gives_the_same_values(arm):
    """Values, radius checks, linear parts and the order choice are those of the original."""
    Q = benchmark_trajectory(arm).q
    Y = np.column_stack([np.linspace(0.0, 0.25, Q.shape[0]), np.full(Q.shape[0], 0.1)])
    tm = expand(arm, Q0, arm.y0, order=8, modes=(1, 2), tol=1e-3, over=Q)
    back = pickle.loads(pickle.dumps(tm))
    assert back is not tm and back.order == tm.order and back.modes == tm.modes
    for quantity in ("eigval", "freq_hz"):
        for lin in (False, True):
            np.testing.assert_array_equal(
                back.evaluate(Q, Y, quantity=quantity, linear_in_design=lin, warn=False),
                tm.evaluate(Q, Y, quantity=quantity, linear_in_design=lin, warn=False))
    dx = tm.offsets(Q, Y, warn=False)
    for a, b in zip(back.error_estimate(dx), tm.error_estimate(dx)):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(back.linear_parts(Q, quantity="freq_hz"),
                    tm.linear_parts(Q, quantity="freq_hz")):
        np.testing.assert_array_equal(a, b)
    assert dict(back.order_choice) == dict(tm.order_choice)
    with pytest.raises(TypeError):
        back.order_choice["order"] = 1  # read-only again
    assert not back.eigval_jets.flags.writeable
    # the loaded model evaluates on its own plan (rebuilt, with its own lock)
    assert back._evaluation_plan is not tm._evaluation_plan


def test_an_expansion_along_a_trajectory_round_trips(arm):
    """Several points (order 2) evaluate to the same values after pickling."""
    Q = benchmark_trajectory(arm).q
    te = expand_along(arm, Q, arm.y0, tol=1e-3, orders=(2,))
    assert len(te.models) >= 2
    back = pickle.loads(pickle.dumps(te))
    np.testing.assert_array_equal(back.evaluate(Q, quantity="freq_hz"),
                                  te.evaluate(Q, quantity="freq_hz"))
    assert back.segments == te.segments and back.max_error == te.max_error


def test_piecewise_assignment_models_round_trip(arm):
    """The assignment's piecewise model (points by tolerance) gives the same QP rows."""
    from pinflex.assignment.points import points_for_tolerance

    Q = benchmark_trajectory(arm).q
    pt = points_for_tolerance(arm, Q, arm.y0, tol=1e-3, modes=(1,), orders=(2,))
    back = pickle.loads(pickle.dumps(pt))
    for a, b in zip(back.linear_parts(Q, quantity="freq_hz"),
                    pt.linear_parts(Q, quantity="freq_hz")):
        np.testing.assert_array_equal(a, b)
    assert back.points_choice == pt.points_choice
