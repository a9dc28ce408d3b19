"""The command line stays quiet when the reader of its output goes away (``| head``)."""

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
