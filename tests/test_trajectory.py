"""Tests of pinflex.trajectory: grids, CSV, workspace paths, inverse kinematics, benchmark A."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from pinflex.cases.benchmark_a_path import (
    BENCHMARK_A_Q0_ABS,
    BENCHMARK_A_Q0_SAMPLE,
    benchmark_a_path,
    benchmark_a_trajectory,
)
from pinflex.exceptions import (
    IKNotConverged,
    InvalidPath,
    InvalidTrajectory,
    JointLimitsExceeded,
    TrajectoryWarning,
)
from pinflex.trajectory import (
    Trajectory,
    absolute_to_relative,
    planar_2r_fk,
    planar_2r_ik,
    relative_to_absolute,
    solve_ik,
    trapezoid_weights,
    workspace_path,
)

L1, L2 = 0.6, 0.45
TWO_LINK_URDF = Path(__file__).resolve().parents[1] / "urdf" / "two_link.urdf"


def planar_2r_model(l1=L1, l2=L2):
    """Pinocchio model of a planar 2R arm (joints about z) with an end-effector frame."""
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "joint1")
    j2 = model.addJoint(j1, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([l1, 0, 0])), "joint2")
    frame = model.addFrame(
        pin.Frame("ee", j2, pin.SE3(np.eye(3), np.array([l2, 0, 0])), pin.FrameType.OP_FRAME)
    )
    return model, model.createData(), frame


def pin_fk(model, data, frame, qs):
    """End-effector positions from Pinocchio for each row of qs."""
    out = []
    for q in qs:
        pin.framesForwardKinematics(model, data, q)
        out.append(data.oMf[frame].translation.copy())
    return np.array(out)


# --------------------------------------------------------------------------- grids and CSV


def test_trapezoid_weights_integrate_linear_functions_exactly():
    """On a random non-uniform grid the weights integrate a + b t exactly."""
    rng = np.random.default_rng(1)
    t = np.sort(rng.uniform(-1.0, 3.0, 40))
    w = trapezoid_weights(t)
    a, b = 0.7, -2.3
    exact = a * (t[-1] - t[0]) + 0.5 * b * (t[-1] ** 2 - t[0] ** 2)
    assert w @ (a + b * t) == pytest.approx(exact, rel=1e-14, abs=1e-14)


def test_trapezoid_weights_match_the_trapezoid_rule_on_curved_functions():
    """For a nonlinear f the weighted sum equals the composite trapezoid rule summed by hand."""
    rng = np.random.default_rng(2)
    t = np.sort(rng.uniform(0.0, 2.0, 25))
    f = np.exp(t) * np.sin(3 * t)
    by_hand = sum(0.5 * (t[k + 1] - t[k]) * (f[k + 1] + f[k]) for k in range(t.size - 1))
    traj = Trajectory(t, f[:, None])
    assert traj.trapezoid_weights() @ f == pytest.approx(by_hand, rel=1e-13)


@pytest.mark.parametrize(
    "times, q",
    [
        ([0.0, 1.0, 1.0], np.zeros((3, 2))),
        ([0.0, 2.0, 1.0], np.zeros((3, 2))),
        ([0.0, 1.0, 2.0], np.zeros((2, 2))),
        ([0.0, 1.0, np.nan], np.zeros((3, 2))),
        ([0.0, 1.0, 2.0], np.array([[0, 0], [np.inf, 0], [0, 0]])),
        ([0.0, 1.0, 2.0], np.zeros(3)),
    ],
)
def test_trajectory_rejects_bad_input(times, q):
    """Repeated or decreasing times, mismatched shapes and non-finite values raise."""
    with pytest.raises(InvalidTrajectory):
        Trajectory(np.array(times), q)


def test_trajectory_arrays_are_read_only():
    """A trajectory's arrays cannot be modified in place."""
    traj = Trajectory(np.arange(3.0), np.zeros((3, 2)))
    with pytest.raises(ValueError):
        traj.q[0, 0] = 1.0


def test_csv_round_trip_is_exact(tmp_path):
    """Writing and reading a CSV file gives back the same numbers and joint names."""
    rng = np.random.default_rng(3)
    traj = Trajectory(np.cumsum(rng.uniform(0.01, 0.1, 20)), rng.normal(size=(20, 3)),
                      ("a", "b", "c"))
    path = tmp_path / "motion.csv"
    traj.to_csv(path)
    assert path.read_text().splitlines()[0] == "t,a,b,c"
    back = Trajectory.from_csv(path)
    np.testing.assert_array_equal(back.times_s, traj.times_s)
    np.testing.assert_array_equal(back.q, traj.q)
    assert back.joint_names == ("a", "b", "c") and back.name == "motion"


def test_csv_without_time_header_raises(tmp_path):
    """A CSV file whose first column is not 't' is rejected."""
    path = tmp_path / "bad.csv"
    path.write_text("time,q1\n0,1\n")
    with pytest.raises(InvalidTrajectory):
        Trajectory.from_csv(path)


def test_check_limits_warns_and_raises_with_the_offending_samples():
    """Samples beyond the limits are reported by warning, or by an error listing them."""
    q = np.array([[0.0, 0.0], [0.5, 2.0], [-1.5, 0.0]])
    traj = Trajectory(np.arange(3.0), q)
    with pytest.warns(TrajectoryWarning):
        mask = traj.check_limits([-1.0, -1.0], [1.0, 1.0])
    np.testing.assert_array_equal(mask, [[False, False], [False, True], [True, False]])
    with pytest.raises(JointLimitsExceeded) as info:
        traj.check_limits([-1.0, -1.0], [1.0, 1.0], on_violation="raise")
    assert info.value.samples == [1, 2] and info.value.joints == ["q2", "q1"]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert not traj.check_limits(-2.0, 2.0).any()


# --------------------------------------------------------------------------- workspace paths


def test_line_and_arc_path_geometry():
    """Samples lie on the given line and arc, and the length is the sum of the pieces."""
    path = workspace_path(
        (0.0, 0.0),
        [("line", (0.3, 0.0)), ("arc", (0.4, 0.1), (0.3, 0.1)), ("arc", (0.5, 0.2), 0.1, "cw")],
        400,
        profile="uniform",
    )
    assert path.length_m == pytest.approx(0.3 + 2 * (0.5 * np.pi * 0.1), rel=1e-14)
    on_line = path.segment == 0
    np.testing.assert_allclose(path.points[on_line, 1], 0.0, atol=1e-15)
    on_arc = path.segment == 1
    r = np.linalg.norm(path.points[on_arc] - [0.3, 0.1], axis=1)
    np.testing.assert_allclose(r, 0.1, rtol=1e-13)
    # clockwise minor arc from (0.4, 0.1) to (0.5, 0.2) has its center at (0.5, 0.1)
    on_cw = path.segment == 2
    np.testing.assert_allclose(np.linalg.norm(path.points[on_cw] - [0.5, 0.1], axis=1), 0.1)
    # uniform speed: equal chord steps within a piece, path ends where the spec ends
    np.testing.assert_allclose(np.diff(path.arc_length_m), path.length_m / 399, rtol=1e-12)
    np.testing.assert_allclose(path.points[-1], [0.5, 0.2], atol=1e-15)


def test_minimum_jerk_profile_starts_and_stops_at_rest():
    """With the minimum-jerk law the first and last steps are much shorter than the middle."""
    path = workspace_path((0.0, 0.0), [("line", (1.0, 0.0))], 101, duration_s=2.0)
    steps = np.diff(path.points[:, 0])
    assert steps[0] < 1e-3 * steps[50] and steps[-1] < 1e-3 * steps[50]
    assert path.points[50, 0] == pytest.approx(0.5, abs=1e-15)  # symmetric law


def test_arc_with_unequal_radii_raises():
    """An arc whose ends are not on one circle about the center is rejected."""
    with pytest.raises(InvalidPath):
        workspace_path((0.0, 0.0), [("arc", (1.0, 0.0), (0.2, 0.0))], 10)


# --------------------------------------------------------------------------- inverse kinematics


def test_planar_2r_closed_form_inverts_forward_kinematics():
    """Closed-form IK recovers random joint values of either elbow branch."""
    rng = np.random.default_rng(4)
    q = np.column_stack([rng.uniform(-np.pi, np.pi, 50), rng.uniform(0.1, np.pi - 0.1, 50)])
    for sign in (1, -1):
        qs = q * [1, sign]
        back = planar_2r_ik(planar_2r_fk(qs, L1, L2), L1, L2, sign)
        np.testing.assert_allclose(planar_2r_fk(back, L1, L2), planar_2r_fk(qs, L1, L2),
                                   atol=1e-14)
        np.testing.assert_allclose(np.angle(np.exp(1j * (back - qs))), 0.0, atol=1e-12)


def test_pinocchio_ik_reproduces_fk_points_and_closed_form():
    """solve_ik on a Pinocchio 2R arm reaches FK points to 1e-10 m and matches the closed form."""
    model, data, frame = planar_2r_model()
    t = np.linspace(0.0, 1.0, 60)
    q_true = np.column_stack([0.4 + 0.8 * t, -1.2 + 0.9 * np.sin(2 * t)])
    points = pin_fk(model, data, frame, q_true)
    sol = solve_ik(model, data, frame, points, q_true[0] + [0.05, -0.05])
    assert np.all(sol.residual_m <= 1e-10)
    np.testing.assert_allclose(pin_fk(model, data, frame, sol.q), points, atol=1e-10)
    closed = planar_2r_ik(points[:, :2], L1, L2, -1)
    np.testing.assert_allclose(sol.q, closed, atol=1e-8)


def test_pinocchio_ik_on_planar_points_uses_the_xy_task():
    """Two-dimensional targets are tracked on x and y only."""
    model, data, frame = planar_2r_model()
    path = workspace_path((0.5, 0.3), [("arc", (0.3, 0.5), (0.3, 0.3))], 30)
    sol = solve_ik(model, data, frame, path.points, np.array([0.3, 1.2]))
    np.testing.assert_allclose(pin_fk(model, data, frame, sol.q)[:, :2], path.points, atol=1e-10)


def test_unreachable_point_raises_ik_not_converged():
    """A point beyond the arm's reach raises IKNotConverged naming the sample."""
    model, data, frame = planar_2r_model()
    points = np.array([[0.5, 0.5, 0.0], [1.2, 0.0, 0.0]])
    with pytest.raises(IKNotConverged) as info:
        solve_ik(model, data, frame, points, np.array([0.3, 1.0]))
    assert info.value.sample == 1
    with pytest.raises(IKNotConverged):
        planar_2r_ik(points[:, :2], L1, L2, 1)


# --------------------------------------------------------------------------- benchmark A


def test_absolute_relative_conversion():
    """Paper 000's q0 = (1.817, 5.312) absolute is (1.817, 3.495) relative, and back."""
    rel = absolute_to_relative(BENCHMARK_A_Q0_ABS)
    np.testing.assert_allclose(rel, [1.817, 3.495], atol=1e-15)
    np.testing.assert_allclose(relative_to_absolute(rel), BENCHMARK_A_Q0_ABS, atol=1e-15)


def test_benchmark_a_trajectory_matches_the_paper_description():
    """152 samples at constant steps, elbow span 3.35–3.77 rad, q0 exactly at sample 76."""
    traj = benchmark_a_trajectory()
    assert traj.n_samples == 152
    np.testing.assert_allclose(np.diff(traj.times_s), traj.times_s[1], rtol=1e-12)
    elbow = traj.q[:, 1]
    assert elbow.min() == pytest.approx(3.35, abs=1e-12)
    assert elbow.max() == pytest.approx(3.77, abs=1e-3)
    np.testing.assert_allclose(traj.q[BENCHMARK_A_Q0_SAMPLE], [1.817, 3.495], atol=1e-12)
    assert 0.4 < BENCHMARK_A_Q0_SAMPLE / 151 < 0.6
    absolute = relative_to_absolute(traj.q)  # inside the q-domain of paper 000's Fig. 3
    assert np.all((absolute[:, 0] > 3 * np.pi / 8) & (absolute[:, 0] < 7 * np.pi / 8))
    assert np.all((absolute[:, 1] > 3 * np.pi / 2) & (absolute[:, 1] < 2 * np.pi))
    assert np.max(np.abs(np.diff(traj.q, axis=0))) < 0.05  # one continuous IK branch


def test_benchmark_a_joint_samples_reproduce_the_path_in_pinocchio():
    """Pinocchio FK of the benchmark-A joint samples (relative coordinates) gives the path."""
    model, data, frame = planar_2r_model()
    traj = benchmark_a_trajectory()
    path = benchmark_a_path()
    np.testing.assert_allclose(pin_fk(model, data, frame, traj.q)[:, :2], path.points,
                               atol=1e-14)
    sol = solve_ik(model, data, frame, path.points, traj.q[0])
    np.testing.assert_allclose(sol.q, traj.q, atol=1e-9)


@pytest.mark.skipif(not TWO_LINK_URDF.exists(), reason="benchmark-A URDF not present")
def test_benchmark_a_trajectory_fits_the_two_link_urdf():
    """The trajectory's columns are the URDF's joints, inside its limits, tool on the path."""
    model = pin.buildModelFromUrdf(str(TWO_LINK_URDF))
    data = model.createData()
    traj = benchmark_a_trajectory()
    assert traj.joint_names == tuple(model.names[1:])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        traj.check_limits(model.lowerPositionLimit, model.upperPositionLimit)
    tool = model.getFrameId("tool")
    np.testing.assert_allclose(pin_fk(model, data, tool, traj.q)[:, :2],
                               benchmark_a_path().points, atol=1e-14)
