"""``pinflex assign``: eigenfrequency assignment along a trajectory from a TOML study."""

from __future__ import annotations

import argparse
import time

from pinflex.cli.common import add_model_arguments, parse_values


def add_parser(sub) -> None:
    """Register the ``assign`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "assign", help="assign eigenfrequencies along a trajectory (TOML study)",
        description="Assign eigenfrequencies along a trajectory: the QP of the Taylor model, "
        "confirmed on the exact model and re-expanded until it is. Exit status: 0 when the "
        "exact model meets everything (status 'met'), 3 when it does not (prediction not "
        "confirmed, a floor, band or budget violated, no improvement, target error above "
        "--target-tol, or no feasible design), 2 for an input error.")
    p.add_argument("config", help="TOML study file (see pinflex.assignment.study)")
    p.add_argument("--out", default=None,
                   help="folder for the charts, assignment.csv and assignment.json")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (design, errors, per-sample frequencies, "
                   "constraints)")
    p.add_argument("--csv", default=None, metavar="FILE",
                   help="per sample and mode: target, before, predicted, exact after")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar on stderr (shown by default when stderr is a terminal)")
    p.add_argument("--parquet", default=None, metavar="FILE",
                   help="the same table as Parquet (needs pyarrow)")
    p.add_argument("--html", default=None, metavar="FILE", help="write an HTML preview")
    p.add_argument("--tol", type=float, default=None, metavar="TOL",
                   help="pick the Taylor order (1-8) instead of the study's: the lowest whose "
                   "estimate of the relative frequency error (the larger of the next two "
                   "orders' terms) along the trajectory (at y0 and the design-box corners) "
                   "meets TOL; reported with its estimate")
    p.add_argument("--points-tol", type=float, default=None, metavar="TOL",
                   help="expand at several points instead of the study's q0: the fewest "
                   "expansion points along the trajectory (then the lowest order, 1-8) whose "
                   "estimate of the relative frequency error (the larger of the next two "
                   "orders' terms) meets TOL at every "
                   "sample at y0; each sample's QP rows come from its segment's model; reports "
                   "the points, the order, the estimate and the exact error of the cover")
    p.add_argument("--confirm-tol", type=float, default=None, metavar="TOL",
                   help="largest relative difference between the answer's predicted and exact "
                   "frequencies (default: the study's, else 0.005)")
    p.add_argument("--target-tol", type=float, default=None, metavar="TOL",
                   help="largest exact target error for the status 'met' (default: the "
                   "study's, else 0.05)")
    add_model_arguments(p, default_joints=None)
    p.set_defaults(func=cmd_assign)


def summary(result, total_s: float) -> dict:
    """The JSON summary of an assignment result and its total time [s]."""
    return {
        "design": result.design,
        "max_error_before": result.max_error_before,
        "max_error_after": result.max_error_after,
        "predicted_max_error_after": result.predicted_max_error_after,
        "max_error_before_sorted": result.max_error_before_sorted,
        "max_error_after_sorted": result.max_error_after_sorted,
        "improved": result.improved,
        "mode_events": [{"kind": e.kind, "sample": e.sample, "modes": list(e.modes)}
                        for e in result.events],
        "floors_model": result.floors_model,
        "floor_margin_hz": result.floor_margin_hz,
        "qp_iterations": int(result.solution.iterations),
        "qp_time_s": float(result.solution.time_s),
        "refinements": result.refinements,
        "timings_s": result.timings_s,
        "total_time_s": total_s,
        "joints": dict(result.joints),
        "status": result.status,
        "confirmed": result.confirmed,
        "prediction_gap": result.prediction_gap,
        "constraints_met": result.constraints_met,
        "iterations": [dict(it) for it in result.iterations],
        "taylor_order": int(result.taylor.order),
        "taylor_order_choice": _order_choice(result.taylor),
        "taylor_points_choice": _points_choice(result.taylor),
        "validity": None if getattr(result, "validity", None) is None else
        result.validity.summary(),
    }


def _points_choice(tm) -> dict | None:
    """The ``--points-tol`` choice as plain JSON (None with one expansion point)."""
    c = getattr(tm, "points_choice", None)
    if not c:
        return None
    return {"tol": c["tol"], "points": list(c["points"]), "order": c["order"],
            "estimate": c["estimate"], "exact_error": c["exact_error"],
            "segments": [list(s) for s in tm.segments],
            "candidates": {str(k): v for k, v in c["candidates"].items()},
            "method": c["method"]}


def _order_choice(tm) -> dict | None:
    """The ``--tol`` order choice as plain JSON (None when the order was given)."""
    c = tm.order_choice
    if c is None:
        return None
    return {"tol": c["tol"], "order": c["order"], "estimate": c["estimate"],
            "estimates": {str(k): v for k, v in c["estimates"].items()}, "method": c["method"]}


def write_preview(model, traj, result, path) -> str | None:
    """Write the assignment's HTML preview; its path, or None without the preview extra."""
    try:
        from pinflex.visualization import assignment_preview_html
    except ImportError:
        return None
    return str(assignment_preview_html(model, traj, result, path))


def cmd_assign(args: argparse.Namespace) -> int:
    """Run ``pinflex assign``."""
    from pathlib import Path

    from pinflex.assignment.charts import assignment_charts
    from pinflex.assignment.report import assignment_data
    from pinflex.assignment.study import load_config, run_config
    from pinflex.outputs import check_dir_target, check_file_target

    if args.out:
        check_dir_target(args.out, "--out")
    if args.html:
        check_file_target(args.html, "--html")
    t0 = time.perf_counter()
    cfg = load_config(args.config)
    if args.joints is not None:
        cfg.joints = args.joints
    if args.set:
        cfg.values = {**(cfg.values or {}), **parse_values(args.set)}
    if args.tol is not None:
        if not args.tol > 0:
            from pinflex.exceptions import ConfigurationError

            raise ConfigurationError(f"--tol {args.tol}: give a positive relative tolerance")
        cfg.taylor_tol = args.tol
    if args.points_tol is not None:
        from pinflex.exceptions import ConfigurationError

        if not args.points_tol > 0:
            raise ConfigurationError(f"--points-tol {args.points_tol}: give a positive "
                                     "relative tolerance")
        if args.tol is not None:
            raise ConfigurationError("give --tol (one expansion point, order by tolerance) or "
                                     "--points-tol (expansion points by tolerance), not both")
        cfg.points_tol = args.points_tol
    for key in ("confirm_tol", "target_tol"):
        value = getattr(args, key)
        if value is not None:
            from pinflex.assignment.study_schema import STUDY

            top = STUDY["options"].keys[key].le  # the study key's bounds: (0, top]
            if not 0 < value <= top:
                from pinflex.exceptions import ConfigurationError

                raise ConfigurationError(f"--{key.replace('_', '-')} {value}: give a positive "
                                         f"fraction up to {top:g}")
            setattr(cfg, key, value)
    import sys

    from pinflex.assignment.result import EXIT_NOT_MET
    from pinflex.exceptions import AssignmentInfeasible

    try:
        model, traj, result = run_config(cfg, progress=not args.no_progress
                                         and sys.stderr.isatty())
    except AssignmentInfeasible as exc:
        if args.json:
            from pinflex.outputs import json_text

            print(json_text({"status": "infeasible", "error": str(exc),
                             "refused_by": exc.refused_by}))
        print(f"pinflex: no feasible design: {exc}", file=sys.stderr)
        return EXIT_NOT_MET
    total = time.perf_counter() - t0
    data = assignment_data(model, traj, result)
    charts, files = [], []
    if args.out:
        charts = [str(p) for p in assignment_charts(result, traj.times_s, args.out, data)]
        files = [str(data.to_csv(Path(args.out) / "assignment.csv")),
                 str(data.to_json(Path(args.out) / "assignment.json"))]
    if args.csv:
        files.append(str(data.to_csv(args.csv)))
    if args.parquet:
        files.append(str(data.to_parquet(args.parquet)))
    html = write_preview(model, traj, result, args.html) if args.html else None
    out = summary(result, total)
    out["design_units"] = {d.name: d.unit for d in model.design}
    out["link_inertia"] = list(model.description.inertia_notes)
    out["charts"] = charts
    out["files"] = files
    out["html"] = html
    out.update(data.to_dict())
    code = 0 if result.ok else EXIT_NOT_MET
    if args.json:
        from pinflex.outputs import json_text

        print(json_text(out))
        return code
    units = {d.name: d.unit for d in model.design}
    print("design: " + ", ".join(f"{k} = {v:.6g} {units[k]}".rstrip()
                                 for k, v in result.design.items()))
    print("joints: " + ", ".join(f"{k} {v}" for k, v in result.joints.items()))
    from pinflex.cli.common import inertia_text

    if inertia_text(model):
        print(inertia_text(model))
    choice = result.taylor.order_choice
    if choice is not None:
        print(f"Taylor order {choice['order']} for --tol {choice['tol']:g} (two-term estimate "
              f"{choice['estimate']:.3g} along the trajectory and design-box corners)")
    points = _points_choice(result.taylor)
    if points is not None:
        print(f"Taylor expansion points for --points-tol {points['tol']:g}: "
              f"{len(points['points'])} at samples {points['points']}, order {points['order']} "
              f"(largest two-term estimate {points['estimate']:.3g}; exact error of the "
              f"cover {points['exact_error']:.3g} along the trajectory at y0)")
    print(f"max error (exact model): {100 * result.max_error_before:.2f} % -> "
          f"{100 * result.max_error_after:.2f} % "
          f"(predicted {100 * result.predicted_max_error_after:.2f} %)"
          f"{'' if result.improved else '  NOT an improvement'}")
    if result.events:
        print(f"tracked modes: {len(result.events)} crossing/veering events; sorted mode numbers: "
              f"{100 * result.max_error_before_sorted:.2f} % -> "
              f"{100 * result.max_error_after_sorted:.2f} %")
    if result.floors_model:
        print(f"floors enforced on: {result.floors_model}; exact margin "
              f"{result.floor_margin_hz:.4g} Hz")
    print(f"status: {result.status_text()}")
    print(f"QP: {result.solution.iterations} iterations, {1e3 * result.solution.time_s:.3f} ms "
          f"(last of {len(result.iterations)}, {result.refinements} re-expansions); "
          f"total {total:.3f} s")
    active = data.active
    print(f"active constraints: {', '.join(active) if active else 'none'}")
    for line in data.constraint_lines():
        print(f"  {line}")
    for c in charts + files:
        print(f"wrote {c}")
    if html:
        print(f"wrote {html}")
    return code
