"""``pinflex size``: the least design mass that keeps frequency floors along a motion."""

from __future__ import annotations

import argparse
import json
import time

from pinflex.cli.common import add_model_arguments, parse_values


def add_parser(sub) -> None:
    """Register the ``size`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "size", help="least design mass under frequency floors along a trajectory (TOML study)",
        description="Least design mass (tube diameters, walls, materials, point masses, joint "
        "stiffnesses) that keeps every floored mode at or above its floor at every trajectory "
        "sample: Taylor steps inside a trust region, each verified on the exact model "
        "(pinflex.assignment.sizing). Reads [constraints].floors and mass_budget_kg, "
        "[expansion] q0, y0 (start), order and design, and [sizing] of a study file. Exit "
        "status: 0 when every floor holds on the exact model, 3 when not (out of reach of the "
        "design variables within their bounds), 2 for an input error.")
    p.add_argument("config", help="TOML study file (see pinflex.assignment.study)")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (design, masses, margin, frequencies, history)")
    p.add_argument("--order", type=int, default=None, metavar="P",
                   help="Taylor order of the steps (default: the study's [expansion].order)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar on stderr (shown by default when stderr is a terminal)")
    add_model_arguments(p, default_joints=None)
    p.set_defaults(func=cmd_size)


def summary(model, result, total_s: float) -> dict:
    """The JSON summary of a sizing result and its total time [s]."""
    units = {d.name: getattr(d, "unit", "") for d in model.design}
    return {
        "status": result.status,
        "feasible": result.feasible,
        "design": result.design,
        "design_start": {d.name: float(v) for d, v in zip(model.design, result.y_start)},
        "units": units,
        "mass_kg": result.mass_kg,
        "mass_start_kg": result.mass_start_kg,
        "added_mass_kg": result.added_mass_kg,
        "floors": [{"mode": m, "freq_hz": f} for m, f in result.floors],
        "margin_hz": result.margin_hz,
        "modes": sorted({m for m, _ in result.floors}),
        "min_freq_hz": result.freq_hz.min(axis=0).tolist(),
        "min_freq_start_hz": result.freq_start_hz.min(axis=0).tolist(),
        "freq_hz": result.freq_hz.tolist(),
        "expansions": result.expansions,
        "history": [{"y": y.tolist(), "mass_kg": m, "margin_hz": g}
                    for y, m, g in result.history],
        "joints": dict(result.joints),
        "link_inertia": list(model.description.inertia_notes),
        "timings_s": result.timings_s,
        "total_time_s": total_s,
    }


def cmd_size(args: argparse.Namespace) -> int:
    """Run ``pinflex size``."""
    import sys

    from pinflex.assignment.result import EXIT_NOT_MET
    from pinflex.assignment.study import load_config, run_sizing
    from pinflex.exceptions import ConfigurationError
    from pinflex.resources import check_order

    t0 = time.perf_counter()
    cfg = load_config(args.config)
    if args.joints is not None:
        cfg.joints = args.joints
    if args.set:
        cfg.values = {**(cfg.values or {}), **parse_values(args.set)}
    if args.order is not None:
        cfg.order = check_order(args.order, "--order")
        if cfg.order < 1:
            raise ConfigurationError("--order 0: sizing steps need order 1 or more")
    model, traj, result = run_sizing(cfg, progress=not args.no_progress and sys.stderr.isatty())
    total = time.perf_counter() - t0
    code = 0 if result.ok else EXIT_NOT_MET
    if args.json:
        print(json.dumps(summary(model, result, total)))
        return code
    units = {d.name: getattr(d, "unit", "") for d in model.design}
    print("design: " + ", ".join(f"{k} = {v:.6g} {units[k]}".rstrip()
                                 for k, v in result.design.items()))
    print("joints: " + ", ".join(f"{k} {v}" for k, v in result.joints.items()))
    from pinflex.cli.common import inertia_text

    if inertia_text(model):
        print(inertia_text(model))
    print(f"design mass: {result.mass_start_kg:.6g} kg -> {result.mass_kg:.6g} kg "
          f"({result.added_mass_kg:+.6g} kg)")
    modes = sorted({m for m, _ in result.floors})
    for m, f in result.floors:
        k = modes.index(m)
        print(f"mode {m} >= {f:g} Hz: lowest exact {result.freq_start_hz[:, k].min():.6g} Hz "
              f"-> {result.freq_hz[:, k].min():.6g} Hz")
    print(f"exact margin {result.margin_hz:.4g} Hz over {traj.q.shape[0]} samples; "
          f"{result.expansions} expansions; total {total:.3f} s")
    print("status: " + ("met: every floor holds on the exact model" if result.ok else
                        "floors unmet: out of reach of these design variables within their "
                        "bounds (widen them, add variables or lower the floors)"))
    return code
