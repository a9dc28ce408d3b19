"""`pinflex simulate` for every arm: plain motions, studies without targets, locked joints.

A plain motion without a study, studies without targets, locked joints with --out, refusals
before the assignment runs.

Reference: the global planar frame FE of benchmark A (tests/reference_fe.py, no pinflex code).
"""

from __future__ import annotations

import json

import numpy as np
import pytest
import reference_fe as ref

from pinflex.erls.joints import joint_transform
from pinflex.exceptions import ModelValidityWarning

Q = (1.8, 5.3)  # absolute link angles of benchmark A (the file's user convention)


def _csv(path, q_of_s, T=0.05, n=11):
    t = np.linspace(0.0, T, n)
    s = t / T
    h = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.array([q_of_s(v) for v in h])
    rows = (f"{float(a)!r},{float(b)!r},{float(c)!r}" for a, (b, c) in zip(t, q))
    path.write_text("t,q1,q2\n" + "\n".join(rows))
    return path


def _locked_elbow(tmp_path):
    from pinflex.description.builtin import builtin_path

    text = builtin_path("two_link.urdf").read_text().replace(
        '<pinflex:flexible link="link1"',
        '<pinflex:joint name="q2" locked="true"/>\n  <pinflex:flexible link="link1"', 1)
    path = tmp_path / "two_locked.urdf"
    path.write_text(text)
    return path


def test_plain_motion_of_a_robot_file_under_gravity_is_the_fe_static_deflection(tmp_path,
                                                                                 capsys):
    """`pinflex simulate ARM --trajectory CSV --gravity ...`: no study, no design variables.

    The arm holds still under gravity with the joints held (the prescribed drive); starting
    from the static deflection it stays there: the tip deflection equals the global FE's
    static solution under its own weight and the two point masses (elbow locked relative,
    base clamped).
    """
    from pinflex.cli import main

    csv = _csv(tmp_path / "hold.csv", lambda h: Q)
    g = np.array([0.0, -9.81])
    rc = main(["simulate", "builtin:two_link.urdf", "--planar", "--trajectory", str(csv),
               "--set", "m1=0.1", "--set", "m2=0.05", "--gravity", "0", "-9.81", "0",
               "--after", "0.01", "--sample-hz", "2000", "--modal-damping", "0.05", "--json"])
    assert rc == 0
    out = json.loads(capsys.readouterr().out)
    (d,) = out["designs"]
    assert d["name"] == "design" and d["y"] == {"m1": 0.1, "m2": 0.05}
    K, _ = ref.planar_two_link_matrices(Q, 0.1, 0.05)
    dofs = ref.planar_chain_dofs([4, 3])
    f = np.zeros(K.shape[0])
    rhoA = 1.9
    for link, (angle, length, n_el) in enumerate(zip(Q, (0.6, 0.45), (4, 3))):
        t = np.array([np.cos(angle), np.sin(angle)])
        nrm = np.array([-t[1], t[0]])
        le = length / n_el
        q_ax, q_tr = rhoA * g @ t, rhoA * g @ nrm  # uniform line load, link axes [N/m]
        for e in range(n_el):  # consistent nodal loads of a uniform load (Hermite, linear)
            for node, sign in ((dofs[link][e], 1.0), (dofs[link][e + 1], -1.0)):
                force = 0.5 * le * (q_ax * t + q_tr * nrm)
                for k in (0, 1):
                    if node[k] >= 0:
                        f[node[k]] += force[k]
                f[node[2]] += sign * q_tr * le**2 / 12.0
    for link, mass in ((0, 0.1), (1, 0.05)):
        f[dofs[link][-1, :2]] += mass * g
    n = K.shape[0]
    keep = [i for i in range(n) if i not in (0, 13)]  # base clamped; elbow rotation shared
    Tm = np.zeros((n, n - 2))
    for col, i in enumerate(keep):
        Tm[i, col] = 1.0
    Tm[13, keep.index(12)] = 1.0
    u = Tm @ np.linalg.solve(Tm.T @ K @ Tm, Tm.T @ f)
    tip = dofs[1][-1, :2]
    assert d["tip_peak_m"] == pytest.approx(float(np.linalg.norm(u[tip])), rel=1e-6)
    assert d["residual_amplitude_m"] <= 1e-6 * d["tip_peak_m"]


def test_a_study_without_targets_simulates_the_model_at_its_values(tmp_path, capsys):
    """No [[targets]]: no assignment, one design, the study's values (same as the plain run)."""
    from pinflex.cli import main

    csv = _csv(tmp_path / "move.csv", lambda h: (Q[0] + 0.2 * h, Q[1] + 0.2 * h))
    study = tmp_path / "s.toml"
    study.write_text('robot = "builtin:two_link.urdf"\nplanar = true\n'
                     'values = { m1 = 0.1, m2 = 0.05 }\n'
                     f'[trajectory]\ncsv = "{csv}"\n'
                     '[simulation]\nafter_s = 0.02\nsample_hz = 2000.0\n')
    assert main(["simulate", str(study), "--json"]) == 0
    (a,) = json.loads(capsys.readouterr().out)["designs"]
    assert main(["simulate", "builtin:two_link.urdf", "--planar", "--trajectory", str(csv),
                 "--set", "m1=0.1", "--set", "m2=0.05", "--after", "0.02",
                 "--sample-hz", "2000", "--json"]) == 0
    (b,) = json.loads(capsys.readouterr().out)["designs"]
    assert a["name"] == b["name"] == "design"
    assert a["tip_peak_m"] == b["tip_peak_m"] and a["tip_peak_m"] > 1e-4


def test_locked_joint_with_out_writes_the_playback(tmp_path, capsys):
    """A locked elbow with --out: charts, series and playback pages (was a matmul crash).

    The drawn elastic state ``[x; A x]`` of the dynamics is in the range of the model's
    locked-joint transform (so the playback draws what was simulated).
    """
    pytest.importorskip("meshcat")
    from pinflex import FlexibleModel
    from pinflex.cli import main
    from pinflex.dynamics import ErlsDynamics

    urdf = _locked_elbow(tmp_path)
    csv = _csv(tmp_path / "move.csv", lambda h: (Q[0] + 0.2 * h, Q[1] + 0.2 * h))
    rc = main(["simulate", str(urdf), "--planar", "--trajectory", str(csv), "--after", "0.01",
               "--sample-hz", "1000", "--out", str(tmp_path / "out"), "--charts", "--preview",
               "--json"])
    assert rc == 0
    files = json.loads(capsys.readouterr().out)["files"]
    assert any(f.endswith("design_playback.html") for f in files)
    assert any(f.endswith("validity.png") for f in files)
    rows = (tmp_path / "out" / "design_validity.csv").read_text().splitlines()
    assert rows[0].startswith("time_s,link_speed_rad_s") and len(rows) > 10
    model = FlexibleModel(urdf, planar=True)
    dyn = ErlsDynamics(model)
    x = np.random.default_rng(3).standard_normal(model.nx)
    full = np.concatenate([x, dyn.joint_offsets(np.array(Q))[0] @ x])
    T = joint_transform(model, np.array(Q))
    solver = np.linalg.lstsq(T, full, rcond=None)[0]
    assert T @ solver == pytest.approx(full, abs=1e-12 * np.abs(full).max())


def test_locked_joints_are_refused_before_the_assignment(tmp_path, capsys, monkeypatch):
    """Locked joints the drive refuses stop the command (status 2) before the assignment.

    ``joints = "locked"`` with a moving trajectory, and the torque drive with a lock.
    """
    import pinflex.assignment.study as study_mod
    from pinflex.cli import main

    def no_assignment(*args, **kwargs):
        raise AssertionError("the assignment ran")

    monkeypatch.setattr(study_mod, "run_config", no_assignment)
    csv = _csv(tmp_path / "move.csv", lambda h: (Q[0] + 0.2 * h, Q[1] + 0.2 * h))
    study = tmp_path / "s.toml"
    study.write_text('robot = "builtin:two_link.urdf"\nplanar = true\njoints = "locked"\n'
                     f'[trajectory]\ncsv = "{csv}"\n[[targets]]\nmode = 1\nfreq_hz = 190.0\n'
                     '[simulation]\nafter_s = 0.02\n')
    assert main(["simulate", str(study)]) == 2
    assert "joint 'q1' is locked but the trajectory turns it by 0.2" in capsys.readouterr().err
    study.write_text(study.read_text().replace('joints = "locked"\n', "").replace(
        "builtin:two_link.urdf", str(_locked_elbow(tmp_path))))
    assert main(["simulate", str(study), "--drive", "torque"]) == 2
    assert "joints ['q2'] are locked" in capsys.readouterr().err
    assert main(["simulate", "builtin:two_link.urdf"]) == 2
    assert "--trajectory" in capsys.readouterr().err


def test_a_fast_motion_is_warned_about_and_strict_refuses_it(tmp_path, capsys):
    """The validity indicator in `pinflex simulate`: a warning, JSON per design, --strict.

    The arm swings 0.2 rad in 5 ms: --strict exits with status 2 before integrating.
    """
    from pinflex.cli import main

    csv = _csv(tmp_path / "fast.csv", lambda h: (Q[0] + 0.2 * h, Q[1] + 0.2 * h), T=0.005)
    args = ["simulate", "builtin:two_link.urdf", "--planar", "--trajectory", str(csv),
            "--after", "0.002", "--sample-hz", "20000"]
    assert main(args + ["--json"]) == 0
    out = capsys.readouterr()
    # the command line prints each warning as one line on stderr (pinflex.cli)
    assert f"pinflex: warning: {ModelValidityWarning.__name__}: the prescribed motion is " \
        "fast for eq. (1)" in out.err
    (d,) = json.loads(out.out)["designs"]
    v = d["validity"]
    assert v["exceeded"] is True and v["indicator"] > v["threshold"] == 0.1
    assert v["indicator"] == max(v["max_speed_ratio"], v["max_accel_ratio"])
    assert main(args + ["--strict"]) == 2
    assert "fast for eq. (1)" in capsys.readouterr().err


def test_a_simulation_reports_its_progress_and_the_numbers_do_not_change(tmp_path, capsys):
    """The prescribed drive calls progress(done, total) once per grid coefficient and stage.

    The 11 samples over 0.05 s give 10 intervals of 5 ms, each interpolated at 2 sub-intervals
    (the drive's grid of at most 5 ms, at least 2 per interval): 21 grid points, plus the
    validity indicator, the integration and the torques. The bar changes no number.
    """
    from pinflex.cli.simulate import run_study
    from pinflex.description.builtin import builtin_path
    from pinflex.dynamics.prescribed import simulate_prescribed
    from pinflex.dynamics.terms import ErlsDynamics
    from pinflex.erls import FlexibleModel
    from pinflex.trajectory import Trajectory

    csv = _csv(tmp_path / "move.csv", lambda h: (Q[0] + 0.2 * h, Q[1] + 0.2 * h))
    model = FlexibleModel(builtin_path("two_link.urdf"), planar=True)
    traj = Trajectory.from_csv(csv, joint_names=model.joint_names)
    calls: list[tuple[int, int]] = []
    dyn = ErlsDynamics(model)
    with_bar = simulate_prescribed(dyn, traj, after_s=0.02, sample_hz=2000.0,
                                   progress=lambda d, n: calls.append((d, n)))
    plain = simulate_prescribed(dyn, traj, after_s=0.02, sample_hz=2000.0)
    assert [d for d, _ in calls] == list(range(1, 25))
    assert {n for _, n in calls} == {24}
    assert np.array_equal(with_bar.x, plain.x) and np.array_equal(with_bar.torques, plain.torques)
    run_study("builtin:two_link.urdf", trajectory=str(csv), planar=True,
              simulation={"after_s": 0.02, "sample_hz": 2000.0}, progress=True)
    err = capsys.readouterr().err
    assert "simulate design" in err and "24/24" in err
