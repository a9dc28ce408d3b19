"""Assignment across a mode crossing, the 'not an improvement' guard, floors checked exactly.

References: the global 3D frame (``crossing_arm``) and the global planar frame of benchmark A
(``reference_fe``), both without pinflex code.
"""

import warnings

import crossing_arm as arm_ref
import numpy as np
import pytest
from conftest import TWO_LINK
from reference_fe import planar_two_link_frequencies

from pinflex import Target, assign_frequencies
from pinflex.cases.benchmark_a_path import benchmark_a_trajectory
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    AssignmentInfeasible,
    AssignmentNotImproved,
    AssignmentWarning,
    ModeCrossingWarning,
)
from pinflex.trajectory import Trajectory

Q0_A = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def crossing_case():
    """Mode 3 (in-plane at the expansion point) to 190 Hz while modes 2/3 cross."""
    model = FlexibleModel(parse(arm_ref.urdf()))
    el = np.linspace(0.0, 0.6, 61)
    Q = np.column_stack([np.full_like(el, 0.3), el])
    traj = Trajectory(np.linspace(0.0, 1.0, 61), Q, model.joint_names)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        res = assign_frequencies(model, traj, [Target(3, 190.0)], q0=Q[30], y0=[0.125, 0.125])
    return Q, res, caught


def test_assignment_across_a_crossing_verifies_the_tracked_mode(crossing_case):
    """Errors are those of the FE's in-plane branch; the sorted 'mode 3' is reported apart."""
    Q, res, caught = crossing_case
    fam_after = [arm_ref.reference_families(q, *res.y) for q in Q]
    fam_before = [arm_ref.reference_families(q, *res.y_before) for q in Q]
    inplane_after = np.array([f[0][0] for f in fam_after])
    inplane_before = np.array([f[0][0] for f in fam_before])
    sorted3_after = np.array([np.sort(np.concatenate(f))[2] for f in fam_after])
    err_after = np.max(np.abs(inplane_after / 190.0 - 1))
    err_before = np.max(np.abs(inplane_before / 190.0 - 1))
    assert res.max_error_after == pytest.approx(err_after, rel=1e-7)
    assert res.max_error_before == pytest.approx(err_before, rel=1e-7)
    assert res.max_error_after_sorted == pytest.approx(
        np.max(np.abs(sorted3_after / 190.0 - 1)), rel=1e-7)
    np.testing.assert_allclose(res.freq_after_hz[:, 0], inplane_after, rtol=1e-9)
    # the tracked answer is an improvement and agrees with the polynomial's prediction;
    # the sorted mode number would have shown a far larger error than predicted
    assert res.improved and res.max_error_after < res.max_error_before
    assert abs(res.predicted_max_error_after - res.max_error_after) < 0.005
    assert res.max_error_after_sorted > 5 * res.max_error_after
    assert any(e.kind == "crossing" and e.modes == (2, 3) for e in res.events)
    assert any(issubclass(w.category, ModeCrossingWarning) for w in caught)
    assert not any(issubclass(w.category, AssignmentNotImproved) for w in caught)


@pytest.fixture(scope="module")
def benchmark_a():
    """Benchmark A and its pick-and-place path in the model's (absolute) coordinates."""
    model = FlexibleModel(TWO_LINK, planar=True)
    tr = benchmark_a_trajectory()
    q_user = np.linalg.solve(model.coord_map, tr.q.T).T
    return model, Trajectory(tr.times_s, q_user, model.joint_names)


def test_no_crossing_warning_and_an_improvement_on_benchmark_a(benchmark_a):
    """Benchmark A's modes do not cross on its path: quiet, tracked == sorted, improved."""
    model, traj = benchmark_a
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModeCrossingWarning)
        warnings.simplefilter("error", AssignmentNotImproved)
        res = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0_A, y0=[0.125, 0.125],
                                 report_modes=(2, 3))
    assert res.improved and res.events == ()
    assert res.max_error_after == res.max_error_after_sorted
    np.testing.assert_array_equal(res.freq_after_hz, res.freq_after_sorted_hz)


def test_a_design_worse_than_the_one_before_is_not_reported_as_an_improvement(benchmark_a):
    """From m1 = 0.231 kg (1.50 % on the exact model) the QP's 0.237 kg is worse: warned."""
    model, traj = benchmark_a
    before = np.array([0.231, 0.0])
    ref = max(abs(planar_two_link_frequencies(q, *before)[1][0] / 190.0 - 1) for q in traj.q)
    with pytest.warns(AssignmentNotImproved):
        res = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0_A, y0=[0.125, 0.125],
                                 y_before=before)
    assert res.max_error_before == pytest.approx(ref, rel=1e-8)
    assert res.max_error_after > res.max_error_before
    assert not res.improved


def test_floor_refused_by_the_polynomial_is_met_on_the_exact_model(benchmark_a):
    """Mode 2 >= 485 Hz: the polynomial says 453.3 Hz at best, the exact model 487.5 Hz."""
    model, traj = benchmark_a
    with pytest.warns(AssignmentWarning, match="declared the frequency floors infeasible"):
        res = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0_A, y0=[0.125, 0.125],
                                 floors=[(2, 485.0)], report_modes=(2,))
    assert res.floors_model == "taylor+exact"
    f2 = np.array([planar_two_link_frequencies(q, *res.y)[1][1] for q in traj.q])
    assert f2.min() >= 485.0 - 1e-6  # the floor holds on the independent FE
    assert f2.min() < 485.5  # and is active: more m1 would break it (the target wants more)
    assert res.floor_margin_hz == pytest.approx(f2.min() - 485.0, abs=1e-6)
    assert res.y[1] == pytest.approx(0.0, abs=1e-9) and 0.0 < res.y[0] < 0.1


def test_floor_out_of_reach_of_the_exact_model_is_refused_and_says_so(benchmark_a):
    """Mode 2 >= 495 Hz is above the exact 487.5 Hz maximum: refused, by the exact model too."""
    model, traj = benchmark_a
    with pytest.raises(AssignmentInfeasible, match="confirmed on the exact model") as err:
        assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0_A, y0=[0.125, 0.125],
                           floors=[(2, 495.0)])
    assert err.value.refused_by == "exact"
