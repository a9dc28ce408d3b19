"""Benchmark A's vibration: the baseline against the assigned (190 Hz) design, for the demo."""

from __future__ import annotations

from pathlib import Path


def vibration_demo(model, trajectory, result, out_dir, say, *, after_s: float = 0.5) -> dict:
    """Simulate the baseline and the assigned design along the trajectory (prescribed motion).

    Prints a side-by-side table with ``say`` and writes ``tip_vibration.png`` in ``out_dir``.

    Returns:
        ``{design name: metrics}`` (see :meth:`VibrationReport.summary`) and the chart path.
    """
    from pinflex.dynamics.charts import deflection_chart
    from pinflex.dynamics.study import SimulationSettings, simulate_design

    settings = SimulationSettings(after_s=after_s)
    reports = [simulate_design(model, trajectory, y, settings, name)[0]
               for name, y in (("baseline", result.y_before), ("assigned", result.y))]
    say(f"\n  Tip vibration along the motion and {after_s:g} s after the stop (prescribed "
        "joint motion, no damping; the held joints make the residual vibration locked-joint)")
    say(f"  {'':28s} {'baseline':>12s} {'assigned':>12s}")
    rows = (("tip peak [mm]", "tip_peak_m", 1e3), ("tip RMS along motion [mm]", "tip_rms_m", 1e3),
            ("residual amplitude [mm]", "residual_amplitude_m", 1e3),
            ("residual frequency [Hz]", "dominant_frequency_hz", 1.0),
            ("locked-joint mode 1 [Hz]", None, 1.0))
    for label, key, scale in rows:
        vals = [r.reference_hz[0] if key is None else getattr(r, key) for r in reports]
        say(f"  {label:28s} " + " ".join(f"{scale * v:12.4f}" for v in vals))
    say(f"  steps {reports[0].steps} / {reports[1].steps}; compute {reports[0].time_s:.2f} s / "
        f"{reports[1].time_s:.2f} s")
    chart = deflection_chart(reports, Path(out_dir) / "tip_vibration.png")
    say(f"  wrote {chart}")
    return {"designs": {r.name: r.summary() for r in reports}, "chart": str(chart)}
