"""PNG charts of assignments and Taylor models (matplotlib, Agg backend, no window)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def assignment_charts(result, times_s: np.ndarray, out_dir: str | Path) -> list[Path]:
    """Write mode 1 before/after with its target, and modes 2–4 before/after (paper Fig. 4–5).

    Args:
        result: An :class:`pinflex.assignment.AssignmentResult`.
        times_s: Trajectory times [s], (ns,).
        out_dir: Folder for the PNG files (created).

    Returns:
        Paths of the files written.
    """
    plt = _plt()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    modes = list(result.modes)
    target_modes = [m for m in modes[: result.targets_hz.shape[0]]]
    design = ", ".join(f"{k} = {v:.4f} kg" for k, v in result.design.items())
    for k, mode in enumerate(target_modes):
        fig, ax = plt.subplots(figsize=(7, 4))
        col = modes.index(mode)
        ax.plot(times_s, result.freq_before_hz[:, col], label="original design", color="0.4")
        ax.plot(times_s, result.freq_after_hz[:, col], label=f"assigned ({design})", color="C0")
        ax.plot(times_s, result.targets_hz[k], "--", label="target", color="C3")
        ax.set_xlabel("time [s]")
        ax.set_ylabel(f"mode {mode} frequency [Hz]")
        ax.set_title(
            f"Mode {mode} along the trajectory: max error {100 * result.max_error_before:.2f} % "
            f"→ {100 * result.max_error_after:.2f} % (exact model)"
        )
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        path = out / f"mode{mode}_assignment.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        written.append(path)
    others = [m for m in modes if m not in target_modes]
    if others:
        fig, axes = plt.subplots(len(others), 1, figsize=(7, 2.4 * len(others)), sharex=True)
        axes = np.atleast_1d(axes)
        for ax, mode in zip(axes, others):
            col = modes.index(mode)
            ax.plot(times_s, result.freq_before_hz[:, col], color="0.4", label="original")
            ax.plot(times_s, result.freq_after_hz[:, col], color="C0", label="assigned")
            ax.set_ylabel(f"mode {mode} [Hz]")
            ax.grid(alpha=0.3)
        axes[0].legend(fontsize=8)
        axes[-1].set_xlabel("time [s]")
        fig.suptitle("Higher modes before and after the assignment (exact model)")
        fig.tight_layout()
        path = out / "higher_modes.png"
        fig.savefig(path, dpi=120)
        plt.close(fig)
        written.append(path)
    return written
