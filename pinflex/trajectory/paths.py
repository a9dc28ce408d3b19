"""Planar workspace paths of lines and circular arcs, sampled at constant time steps."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal, Sequence

import numpy as np
from numpy.typing import ArrayLike

from pinflex.exceptions import (
    InvalidPath,
)
from pinflex.linalg import readonly as _readonly


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


def parse_pieces(start: ArrayLike, segments: Sequence[tuple]) -> list[_Piece]:
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
            offset = float(np.sqrt(max(float(radius**2 - half**2), 0.0)))
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


def path_timing(tau: np.ndarray, profile: str) -> np.ndarray:
    """Arc-length fraction at normalised times ``tau`` in [0, 1] for a timing ``profile``."""
    if profile == "uniform":
        return tau
    if profile == "minimum_jerk":
        return tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    raise InvalidPath(f"unknown timing profile {profile!r}; use 'minimum_jerk' or 'uniform'")


def workspace_path(
    start: ArrayLike,
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
    pieces = parse_pieces(start, segments)
    lengths = np.array([p.length for p in pieces])
    cumulative = np.concatenate([[0.0], np.cumsum(lengths)])
    total = float(cumulative[-1])
    times = np.linspace(0.0, duration_s, int(n_samples))
    s = total * path_timing(times / duration_s, profile)
    segment = np.clip(np.searchsorted(cumulative, s, side="right") - 1, 0, len(pieces) - 1)
    points = np.empty((s.size, 2))
    for n, piece in enumerate(pieces):
        on = segment == n
        points[on] = piece.at(np.clip(s[on] - cumulative[n], 0.0, piece.length))
    return WorkspacePath(
        _readonly(times), _readonly(points), _readonly(s), segment, total, profile
    )
