"""Joint trajectories, planar workspace paths and inverse kinematics.

A :class:`Trajectory` is the time grid ``t_k`` and the joint samples ``q(t_k)`` along which
paper 000 (Belotti et al. 2021, Sec. 2.4) integrates its assignment cost, eq. (10): the
integrals (13)–(14) become weighted sums with :meth:`Trajectory.trapezoid_weights`, as the
paper does in Sec. 3.3.

Conventions:

* ``q`` holds the model's joint coordinates, one value per joint: revolute angles [rad],
  prismatic displacements [m]. For the benchmark-A arm these are Pinocchio's coordinates, the
  base angle and the RELATIVE elbow angle, ``q_rel = (q1, q2 - q1)``; paper 000 prints ABSOLUTE
  link angles. :func:`absolute_to_relative` and :func:`relative_to_absolute` convert.
* Workspace paths live in the x–y plane of the world frame [m]; planar arms turn about z.

Benchmark A (SPEC §5) is built without the modal model: :func:`planar_2r_ik` inverts the
planar two-link arm in closed form and :func:`benchmark_a_trajectory` returns the 152-sample
pick-and-place motion through the paper's expansion point ``q0``. The Pinocchio solver
:func:`solve_ik` handles any model and is checked against the closed form in the tests.
"""

from __future__ import annotations

import csv
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, Sequence

import numpy as np
from scipy.optimize import brentq

from pinflex._arrays import readonly as _readonly
from pinflex.exceptions import (
    IKNotConverged,
    InvalidPath,
    InvalidTrajectory,
    JointLimitsExceeded,
    TrajectoryWarning,
)

__all__ = [
    "BENCHMARK_A_L1_M",
    "BENCHMARK_A_L2_M",
    "BENCHMARK_A_Q0_ABS",
    "BENCHMARK_A_Q0_SAMPLE",
    "IKSolution",
    "Trajectory",
    "WorkspacePath",
    "absolute_to_relative",
    "benchmark_a_path",
    "benchmark_a_trajectory",
    "planar_2r_fk",
    "planar_2r_ik",
    "relative_to_absolute",
    "solve_ik",
    "trapezoid_weights",
    "workspace_path",
]



def trapezoid_weights(times_s: np.ndarray) -> np.ndarray:
    """Weights ``w`` such that ``w @ f(t)`` is the trapezoidal integral of ``f`` on the grid.

    Args:
        times_s: Strictly increasing sample times, shape (ns,), ns >= 2 [s].

    Returns:
        Weights of shape (ns,) [s]: ``w_0 = (t_1 - t_0)/2``, ``w_k = (t_{k+1} - t_{k-1})/2``,
        ``w_{ns-1} = (t_{ns-1} - t_{ns-2})/2``. They sum to ``t_{ns-1} - t_0``.

    Raises:
        InvalidTrajectory: Fewer than two samples, or times not strictly increasing.
    """
    t = np.asarray(times_s, dtype=float)
    if t.ndim != 1 or t.size < 2:
        raise InvalidTrajectory(
            f"trapezoidal weights need a 1-D grid of at least 2 times, got shape {t.shape}"
        )
    dt = np.diff(t)
    if not np.all(dt > 0.0):
        k = int(np.argmin(dt))
        raise InvalidTrajectory(
            f"times must increase strictly; t[{k}] = {t[k]!r} >= t[{k + 1}] = {t[k + 1]!r}"
        )
    w = np.zeros_like(t)
    w[:-1] += 0.5 * dt
    w[1:] += 0.5 * dt
    return w


@dataclass(frozen=True)
class Trajectory:
    """Joint samples on a time grid.

    Attributes:
        times_s: Sample times, strictly increasing, shape (ns,) [s].
        q: Joint values, shape (ns, nv), in the model's joint convention (one value per
            joint: revolute [rad], prismatic [m]). Read-only.
        joint_names: One name per column of ``q``; defaults to ``("q1", ..., "qnv")``.
        name: Optional label (used in plots and reports).
    """

    times_s: np.ndarray
    q: np.ndarray
    joint_names: tuple[str, ...] = field(default=())
    name: str | None = None

    def __post_init__(self):
        t = np.asarray(self.times_s, dtype=float)
        q = np.asarray(self.q, dtype=float)
        if t.ndim != 1 or t.size < 1:
            raise InvalidTrajectory(f"times_s must have shape (ns,) with ns >= 1, got {t.shape}")
        if q.ndim != 2 or q.shape[0] != t.size:
            raise InvalidTrajectory(
                f"q must have shape (ns, nv) = ({t.size}, nv) to match times_s, got {q.shape}; "
                "pass one row per sample and one column per joint"
            )
        if not np.all(np.isfinite(t)):
            bad_t = _bad_rows(~np.isfinite(t))
            raise InvalidTrajectory(f"times_s has non-finite entries at samples {bad_t}")
        bad_q = ~np.all(np.isfinite(q), axis=1)
        if np.any(bad_q):
            raise InvalidTrajectory(f"q has non-finite entries at samples {_bad_rows(bad_q)}")
        if t.size > 1 and not np.all(np.diff(t) > 0.0):
            k = int(np.argmin(np.diff(t)))
            raise InvalidTrajectory(
                f"times_s must increase strictly; t[{k}] = {t[k]!r} >= t[{k + 1}] = {t[k + 1]!r}"
            )
        names = tuple(self.joint_names) or tuple(f"q{j + 1}" for j in range(q.shape[1]))
        if len(names) != q.shape[1]:
            raise InvalidTrajectory(
                f"{len(names)} joint names given for {q.shape[1]} columns of q: {names}"
            )
        object.__setattr__(self, "times_s", _readonly(t))
        object.__setattr__(self, "q", _readonly(q))
        object.__setattr__(self, "joint_names", names)

    @property
    def n_samples(self) -> int:
        """Number of samples ns."""
        return self.times_s.size

    @property
    def duration_s(self) -> float:
        """Duration ``t_{ns-1} - t_0`` [s]."""
        return float(self.times_s[-1] - self.times_s[0])

    def trapezoid_weights(self) -> np.ndarray:
        """Trapezoidal quadrature weights on ``times_s``, shape (ns,) [s].

        ``self.trapezoid_weights() @ f`` approximates ``∫ f(t) dt``; exact for f linear in t.
        """
        return trapezoid_weights(self.times_s)

    def check_limits(
        self,
        lower: np.ndarray,
        upper: np.ndarray,
        *,
        on_violation: Literal["warn", "raise"] = "warn",
    ) -> np.ndarray:
        """Find samples outside joint limits.

        Args:
            lower: Lower joint limits, shape (nv,) (e.g. ``model.lowerPositionLimit``).
            upper: Upper joint limits, shape (nv,).
            on_violation: ``"warn"`` issues a :class:`TrajectoryWarning`, ``"raise"`` raises
                :class:`JointLimitsExceeded`.

        Returns:
            Boolean mask of shape (ns, nv), True where a limit is exceeded.

        Raises:
            InvalidTrajectory: Limits of the wrong shape.
            JointLimitsExceeded: With ``on_violation="raise"`` if any sample is outside.
        """
        nv = self.q.shape[1]
        try:
            lo = np.broadcast_to(np.asarray(lower, dtype=float), (nv,))
            hi = np.broadcast_to(np.asarray(upper, dtype=float), (nv,))
        except ValueError as err:
            raise InvalidTrajectory(
                f"limits must be scalars or have shape ({nv},), got lower {np.shape(lower)} "
                f"and upper {np.shape(upper)}"
            ) from err
        mask = (self.q < lo) | (self.q > hi)
        if np.any(mask):
            samples, joints = np.nonzero(mask)
            error = JointLimitsExceeded(
                samples=samples,
                joints=[self.joint_names[j] for j in joints],
                values=self.q[samples, joints],
                lower=lo[joints],
                upper=hi[joints],
            )
            if on_violation == "raise":
                raise error
            warnings.warn(str(error), TrajectoryWarning, stacklevel=2)
        return mask

    def to_csv(self, path: str | Path) -> None:
        """Write ``t, <joint names...>`` with 17 significant digits (exact round trip)."""
        with open(path, "w", newline="") as stream:
            writer = csv.writer(stream)
            writer.writerow(["t", *self.joint_names])
            for t, row in zip(self.times_s, self.q):
                writer.writerow([repr(float(t)), *(repr(float(v)) for v in row)])

    @classmethod
    def from_csv(cls, path: str | Path, *, name: str | None = None) -> Trajectory:
        """Read a CSV file whose header is ``t`` followed by joint names.

        Args:
            path: File to read; times in [s], joint values in the model's convention.
            name: Label of the trajectory; defaults to the file stem.

        Raises:
            InvalidTrajectory: Missing ``t`` column, ragged or non-numeric rows.
        """
        path = Path(path)
        with open(path, newline="") as stream:
            rows = [row for row in csv.reader(stream) if row and not row[0].startswith("#")]
        if not rows or rows[0][0].strip() != "t":
            raise InvalidTrajectory(
                f"{path.name}: the first row must be a header 't, <joint names...>'"
            )
        header = [h.strip() for h in rows[0]]
        try:
            data = np.array([[float(v) for v in row] for row in rows[1:]], dtype=float)
        except ValueError as err:
            raise InvalidTrajectory(f"{path.name}: non-numeric entry ({err})") from err
        if data.ndim != 2 or data.shape[0] == 0 or data.shape[1] != len(header):
            raise InvalidTrajectory(
                f"{path.name}: every row must have {len(header)} values (t and "
                f"{len(header) - 1} joints)"
            )
        return cls(data[:, 0], data[:, 1:], tuple(header[1:]), name or path.stem)


def _bad_rows(mask: np.ndarray, limit: int = 10) -> str:
    rows = np.flatnonzero(mask)
    text = ", ".join(str(r) for r in rows[:limit])
    return text + (f", ... ({rows.size} in all)" if rows.size > limit else "")


# --------------------------------------------------------------------------- workspace paths


@dataclass(frozen=True)
class WorkspacePath:
    """A planar end-effector path sampled at constant time intervals.

    Attributes:
        times_s: Sample times ``k T / (ns - 1)``, shape (ns,) [s].
        points: End-effector positions in the world x–y plane, shape (ns, 2) [m].
        arc_length_m: Arc length from the start at each sample, shape (ns,) [m].
        segment: Index of the segment each sample lies on, shape (ns,).
        length_m: Total length of the path [m].
        profile: Timing law, ``"minimum_jerk"`` or ``"uniform"``.
    """

    times_s: np.ndarray
    points: np.ndarray
    arc_length_m: np.ndarray
    segment: np.ndarray
    length_m: float
    profile: str

    def points_3d(self, z_m: float = 0.0) -> np.ndarray:
        """Positions padded with a constant ``z`` [m], shape (ns, 3)."""
        return np.column_stack([self.points, np.full(len(self.points), z_m)])


@dataclass(frozen=True)
class _Piece:
    start: np.ndarray
    end: np.ndarray
    center: np.ndarray | None  # None for a line
    radius: float
    angle0: float
    sweep: float  # signed [rad]: > 0 counter-clockwise

    @property
    def length(self) -> float:
        if self.center is None:
            return float(np.linalg.norm(self.end - self.start))
        return self.radius * abs(self.sweep)

    def at(self, s: np.ndarray) -> np.ndarray:
        frac = s / self.length
        if self.center is None:
            return self.start + frac[:, None] * (self.end - self.start)
        angle = self.angle0 + frac * self.sweep
        return self.center + self.radius * np.column_stack([np.cos(angle), np.sin(angle)])


def _parse_pieces(start: Sequence[float], segments: Sequence[tuple]) -> list[_Piece]:
    """Turn the segment spec of :func:`workspace_path` into geometric pieces."""
    current = np.asarray(start, dtype=float)
    if current.shape != (2,):
        raise InvalidPath(f"the start point must be (x, y) [m], got shape {current.shape}")
    pieces = []
    for n, spec in enumerate(segments):
        if not spec or spec[0] not in ("line", "arc"):
            raise InvalidPath(
                f"segment {n}: expected ('line', end) or ('arc', end, ...), got {spec!r}"
            )
        end = np.asarray(spec[1], dtype=float)
        if end.shape != (2,):
            raise InvalidPath(f"segment {n}: the end point must be (x, y) [m], got {spec[1]!r}")
        chord = end - current
        if np.linalg.norm(chord) <= 1e-12:
            raise InvalidPath(f"segment {n} has zero length (ends where it starts, {end})")
        if spec[0] == "line":
            if len(spec) != 2:
                raise InvalidPath(f"segment {n}: a line is ('line', end), got {spec!r}")
            pieces.append(_Piece(current, end, None, 0.0, 0.0, 0.0))
            current = end
            continue
        if len(spec) not in (3, 4):
            raise InvalidPath(
                f"segment {n}: an arc is ('arc', end, center_or_radius[, 'ccw'|'cw']), got {spec!r}"
            )
        direction = spec[3] if len(spec) == 4 else None
        if direction not in (None, "ccw", "cw"):
            raise InvalidPath(
                f"segment {n}: arc direction must be 'ccw' or 'cw', got {direction!r}"
            )
        if np.ndim(spec[2]) == 0:
            radius = float(spec[2])
            half = 0.5 * np.linalg.norm(chord)
            if not radius >= half:
                raise InvalidPath(
                    f"segment {n}: radius {radius:g} m is smaller than half the chord {half:g} m"
                )
            normal = np.array([-chord[1], chord[0]]) / (2.0 * half)  # left of the chord
            offset = np.sqrt(max(radius**2 - half**2, 0.0))
            # minor arc: its center lies left of the chord for ccw, right for cw
            sign = 1.0 if direction in (None, "ccw") else -1.0
            center = current + 0.5 * chord + sign * offset * normal
        else:
            center = np.asarray(spec[2], dtype=float)
            if center.shape != (2,):
                raise InvalidPath(f"segment {n}: the center must be (x, y) [m], got {spec[2]!r}")
            radius = float(np.linalg.norm(current - center))
            r_end = float(np.linalg.norm(end - center))
            if abs(r_end - radius) > 1e-9 * max(1.0, radius):
                raise InvalidPath(
                    f"segment {n}: start and end are at distances {radius:.12g} m and "
                    f"{r_end:.12g} m from the center; an arc needs equal distances"
                )
        a0 = float(np.arctan2(*(current - center)[::-1]))
        a1 = float(np.arctan2(*(end - center)[::-1]))
        sweep = (a1 - a0) % (2.0 * np.pi)  # counter-clockwise sweep in [0, 2π)
        if direction == "cw" or (direction is None and sweep > np.pi):
            sweep -= 2.0 * np.pi
        pieces.append(_Piece(current, end, center, radius, a0, sweep))
        current = end
    if not pieces:
        raise InvalidPath("a workspace path needs at least one segment")
    return pieces


def _timing(tau: np.ndarray, profile: str) -> np.ndarray:
    if profile == "uniform":
        return tau
    if profile == "minimum_jerk":
        return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    raise InvalidPath(f"unknown timing profile {profile!r}; use 'minimum_jerk' or 'uniform'")


def workspace_path(
    start: Sequence[float],
    segments: Sequence[tuple],
    n_samples: int,
    *,
    duration_s: float = 1.0,
    profile: Literal["minimum_jerk", "uniform"] = "minimum_jerk",
) -> WorkspacePath:
    """Sample a planar path of lines and circular arcs at constant time intervals.

    The segment spec is a list of pieces, each starting where the previous one ends:

    * ``("line", (x, y))``: straight line to ``(x, y)`` [m];
    * ``("arc", (x, y), (cx, cy)[, "ccw" | "cw"])``: arc about the center ``(cx, cy)``;
      without a direction, the shorter way round;
    * ``("arc", (x, y), radius[, "ccw" | "cw"])``: the minor arc of that radius [m], turning
      counter-clockwise (default) or clockwise.

    Timing: samples are at ``t_k = k T / (ns - 1)``. With ``profile="uniform"`` the arc length
    grows linearly in time (constant speed, velocity jumps at the ends). With
    ``profile="minimum_jerk"`` (default) the arc length follows the rest-to-rest quintic
    ``s(τ) = S (10τ³ − 15τ⁴ + 6τ⁵)``, ``τ = t/T``: zero speed and acceleration at both ends.

    Args:
        start: Start point (x, y) [m].
        segments: Pieces as described above.
        n_samples: Number of samples ns >= 2.
        duration_s: Duration T [s].
        profile: ``"minimum_jerk"`` or ``"uniform"``.

    Returns:
        The sampled :class:`WorkspacePath`.

    Raises:
        InvalidPath: Malformed pieces, arcs whose ends are not on one circle, zero-length pieces,
            fewer than two samples or a non-positive duration.
    """
    if int(n_samples) < 2:
        raise InvalidPath(f"n_samples must be >= 2, got {n_samples}")
    if not duration_s > 0.0:
        raise InvalidPath(f"duration_s must be positive, got {duration_s!r}")
    pieces = _parse_pieces(start, segments)
    lengths = np.array([p.length for p in pieces])
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    total = float(cumulative[-1])
    times = np.linspace(0.0, duration_s, int(n_samples))
    s = total * _timing(times / duration_s, profile)
    segment = np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(pieces) - 1)
    points = np.empty((s.size, 2))
    for n, piece in enumerate(pieces):
        on = segment == n
        points[on] = piece.at(np.clip(s[on] - cumulative[n], 0.0, piece.length))
    return WorkspacePath(
        _readonly(times), _readonly(points), _readonly(s), segment, total, profile
    )


# --------------------------------------------------------------------------- inverse kinematics


@dataclass(frozen=True)
class IKSolution:
    """Result of :func:`solve_ik` along a sequence of points.

    Attributes:
        q: Configurations, shape (ns, nq) (Pinocchio configuration vectors).
        residual_m: Position error at each sample, shape (ns,) [m].
        iterations: Gauss–Newton iterations spent at each sample, shape (ns,).
    """

    q: np.ndarray
    residual_m: np.ndarray
    iterations: np.ndarray


def solve_ik(
    model,
    data,
    frame_id: int,
    points: np.ndarray,
    q_init: np.ndarray,
    *,
    tol_m: float = 1e-10,
    max_iter: int = 100,
    damping: float = 1e-3,
) -> IKSolution:
    """Position-only inverse kinematics of one frame, warm-started along the points.

    Levenberg–Marquardt (damped Gauss–Newton) on ``e(q) = p* − p(q)``: with ``J`` the linear
    rows of the frame Jacobian in LOCAL_WORLD_ALIGNED axes (only the x–y rows if ``points``
    are 2-D), the step ``Δq = Jᵀ (J Jᵀ + μ I)⁻¹ e`` is applied with ``pin.integrate``. A step
    that reduces ``|e|`` is kept and ``μ`` shrinks by 10 (down to ``1e-14``); otherwise ``μ``
    grows by 10. ``μ`` starts at ``damping · |e|²``. Each sample starts from the previous
    solution (the first from ``q_init``), so the IK follows one branch along a continuous path.

    Args:
        model: Pinocchio model.
        data: Its data.
        frame_id: Frame whose origin follows the points.
        points: Targets in the world frame, shape (ns, 3), or (ns, 2) for an x–y task [m].
        q_init: Configuration to start the first sample from, shape (nq,).
        tol_m: Accept a sample when ``|e| <= tol_m`` [m].
        max_iter: Iteration limit per sample.
        damping: Initial damping factor (relative to ``|e|²``).

    Returns:
        The :class:`IKSolution`.

    Raises:
        IKNotConverged: A point was not reached to ``tol_m`` (out of reach, or the iteration
            stalled); carries the sample index, the target, the residual and the last q.
    """
    import pinocchio as pin

    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise InvalidPath(f"points must have shape (ns, 2) or (ns, 3), got {pts.shape}")
    rows = slice(0, pts.shape[1])
    q = np.array(q_init, dtype=float)
    if q.shape != (model.nq,):
        raise InvalidPath(f"q_init must have shape ({model.nq},), got {q.shape}")

    def error(qv):
        pin.framesForwardKinematics(model, data, qv)
        return pts_k - data.oMf[frame_id].translation[rows]

    out_q = np.empty((pts.shape[0], model.nq))
    residual = np.empty(pts.shape[0])
    iterations = np.zeros(pts.shape[0], dtype=int)
    for k, pts_k in enumerate(pts):
        e = error(q)
        norm = float(np.linalg.norm(e))
        mu = damping * norm**2
        it = 0
        while norm > tol_m and it < max_iter:
            it += 1
            J = pin.computeFrameJacobian(model, data, q, frame_id, pin.LOCAL_WORLD_ALIGNED)[rows]
            while True:
                dq = J.T @ np.linalg.solve(J @ J.T + (mu + 1e-14) * np.eye(J.shape[0]), e)
                q_new = pin.integrate(model, q, dq)
                e_new = error(q_new)
                norm_new = float(np.linalg.norm(e_new))
                if norm_new < norm:
                    q, e, norm = q_new, e_new, norm_new
                    mu = max(mu / 10.0, 1e-14)
                    break
                mu = 10.0 * mu + 1e-12
                if mu > 1e12:
                    break
            if mu > 1e12:
                break
        if norm > tol_m:
            raise IKNotConverged(k, pts_k, norm, q, tol_m)
        out_q[k], residual[k], iterations[k] = q, norm, it
    return IKSolution(_readonly(out_q), _readonly(residual), iterations)


# --------------------------------------------------------------------------- planar 2R arm


def absolute_to_relative(q_abs: np.ndarray) -> np.ndarray:
    """Absolute link angles (paper 000) → relative joint angles (Pinocchio), planar chain.

    ``q_rel[..., 0] = q_abs[..., 0]`` and ``q_rel[..., j] = q_abs[..., j] − q_abs[..., j−1]``
    [rad]; works on a single configuration (n,) or on samples (ns, n).
    """
    q_abs = np.asarray(q_abs, dtype=float)
    return np.concatenate([q_abs[..., :1], np.diff(q_abs, axis=-1)], axis=-1)


def relative_to_absolute(q_rel: np.ndarray) -> np.ndarray:
    """Relative joint angles (Pinocchio) → absolute link angles (paper 000): cumulative sum."""
    return np.cumsum(np.asarray(q_rel, dtype=float), axis=-1)


def planar_2r_fk(q_rel: np.ndarray, l1_m: float, l2_m: float) -> np.ndarray:
    """End-effector position of a planar 2R arm, shape (..., 2) [m].

    Joint 1 turns about z at the origin, joint 2 about z at the tip of link 1 (``l1_m``),
    the end effector is at ``l2_m`` along link 2; ``q_rel`` (..., 2) are relative angles [rad].
    """
    q = np.asarray(q_rel, dtype=float)
    a1, a2 = q[..., 0], q[..., 0] + q[..., 1]
    return np.stack(
        [l1_m * np.cos(a1) + l2_m * np.cos(a2), l1_m * np.sin(a1) + l2_m * np.sin(a2)], axis=-1
    )


def planar_2r_ik(
    points: np.ndarray,
    l1_m: float,
    l2_m: float,
    elbow_sign: int,
    *,
    q_ref: Sequence[float] | None = None,
) -> np.ndarray:
    """Closed-form inverse kinematics of a planar 2R arm (same geometry as :func:`planar_2r_fk`).

    ``cos θ2 = (r² − l1² − l2²) / (2 l1 l2)``, ``θ2 = elbow_sign · arccos(...)``,
    ``θ1 = atan2(y, x) − atan2(l2 sin θ2, l1 + l2 cos θ2)``. The angles are then unwrapped
    along the samples (continuous in time) and, if ``q_ref`` is given, shifted by a multiple
    of 2π per joint so that the first sample is nearest to ``q_ref``.

    Args:
        points: Positions, shape (ns, 2) [m].
        l1_m: Length of link 1 [m].
        l2_m: Length of link 2 [m].
        elbow_sign: +1 for ``sin θ2 >= 0``, −1 for ``sin θ2 <= 0``.
        q_ref: Relative angles selecting the 2π branch, shape (2,) [rad].

    Returns:
        Relative joint angles (θ1, θ2), shape (ns, 2) [rad].

    Raises:
        IKNotConverged: A point lies outside the annulus ``|l1 − l2| <= r <= l1 + l2``.
    """
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    if elbow_sign not in (1, -1):
        raise InvalidPath(f"elbow_sign must be +1 or -1, got {elbow_sign!r}")
    r2 = np.sum(pts**2, axis=1)
    c2 = (r2 - l1_m**2 - l2_m**2) / (2.0 * l1_m * l2_m)
    tol = 1e-12
    outside = np.abs(c2) > 1.0 + tol
    if np.any(outside):
        k = int(np.flatnonzero(outside)[0])
        reach = abs(np.sqrt(r2[k]) - np.clip(np.sqrt(r2[k]), abs(l1_m - l2_m), l1_m + l2_m))
        raise IKNotConverged(k, pts[k], float(reach), None, 0.0)
    th2 = elbow_sign * np.arccos(np.clip(c2, -1.0, 1.0))
    th1 = np.arctan2(pts[:, 1], pts[:, 0]) - np.arctan2(
        l2_m * np.sin(th2), l1_m + l2_m * np.cos(th2)
    )
    q = np.unwrap(np.column_stack([th1, th2]), axis=0)
    if q_ref is not None:
        turns = np.round((np.asarray(q_ref, dtype=float) - q[0]) / (2.0 * np.pi))
        q = q + 2.0 * np.pi * turns
    return q


# --------------------------------------------------------------------------- benchmark A

BENCHMARK_A_L1_M = 0.6
"""Length of link 1 of paper 000's two-link arm [m]."""
BENCHMARK_A_L2_M = 0.45
"""Length of link 2 [m]."""
BENCHMARK_A_Q0_ABS = (1.817, 5.312)
"""Paper 000's expansion point in ABSOLUTE link angles [rad] (relative: (1.817, 3.495))."""
BENCHMARK_A_Q0_SAMPLE = 76
"""Index of the benchmark-A sample that lies exactly at the end-effector point of q0."""

_ELBOW_MIN_RAD = 3.35  # smallest elbow angle q2 − q1 along the path (at the pick point)
_ELBOW_MAX_RAD = 3.77  # largest elbow angle, reached on the rounded far corner
_FILLET_M = 0.01  # radius of the two rounded corners [m]


def _elbow_radius(elbow_rad: float) -> float:
    """Distance from the base to the end effector for a given relative elbow angle [m]."""
    l1, l2 = BENCHMARK_A_L1_M, BENCHMARK_A_L2_M
    return float(np.sqrt(l1**2 + l2**2 + 2.0 * l1 * l2 * np.cos(elbow_rad)))


def _benchmark_a_pieces(x_pick: float) -> tuple[np.ndarray, list[tuple], float]:
    """Start, segment spec and arc-length position of p(q0) for a pick abscissa [m]."""
    p0 = planar_2r_fk(absolute_to_relative(BENCHMARK_A_Q0_ABS), BENCHMARK_A_L1_M, BENCHMARK_A_L2_M)
    y_top = float(p0[1])
    y_station = float(np.sqrt(_elbow_radius(_ELBOW_MIN_RAD) ** 2 - x_pick**2))
    f = _FILLET_M
    # the far corner's fillet (center c, radius f) touches the circle r(3.77): |c| + f = r
    x_place = f + float(np.sqrt((_elbow_radius(_ELBOW_MAX_RAD) - f) ** 2 - (y_top - f) ** 2))
    start = np.array([x_pick, y_station])
    segments = [
        ("line", (x_pick, y_top - f)),
        ("arc", (x_pick + f, y_top), (x_pick + f, y_top - f), "cw"),
        ("line", (x_place - f, y_top)),
        ("arc", (x_place, y_top - f), (x_place - f, y_top - f), "cw"),
        ("line", (x_place, y_station)),
    ]
    s_p0 = (y_top - f - y_station) + 0.5 * np.pi * f + (p0[0] - x_pick - f)
    return start, segments, float(s_p0)


def benchmark_a_path(n_samples: int = 152, duration_s: float = 1.51) -> WorkspacePath:
    """Workspace path of benchmark A (SPEC §5), a pick-and-place through paper 000's q0.

    Paper 000 shows its 152-sample path only as a figure; this one is built to match what the
    paper states: constant time steps, 152 samples, an elbow angle ``q2 − q1`` spanning about
    3.35–3.77 rad, the expansion point ``q0 = [1.817, 5.312]`` rad (absolute) about in the
    middle, and all samples inside the domain ``[3π/8, 7π/8] × [3π/2, 2π]`` of its Fig. 3.

    Construction (world x–y plane, base at the origin; no gravity in the benchmark, +y is
    called "up"): with the elbow angle folded past π, the end effector stays inside the annulus
    ``0.185 m <= r <= 0.354 m`` and the elbow angle is a function of ``r`` only, so the span is
    set by the distances reached:

    1. pick at ``A = (x_A, y_s)`` with ``|A| = r(3.35 rad)``, so the elbow angle starts at its
       minimum 3.35 rad;
    2. rise straight up to the transfer height ``y = y(q0) = 0.2104 m``;
    3. move along the line ``y = y(q0)``, through ``p(q0)``, to ``x_B``; both corners are
       rounded with 10 mm arcs, and ``x_B`` is set so that the far corner's arc touches the
       circle ``r = r(3.77 rad)``: the elbow angle peaks there at 3.77 rad;
    4. descend straight down to the place point ``B = (x_B, y_s)``.

    The timing is minimum-jerk along the whole path (rest to rest). The one free parameter
    ``x_A`` is solved (Brent) so that sample 76 of 152 falls exactly on ``p(q0)``; this gives
    ``x_A ≈ −0.0804 m``, ``y_s ≈ 0.1665 m`` (a 43.9 mm lift), ``x_B ≈ 0.2902 m``, a path
    of 0.450 m. Absolute angles stay in q1 ∈ [1.356, 2.617], q2 ∈ [5.081, 6.067] rad.

    Args:
        n_samples: Number of samples (152 in the paper); ``p(q0)`` is hit exactly only for 152.
        duration_s: Duration [s]; the default gives 10 ms steps.

    Returns:
        The sampled :class:`WorkspacePath`.
    """
    tau = BENCHMARK_A_Q0_SAMPLE / 151.0
    target = float(_timing(np.array(tau), "minimum_jerk"))

    def mismatch(x_pick: float) -> float:
        start, segments, s_p0 = _benchmark_a_pieces(x_pick)
        lengths = [p.length for p in _parse_pieces(start, segments)]
        return s_p0 / sum(lengths) - target

    x_pick = brentq(mismatch, -0.15, 0.05, xtol=1e-16, rtol=1e-15)
    start, segments, _ = _benchmark_a_pieces(x_pick)
    return workspace_path(start, segments, n_samples, duration_s=duration_s)


def benchmark_a_trajectory(n_samples: int = 152, duration_s: float = 1.51) -> Trajectory:
    """Joint trajectory of benchmark A in RELATIVE coordinates (Pinocchio's convention).

    The path of :func:`benchmark_a_path` solved by :func:`planar_2r_ik` on the elbow branch
    ``sin(q2 − q1) < 0`` and shifted so that the elbow angle lies in (π, 2π), as in paper 000.
    Columns, named after the joints of ``urdf/two_link.urdf``: ``q1`` = base angle and
    ``q2`` = Pinocchio's value of joint q2, the relative elbow angle q2 − q1 [rad]; use
    :func:`relative_to_absolute` for the paper's absolute angles. Elbow angle span with the
    defaults: 3.3500 rad (sample 0) to 3.7699 rad (sample 115); sample 76 equals
    ``(1.817, 3.495)`` to round-off.
    """
    path = benchmark_a_path(n_samples, duration_s)
    q_ref = absolute_to_relative(BENCHMARK_A_Q0_ABS)
    q = planar_2r_ik(path.points, BENCHMARK_A_L1_M, BENCHMARK_A_L2_M, -1, q_ref=q_ref)
    return Trajectory(path.times_s, q, ("q1", "q2"), "benchmark A pick-and-place")
