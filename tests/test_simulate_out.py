"""`pinflex simulate --out`: the run's data always, charts and playback only when asked.

The data files hold the in-memory result's numbers exactly; `pinflex report DIR` draws, from
that data alone (and the unchanged robot file), the same charts and playback page as
`simulate --out DIR --charts --preview` writes directly.
"""

from __future__ import annotations

import base64
import gzip
import json
import re

import numpy as np
import pytest

Q = (1.8, 5.3)  # absolute link angles of benchmark A (the file's user convention)


def _csv(path, T=0.05, n=11):
    t = np.linspace(0.0, T, n)
    h = 10 * (t / T) ** 3 - 15 * (t / T) ** 4 + 6 * (t / T) ** 5
    rows = (f"{float(a)!r},{Q[0] + 0.2 * float(b)!r},{Q[1] - 0.3 * float(b)!r}"
            for a, b in zip(t, h))
    path.write_text("t,q1,q2\n" + "\n".join(rows))
    return path


def _argv(robot, csv, *extra):
    return ["simulate", str(robot), "--planar", "--trajectory", str(csv), "--after", "0.02",
            "--sample-hz", "1000", "--set", "m2=0.05", *extra]


def _run(capsys, argv):
    from pinflex.cli import main

    rc = main(argv)
    out = capsys.readouterr()
    return rc, out


def _robot(tmp_path):
    from pinflex.description.builtin import builtin_path

    path = tmp_path / "arm.urdf"
    path.write_text(builtin_path("two_link.urdf").read_text())
    return path


def test_out_writes_the_data_with_the_in_memory_numbers(tmp_path, capsys):
    """Series JSON, npz and validity CSV equal the in-memory run; no chart, no page."""
    from pinflex.cli.simulate import run_study
    from pinflex.dynamics.saved import load_run, run_dynamics
    from pinflex.dynamics.response import frame_deflection

    robot, csv = _robot(tmp_path), _csv(tmp_path / "move.csv")
    out = tmp_path / "run"
    rc, printed = _run(capsys, _argv(robot, csv, "--out", str(out), "--json"))
    assert rc == 0, printed.err
    files = json.loads(printed.out)["files"]
    names = sorted(p.name for p in out.iterdir())
    assert names == ["design_run.npz", "design_series.json", "design_validity.csv", "run.json"]
    assert sorted(f.rsplit("/", 1)[-1] for f in files) == names

    reports, sims, settings, _, _ = run_study(
        robot, values={"m2": 0.05}, trajectory=str(csv), planar=True,
        simulation={"after_s": 0.02, "sample_hz": 1000.0})
    (rep,), ((sim, dyn),) = reports, sims
    series = json.loads((out / "design_series.json").read_text())
    assert np.array_equal(series["times_s"], rep.times_s)
    assert np.array_equal(series["deflection_m"], rep.deflection_m)
    assert series["tip_peak_m"] == rep.tip_peak_m and series["y"] == {"m1": 0.125, "m2": 0.05}
    with np.load(out / "design_run.npz") as data:
        for k in ("times_s", "x", "xd", "q", "qd", "q_physical", "torques"):
            assert np.array_equal(data[k], getattr(sim, k)), k
        assert float(data["stop_s"]) == sim.stop_s and int(data["steps"]) == sim.steps
        assert np.array_equal(data["validity_speed_ratio"], sim.validity.speed_ratio)
    rows = np.loadtxt(out / "design_validity.csv", delimiter=",", skiprows=1)
    assert np.allclose(rows[:, 0], sim.validity.times_s, rtol=1e-8, atol=0)
    assert np.allclose(rows[:, -1], sim.validity.accel_ratio[:, -1], rtol=1e-8, atol=0)

    saved = load_run(out)
    (back,), (bsim,) = saved.reports, saved.sims
    assert back.summary() | {"time_s": 0} == rep.summary() | {"time_s": 0}
    assert bsim.drive == sim.drive and bsim.joint_condition == "locked"
    assert bsim.validity.summary() == sim.validity.summary()
    # the saved state is enough: the deflection recomputed on the rebuilt model is the file's
    again = frame_deflection(run_dynamics(saved, 0), bsim, "tool")
    assert np.abs(again - rep.deflection_m).max() <= 1e-14 * np.abs(rep.deflection_m).max()


@pytest.mark.parametrize("flags, suffixes", [((), set()), (("--charts",), {".png"}),
                                             (("--preview",), {".html"}),
                                             (("--charts", "--preview"), {".png", ".html"})])
def test_charts_and_pages_only_when_asked(tmp_path, capsys, flags, suffixes):
    """--charts writes the PNGs, --preview the playback page; neither by default."""
    if "--preview" in flags:
        pytest.importorskip("meshcat")
    robot, csv = _robot(tmp_path), _csv(tmp_path / "move.csv")
    out = tmp_path / "run"
    rc, printed = _run(capsys, _argv(robot, csv, "--out", str(out), *flags))
    assert rc == 0, printed.err
    extra = {p.suffix for p in out.iterdir()} - {".json", ".npz", ".csv"}
    assert extra == suffixes
    assert (out / "tip_deflection.png").is_file() == ("--charts" in flags)
    assert (out / "design_playback.html").is_file() == ("--preview" in flags)


def test_charts_or_preview_without_out_is_refused_before_work(tmp_path, capsys, monkeypatch):
    """--charts / --preview need --out: a one-line error, status 2, nothing simulated."""
    import pinflex.cli.simulate as simulate

    def fail(*a, **k):
        raise AssertionError("simulated before refusing")

    monkeypatch.setattr(simulate, "run_study", fail)
    robot, csv = _robot(tmp_path), _csv(tmp_path / "move.csv")
    for flag in ("--charts", "--preview"):
        rc, printed = _run(capsys, _argv(robot, csv, flag))
        assert rc == 2
        assert printed.err.count("\n") == 1 and "--out DIR" in printed.err


def _scene(page: str) -> tuple[str, bytes, str]:
    """The page with its packed scene unpacked and meshcat's object ids numbered in order."""
    m = re.search(r'pinflexUnpack\("([^"]+)"', page)
    data = gzip.decompress(base64.b64decode(m.group(1)))
    ids: dict = {}
    data = re.sub(rb"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}",
                  lambda u: b"%036d" % ids.setdefault(u.group(0), len(ids)), data)
    return page[:m.start()], data, page[m.end():]


@pytest.mark.parametrize("locked", [False, True])
def test_report_from_the_saved_run_equals_the_direct_output(tmp_path, capsys, locked):
    """`pinflex report DIR` = `simulate --out DIR --charts --preview`, file by file.

    Charts byte for byte; the playback page up to meshcat's object ids (time-based, new on
    every drawing). Also with the elbow locked (the page draws the solver coordinates of the
    locked-joint model rebuilt from the file).
    """
    pytest.importorskip("meshcat")
    robot, csv = _robot(tmp_path), _csv(tmp_path / "move.csv")
    if locked:
        robot.write_text(robot.read_text().replace(
            '<pinflex:flexible link="link1"',
            '<pinflex:joint name="q2" locked="true"/>\n  <pinflex:flexible link="link1"', 1))
        assert "locked" in robot.read_text()
        rows = csv.read_text().splitlines()  # absolute angles: the elbow turns with link 1
        csv.write_text("\n".join([rows[0]] + [",".join(r.split(",")[:2] + [repr(
            float(r.split(",")[1]) + Q[1] - Q[0])]) for r in rows[1:]]))
    direct = tmp_path / "direct"
    rc, printed = _run(capsys, _argv(robot, csv, "--out", str(direct), "--charts", "--preview",
                                     "--exaggeration", "150"))
    assert rc == 0, printed.err
    later = tmp_path / "later"
    rc, printed = _run(capsys, ["report", str(direct), "--out", str(later), "--exaggeration",
                                "150", "--json"])
    assert rc == 0, printed.err
    written = json.loads(printed.out)["files"]
    assert sorted(f.rsplit("/", 1)[-1] for f in written) == [
        "design_playback.html", "tip_deflection.png", "validity.png"]
    for name in ("tip_deflection.png", "validity.png"):
        assert (later / name).read_bytes() == (direct / name).read_bytes(), name
    a = _scene((direct / "design_playback.html").read_text())
    b = _scene((later / "design_playback.html").read_text())
    assert a == b
    # a different exaggeration draws a different scene (the comparison can fail)
    rc, printed = _run(capsys, ["report", str(direct), "--out", str(tmp_path / "x"),
                                "--no-charts", "--exaggeration", "100"])
    assert rc == 0 and _scene((tmp_path / "x" / "design_playback.html").read_text())[1] != a[1]


def test_report_refuses_a_changed_robot_file_and_a_folder_without_a_run(tmp_path, capsys):
    """The playback needs the model as simulated: a changed robot file is refused (status 2);
    the charts alone are still drawn from the data; a folder without run.json is refused."""
    robot, csv = _robot(tmp_path), _csv(tmp_path / "move.csv")
    out = tmp_path / "run"
    assert _run(capsys, _argv(robot, csv, "--out", str(out)))[0] == 0
    robot.write_text(robot.read_text().replace('<robot name="', '<robot name="changed_', 1))
    rc, printed = _run(capsys, ["report", str(out)])
    assert rc == 2 and "changed since the run" in printed.err
    rc, printed = _run(capsys, ["report", str(out), "--no-preview"])
    assert rc == 0 and (out / "tip_deflection.png").is_file()
    rc, printed = _run(capsys, ["report", str(tmp_path)])
    assert rc == 2 and "no readable run.json" in printed.err
