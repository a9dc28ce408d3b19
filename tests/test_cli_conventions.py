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
    import pytest

    from pinflex.cli import main

    with pytest.raises(SystemExit) as info:
        main(["modes", "robot.urdf", "--modes", "abc"])
    assert info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == ["pinflex modes: error: argument --modes: invalid int value: 'abc' "
                   "(see 'pinflex modes --help')"]


def test_version_is_the_package_version(capsys):
    """`pinflex --version` prints the installed package's version and exits 0."""
    from importlib.metadata import version

    import pytest

    import pinflex
    from pinflex.cli import main

    with pytest.raises(SystemExit) as stop:
        main(["--version"])
    assert stop.value.code == 0
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
