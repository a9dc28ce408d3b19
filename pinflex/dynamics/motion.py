"""Joint motion from trajectory samples: a rest-to-rest quintic spline that holds at the end."""

from __future__ import annotations

import warnings

import numpy as np
from scipy.interpolate import make_interp_spline

from pinflex.exceptions import InvalidTrajectory, TrajectoryWarning


class JointMotion:
    """``q(t)``, ``q̇(t)``, ``q̈(t)`` through the samples of a :class:`~pinflex.Trajectory`.

    The interpolant is a quintic spline through every sample with zero velocity and
    acceleration at both ends (the joints start and end at rest), so ``q̈`` is continuous
    everywhere, also at the stop. Before the first sample the joints rest at the first
    sample, after the last one they hold the last sample. A trajectory whose samples do not
    start or end at rest (a finite-difference speed at an end above 5 % of the peak) is
    interpolated all the same and warned about with :class:`TrajectoryWarning`.

    Args:
        trajectory: Joint samples in the model's user coordinates.
    """

    def __init__(self, trajectory):
        """Fit the rest-to-rest quintic spline through the samples.

        Args:
            trajectory: A :class:`~pinflex.Trajectory` (``times_s`` (n,) [s] increasing,
                ``q`` (n, nv) [rad or m]).

        Raises:
            InvalidTrajectory: Fewer than 2 samples.
        """
        t = np.asarray(trajectory.times_s, dtype=float)
        q = np.asarray(trajectory.q, dtype=float)
        if t.size < 2:
            raise InvalidTrajectory("a joint motion needs at least 2 samples")
        self.trajectory = trajectory
        self.t0, self.t1 = float(t[0]), float(t[-1])
        self.q_start, self.q_end = q[0].copy(), q[-1].copy()
        zero = np.zeros(q.shape[1])
        bc = ([(1, zero), (2, zero)], [(1, zero), (2, zero)])
        self._spline = make_interp_spline(t, q, k=5, bc_type=bc)
        self._d1 = self._spline.derivative(1)
        self._d2 = self._spline.derivative(2)
        speed = np.abs(np.diff(q, axis=0) / np.diff(t)[:, None])
        peak = float(speed.max()) if speed.size else 0.0
        if peak > 0.0 and max(speed[0].max(), speed[-1].max()) > 0.05 * peak:
            warnings.warn(
                "the trajectory does not start and end at rest (end speed "
                f"{max(speed[0].max(), speed[-1].max()):.3g} vs peak {peak:.3g} per s); the "
                "joint motion is interpolated rest to rest, which changes its ends",
                TrajectoryWarning, stacklevel=2)

    @property
    def duration_s(self) -> float:
        """Time of the motion from the first to the last sample [s]."""
        return self.t1 - self.t0

    def __call__(self, t: float):
        """``(q, q̇, q̈)`` at time ``t`` [s]."""
        if t <= self.t0:
            z = np.zeros_like(self.q_start)
            return self.q_start.copy(), z, z.copy()
        if t >= self.t1:
            z = np.zeros_like(self.q_end)
            return self.q_end.copy(), z, z.copy()
        return self._spline(t), self._d1(t), self._d2(t)

    def sample(self, times: np.ndarray):
        """``(q, q̇, q̈)`` at many times, each (n, nv).

        Args:
            times: Times (n,) [s]; outside the samples the joints rest at the first or hold
                the last sample (zero velocity and acceleration).

        Returns:
            ``(q, qd, qdd)``, each (n, nv): [rad or m], [rad/s or m/s], [rad/s² or m/s²].
        """
        times = np.asarray(times, dtype=float)
        tc = np.clip(times, self.t0, self.t1)
        q, qd, qdd = self._spline(tc), self._d1(tc), self._d2(tc)
        out = (times <= self.t0) | (times >= self.t1)
        qd[out] = 0.0
        qdd[out] = 0.0
        return q, qd, qdd
