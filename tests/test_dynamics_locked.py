"""Locked joints in the dynamics: held by the prescribed drive, refused where they cannot be."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from arms import locked_global_fe as _locked_global_fe
from arms import move as _move

from pinflex import FlexibleModel
from pinflex.dynamics import ErlsDynamics, simulate_prescribed, vibration_report
from pinflex.dynamics.frf import linear_pose
from pinflex.dynamics.simulate import simulate_torque
from pinflex.exceptions import ConfigurationError

URDF = Path(__file__).resolve().parents[1] / "urdf"


def test_locked_elbow_is_held_by_the_prescribed_drive():
    """Elbow locked, shoulder moved: same motion as the free model, rings at the FE frequency.

    The user coordinates are absolute, so a held elbow keeps q2 − q1 constant.
    """
    y = np.array([0.1, 0.05])
    traj = _move([1.7, 5.1], [1.9, 5.3], 0.12, n=25)
    locked = FlexibleModel(URDF / "two_link.urdf", planar=True, joints={"q2": "locked"})
    free = FlexibleModel(URDF / "two_link.urdf", planar=True)
    assert locked.ndof == free.ndof - 1  # the modal layout drops the locked coordinate
    dyn = ErlsDynamics(locked, y=y)
    assert dyn.ndof == free.ndof and dyn.locked == (("q2", 1),)
    sim = simulate_prescribed(dyn, traj, after_s=0.25, sample_hz=4000.0)
    ref = simulate_prescribed(ErlsDynamics(free, y=y), traj, after_s=0.25, sample_hz=4000.0)
    assert np.abs(sim.x - ref.x).max() <= 1e-12 * np.abs(ref.x).max()
    rep = vibration_report(dyn, sim, frame="tool")
    Kl, Ml, _ = _locked_global_fe(np.array([1.9, 5.3]), *y)
    f_fe = np.sqrt(scipy.linalg.eigh(Kl, Ml, eigvals_only=True)[0]) / (2 * math.pi)
    assert rep.dominant_frequency_hz == pytest.approx(f_fe, rel=2e-4)


def test_locked_joints_are_refused_where_the_drive_cannot_hold_them():
    """A trajectory turning a locked joint, the torque drive and a free-joint FRF: named errors."""
    y = np.array([0.1, 0.05])
    locked = FlexibleModel(URDF / "two_link.urdf", planar=True, joints={"q2": "locked"})
    dyn = ErlsDynamics(locked, y=y)
    with pytest.raises(ConfigurationError, match="'q2' is locked but the trajectory turns it"):
        simulate_prescribed(dyn, _move([1.7, 5.1], [2.2, 5.4], 0.3, n=11), after_s=0.01)
    with pytest.raises(ConfigurationError, match="stiff spring"):
        simulate_torque(dyn, q0=np.array([1.7, 5.1]), duration_s=0.01)
    with pytest.raises(ConfigurationError, match="joints='locked'"):
        linear_pose(dyn, np.array([1.7, 5.1]), [("force", "tool", (0, 0, 0), (0, 1, 0))],
                    [("displacement", "tool", (0, 0, 0), (0, 1, 0))])
    # every joint locked: the FRF with joints='locked' is the one of the free model's locks
    free = ErlsDynamics(FlexibleModel(URDF / "two_link.urdf", planar=True), y=y)
    io = ([("force", "tool", (0, 0, 0), (0, 1, 0))],
          [("displacement", "tool", (0, 0, 0), (0, 1, 0))])
    a = linear_pose(dyn, np.array([1.7, 5.1]), *io, joints="locked")
    b = linear_pose(free, np.array([1.7, 5.1]), *io, joints="locked")
    assert np.abs(a.K - b.K).max() == 0.0 and np.abs(a.M - b.M).max() == 0.0
