"""``pinflex demo``: benchmark A (paper 000) end to end: modes, Taylor model, assignment."""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from pinflex.cli.assign import summary, write_preview
from pinflex.cli.common import add_model_arguments, joints_text, parse_values
from pinflex.outputs import output_dir

PAPER = {
    "taylor_traj_full": 0.09, "taylor_traj_lin": 1.64,
    "taylor_y_full": 0.05, "taylor_y_lin": 1.34,
    "m1": 0.2254, "m2": 0.0, "err_before": 8.31, "err_after": 1.48,
}


def add_parser(sub) -> None:
    """Register the ``demo`` subcommand on an ``argparse`` subparsers object."""
    d = sub.add_parser("demo", help="benchmark A end to end: modes, Taylor model, assignment")
    d.add_argument("--out", default="pinflex-demo", help="output folder (default: pinflex-demo)")
    d.add_argument("--json", action="store_true", help="print one JSON object")
    d.add_argument("--html", default=None, metavar="FILE",
                   help="HTML preview file (default: OUT/preview.html)")
    d.add_argument("--vibration", action="store_true",
                   help="also simulate the tip vibration of the baseline and the assigned design "
                   "along the motion (pinflex.dynamics)")
    d.add_argument("--no-brute-force", action="store_true",
                   help="skip the exact grid search that checks the QP's answer")
    add_model_arguments(d)
    d.set_defaults(func=cmd_demo)


def cmd_demo(args: argparse.Namespace) -> int:
    """Run ``pinflex demo``: benchmark A end to end, beside paper 000's figures."""
    from pinflex.assignment import Target, assign_frequencies, brute_force, exact_cost
    from pinflex.assignment.charts import assignment_charts
    from pinflex.assignment.study import builtin_path, user_trajectory
    from pinflex.erls import FlexibleModel
    from pinflex.parametric import expand

    out_dir = Path(args.out)
    out_dir = output_dir(out_dir)
    log = sys.stderr if args.json else sys.stdout

    def say(msg=""):
        print(msg, file=log, flush=True)

    t_all = time.perf_counter()
    model = FlexibleModel(builtin_path("two_link.urdf"), planar=True, joints=args.joints,
                          values=parse_values(args.set))
    traj = user_trajectory(model, "benchmark_a")
    q0 = np.array([1.817, 5.312])
    y0 = model.y0
    say("pinflex demo: benchmark A (paper 000), planar two-link flexible arm")
    say(f"  {model.ndof} dof = {model.nx} elastic + {model.ndof - model.nx} joint "
        f"({model.n_rigid} rigid modes); q0 = {q0.tolist()} rad (absolute link angles); "
        f"y0 = {', '.join(f'{d.name} = {d.nominal:g}' for d in model.design)}")
    say(f"  {joints_text(model)}")
    modal = model.modes(q0, y0, n_modes=4)
    say("  modes at (q0, y0): " + ", ".join(f"{f:.2f}" for f in modal.freq_hz) + " Hz")

    # Taylor model accuracy (paper Sec. 3.2)
    t0 = time.perf_counter()
    tm = expand(model, q0, y0, order=4)
    t_expand = time.perf_counter() - t0
    Q = traj.q
    grid = np.linspace(0.0, 0.25, 26)
    Yg = np.array([[a, b] for a in grid for b in grid])
    Qg = np.tile(q0, (len(Yg), 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        ex_t = model.frequencies(Q, np.zeros(2), n_modes=1)[:, 0]
        ex_y = model.frequencies(Qg, Yg, n_modes=1)[:, 0]
    errs = {}
    for key, QQ, YY, ex in (("traj", Q, np.zeros(2), ex_t), ("y", Qg, Yg, ex_y)):
        for lin in (False, True):
            approx = tm.evaluate(QQ, YY, quantity="freq_hz", linear_in_design=lin)[:, 0]
            errs[f"taylor_{key}_{'lin' if lin else 'full'}"] = 100 * float(
                np.max(np.abs(approx / ex - 1)))
    say("\n  Taylor model of mode 1, p = 4 (max relative error, exact model as reference)")
    say(f"  {'domain':42s} {'full':>8s} {'paper':>7s} {'lin. y':>8s} {'paper':>7s}")
    say(f"  {'trajectory (152 samples), y = 0':42s} {errs['taylor_traj_full']:7.3f}% "
        f"{PAPER['taylor_traj_full']:6.2f}% {errs['taylor_traj_lin']:7.3f}% "
        f"{PAPER['taylor_traj_lin']:6.2f}%")
    say(f"  {'q0, y in [0, 0.25]^2 (26 x 26 grid)':42s} {errs['taylor_y_full']:7.3f}% "
        f"{PAPER['taylor_y_full']:6.2f}% {errs['taylor_y_lin']:7.3f}% "
        f"{PAPER['taylor_y_lin']:6.2f}%")

    # Assignment (paper Sec. 3.3)
    result = assign_frequencies(model, traj, [Target(1, 190.0)], q0=q0, y0=y0, order=4,
                                report_modes=(2, 3, 4))
    say("\n  Assignment of mode 1 to 190 Hz along the trajectory (ProxQP, exact verification)")
    say(f"  {'':24s} {'pinflex':>10s} {'paper':>10s}")
    say(f"  {'m1 [kg]':24s} {result.design['m1']:10.4f} {PAPER['m1']:10.4f}")
    say(f"  {'m2 [kg]':24s} {result.design['m2']:10.4f} {PAPER['m2']:10.4f}")
    say(f"  {'max error before':24s} {100 * result.max_error_before:9.2f}% "
        f"{PAPER['err_before']:9.2f}%")
    say(f"  {'max error after':24s} {100 * result.max_error_after:9.2f}% "
        f"{PAPER['err_after']:9.2f}%")
    say(f"  QP: {result.solution.iterations} iterations, {1e3 * result.solution.time_s:.3f} ms")
    brute = None
    if not args.no_brute_force:
        brute = brute_force(model, traj, [Target(1, 190.0)], points=11, zoom_levels=2)
        ours_cost, _ = exact_cost(model, traj, [Target(1, 190.0)], result.y[None])
        say(f"  exact grid search ({brute.evaluations} designs): best cost at m1, m2 = "
            f"{brute.y_best_cost.round(4).tolist()} (cost {brute.best_cost:.4g}; ours "
            f"{ours_cost[0]:.4g}, gap {100 * (ours_cost[0] / brute.best_cost - 1):.2f} %); "
            f"best max error {100 * brute.best_max_error:.2f} % at "
            f"{brute.y_best_max_error.round(4).tolist()}")
    charts = assignment_charts(result, traj.times_s, out_dir)
    html = write_preview(model, traj, result, args.html or out_dir / "preview.html")
    t = result.timings_s
    say(f"\n  compute: expansion {1e3 * t_expand:.1f} ms; assignment end to end "
        f"{1e3 * t['total']:.1f} ms (expansion+build {1e3 * t['expansion_and_build']:.1f}, QP "
        f"{1e3 * t['qp']:.1f}, exact verification {1e3 * t['exact_verification']:.1f})")
    for c in charts:
        say(f"  wrote {c}")
    if html:
        say(f"  wrote {html}")
    vib = None
    if args.vibration:
        from pinflex.dynamics.demo import vibration_demo

        vib = vibration_demo(model, traj, result, out_dir, say)
    total = time.perf_counter() - t_all
    say(f"  demo finished in {total:.1f} s; outputs in {out_dir}/")
    if args.json:
        out = summary(result, total)
        out.update({"taylor_errors_percent": errs, "paper": PAPER, "ndof": model.ndof,
                    "charts": [str(c) for c in charts], "html": html, "out": str(out_dir)})
        if vib is not None:
            out["vibration"] = vib
        if brute is not None:
            out["brute_force"] = {"y_best_cost": brute.y_best_cost.tolist(),
                                  "y_best_max_error": brute.y_best_max_error.tolist(),
                                  "best_max_error": brute.best_max_error}
        print(json.dumps(out))
    return 0
