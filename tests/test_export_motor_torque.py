"""Exported B as motor torques: the export's receptances equal the direct harmonic solve.

The second formulation is pinflex.dynamics (eq. 1's terms from its own material points, the
motor torque's generalized force ``Gᵀ τ`` from the dynamics' joint offsets), solved directly at
each frequency; the export is the ERLS modal assembly in state-space form.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pinflex.dynamics import Damping, ErlsDynamics
from pinflex.dynamics.frf import frf_direct, linear_pose
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.native.export import linear_model

URDF = Path(__file__).resolve().parents[1] / "urdf" / "two_link.urdf"
Q = np.array([1.8, 5.3])
Y = (0.1, 0.05)
TIP = ("displacement", "tool", (0, 0, 0), (0, 1, 0))


def _state_space_receptance(data, Yrow, freqs_hz):
    nd = data["M"].shape[0]
    A, B = data["A"], data["B"]
    Cp = np.zeros((1, 2 * nd))
    Cp[0, :nd] = Yrow
    return np.array([Cp @ np.linalg.solve(2j * np.pi * f * np.eye(2 * nd) - A, B)
                     for f in freqs_hz])[:, 0, :]


def test_exported_receptances_equal_the_motor_torque_harmonic_solve():
    """Tip receptance to both joint torques, Rayleigh-damped: export = direct solve, 1e-8."""
    arm = FlexibleModel(URDF, planar=True)
    dyn = ErlsDynamics(arm, y=list(Y))
    damping = Damping("rayleigh", 0.4, 2e-5)
    lp = linear_pose(dyn, Q, [("torque", "q1"), ("torque", "q2")], [TIP], damping=damping)
    freqs = np.array([2.0, 20.0, 50.0, 150.0, 500.0])
    ref = frf_direct(lp, freqs)[:, 0, :]
    data = linear_model(arm, Q, y=Y, rayleigh=(0.4, 2e-5))
    assert data["M"] == pytest.approx(lp.M, abs=1e-9 * np.abs(lp.M).max())
    got = _state_space_receptance(data, lp.Y[0], freqs)
    assert np.abs(got - ref).max() <= 1e-8 * np.abs(ref).max()
    # the generalized-coordinate reading leaves the reaction on the flexible upper arm out:
    # the elbow torque's receptance differs
    gen = _state_space_receptance(
        linear_model(arm, Q, y=Y, rayleigh=(0.4, 2e-5), torque_input="generalized"),
        lp.Y[0], freqs)
    assert np.max(np.abs(gen[:, 1] / ref[:, 1] - 1.0)) > 0.5  # measured 0.91 at 150 Hz
    with pytest.raises(ConfigurationError):
        linear_model(arm, Q, y=Y, torque_input="stator")


def test_a_locked_joint_takes_no_motor_torque():
    """A locked elbow's input column is zero (a reaction); the base torque acts (``Gᵀ``)."""
    arm = FlexibleModel(URDF, planar=True, joints={"q2": "locked"})
    data = linear_model(arm, Q, y=Y)
    nd = arm.ndof
    Bu = data["M"] @ data["B"][nd:]
    assert np.abs(Bu[:, 1]).max() <= 1e-12 * np.abs(Bu[:, 0]).max()
    assert np.abs(Bu[:, 0]).max() > 0.0
