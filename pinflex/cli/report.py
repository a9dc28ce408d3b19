"""``pinflex report``: charts and playback pages of a simulation saved by ``simulate --out``."""

from __future__ import annotations

import argparse
import sys


def add_parser(sub) -> None:
    """Register the ``report`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "report", help="charts and meshcat playback pages of a run saved by 'pinflex simulate "
        "--out DIR', from its data (no simulation is run again)")
    p.add_argument("folder", metavar="DIR", help="the --out folder of 'pinflex simulate'")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for the charts and pages (default: DIR itself)")
    p.add_argument("--no-charts", action="store_true",
                   help="no charts (tip_deflection.png, validity.png)")
    p.add_argument("--no-preview", action="store_true",
                   help="no playback pages (NAME_playback.html; these rebuild the model from "
                   "the run's robot file, which must be unchanged)")
    p.add_argument("--exaggeration", type=float, default=200.0,
                   help="factor on the elastic motion in the playback pages (default 200)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=cmd_report)


def cmd_report(args: argparse.Namespace) -> int:
    """Run ``pinflex report``."""
    from pinflex.cli.simulate import write_charts, write_previews
    from pinflex.dynamics.saved import load_run, run_dynamics
    from pinflex.exceptions import ConfigurationError
    from pinflex.outputs import output_dir

    if not 0.0 < args.exaggeration <= 1e6:
        raise ConfigurationError(f"--exaggeration {args.exaggeration:g}: give a factor above 0 "
                                 "and at most 1e6 (--no-preview: no playback)")
    if not args.no_preview:
        from pinflex.visualization.offline import require_meshcat

        require_meshcat("the playback pages of 'pinflex report'")
    saved = load_run(args.folder)
    out = output_dir(args.out or args.folder)
    files: list[str] = []
    if not args.no_charts:
        files += write_charts(saved.reports, saved.sims, out)
    if not args.no_preview:
        dyns = [run_dynamics(saved, i) for i in range(len(saved.reports))]
        files += write_previews(saved.reports, saved.sims, dyns, out, args.exaggeration)
    if args.json:
        from pinflex.outputs import json_text

        print(json_text({"designs": [r.name for r in saved.reports], "files": files}))
        return 0
    for f in files:
        sys.stdout.write(f"wrote {f}\n")
    return 0
