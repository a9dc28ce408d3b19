"""One benchmark script, two source trees of pinflex: before/after figures from one run.

Two versions of pinflex cannot share one Python process (one ``pinflex`` package per
process), so this driver alternates whole processes: round ``r`` runs the benchmark from the
old tree then the new one (the order flips every round), each process importing pinflex
from its own tree (``PYTHONPATH``; checked before the first round) and writing its figures
as JSON (the benchmark's ``--json``). Inside each process the benchmark's own ratios are
interleaved as usual. Reported for every figure: its median and range over the rounds in
each tree, and the per-round ``new / old`` quotient (median and range) of the pair measured
back to back. The BLAS thread setting (single thread unless the caller set one) and the load
average before each process are printed: on a loaded machine read the ranges, and prefer the
CPU-time figures.

Run: ``python benchmarks/compare_trees.py OLD_TREE NEW_TREE --script bench_modal.py
[--rounds 3] [--json FILE] -- --quick`` (arguments after ``--`` go to the benchmark; each
tree runs its own copy of the script, so renamed modules are followed).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, pin_single_thread

pin_single_thread()

import numpy as np  # noqa: E402

#: leaves of a benchmark's JSON compared between the trees (times [s] and ratios)
FIGURES = ("ratio_median", "num_median_s", "den_median_s", "median_s", "p6_median_s",
           "cpu_ratio_to_frequencies", "speedup_median")


def leaves(tree: dict, prefix: str = "") -> dict[str, float]:
    """``{path: value}`` of the figures in a benchmark's JSON output."""
    out: dict[str, float] = {}
    for key, value in tree.items():
        path = f"{prefix}/{key}" if prefix else key
        if isinstance(value, dict):
            out.update(leaves(value, path))
        elif key in FIGURES and isinstance(value, (int, float)):
            out[path] = float(value)
    return out


def source_of(tree: Path) -> str:
    """The folder ``import pinflex`` resolves to with ``tree`` on the path."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    res = subprocess.run([sys.executable, "-c", "import pinflex; print(pinflex.__file__)"],
                         env=env, capture_output=True, text=True, check=True, cwd=tree)
    return str(Path(res.stdout.strip()).parent)


def run_once(tree: Path, script: str, extra: list[str]) -> dict[str, float]:
    """One benchmark process from ``tree``; its figures."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "figures.json"
        subprocess.run([sys.executable, str(tree / "benchmarks" / script), *extra,
                        "--json", str(out)], env=env, check=True, stdout=subprocess.DEVNULL,
                       cwd=tmp)
        return leaves(json.loads(out.read_text()))


def spread(values) -> str:
    """``median (min-max)`` with four significant digits."""
    v = np.asarray(values, dtype=float)
    return f"{np.median(v):.4g} ({v.min():.4g}-{v.max():.4g})"


def main(argv=None):
    """Run the comparison."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("old", type=Path, help="source tree of the old version")
    parser.add_argument("new", type=Path, help="source tree of the new version")
    parser.add_argument("--script", required=True, help="benchmark file name in benchmarks/")
    parser.add_argument("--rounds", type=int, default=3, help="process pairs (default 3)")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    argv = list(sys.argv[1:] if argv is None else argv)
    cut = argv.index("--") if "--" in argv else len(argv)
    args = parser.parse_args(argv[:cut])
    args.extra = argv[cut + 1:]  # for the benchmark
    trees = {"old": args.old.resolve(), "new": args.new.resolve()}
    for name, tree in trees.items():
        src = source_of(tree)
        if not src.startswith(str(tree)):
            parser.error(f"{name} tree {tree}: 'import pinflex' resolves to {src}")
    print(f"compare_trees {args.script} {' '.join(args.extra)}: {blas_threads()}; "
          f"{args.rounds} rounds of one process per tree, order alternating")
    runs: dict[str, list[dict[str, float]]] = {"old": [], "new": []}
    loads = []
    for r in range(args.rounds):
        for name in ("old", "new") if r % 2 == 0 else ("new", "old"):
            loads.append(os.getloadavg()[0])
            runs[name].append(run_once(trees[name], args.script, args.extra))
            print(f"  round {r + 1} {name}: done (load average before: {loads[-1]:.1f})",
                  flush=True)
    keys = [k for k in runs["new"][0] if all(k in run for run in runs["old"] + runs["new"])]
    print(f"load average (1 min) before each process: {spread(loads)}")
    print(f"{'figure':60s} {'old: median (range)':28s} {'new: median (range)':28s} "
          "new/old per round")
    table = {}
    for key in keys:
        old = [run[key] for run in runs["old"]]
        new = [run[key] for run in runs["new"]]
        quotient = np.array(new) / np.array(old)
        table[key] = {"old": old, "new": new, "new_over_old": quotient.tolist()}
        print(f"{key:60s} {spread(old):28s} {spread(new):28s} {spread(quotient)}")
    if args.json:
        Path(args.json).write_text(json.dumps(
            {"script": args.script, "extra": args.extra, "blas": blas_threads(),
             "rounds": args.rounds, "load_average": loads, "figures": table}, indent=2))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
