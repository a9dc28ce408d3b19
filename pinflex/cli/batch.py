"""``pinflex batch``: resumable batch studies on Dask (``prbdm``, ``assign``, ``report``).

Registered on the main parser by :func:`add_parser`; errors and exit codes are those of
:func:`pinflex.cli.main`.
"""

from __future__ import annotations

import argparse
import json
from dataclasses import asdict


def add_parser(sub) -> argparse.ArgumentParser:
    """Register ``batch`` (with ``prbdm``, ``assign`` and ``report``) on a subparsers object.

    Every leaf parser sets ``func`` to a function of the parsed arguments returning the exit
    code (0 on success, 130 if interrupted).
    """
    batch = sub.add_parser(
        "batch", help="resumable batch studies on Dask: random-beam PRBDM fits, assignment "
        "sweeps, reports",
        description="Resumable batch studies on Dask. Rows go to an SQLite store keyed by "
        "(seed, item, config hash); rerunning a command skips finished keys.")
    bsub = batch.add_subparsers(dest="batch_command", required=True)

    p = bsub.add_parser("prbdm", help="fit PRBDMs to seeded random beams (paper 001, Sec. 2.1)")
    p.add_argument("--beams", type=int, required=True, metavar="N", help="number of beams")
    p.add_argument("--seed", type=int, default=0, metavar="S", help="study seed (default 0)")
    p.add_argument("--links", type=int, nargs="+", default=[4], metavar="N",
                   help="joint counts of the nR models to fit, one configuration each "
                   "(default: 4)")
    p.add_argument("--modes", type=int, nargs="+", default=None, metavar="M",
                   help="matched modes per --links entry, or one value for all (default: n)")
    p.add_argument("--objective", default="combined",
                   choices=("eigen", "deflection", "combined", "pareto"),
                   help="mapping objective (default: combined; eigen-only fits of n modes at "
                   "one pose are exactly determined)")
    p.add_argument("--starts", type=int, default=16, help="multistart points (default 16)")
    p.add_argument("--stiffness-law", default="segment", choices=("segment", "paper"),
                   help="spring law (default: segment)")
    p.add_argument("--poses", default="straight", choices=("straight", "paper"),
                   help="comparison poses (default: straight)")
    p.add_argument("--sections", type=int, default=10, metavar="P",
                   help="random interior vertices per planform (default 10, as the paper)")
    p.add_argument("--truth-modes", type=int, default=5,
                   help="bending modes of the reference beam FE (default 5)")
    p.add_argument("--alphas", type=float, nargs="*", default=None, metavar="A",
                   help="load levels PL^2/EI of the elastica reference (default 0.5 1 2 5; "
                   "give none to skip deflection)")
    _common(p)
    p.set_defaults(func=cmd_prbdm)

    a = bsub.add_parser("assign", help="sweep assignment studies (targets x trajectories x "
                        "constraints)")
    a.add_argument("config", help="TOML study file (see pinflex.assignment.study)")
    a.add_argument("--sweep", action="append", default=[], metavar="KEY=V1,V2",
                   help="vary a study key over values, e.g. targets.0.freq_hz=185,190,195 or "
                   "constraints.mass_budget_kg=0.1,0.2 (repeatable: Cartesian product)")
    _common(a)
    a.set_defaults(func=cmd_assign)

    r = bsub.add_parser("report", help="error distributions, failures and histograms of a store")
    r.add_argument("store", help="SQLite store written by pinflex batch")
    r.add_argument("--out", default=None, metavar="DIR",
                   help="folder for the histogram PNGs (default: STORE's name + '-report')")
    r.add_argument("--no-plots", action="store_true", help="print only, write no PNG")
    r.add_argument("--json", action="store_true", help="print one JSON object")
    r.add_argument("--table", default=None, metavar="CSV",
                   help="per-case table of assignment sweeps (default: cases.csv in the "
                   "report folder)")
    r.set_defaults(func=cmd_report)
    return batch


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--store", required=True, metavar="PATH", help="SQLite result store")
    p.add_argument("--scheduler", default=None, metavar="ADDRESS",
                   help="existing Dask scheduler, e.g. tcp://HOST:8786 (default: a local "
                   "cluster)")
    p.add_argument("--workers", type=int, default=None, metavar="K",
                   help="worker processes of the local cluster (default: one per core)")
    p.add_argument("--retry-failed", action="store_true",
                   help="rerun keys stored as failed (default: keep their recorded error)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar on stderr")
    p.add_argument("--json", action="store_true", help="print the summary as one JSON object")


def _finish(summary, args, unit: str) -> int:
    if args.json:
        print(json.dumps(dict(asdict(summary), rate_per_s=summary.rate_per_s)))
    else:
        print(summary.text(unit))
        print(f"store: {args.store}  (inspect with: pinflex batch report {args.store})")
    return 130 if summary.interrupted else 0


def cmd_prbdm(args: argparse.Namespace) -> int:
    """Run ``pinflex batch prbdm``."""
    from pinflex.batch.runner import run_prbdm
    from pinflex.batch.tasks import PrbdmStudy
    from pinflex.prbdm.options import DEFAULT_ALPHAS

    study = PrbdmStudy(
        seed=args.seed, n_beams=args.beams, links=tuple(args.links),
        modes=None if args.modes is None else tuple(args.modes), objective=args.objective,
        n_starts=args.starts, stiffness_law=args.stiffness_law, poses=args.poses,
        n_sections=args.sections, truth_modes=args.truth_modes,
        alphas=DEFAULT_ALPHAS if args.alphas is None else tuple(args.alphas))
    summary = run_prbdm(study, args.store, args.scheduler, args.workers, args.retry_failed,
                        progress=not args.no_progress)
    return _finish(summary, args, "beam")


def cmd_assign(args: argparse.Namespace) -> int:
    """Run ``pinflex batch assign``."""
    from pinflex.batch.runner import run_assign
    from pinflex.batch.sweep import parse_sweeps

    summary = run_assign(args.config, parse_sweeps(args.sweep), args.store, args.scheduler,
                         args.workers, args.retry_failed, progress=not args.no_progress)
    return _finish(summary, args, "case")


def cmd_report(args: argparse.Namespace) -> int:
    """Run ``pinflex batch report``."""
    from pathlib import Path

    from pinflex.batch.report import build_report, case_table, write_histograms

    report = build_report(args.store)
    pngs = [] if args.no_plots else write_histograms(args.store, args.out)
    cases = case_table(args.store)
    table_path = None
    if cases.rows:
        store = Path(args.store)
        default = (Path(args.out) if args.out else store.with_name(store.stem + "-report"))
        table_path = cases.to_csv(args.table or default / "cases.csv")
    if args.json:
        print(json.dumps(dict(report.to_dict(), histograms=[str(p) for p in pngs],
                              cases={"columns": cases.columns, "rows": cases.rows},
                              table=str(table_path) if table_path else None)))
        return 0
    print(report.text())
    if cases.rows:
        print("")
        print(cases.text())
        print(f"wrote {table_path}")
    for path in pngs:
        print(f"wrote {path}")
    return 0
