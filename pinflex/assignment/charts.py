"""PNG charts of assignments (matplotlib's object API, no pyplot state, no window).

Each target mode gets a chart of its frequency before, predicted and exact after, with the
target; the other reported modes (floors, bands, reported modes) share one chart with a panel
per mode, each drawing its floor (a line and a shaded region below it) and its forbidden band
(a shaded band). Below the frequencies every chart draws the validity indicator of eq. (1)
along the trajectory (:mod:`pinflex.erls.validity`) when the result carries it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pinflex.erls.validity import figure_with_validity
from pinflex.outputs import output_dir, save_figure


def _constraints_of(result, mode: int, ax) -> None:
    settings = result.settings or {}
    for m, f in settings.get("floors", []):
        if m == mode:
            ax.axhline(f, color="C3", lw=1.2, ls="-", label=f"floor {f:g} Hz")
            ax.axhspan(ax.get_ylim()[0] if ax.get_ylim()[0] < f else f - 1.0, f,
                       color="C3", alpha=0.08)
    for m, a, b in settings.get("bands", []):
        if m == mode:
            ax.axhspan(a, b, color="C1", alpha=0.18, label=f"forbidden band {a:g}–{b:g} Hz")


def assignment_figures(result, times_s: np.ndarray, data=None) -> dict:
    """The charts of :func:`assignment_charts` as matplotlib Figures, by file name.

    Each chart has, below its frequency panels, the validity indicator of eq. (1) along the
    trajectory at the design after (``|ω_L|²/ω₁²`` and ``|α_L|/ω₁²`` per sample, the
    ``speed_ratio`` and ``accel_ratio`` of the assignment CSV, with the threshold) when the
    result carries it (:func:`pinflex.erls.validity.draw_validity`).

    Args:
        result: An :class:`pinflex.assignment.AssignmentResult`.
        times_s: Trajectory times [s], (ns,).
        data: Its :class:`pinflex.assignment.report.AssignmentData` (optional).

    Returns:
        ``{"mode<m>_assignment.png": Figure, ..., "other_modes.png": Figure}``.
    """
    figures = {}
    validity = getattr(result, "validity", None)
    n_targets = result.targets_hz.shape[0]
    target_modes = list(result.modes[:n_targets])
    if data is not None:
        modes = list(data.modes)
        before, after, predicted = data.before_hz, data.after_hz, data.predicted_hz
    else:
        modes = list(result.modes)
        before, after = result.freq_before_hz, result.freq_after_hz
        predicted = np.full_like(after, np.nan)
    design = ", ".join(f"{k} = {v:.4f} kg" for k, v in result.design.items())
    for k, mode in enumerate(target_modes):
        fig, (ax,), _ = figure_with_validity(validity, 7.0, 4.0, dpi=120)
        col = modes.index(mode)
        ax.plot(times_s, before[:, col], label="before (exact)", color="0.4")
        if np.all(np.isfinite(predicted[:, col])):
            ax.plot(times_s, predicted[:, col], ":", label="after, predicted (Taylor)",
                    color="C2")
        ax.plot(times_s, after[:, col], label=f"after, exact ({design})", color="C0")
        ax.plot(times_s, result.targets_hz[k], "--", label="target", color="C3")
        _constraints_of(result, mode, ax)
        ax.set_ylabel(f"mode {mode} frequency [Hz]")
        ax.set_title(
            f"Mode {mode}: max target error {100 * result.max_error_before:.2f} % → "
            f"{100 * result.max_error_after:.2f} % (exact model)", fontsize=10,
        )
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
        fig.tight_layout()
        figures[f"mode{mode}_assignment.png"] = fig
    others = sorted(m for m in modes if m not in target_modes)
    if others:
        fig, axes, _ = figure_with_validity(validity, 7.0, 2.4 * len(others) + 0.6,
                                            len(others), dpi=120)
        for ax, mode in zip(axes, others):
            col = modes.index(mode)
            ax.plot(times_s, before[:, col], color="0.4", label="before (exact)")
            if np.all(np.isfinite(predicted[:, col])):
                ax.plot(times_s, predicted[:, col], ":", color="C2", label="after, predicted")
            ax.plot(times_s, after[:, col], color="C0", label="after (exact)")
            _constraints_of(result, mode, ax)
            ax.set_ylabel(f"mode {mode} [Hz]")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=7, loc="best")
        fig.suptitle(f"Modes {', '.join(map(str, others))} before and after the assignment",
                     fontsize=10)
        fig.tight_layout()
        figures["other_modes.png"] = fig
    return figures


def assignment_charts(result, times_s: np.ndarray, out_dir: str | Path, data=None) -> list[Path]:
    """Write the target modes' charts and one chart of the other modes (paper Fig. 4–5).

    Args:
        result: An :class:`pinflex.assignment.AssignmentResult`.
        times_s: Trajectory times [s], (ns,).
        out_dir: Folder for the PNG files (created).
        data: Its :class:`pinflex.assignment.report.AssignmentData` (adds the Taylor
            prediction after and the floor/band modes); optional.

    Returns:
        Paths of the files written: ``mode<m>_assignment.png`` per target mode, and
        ``other_modes.png`` when modes other than the targets are reported; each with the
        validity indicator's panel when the result carries it (:func:`assignment_figures`).
    """
    out = output_dir(Path(out_dir), "chart folder")
    return [save_figure(fig, out / name)
            for name, fig in assignment_figures(result, times_s, data).items()]
