"""``pinflex modes`` says which joint condition it used and what a held arm rings at."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from pinflex.erls import FlexibleModel

ROOT = Path(__file__).resolve().parents[1]
UR3 = ROOT / "urdf" / "ur3_tubes.xml"
Q = ["0", "-1.2", "1.4", "-1.8", "-1.57", "0"]


def _modes(*args):
    out = subprocess.run([sys.executable, "-m", "pinflex", "modes", *map(str, args)],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    return out.stdout


def test_free_joints_print_the_locked_and_servo_modes_of_the_held_arm():
    """UR3 with --joints free: 277 Hz is an arm whose joints carry no torque; the same run
    names the locked (63 Hz) and servo-spring (29 Hz) values of the held arm."""
    q = np.array(Q, dtype=float)
    text = _modes(UR3, "--q", *Q, "--modes", "3", "--joints", "free")
    assert "joint condition: free" in text and "--joints free" in text
    locked = FlexibleModel(UR3, joints="locked").frequencies(q, n_modes=3)
    servo = FlexibleModel(UR3).frequencies(q, n_modes=3)
    line = next(s for s in text.splitlines() if s.startswith("note: free joints"))
    assert f"{locked[0]:.4g}" in line and f"{servo[0]:.4g}" in line
    data = json.loads(_modes(UR3, "--q", *Q, "--modes", "3", "--joints", "free", "--json"))
    np.testing.assert_allclose(data["held_frequencies_hz"]["locked"], locked, rtol=1e-12)
    np.testing.assert_allclose(data["held_frequencies_hz"]["annotated"], servo, rtol=1e-12)
    assert data["frequencies_hz"][0] > 3 * locked[0] > 3 * servo[0]


def test_held_arm_line_only_when_a_joint_is_free():
    """On the file's servo springs (the default) no joint is free: no note, the condition."""
    text = _modes(UR3, "--q", *Q, "--modes", "2")
    assert "joint condition: 6 on springs (servos) (the file's <pinflex:joint>" in text
    assert "note: free joints" not in text
    data = json.loads(_modes(UR3, "--q", *Q, "--modes", "2", "--json"))
    assert data["held_frequencies_hz"] == {}
