"""Joint trajectories: time grid, joint samples, trapezoidal weights, CSV, limits."""

from __future__ import annotations

import csv
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from pinflex.exceptions import (
    InvalidTrajectory,
    JointLimitsExceeded,
    TrajectoryWarning,
)
from pinflex.linalg import readonly as _readonly


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
        lower: ArrayLike,
        upper: ArrayLike,
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
        """Write ``t, <joint names...>`` with 17 significant digits (exact round trip).

        The file is written atomically (:func:`pinflex.outputs.atomic_path`).

        Args:
            path: File to write; times in [s], joint values in the trajectory's convention
                [rad or m].

        Raises:
            OutputError: ``path`` is a folder or cannot be written.
        """
        from pinflex.outputs import atomic_path

        with atomic_path(path, "trajectory CSV") as tmp, open(tmp, "w", newline="") as stream:
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
        import io

        from pinflex.description.source import read_text

        path = Path(path)
        text = read_text(path, "trajectory CSV", InvalidTrajectory)
        try:
            rows = [row for row in csv.reader(io.StringIO(text, newline=""))
                    if row and not row[0].startswith("#")]
        except csv.Error as err:
            raise InvalidTrajectory(f"{path.name}: not a CSV file ({err})") from err
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
