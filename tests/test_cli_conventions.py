"""Command-line conventions: one line per error, quiet when the reader goes away."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_closed_stdout_is_not_an_internal_error():
    """A closed pipe on stdout ends the command with status 141 and nothing on stderr."""
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(
        [sys.executable, "-m", "pinflex", "modes", str(ROOT / "urdf" / "two_link.urdf"),
         "--q", "1.817", "5.312", "--planar"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
    )
    proc.stdout.close()  # the reader is gone before the table is printed
    _, err = proc.communicate(timeout=300)
    assert proc.returncode == 141, err.decode()
    assert err.decode() == ""


def test_usage_errors_are_one_line(capsys):
    """An argparse usage error is one line naming the subcommand and the way to help; status 2."""
    from pinflex.cli import main

    assert main(["modes", "robot.urdf", "--modes", "abc"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["pinflex modes: error: argument --modes: 'abc' is not an integer "
                   "(see 'pinflex modes --help')"]
    # numbers follow pinflex's grammar, not Python's float(): 1_0, nan, Unicode digits
    for bad in ("1_0", "nan", "\u0663", "\uff13", "\u00a03"):
        assert main(["modes", "robot.urdf", "--q", bad]) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "argument --q" in err, err


def test_version_is_the_package_version(capsys):
    """`pinflex --version` prints the installed package's version and exits 0."""
    from importlib.metadata import version

    import pinflex
    from pinflex.cli import main

    assert main(["--version"]) == 0  # main returns the status (no SystemExit escapes it)
    assert capsys.readouterr().out.strip() == f"pinflex {pinflex.__version__}"
    assert version("pinflex") == pinflex.__version__  # pyproject.toml and the package agree


def test_simulate_reports_progress_by_stage(capsys):
    """`pinflex simulate` draws one bar over the assignment and the two simulations."""
    import re

    from pinflex.cli.simulate import run_study

    study = Path(__file__).resolve().parents[1] / "examples" / "benchmark_a.toml"
    run_study(study, progress=True)
    err = [line for line in capsys.readouterr().err.splitlines() if line.startswith("simulate")]
    assert re.match(r"simulate: assignment, baseline, assigned \[#+\] 3/3 100%", err[-1]), err


def _bar_lines(stream) -> list[str]:
    return [ln for ln in stream.getvalue().splitlines() if ln.strip()]


def test_modes_along_reports_progress_per_chunk_and_chunks_change_nothing(monkeypatch):
    """Tracking solves its samples in chunks (one bar step per sample); the chunked tracking
    of a UR5 motion, whose shapes are compared across chunk boundaries through the joined pose
    map, equals the one-batch tracking: frequencies, order, step MACs and events."""
    import io

    import numpy as np

    import pinflex
    from pinflex.erls import tracking
    from pinflex.erls.along import modes_along
    from pinflex.progress import ProgressBar
    from pinflex.trajectory.cartesian import path_from_spec

    arm = pinflex.FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml")
    traj = path_from_spec(arm, {"frame": "ee_link", "waypoints": [[0.15, 0, -0.1]],
                                "relative": True, "start_q": [0, -1, 1.2, 0.3, 0.5, 0],
                                "samples": 40, "duration_s": 2})
    whole = modes_along(arm, traj, modes=4)
    monkeypatch.setattr(tracking, "_CHUNK", 7)
    out = io.StringIO()
    bar = ProgressBar(traj.n_samples, "modes along: samples", stream=out, log_interval_s=0.0)
    chunked = modes_along(arm, traj, modes=4, progress=bar)
    lines = _bar_lines(out)
    assert len(lines) == 6 and lines[-1].startswith("modes along: samples [")
    assert " 40/40 100%" in lines[-1]
    assert [int(ln.split("] ")[1].split("/")[0]) for ln in lines] == [7, 14, 21, 28, 35, 40]
    np.testing.assert_allclose(chunked.freq_hz, whole.freq_hz, rtol=1e-12)
    np.testing.assert_array_equal(chunked.order, whole.order)
    np.testing.assert_allclose(chunked.mac_step, whole.mac_step, rtol=1e-10, atol=1e-12)
    assert chunked.events == whole.events


def test_path_reports_progress_per_sample(tmp_path, monkeypatch):
    """`pinflex path` advances its bar once per IK sample (position-only and with orientation)."""
    import io

    import pinflex
    from pinflex.progress import ProgressBar
    from pinflex.trajectory.cartesian import path_from_spec

    arm = pinflex.FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml")
    for orientation in ("free", "keep"):
        out = io.StringIO()
        bar = ProgressBar(25, "path: samples", stream=out, log_interval_s=0.0)
        traj = path_from_spec(arm, {"frame": "ee_link", "waypoints": [[0.1, 0, -0.05]],
                                    "relative": True, "start_q": [0, -1, 1.2, 0.3, 0.5, 0],
                                    "samples": 25, "orientation": orientation}, progress=bar)
        lines = _bar_lines(out)
        assert traj.n_samples == 25 and len(lines) == 25, orientation
        assert " 25/25 100%" in lines[-1] and " 1/25 " in lines[0]


def test_long_commands_take_no_progress():
    """Every command the command-line reference names as drawing a progress bar accepts
    --no-progress."""
    import argparse
    import importlib.util
    import re

    from pinflex.cli import build_parser

    spec = importlib.util.spec_from_file_location("reference", ROOT / "docs" / "_site" /
                                                  "reference.py")
    assert spec is not None and spec.loader is not None
    reference = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(reference)
    page = reference.cli_page()
    named = re.search(r"progress bar on stderr when it is a terminal \((.*?)\)", page,
                      flags=re.S).group(1)
    commands = {c.split()[0] for c in re.findall(r"`([a-z -]+)`", named)}
    assert {"modes", "path", "simulate", "view"} <= commands
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))

    def runners(p):  # the parsers that run work: the command, or its own subcommands (batch)
        subs = [a for a in p._actions if isinstance(a, argparse._SubParsersAction)]
        if not subs:
            return [p]
        return [c for a in subs for n, c in a.choices.items() if n != "report"]

    for name in sorted(commands):
        for p in runners(sub.choices[name]):
            assert "--no-progress" in {o for a in p._actions for o in a.option_strings}, p.prog
