"""What an assignment asks for: target frequency histories, and the trajectory they hold on.

:class:`Target` is one mode's wanted frequency history; :func:`target_matrix` checks targets
and spreads them over the samples; :func:`check_trajectory_limits` checks a trajectory
against the model before any work (one column per joint, inside the URDF limits).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.trajectory import Trajectory
from pinflex.validation import float_array

__all__ = ["Target", "check_trajectory_limits", "target_matrix"]


@dataclass(frozen=True)
class Target:
    """A desired frequency history of one mode.

    Attributes:
        mode: Non-rigid mode number (1 = lowest).
        freq_hz: Desired frequency [Hz]: a constant or one value per trajectory sample.
        weight: Weight of the mode in the cost.
    """

    mode: int
    freq_hz: float | np.ndarray
    weight: float = 1.0



def target_matrix(targets: Sequence[Target], ns: int) -> np.ndarray:
    """Target frequencies (n_targets, ns) [Hz] of ``targets`` on ``ns`` samples (checked)."""
    out = np.empty((len(targets), ns))
    for i, t in enumerate(targets):
        f = float_array(t.freq_hz, f"the target of mode {t.mode}")
        if f.ndim > 1 or f.size not in (1, ns):
            raise ConfigurationError(
                f"the target of mode {t.mode} has {f.size} frequencies; give one or one per "
                f"trajectory sample ({ns})")
        f = np.broadcast_to(f.reshape(-1), (ns,))
        if np.any(~np.isfinite(f)) or np.any(f <= 0):
            raise ConfigurationError(f"target of mode {t.mode} must be positive frequencies [Hz]")
        out[i] = f
    return out


def check_trajectory_limits(model: FlexibleModel, trajectory: Trajectory) -> None:
    """Warn (TrajectoryWarning) when a trajectory leaves the URDF joint limits or is in degrees.

    The samples are converted to Pinocchio's joint values, which the limits refer to, and
    checked with :meth:`Trajectory.check_limits` (1e-9 of slack for round-off). A revolute
    or continuous joint whose values go beyond one turn (|q| > 2π) is named as looking like
    degrees: joint values are in radians, and a continuous joint without limits would
    otherwise take 90 for a quarter turn silently.

    Args:
        model: The flexible model whose URDF holds the limits [rad or m].
        trajectory: Joint samples (ns, nv) in the model's user coordinates, one value per
            moving joint.

    Raises:
        InvalidTrajectory: If the samples do not have one column per joint of the model.
    """
    q = trajectory.in_order(model.joint_names)
    from pinflex.trajectory.cartesian import warn_if_degrees

    joints = [model.description.joints[name] for name in model.joint_names]
    in_pin = Trajectory(trajectory.times_s, q @ model.coord_map.T, model.joint_names)
    warn_if_degrees(model, in_pin.q)
    in_pin.check_limits([j.lower - 1e-9 for j in joints], [j.upper + 1e-9 for j in joints])

