"""Eigenfrequencies along a joint trajectory, modes followed by their shapes.

:func:`modes_along` evaluates the modal model at every sample of a
:class:`~pinflex.Trajectory` and follows each requested mode by its shape
(:func:`pinflex.erls.tracking.track_modes`, mass-weighted MAC), so that "mode 2" is the same
physical mode along the whole motion even where two modes cross. Mode numbers are the sorted
numbers at the first sample. The result carries the tracked and the sorted frequencies, the
sorted number of each tracked mode at each sample, the MAC of each step and the crossing /
veering / ambiguous events, and writes itself as CSV, JSON or a PNG chart.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

import numpy as np

from pinflex.checks import check_q, check_y
from pinflex.exceptions import ConfigurationError, InvalidTrajectory
from pinflex.progress import ProgressBar
from pinflex.trajectory import Trajectory


@dataclass(frozen=True)
class ModesAlong:
    """Frequencies of tracked modes along a trajectory.

    Attributes:
        robot: Robot name.
        times_s: Sample times (ns,) [s].
        q: Joint samples (ns, nv), the arm's coordinates [rad or m].
        joint_names: Names of the columns of ``q``.
        modes: Mode numbers (1 = lowest non-rigid mode at the first sample).
        freq_hz: Tracked frequencies (ns, k) [Hz]; column c follows mode ``modes[c]``.
        sorted_hz: The lowest k frequencies sorted at each sample (ns, k) [Hz].
        order: Sorted number (1-based) of each tracked mode at each sample (ns, k).
        mac_step: MAC of each tracked mode with the previous sample (ns, k).
        events: Crossings, veerings and ambiguous steps, as dictionaries
            (``kind``, ``sample``, ``time_s``, ``modes``, ``freq_hz``, ``mac``).
        design: Design values used ``{name: kg}``.
        validity: The validity indicator of eq. (1) along the motion
            (:class:`pinflex.erls.validity.Validity`, against the lowest tracked modes'
            sorted frequencies), or None.
    """

    robot: str
    times_s: np.ndarray
    q: np.ndarray
    joint_names: tuple[str, ...]
    modes: tuple[int, ...]
    freq_hz: np.ndarray
    sorted_hz: np.ndarray
    order: np.ndarray
    mac_step: np.ndarray
    events: tuple[dict, ...]
    design: dict
    validity: Any = None

    @property
    def n_samples(self) -> int:
        """Number of samples ns."""
        return int(self.times_s.size)

    def columns(self) -> list[str]:
        """CSV header: ``t``, joints, then per mode tracked, sorted, order and MAC columns."""
        cols = ["t", *self.joint_names]
        for m in self.modes:
            cols += [f"mode{m}_hz", f"sorted{m}_hz", f"mode{m}_order", f"mode{m}_mac"]
        if self.validity is not None:
            cols += ["speed_ratio", "accel_ratio"]
        return cols

    def to_csv(self, path: str | Path) -> Path:
        """Write one row per sample (17 significant digits); returns the path."""
        from pinflex.outputs import atomic_path

        path = Path(path)
        with atomic_path(path, "CSV") as tmp, open(tmp, "w", newline="") as stream:
            w = csv.writer(stream)
            w.writerow(self.columns())
            for s in range(self.n_samples):
                row = [repr(float(self.times_s[s])), *(repr(float(v)) for v in self.q[s])]
                for c in range(len(self.modes)):
                    row += [repr(float(self.freq_hz[s, c])), repr(float(self.sorted_hz[s, c])),
                            str(int(self.order[s, c])), repr(float(self.mac_step[s, c]))]
                if self.validity is not None:
                    row += [repr(float(self.validity.speed_ratio[s, 0])),
                            repr(float(self.validity.accel_ratio[s, 0]))]
                w.writerow(row)
        return path

    def to_dict(self) -> dict:
        """JSON-ready dictionary (lists of floats)."""
        return {
            "robot": self.robot,
            "joint_names": list(self.joint_names),
            "design": {k: float(v) for k, v in self.design.items()},
            "modes": list(self.modes),
            "times_s": self.times_s.tolist(),
            "q": self.q.tolist(),
            "frequencies_hz": self.freq_hz.tolist(),
            "sorted_frequencies_hz": self.sorted_hz.tolist(),
            "sorted_order": self.order.astype(int).tolist(),
            "mac_step": self.mac_step.tolist(),
            "events": [dict(e) for e in self.events],
            "summary": self.summary(),
            "validity": None if self.validity is None else self.validity.to_dict(),
        }

    def to_json(self) -> str:
        """:meth:`to_dict` as one JSON text."""
        from pinflex.outputs import json_text

        return json_text(self.to_dict())

    def summary(self) -> list[dict]:
        """Per mode: minimum, maximum, start and end frequency [Hz]."""
        return [
            {
                "mode": m,
                "min_hz": float(self.freq_hz[:, c].min()),
                "max_hz": float(self.freq_hz[:, c].max()),
                "start_hz": float(self.freq_hz[0, c]),
                "end_hz": float(self.freq_hz[-1, c]),
            }
            for c, m in enumerate(self.modes)
        ]

    def table(self) -> str:
        """A readable terminal table: one line per mode, then the events."""
        lines = [
            f"{self.robot}: {self.n_samples} samples over {self.times_s[-1] - self.times_s[0]:.4g}"
            " s, modes followed by shape (MAC)",
            f"{'mode':>4}  {'min [Hz]':>12}  {'max [Hz]':>12}  {'start [Hz]':>12}  "
            f"{'end [Hz]':>12}",
        ]
        for row in self.summary():
            lines.append(
                f"{row['mode']:>4}  {row['min_hz']:>12.6g}  {row['max_hz']:>12.6g}  "
                f"{row['start_hz']:>12.6g}  {row['end_hz']:>12.6g}"
            )
        if self.events:
            lines.append("events:")
            for e in self.events:
                lines.append(
                    f"  {e['kind']:<9} t = {e['time_s']:.4g} s (sample {e['sample']}), modes "
                    f"{', '.join(str(m) for m in e['modes'])}"
                )
        else:
            lines.append("no crossings or veerings among the tracked modes")
        v = self.validity
        if v is not None:
            lines.append(
                f"validity of eq. (1): |omega|^2/omega_1^2 = {v.max_speed_ratio:.3g}, "
                f"|alpha|/omega_1^2 = {v.max_accel_ratio:.3g} (threshold {v.threshold:g}"
                f"{'; EXCEEDED: the modes of the moving arm differ' if v.exceeded else ''})")
        return "\n".join(lines)

    def __repr__(self) -> str:
        return self.table()

    def figure(self):
        """The chart as a matplotlib Figure (what :meth:`plot` writes).

        Top: tracked frequencies (lines), sorted ones (dots), events (vertical lines). Below,
        when the validity indicator is set: ``|ω_L|²/ω₁²`` and ``|α_L|/ω₁²`` per sample (the
        CSV's ``speed_ratio`` and ``accel_ratio``) with the threshold
        (:func:`pinflex.erls.validity.draw_validity`).
        """
        from pinflex.erls.validity import figure_with_validity

        fig, (ax,), _ = figure_with_validity(self.validity, 7.5, 4.2)
        t = self.times_s
        for c, m in enumerate(self.modes):
            line, = ax.plot(t, self.freq_hz[:, c], lw=1.8, label=f"mode {m} (tracked)")
            ax.plot(t, self.sorted_hz[:, c], ".", ms=3, color=line.get_color(), alpha=0.5)
        for e in self.events:
            style = {"crossing": "--", "veering": ":", "ambiguous": "-."}.get(e["kind"], ":")
            ax.axvline(e["time_s"], color="0.4", ls=style, lw=0.9)
        ax.set_ylabel("frequency [Hz]")
        ax.set_title(f"{self.robot}: eigenfrequencies along the trajectory "
                     "(dots: sorted, lines: tracked)", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
        fig.tight_layout()
        return fig

    def plot(self, path: str | Path) -> Path:
        """Write :meth:`figure` as a PNG; returns the path."""
        from pinflex.outputs import save_figure

        return save_figure(self.figure(), path)


def trajectory_for(arm, traj: Trajectory) -> np.ndarray:
    """Joint samples (ns, nv) of a trajectory in the arm's joint order.

    Columns are matched by joint name (:meth:`Trajectory.in_order`); a trajectory built
    without names with exactly ``nv`` (or ``nq``) columns is taken in the arm's order (or as
    Pinocchio configurations).

    Raises:
        InvalidTrajectory: Columns naming no joint, joints without a column, duplicates.
    """
    if not traj.named and traj.q.shape[1] == arm.model.nq != arm.nv:
        return check_q(arm, traj.q)
    return check_q(arm, traj.in_order(arm.joint_names))


def modes_along(
    arm,
    trajectory: Trajectory,
    y=None,
    *,
    modes=3,
    extra: int = 3,
    check_limits: Literal["warn", "raise"] | None = "warn",
    strict: bool = False,
    validity_threshold: float | None = None,
    progress: ProgressBar | None = None,
) -> ModesAlong:
    """Tracked eigenfrequencies of ``arm`` along ``trajectory``.

    Args:
        arm: A :class:`~pinflex.FlexibleModel`.
        trajectory: Joint samples; columns named after the arm's joints (any order).
        y: Design values [kg] (default nominal), one or one per sample.
        modes: Number of lowest modes (int) or mode numbers (sequence), numbered at sample 0.
        extra: Modes tracked above the highest requested one, so a requested mode can cross
            a higher one and still be followed.
        check_limits: ``"warn"``, ``"raise"`` or ``None``: what to do with samples outside
            the URDF joint limits.
        strict: Refuse (:class:`~pinflex.exceptions.ModelValidityError`) a motion whose
            validity indicator (:mod:`pinflex.erls.validity`; rates from the samples by
            finite differences) is above ``validity_threshold``; otherwise warn
            (:class:`~pinflex.exceptions.ModelValidityWarning`): the frozen-pose modes are
            not those of the moving arm there (:func:`pinflex.dynamics.modes_at_speed`).
        validity_threshold: Default :data:`pinflex.erls.validity.VALIDITY_THRESHOLD`.
        progress: A progress bar advanced by one per sample solved (optional; see
            :func:`~pinflex.erls.tracking.track_modes`).

    Returns:
        :class:`ModesAlong` (``validity`` set for two samples or more).
    """
    from pinflex.erls.tracking import track_modes
    from pinflex.trajectory.cartesian import check_joint_limits

    Q = trajectory_for(arm, trajectory)
    from pinflex.resources import check_poses

    check_poses(Q.shape[0], arm.ndof, "the frequencies along the trajectory",
                "resample the trajectory more coarsely")
    if check_limits is not None:
        check_joint_limits(
            arm, Trajectory(trajectory.times_s, Q, arm.joint_names), on_violation=check_limits
        )
    mode_list = tuple(range(1, int(modes) + 1)) if np.ndim(modes) == 0 else tuple(
        int(m) for m in modes
    )
    if not mode_list or min(mode_list) < 1 or max(mode_list) > arm.n_elastic:
        raise ConfigurationError(f"modes {mode_list} must lie in 1..{arm.n_elastic}")
    tr = track_modes(arm, Q, y, modes=mode_list, extra=extra, progress=progress)
    sorted_all = np.sqrt(np.asarray(tr.sorted_eigvals)) / (2.0 * np.pi)
    k = len(mode_list)
    times = np.asarray(trajectory.times_s, dtype=float)
    events = tuple(
        {
            "kind": e.kind,
            "sample": int(e.sample),
            "time_s": float(times[e.sample]),
            "modes": [int(m) for m in np.atleast_1d(e.modes)],
            "freq_hz": [float(f) for f in np.atleast_1d(e.freq_hz)],
            "mac": float(e.mac),
        }
        for e in tr.events
    )
    yv = check_y(arm, y)
    design = {d.name: float(v) for d, v in zip(arm.design, np.atleast_2d(yv)[0])}
    indicator = None
    if times.size >= 2:
        from pinflex.erls.validity import VALIDITY_THRESHOLD, sample_rates, validity

        qd, qdd = sample_rates(times, Q)
        omega = 2.0 * np.pi * sorted_all[:, :3]
        indicator = validity(
            arm, times, Q, qd, qdd, omega, strict=strict, what="the trajectory",
            threshold=VALIDITY_THRESHOLD if validity_threshold is None else validity_threshold,
            basis="model")
    return ModesAlong(
        robot=arm.description.name,
        times_s=times,
        q=np.asarray(Q),
        joint_names=tuple(arm.joint_names),
        modes=mode_list,
        freq_hz=np.asarray(tr.freq_hz),
        sorted_hz=sorted_all[:, [m - 1 for m in mode_list]] if sorted_all.shape[1] >= max(
            mode_list) else sorted_all[:, :k],
        order=np.asarray(tr.order),
        mac_step=np.asarray(tr.mac_step),
        events=events,
        design=design,
        validity=indicator,
    )
