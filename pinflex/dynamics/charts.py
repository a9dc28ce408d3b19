"""Charts of simulated vibration (matplotlib object API, no global state)."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _figure(width: float, height: float):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def deflection_chart(reports, path) -> Path:
    """Side-by-side charts of the frame deflection ``|δ|`` and its components per design."""
    fig = _figure(5.0 * len(reports), 3.8)
    axes = fig.subplots(1, len(reports), sharey=True, squeeze=False)[0]
    for ax, rep in zip(axes, reports):
        t = rep.times_s
        d = 1e3 * rep.deflection_m
        for k, c in enumerate("xyz"):
            if np.any(d[:, k]):
                ax.plot(t, d[:, k], lw=0.8, label=f"δ{c}")
        ax.plot(t, np.linalg.norm(d, axis=1), color="k", lw=1.0, label="|δ|")
        ax.axvline(rep.stop_s, color="grey", ls="--", lw=0.8)
        f = rep.dominant_frequency_hz
        ax.set_title(f"{rep.name}: peak {1e3 * rep.tip_peak_m:.3f} mm, residual "
                     f"{1e3 * rep.residual_amplitude_m:.3f} mm"
                     + (f" at {f:.1f} Hz" if np.isfinite(f) else ""), fontsize=9)
        ax.set_xlabel("time [s] (dashed: stop)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel(f"deflection of '{reports[0].frame}' [mm]")
    axes[0].legend(fontsize=8)
    from pinflex.outputs import save_figure

    return save_figure(fig, Path(path), dpi=120)


def bode_chart(freqs_hz, H, labels, path, *, title: str = "") -> Path:
    """Bode chart (magnitude in dB and phase in degrees against frequency in Hz)."""
    fig = _figure(6.5, 5.0)
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    H = np.atleast_2d(np.asarray(H))
    if H.shape[0] != len(labels):
        H = H.T
    for h, lab in zip(H, labels):
        ax1.semilogx(freqs_hz, 20 * np.log10(np.maximum(np.abs(h), 1e-300)), lw=1.0, label=lab)
        ax2.semilogx(freqs_hz, np.degrees(np.unwrap(np.angle(h))), lw=1.0)
    ax1.set_ylabel("magnitude [dB]")
    ax2.set_ylabel("phase [deg]")
    ax2.set_xlabel("frequency [Hz]")
    for a in (ax1, ax2):
        a.grid(alpha=0.3, which="both")
    ax1.legend(fontsize=8)
    if title:
        ax1.set_title(title, fontsize=9)
    from pinflex.outputs import save_figure

    return save_figure(fig, Path(path), dpi=120)


def validity_chart(named, path) -> Path:
    """The validity indicator of eq. (1) along each run: both ratios of mode 1 against time.

    Args:
        named: ``[(name, Validity), ...]`` (:class:`pinflex.erls.validity.Validity`).
        path: PNG file.
    """
    from pinflex.erls.validity import draw_validity

    fig = _figure(6.0, 3.6)
    ax = fig.subplots()
    for k, (name, v) in enumerate(named):
        draw_validity(ax, v, label=name, threshold=k == 0)
    if named:
        top = max([named[0][1].threshold] + [v.indicator for _, v in named])
        ax.set_ylim(bottom=1e-5 * top, top=3.0 * top)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("relative size of the terms eq. (1) leaves out")
    ax.set_title("validity of eq. (1) along the motion (pinflex.erls.validity)", fontsize=9)
    ax.legend(fontsize=7)
    from pinflex.outputs import save_figure

    return save_figure(fig, path)
