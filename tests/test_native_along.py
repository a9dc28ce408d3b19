"""3-D workspace paths with IK, and frequencies along a trajectory (API and CLI)."""

from __future__ import annotations

import csv
import json

import numpy as np
import pinocchio as pin
import pytest

import pinflex
from pinflex import Beam, Mass, Material
from pinflex.beam import hollow_circle
from pinflex.cli import main
from pinflex.erls.along import modes_along
from pinflex.exceptions import IKNotConverged, InvalidPath, InvalidTrajectory, JointLimitsExceeded
from pinflex.trajectory import Trajectory
from pinflex.trajectory.cartesian import frame_position, path_trajectory, sample_polyline

ALU = Material(E=70e9, G=26.3e9, density=2700.0)
Q0 = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])
OVERLAY = """<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" name="ur10_flexible"
    base="example-robot-data:ur_description/urdf/ur10_robot.urdf">
  <pinflex:flexible link="upper_arm_link" elements="3" tip="0 0 0.612" normal="0 1 0">
    <pinflex:material E="70e9" G="26.3e9" density="2700"/>
    <pinflex:section shape="hollow_circle" outer_diameter="0.11" inner_diameter="0.1"/>
  </pinflex:flexible>
  <pinflex:point_mass name="payload" link="ee_link" mass="2.0" design="true" upper="8"/>
</pinflex:overlay>"""


@pytest.fixture(scope="module")
def arm():
    """UR10 with a flexible upper arm and a payload."""
    return pinflex.example_robot(
        "ur10",
        flexible={"upper_arm_link": Beam(hollow_circle(0.11, 0.1), ALU, 3, tip=(0, 0, 0.612),
                                         normal=(0, 1, 0))},
        masses={"payload": Mass("ee_link", 2.0, design=True, upper=8.0)},
    )


def test_polyline_timing_is_minimum_jerk():
    """Samples lie on the segments; arc length follows 10τ³ − 15τ⁴ + 6τ⁵."""
    pts = np.array([[0, 0, 0], [0.3, 0, 0], [0.3, 0.4, 0]], dtype=float)
    t, p = sample_polyline(pts, 21, 2.0)
    tau = t / 2.0
    s = np.where(p[:, 1] > 0, 0.3 + p[:, 1], p[:, 0])
    np.testing.assert_allclose(s, 0.7 * (10 * tau**3 - 15 * tau**4 + 6 * tau**5), atol=1e-15)
    assert np.all((np.abs(p[:, 0] - 0.3) < 1e-15) | (np.abs(p[:, 1]) < 1e-15))
    with pytest.raises(InvalidPath, match="coincide"):
        sample_polyline(pts[[0, 0, 1]], 5, 1.0)


def test_path_follows_waypoints_with_orientation(arm):
    """FK of the IK solution: on the polyline, orientation held, continuous samples."""
    p0 = frame_position(arm, "ee_link", Q0)
    pts = np.array([p0, p0 + [0.0, 0.3, -0.15], p0 + [-0.2, 0.3, 0.0]])
    traj = path_trajectory(arm, "ee_link", pts, n_samples=25, duration_s=2.0, q_init=Q0,
                           orientation="keep")
    assert traj.joint_names == arm.joint_names
    _, target = sample_polyline(pts, 25, 2.0)
    model, data = arm.model, arm.model.createData()
    fid = model.getFrameId("ee_link")
    pin.framesForwardKinematics(model, data, arm.pin_configuration(Q0))
    R0 = data.oMf[fid].rotation.copy()
    for q, p in zip(traj.q, target):
        pin.framesForwardKinematics(model, data, arm.pin_configuration(q))
        np.testing.assert_allclose(data.oMf[fid].translation, p, atol=1e-9)
        np.testing.assert_allclose(data.oMf[fid].rotation, R0, atol=1e-9)
    assert np.abs(np.diff(traj.q, axis=0)).max() < 0.2
    np.testing.assert_allclose(traj.q[0], Q0, atol=1e-9)


def test_path_limits_and_reach(arm):
    """Joint limits are checked (UR10 limited URDF) and unreachable points are named."""
    limited = pinflex.example_robot("ur10_limited")
    q_start = Q0 + [2.9, 0, 0, 0, 0, 0]
    p0 = frame_position(limited, "ee_link", q_start)
    with pytest.raises(JointLimitsExceeded):
        # a half turn of the base about z: shoulder_pan leaves [-pi, pi]
        c, s = np.cos(2.5), np.sin(2.5)
        pts = [p0, [c * p0[0] - s * p0[1], s * p0[0] + c * p0[1], p0[2]]]
        path_trajectory(limited, "ee_link", pts, n_samples=30, q_init=q_start)
    with pytest.raises(IKNotConverged):
        path_trajectory(arm, "ee_link", [p0, p0 + [5.0, 0, 0]], n_samples=5, q_init=Q0)


def test_modes_along_sorted_frequencies_equal_direct_solve(arm):
    """The sorted columns are the direct eigenfrequencies; tracked ones are a permutation."""
    p0 = frame_position(arm, "ee_link", Q0)
    traj = path_trajectory(arm, "ee_link", [p0, p0 + [0, 0.3, -0.1]], n_samples=12,
                           duration_s=1.0, q_init=Q0)
    res = modes_along(arm, traj, modes=3)
    direct = arm.frequencies(traj.q)[:, :3]
    np.testing.assert_allclose(res.sorted_hz, direct, rtol=1e-10)
    for s in range(res.n_samples):
        np.testing.assert_allclose(res.freq_hz[s], arm.frequencies(traj.q[s])[res.order[s] - 1],
                                   rtol=1e-10)
    assert res.mac_step.min() > 0.9
    # columns in another order are matched by name
    rev = Trajectory(traj.times_s, traj.q[:, ::-1], traj.joint_names[::-1])
    np.testing.assert_allclose(modes_along(arm, rev, modes=3).freq_hz, res.freq_hz)
    with pytest.raises(InvalidTrajectory, match="no column for joints .shoulder_pan_joint"):
        modes_along(arm, Trajectory(traj.times_s, traj.q, tuple("abcdef")))


def test_cli_path_and_modes_along(tmp_path, arm):
    """`pinflex path` then `pinflex modes --trajectory` (table, CSV, JSON, PNG)."""
    robot = tmp_path / "ur10_flexible.xml"
    robot.write_text(OVERLAY)
    traj_csv = tmp_path / "traj.csv"
    argv = ["path", str(robot), "--frame", "ee_link", "--q", *map(str, Q0), "--relative",
            "--through", "0", "0.3", "-0.1", "--samples", "10", "--duration", "1.5",
            "--orientation", "keep", "--out", str(traj_csv)]
    assert main(argv) == 0
    traj = Trajectory.from_csv(traj_csv)
    assert traj.n_samples == 10 and traj.joint_names == arm.joint_names
    out_csv, png = tmp_path / "along.csv", tmp_path / "along.png"
    assert main(["modes", str(robot), "--trajectory", str(traj_csv), "--csv", str(out_csv),
                 "--png", str(png)]) == 0
    assert png.stat().st_size > 10_000
    with open(out_csv) as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 10
    direct = arm.frequencies(traj.q)
    got = np.array([[float(r[f"sorted{m}_hz"]) for m in (1, 2, 3)] for r in rows])
    np.testing.assert_allclose(got, direct[:, :3], rtol=1e-10)


def test_cli_modes_along_json(tmp_path, arm, capsys):
    """--json prints one object with frequencies per sample and the events."""
    robot = tmp_path / "ur10_flexible.xml"
    robot.write_text(OVERLAY)
    q = np.linspace(Q0, Q0 + [0.3, 0.2, -0.2, 0, 0, 0], 6)
    Trajectory(np.linspace(0, 1, 6), q, arm.joint_names).to_csv(tmp_path / "t.csv")
    assert main(["modes", str(robot), "--trajectory", str(tmp_path / "t.csv"), "--json",
                 "--modes", "2"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["modes"] == [1, 2] and len(data["frequencies_hz"]) == 6
    np.testing.assert_allclose(np.sort(data["frequencies_hz"], axis=1),
                               arm.frequencies(q)[:, :2], rtol=1e-10)
    assert main(["modes", str(robot), "--csv", "x.csv"]) == 2
    assert main(["modes", str(robot), "--trajectory", str(tmp_path / "t.csv"), "--png"]) == 0
    assert (tmp_path / "t_modes.png").stat().st_size > 10_000


def test_study_path_table(tmp_path, arm):
    """A TOML study's [trajectory.path] gives the same trajectory as the Python call."""
    from pinflex.assignment.study import load_config

    robot = tmp_path / "ur10_flexible.xml"
    robot.write_text(OVERLAY)
    cfg = tmp_path / "study.toml"
    cfg.write_text(
        'robot = "ur10_flexible.xml"\n[trajectory.path]\nframe = "ee_link"\n'
        "waypoints = [[0, 0.3, -0.1], [-0.2, 0.3, 0.0]]\nrelative = true\n"
        f"start_q = {Q0.tolist()}\nsamples = 8\nduration_s = 1.5\norientation = \"keep\"\n"
        "[[targets]]\nmode = 1\nfreq_hz = 150.0\n"
    )
    study = load_config(cfg)
    model = study.build_model()
    traj = study.build_trajectory(model)
    p0 = frame_position(arm, "ee_link", Q0)
    ref = path_trajectory(arm, "ee_link", [p0, p0 + [0, 0.3, -0.1], p0 + [-0.2, 0.3, 0]],
                          n_samples=8, duration_s=1.5, q_init=Q0, orientation="keep")
    np.testing.assert_allclose(traj.q, ref.q, atol=1e-12)
    np.testing.assert_allclose(traj.times_s, ref.times_s)


def test_tracking_reference_point_of_a_six_joint_arm(arm):
    """A reference (q0, y0) with 6 joints and 1 design value is a point, not a sample index."""
    from pinflex.erls.tracking import track_modes

    Q = np.linspace(Q0, Q0 + [0.2, 0.1, -0.1, 0, 0, 0], 5)
    tr = track_modes(arm, Q, modes=(1, 2), reference=(Q0 + 0.01, np.array([2.0])))
    np.testing.assert_allclose(np.sort(tr.freq_hz, axis=1), arm.frequencies(Q)[:, :2],
                               rtol=1e-9)
