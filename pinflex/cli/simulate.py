"""``pinflex simulate``: time simulation of the baseline and the assigned design of a study."""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

from pinflex.cli.common import add_model_arguments, parse_values


def add_parser(sub) -> None:
    """Register the ``simulate`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "simulate", help="simulate the baseline and the assigned design of a study (eq. 1)")
    p.add_argument("config", help="study TOML of 'pinflex assign' with a [simulation] table "
                   "(see pinflex.dynamics.study)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for the charts and the time series (JSON)")
    p.add_argument("--exaggeration", type=float, default=200.0,
                   help="with --out: factor on the elastic motion in the meshcat playback pages "
                   "(0: no playback; default 200)")
    p.add_argument("--tol", type=float, default=None, metavar="TOL",
                   help="prescribed drive: halve the time step until the Richardson estimate of "
                   "its error (relative to the largest elastic coordinate) is at most TOL; "
                   "overrides the study's [simulation] tol")
    add_model_arguments(p, default_joints=None)
    p.set_defaults(func=cmd_simulate)


def run_study(path, joints: str | None = None, values: dict[str, float] | None = None,
              tol: float | None = None) -> tuple[list, list, Any, Any]:
    """Assign the study's design, then simulate the baseline and the assigned design.

    Args:
        path: Study TOML with a ``[simulation]`` table.
        joints: Joint conditions overriding the study's ``joints`` key (``--joints``).
        values: Parameter values overriding and adding to the study's ``values`` (``--set``).
        tol: Step-error tolerance overriding the study's ``tol`` (``--tol``).

    Returns:
        ``(reports, [(simulation, dynamics)], settings, assignment result)``.
    """
    from pinflex.assignment.study import run_config
    from pinflex.dynamics.study import load_simulation_study, simulate_design

    cfg, settings = load_simulation_study(path)
    if tol is not None:
        import dataclasses

        from pinflex.dynamics.study import parse_simulation_table

        parse_simulation_table({"tol": tol})  # the same checks as in the file
        settings = dataclasses.replace(settings, tol=float(tol))
    if joints is not None:
        cfg.joints = joints
    if values:
        cfg.values = {**(cfg.values or {}), **values}
    model, traj, result = run_config(cfg)
    designs = [("baseline", result.y_before), ("assigned", result.y)]
    reports, sims = [], []
    for name, y in designs:
        rep, sim, dyn = simulate_design(model, traj, y, settings, name)
        reports.append(rep)
        sims.append((sim, dyn))
    return reports, sims, settings, result


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run ``pinflex simulate``."""
    t0 = time.perf_counter()
    reports, sims, settings, result = run_study(
        args.config, args.joints, parse_values(args.set) if args.set else None, args.tol)
    total = time.perf_counter() - t0
    files: list[str] = []
    if args.out:
        from pinflex.dynamics.charts import deflection_chart
        from pinflex.outputs import output_dir, write_text

        out = output_dir(args.out)
        files.append(str(deflection_chart(reports, out / "tip_deflection.png")))
        for rep in reports:
            p = out / f"{rep.name}_series.json"
            write_text(p, rep.to_json(series=True), "simulation JSON")
            files.append(str(p))
        if args.exaggeration > 0:
            playback: Any = None
            try:
                from pinflex.visualization.playback import simulation_playback_html as playback
            except ImportError:  # the preview extra (meshcat) is not installed
                pass
            if playback is not None:
                for rep, (sim, dyn) in zip(reports, sims):
                    files.append(str(playback(dyn, sim, out / f"{rep.name}_playback.html",
                                              exaggeration=args.exaggeration)))
    designs = []
    for rep in reports:
        d = rep.summary()
        designs.append({
            "name": rep.name, "y": d["y"], "final_q": d["final_q"],
            "tip_peak_m": d["tip_peak_m"], "tip_rms_m": d["tip_rms_m"],
            "residual_amplitude_m": d["residual_amplitude_m"],
            "dominant_frequency_hz": d["dominant_frequency_hz"],
            "steps": d["steps"], "time_s": d["time_s"],
            "step_error_estimate": d.get("error_estimate"),
            "residual_joint_condition": d["joint_condition"],
            "residual_reference_hz": d["reference_hz"], "frame": d["frame"],
        })
    out_json = {"drive": settings.drive, "designs": designs, "files": files,
                "total_time_s": total}
    if args.json:
        print(json.dumps(out_json))
        return 0
    w = sys.stdout.write
    w(f"drive: {settings.drive}; output frame '{reports[0].frame}'; residual vibration with "
      f"{reports[0].joint_condition} joints\n")
    for d in designs:
        f = d["dominant_frequency_hz"]
        w(f"  {d['name']:9s} y = {d['y']}: peak {1e3 * d['tip_peak_m']:.4f} mm, RMS "
          f"{1e3 * d['tip_rms_m']:.4f} mm, residual {1e3 * d['residual_amplitude_m']:.4f} mm at "
          f"{'-' if f is None else f'{f:.3f}'} Hz (reference "
          f"{d['residual_reference_hz'][0]:.3f} Hz); {d['steps']} steps, {d['time_s']:.2f} s\n")
    for f in files:
        w(f"wrote {f}\n")
    return 0
