"""``pinflex demo``: benchmark A (paper 000) end to end: modes, Taylor model, assignment.

The demo is a list of sections (:data:`SECTIONS`), each a function of one shared
:class:`Demo` that prints its lines and adds its results to ``demo.report`` (the ``--json``
object). A new section is a function and one entry in the list. The numbers come from
:mod:`pinflex.cases.benchmark_a`, which the benchmarks call too.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

from pinflex.cli.assign import summary, write_preview
from pinflex.cli.common import add_model_arguments, joints_text, parse_values
from pinflex.outputs import output_dir


def add_parser(sub) -> None:
    """Register the ``demo`` subcommand on an ``argparse`` subparsers object."""
    d = sub.add_parser("demo", help="benchmark A end to end: modes, Taylor model, assignment")
    d.add_argument("--out", default="pinflex-demo", help="output folder (default: pinflex-demo)")
    d.add_argument("--json", action="store_true", help="print one JSON object")
    d.add_argument("--html", default=None, metavar="FILE",
                   help="HTML preview file (default: OUT/preview.html)")
    d.add_argument("--no-brute-force", action="store_true",
                   help="skip the exact grid search that checks the QP's answer")
    d.add_argument("--vibration", action="store_true",
                   help="simulate the tip vibration of the baseline and the assigned design along "
                   "the motion (pinflex.dynamics; the default, kept for scripts)")
    d.add_argument("--no-vibration", action="store_true",
                   help="skip the vibration simulation (about 3 s of compute)")
    add_model_arguments(d)
    d.set_defaults(func=cmd_demo)


@dataclass
class Demo:
    """State shared by the demo's sections.

    Attributes:
        args: The parsed command line.
        model: Benchmark A's arm.
        trajectory: Benchmark A's trajectory.
        out_dir: Output folder (created).
        log: Where the sections print (stderr with ``--json``).
        report: The ``--json`` object the sections fill.
        results: Objects a section leaves for later ones (e.g. ``"assignment"``).
    """

    args: argparse.Namespace
    model: Any
    trajectory: Any
    out_dir: Path
    log: TextIO
    report: dict[str, Any] = field(default_factory=dict)
    results: dict[str, Any] = field(default_factory=dict)

    def say(self, msg: str = "") -> None:
        """Print one line of the demo."""
        print(msg, file=self.log, flush=True)


def modes_section(demo: Demo) -> None:
    """Model size and the lowest modes at (q0, y0)."""
    from pinflex.cases.benchmark_a import Q0

    model = demo.model
    demo.say("pinflex demo: benchmark A (paper 000), planar two-link flexible arm")
    demo.say(f"  {model.ndof} dof = {model.nx} elastic + {model.ndof - model.nx} joint "
             f"({model.n_rigid} rigid modes); q0 = {Q0.tolist()} rad (absolute link angles); "
             f"y0 = {', '.join(f'{d.name} = {d.nominal:g}' for d in model.design)}")
    demo.say(f"  {joints_text(model)}")
    modal = model.modes(Q0, model.y0, n_modes=4)
    demo.say("  modes at (q0, y0): " + ", ".join(f"{f:.2f}" for f in modal.freq_hz) + " Hz")
    demo.report["ndof"] = model.ndof


def taylor_section(demo: Demo) -> None:
    """Accuracy of the p = 4 Taylor model of mode 1 beside the paper's (Sec. 3.2)."""
    from pinflex.cases.benchmark_a import PAPER, expand_mode1, taylor_errors

    t0 = time.perf_counter()
    tm = expand_mode1(demo.model)
    demo.results["expansion_s"] = time.perf_counter() - t0
    errs = taylor_errors(demo.model, demo.trajectory, tm)
    demo.say("\n  Taylor model of mode 1, p = 4 (max relative error, exact model as reference)")
    demo.say(f"  {'domain':42s} {'full':>8s} {'paper':>7s} {'lin. y':>8s} {'paper':>7s}")
    for key, label in (("traj", "trajectory (152 samples), y = 0"),
                       ("y", "q0, y in [0, 0.25]^2 (26 x 26 grid)")):
        full, lin = f"taylor_{key}_full", f"taylor_{key}_lin"
        demo.say(f"  {label:42s} {errs[full]:7.3f}% {PAPER[full]:6.2f}% {errs[lin]:7.3f}% "
                 f"{PAPER[lin]:6.2f}%")
    demo.report["taylor_errors_percent"] = errs


def assignment_section(demo: Demo) -> None:
    """Mode 1 assigned to 190 Hz, checked by the exact model and a grid search (Sec. 3.3)."""
    from pinflex.cases.benchmark_a import PAPER, assign_mode1, grid_check

    result = assign_mode1(demo.model, demo.trajectory)
    demo.results["assignment"] = result
    demo.say("\n  Assignment of mode 1 to 190 Hz along the trajectory (ProxQP, exact verification)")
    demo.say(f"  {'':24s} {'pinflex':>10s} {'paper':>10s}")
    demo.say(f"  {'m1 [kg]':24s} {result.design['m1']:10.4f} {PAPER['m1']:10.4f}")
    demo.say(f"  {'m2 [kg]':24s} {result.design['m2']:10.4f} {PAPER['m2']:10.4f}")
    demo.say(f"  {'max error before':24s} {100 * result.max_error_before:9.2f}% "
             f"{PAPER['err_before']:9.2f}%")
    demo.say(f"  {'max error after':24s} {100 * result.max_error_after:9.2f}% "
             f"{PAPER['err_after']:9.2f}%")
    demo.say(f"  QP: {result.solution.iterations} iterations, "
             f"{1e3 * result.solution.time_s:.3f} ms")
    if demo.args.no_brute_force:
        return
    brute, ours = grid_check(demo.model, demo.trajectory, result)
    demo.say(f"  exact grid search ({brute.evaluations} designs): best cost at m1, m2 = "
             f"{brute.y_best_cost.round(4).tolist()} (cost {brute.best_cost:.4g}; ours "
             f"{ours:.4g}, gap {100 * (ours / brute.best_cost - 1):.2f} %); "
             f"best max error {100 * brute.best_max_error:.2f} % at "
             f"{brute.y_best_max_error.round(4).tolist()}")
    demo.report["brute_force"] = {"y_best_cost": brute.y_best_cost.tolist(),
                                  "y_best_max_error": brute.y_best_max_error.tolist(),
                                  "best_max_error": brute.best_max_error}


def outputs_section(demo: Demo) -> None:
    """Charts and the HTML preview of the assignment, and the compute times."""
    from pinflex.assignment.charts import assignment_charts

    result = demo.results["assignment"]
    charts = assignment_charts(result, demo.trajectory.times_s, demo.out_dir)
    html = write_preview(demo.model, demo.trajectory, result,
                         demo.args.html or demo.out_dir / "preview.html")
    t = result.timings_s
    demo.say(f"\n  compute: expansion {1e3 * demo.results['expansion_s']:.1f} ms; assignment end "
             f"to end {1e3 * t['total']:.1f} ms (expansion+build "
             f"{1e3 * t['expansion_and_build']:.1f}, QP {1e3 * t['qp']:.1f}, exact verification "
             f"{1e3 * t['exact_verification']:.1f})")
    for c in charts:
        demo.say(f"  wrote {c}")
    if html:
        demo.say(f"  wrote {html}")
    demo.report.update({"charts": [str(c) for c in charts], "html": html})


def vibration_section(demo: Demo) -> None:
    """Tip vibration of the baseline and the assigned design (unless ``--no-vibration``)."""
    if getattr(demo.args, "no_vibration", False):
        return
    from pinflex.cases.vibration_demo import vibration_demo

    demo.report["vibration"] = vibration_demo(demo.model, demo.trajectory,
                                              demo.results["assignment"], demo.out_dir, demo.say)


#: The demo's sections, in order.
SECTIONS: list[Callable[[Demo], None]] = [
    modes_section,
    taylor_section,
    assignment_section,
    outputs_section,
    vibration_section,
]


def cmd_demo(args: argparse.Namespace) -> int:
    """Run ``pinflex demo``: benchmark A end to end, beside paper 000's figures."""
    from pinflex.cases.benchmark_a import PAPER, benchmark_model, benchmark_trajectory

    t_all = time.perf_counter()
    out_dir = output_dir(Path(args.out))
    model = benchmark_model(joints=args.joints, values=parse_values(args.set))
    demo = Demo(args, model, benchmark_trajectory(model), out_dir,
                sys.stderr if args.json else sys.stdout)
    for section in SECTIONS:
        section(demo)
    total = time.perf_counter() - t_all
    demo.say(f"  demo finished in {total:.1f} s; outputs in {out_dir}/")
    if args.json:
        out = summary(demo.results["assignment"], total)
        out.update({"paper": PAPER, "out": str(out_dir), **demo.report})
        from pinflex.outputs import json_text

        print(json_text(out))
    return 0
