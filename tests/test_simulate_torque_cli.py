"""`pinflex simulate` with the torque drive: a study file end to end, servo residual vibration."""

from __future__ import annotations

import json

import numpy as np
import pytest


@pytest.mark.slow
def test_torque_drive_from_a_study_file(tmp_path, capsys):
    """Computed torque + PD along a short move: the arm rings at the servo-joint frequency.

    After the stop the PD gains act as joint springs of stiffness kp (damping kd = 0 here):
    the residual vibration's frequency must be one of the modes of the model with those
    springs (the modal analysis, not the simulation). Slow (minutes): the adaptive steps of
    the torque drive resolve the stiff modes that the motor torques excite.
    """
    from pinflex.cli import main

    t = np.linspace(0.0, 0.12, 25)
    s = t / 0.12
    h = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.array([1.7, 5.1])[None] + h[:, None] * np.array([0.2, 0.2])[None]
    csv = tmp_path / "move.csv"
    csv.write_text("t,q1,q2\n" + "\n".join(f"{a},{b},{c}" for a, (b, c) in zip(t, q)))
    study = tmp_path / "s.toml"
    study.write_text(
        'robot = "builtin:two_link.urdf"\nplanar = true\n'
        f'[trajectory]\ncsv = "{csv}"\n'
        '[[targets]]\nmode = 1\nfreq_hz = 190.0\n'
        '[options]\nbaseline = { m1 = 0.0, m2 = 0.0 }\n'
        '[simulation]\ndrive = "torque"\nafter_s = 0.25\nkp = 3000.0\nkd = 0.0\n'
        'sample_hz = 4000.0\n')
    assert main(["simulate", str(study), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["drive"] == "torque"
    assert [d["name"] for d in out["designs"]] == ["baseline", "assigned"]
    for d in out["designs"]:
        assert d["residual_joint_condition"] == "servo"
        assert d["tip_peak_m"] > 1e-6
        f = d["dominant_frequency_hz"]
        nearest = min(d["residual_reference_hz"][:3], key=lambda r: abs(r - f))
        # 0.25 s after the stop hold about 3 periods of the assigned design's 13 Hz servo
        # mode beside a 35 Hz one: the fit is good to ~1 % there (measured 0.67 %; baseline
        # 0.03 %); holding the ERLS coordinates instead of the motor angles moves the
        # frequencies by > 10 % (tests/test_dynamics.py)
        assert f == pytest.approx(nearest, rel=1e-2)
        assert d["steps"] > 1000
