"""Joint trajectories: time grid, joint samples, trapezoidal weights, CSV, limits."""

from __future__ import annotations

import csv
import warnings
from collections.abc import Sequence
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
from pinflex.validation import float_array, parse_number


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
    #: Whether the columns were named (False: default names ``q1..qn``, taken by position).
    named: bool = field(default=False, init=False, repr=False, compare=False)

    def __post_init__(self):
        t = _samples(self.times_s, "times_s")
        q = _samples(self.q, "q")
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
                f"times_s must increase strictly; t[{k}] = {float(t[k])!r} >= "
                f"t[{k + 1}] = {float(t[k + 1])!r}"
            )
        big_t, big_q = np.abs(t) > MAX_TIME_S, np.any(np.abs(q) > MAX_JOINT_VALUE, axis=1)
        if np.any(big_t):
            raise InvalidTrajectory(f"times_s beyond {MAX_TIME_S:g} s at samples "
                                    f"{_bad_rows(big_t)}: times are in seconds")
        if np.any(big_q):
            raise InvalidTrajectory(f"q beyond {MAX_JOINT_VALUE:g} (rad or m) at samples "
                                    f"{_bad_rows(big_q)}: joint values are in radians or metres")
        given = self.joint_names
        if self.name is not None and not isinstance(self.name, str):
            raise InvalidTrajectory(f"name must be a string or None, got {self.name!r}")
        if isinstance(given, str) or not isinstance(given, Sequence | np.ndarray) or \
                not all(isinstance(n, str) for n in given):
            raise InvalidTrajectory(f"joint_names must be a sequence of names, got {given!r}")
        names = tuple(given) or tuple(f"q{j + 1}" for j in range(q.shape[1]))
        if len(names) != q.shape[1]:
            raise InvalidTrajectory(
                f"{len(names)} joint names given for {q.shape[1]} columns of q: {names}"
            )
        if len(set(names)) != len(names):
            check_columns(names, tuple(dict.fromkeys(names)), "joint_names")
        object.__setattr__(self, "named", bool(given))
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
        if not isinstance(on_violation, str) or on_violation not in ("warn", "raise"):
            raise InvalidTrajectory(f"on_violation = {on_violation!r}: expected 'warn' or "
                                    "'raise'")
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

    def in_order(self, joint_names) -> np.ndarray:
        """Joint samples (ns, len(joint_names)) with the columns matched by name.

        Columns are taken by joint name in any order; a trajectory built without names
        (``Trajectory(t, q)``, default names ``q1..qn``) with exactly one column per joint is
        taken in the given order.

        Raises:
            InvalidTrajectory: Columns naming no joint (with the closest name), joints
                without a column, or a column count that does not match.
        """
        want = tuple(joint_names)
        names = self.joint_names
        if names == want:
            return self.q
        if not self.named and self.q.shape[1] == len(want):
            return self.q
        check_columns(names, want, "the trajectory")
        return self.q[:, [names.index(n) for n in want]]

    @classmethod
    def from_csv(cls, path: str | Path, *, joint_names=None, name: str | None = None,
                 max_samples: int | None = None) -> Trajectory:
        """Read a CSV file whose header is ``t`` followed by joint names.

        This is pinflex's one reader of trajectory files (``pinflex modes/export/view
        --trajectory``, ``csv = "..."`` in studies, batch sweeps, simulations). Columns are
        matched by name: with ``joint_names`` the header must name exactly those joints, in
        any order, and the result has its columns in that order. Every cell is read by
        pinflex's number grammar (:func:`pinflex.validation.parse_number`).

        Args:
            path: File to read; times in [s], joint values in the model's convention.
            joint_names: The robot's moving joints (e.g. ``model.joint_names``); None keeps
                the file's columns and order.
            name: Label of the trajectory; defaults to the file stem.
            max_samples: Most data rows accepted (default :data:`MAX_SAMPLES`), checked by
                counting the rows before any is parsed.

        Raises:
            InvalidTrajectory: No ``t`` header; unknown, missing, duplicate or extra columns
                (named, with the closest joint name); ragged, empty or non-numeric rows
                (row and column named); too many rows; non-increasing times.
        """
        import io

        from pinflex.description.source import read_text

        text = read_text(path, "trajectory CSV", InvalidTrajectory)
        label = Path(path).name
        from pinflex.validation import require_count

        limit = MAX_SAMPLES if max_samples is None else require_count(
            max_samples, "max_samples", error=InvalidTrajectory)
        lines = text.count("\n") + 1
        if lines - 1 > limit:
            rows_est = sum(1 for line in text.splitlines()[1:] if line.strip()
                           and not line.lstrip().startswith("#"))
            if rows_est > limit:
                raise InvalidTrajectory(
                    f"{label}: {rows_est} samples, more than the {limit} a trajectory file may "
                    "have (each sample is a full modal analysis); resample the motion"
                )
        try:
            rows = [row for row in csv.reader(io.StringIO(text, newline=""))
                    if row and any(c.strip() for c in row) and not row[0].lstrip().startswith("#")]
        except csv.Error as err:
            raise InvalidTrajectory(f"{label}: not a CSV file ({err})") from err
        if not rows or rows[0][0].strip(" \t") != "t":
            raise InvalidTrajectory(
                f"{label}: the first row must be a header 't, <joint names...>'"
                + (f" (t, {', '.join(joint_names)})" if joint_names is not None else "")
            )
        header = [h.strip(" \t") for h in rows[0]]
        columns = tuple(header[1:])
        if joint_names is not None:
            check_columns(columns, tuple(joint_names), f"{label}: the header")
        elif len(set(columns)) != len(columns) or "t" in columns:
            check_columns(columns, columns, f"{label}: the header")
        if len(rows) < 2:
            raise InvalidTrajectory(f"{label}: the file has a header but no samples")
        data = np.empty((len(rows) - 1, len(header)))
        for i, row in enumerate(rows[1:]):
            if len(row) != len(header):
                raise InvalidTrajectory(
                    f"{label}: sample {i + 1} has {len(row)} values; every row needs "
                    f"{len(header)} (t and {len(header) - 1} joints)"
                )
            for j, cell in enumerate(row):
                try:
                    data[i, j] = parse_number(cell)
                except ValueError as err:
                    raise InvalidTrajectory(
                        f"{label}: sample {i + 1}, column '{header[j]}': {err}"
                    ) from None
        q = data[:, 1:]
        if joint_names is not None:
            q = q[:, [columns.index(n) for n in joint_names]]
            columns = tuple(joint_names)
        return cls(data[:, 0], q, columns, name or Path(path).stem)


def in_model_order(model, trajectory: Trajectory) -> Trajectory:
    """The trajectory with its columns in ``model.joint_names`` order (matched by name).

    Raises:
        InvalidTrajectory: Not a :class:`Trajectory`, or its columns do not name the
            model's joints (see :meth:`Trajectory.in_order`).
    """
    if not isinstance(trajectory, Trajectory):
        raise InvalidTrajectory(f"expected a Trajectory, got {type(trajectory).__name__}")
    names = tuple(model.joint_names)
    if trajectory.joint_names == names:
        return trajectory
    return Trajectory(trajectory.times_s, trajectory.in_order(names), names, trajectory.name)


#: Most samples of a trajectory file (each sample costs a modal analysis of the arm).
MAX_SAMPLES = 100_000

#: Largest joint value of a trajectory [rad or m] (the bound of a study's ``q0`` too).
MAX_JOINT_VALUE = 1e6

#: Largest sample time [s] (about 30 years).
MAX_TIME_S = 1e9


def check_columns(names, joints, what: str) -> None:
    """Refuse columns that do not name exactly ``joints``: unknown, missing, duplicates.

    Raises:
        InvalidTrajectory: Naming every bad column, with the closest joint name.
    """
    from pinflex.validation import closest

    names, joints = tuple(names), tuple(joints)
    problems = []
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        problems.append("duplicate column" + ("s " if len(dup) > 1 else " ")
                        + ", ".join(f"'{n}'" for n in dup))
    if "t" in names:
        problems.append("'t' is the time column and comes first only")
    unknown = [n for n in dict.fromkeys(names) if n not in joints and n != "t"]
    for n in unknown:
        hit = closest(n, [j for j in joints if j not in names])
        problems.append(f"column '{n}' names no joint of the robot"
                        + (f" (did you mean '{hit}'?)" if hit else ""))
    missing = [j for j in joints if j not in names]
    if missing:
        problems.append("no column for joint" + ("s " if len(missing) > 1 else " ")
                        + ", ".join(f"'{j}'" for j in missing))
    if problems:
        raise InvalidTrajectory(
            f"{what} does not name the robot's joints: " + "; ".join(problems)
            + f" (expected the columns t, {', '.join(joints)} in any order)"
        )


def _samples(value, name: str) -> np.ndarray:
    """Float samples; strings, booleans, complex and masked values refused by name."""
    if type(value) is np.ndarray and value.dtype == np.float64:
        return value
    return float_array(value, name, InvalidTrajectory)


def _bad_rows(mask: np.ndarray, limit: int = 10) -> str:
    rows = np.flatnonzero(mask)
    text = ", ".join(str(r) for r in rows[:limit])
    return text + (f", ... ({rows.size} in all)" if rows.size > limit else "")
