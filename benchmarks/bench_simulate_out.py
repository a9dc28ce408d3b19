"""What ``pinflex simulate --out DIR`` costs beyond the simulation itself.

Run: ``python benchmarks/bench_simulate_out.py [--rounds N] [--json] [--no-pictures]``.

Two commands, each run in one process through ``pinflex.cli.main`` (single-thread BLAS unless
the environment sets it), round by round interleaved, the order alternating between rounds:

* benchmark A's study (``pinflex simulate examples/benchmark_a.toml``: the assignment, then
  the baseline and the assigned design simulated);
* a spatial arm along a plain motion (``pinflex simulate urdf/ur3_tubes.xml --trajectory
  MOVE.csv --frame tool0 --after 0.05``: no assignment), MOVE.csv a quintic rest-to-rest
  move of 0.5 s from the first pose of ``examples/real_arms/ur3_motion.csv``, written by the
  benchmark (0.1 rad on each of the first three joints; a short run, where fixed costs weigh
  most).

Sides: without ``--out`` (the physics and the printed summary), with ``--out DIR`` (plus the
run's data: series JSON, npz, validity CSV, run.json) and, unless ``--no-pictures``, with
``--out DIR --charts --preview`` (what ``--out`` wrote before the pictures became optional).
Reported: per round the ratios (side / without ``--out``) of process CPU time
(``time.process_time``) and of wall time, median and range over the rounds, and the median
times. Target of ``--out``: below 1.2x.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import os
import sys
import tempfile
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

def _ur3_move(path: Path) -> Path:
    """The UR3 case's motion: 0.5 s quintic rest-to-rest, 21 samples (module doc)."""
    import numpy as np

    lines = (ROOT / "examples" / "real_arms" / "ur3_motion.csv").read_text().splitlines()
    q0 = np.array([float(v) for v in lines[1].split(",")[1:]])
    t = np.linspace(0.0, 0.5, 21)
    s = t / 0.5
    h = 10 * s**3 - 15 * s**4 + 6 * s**5
    rows = [lines[0]] + [",".join(f"{float(v)!r}" for v in (ti, *(q0 + hi * np.array(
        [0.1, 0.1, 0.1, 0.0, 0.0, 0.0])))) for ti, hi in zip(t, h)]
    path.write_text("\n".join(rows) + "\n")
    return path


def _cases(tmp: Path) -> dict:
    return {
        "benchmark A study": ["simulate", str(ROOT / "examples" / "benchmark_a.toml")],
        "UR3 plain motion": ["simulate", str(ROOT / "urdf" / "ur3_tubes.xml"), "--trajectory",
                             str(_ur3_move(tmp / "MOVE.csv")), "--frame", "tool0",
                             "--after", "0.05"],
    }


def _run(argv: list[str]) -> tuple[float, float]:
    from pinflex.cli import main

    c0, w0 = time.process_time(), time.perf_counter()
    with contextlib.redirect_stdout(io.StringIO()), warnings.catch_warnings():
        warnings.simplefilter("ignore")
        rc = main([*argv, "--json", "--no-progress"])
    if rc != 0:
        raise RuntimeError(f"pinflex {' '.join(argv)} exited with {rc}")
    return time.process_time() - c0, time.perf_counter() - w0


def _stats(num, den) -> dict:
    import numpy as np

    r = np.asarray(num) / np.asarray(den)
    return {"median": float(np.median(r)), "range": [float(r.min()), float(r.max())]}


def main(argv=None) -> int:
    """Run the benchmark."""
    from interleave import blas_threads, pin_single_thread

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rounds", type=int, default=5, help="timing rounds (default 5)")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--no-pictures", action="store_true",
                    help="leave out the side with --charts --preview")
    args = ap.parse_args(argv)
    if "numpy" not in sys.modules:
        pin_single_thread()
    import numpy as np

    tmp = Path(tempfile.mkdtemp(prefix="bench_simulate_out-"))
    sides = {"plain": [], "out": ["--out", str(tmp / "out")]}
    if not args.no_pictures:
        sides["out+charts+preview"] = ["--out", str(tmp / "pictures"), "--charts", "--preview"]
    load0 = os.getloadavg()
    result: dict = {"blas_threads": blas_threads(), "rounds": args.rounds, "cases": {}}
    for case, base in _cases(tmp).items():
        for extra in sides.values():  # warm-up: imports, caches, folders
            _run(base + extra)
        cpu: dict = {s: [] for s in sides}
        wall: dict = {s: [] for s in sides}
        for r in range(args.rounds):
            for s in (list(sides) if r % 2 == 0 else list(sides)[::-1]):
                c, w = _run(base + sides[s])
                cpu[s].append(c)
                wall[s].append(w)
        entry: dict = {"command": "pinflex " + " ".join(
            a.replace(str(ROOT) + os.sep, "").replace(str(tmp) + os.sep, "") for a in base)}
        for s in sides:
            entry[s] = {"cpu_median_s": float(np.median(cpu[s])),
                        "wall_median_s": float(np.median(wall[s]))}
            if s != "plain":
                entry[s]["cpu_ratio"] = _stats(cpu[s], cpu["plain"])
                entry[s]["wall_ratio"] = _stats(wall[s], wall["plain"])
        result["cases"][case] = entry
    result["load_average"] = [load0[0], os.getloadavg()[0]]
    if args.json:
        print(json.dumps(result))
        return 0
    print(f"pinflex simulate with and without --out; {result['blas_threads']}; load average "
          f"{load0[0]:.1f} -> {os.getloadavg()[0]:.1f} on {os.cpu_count()} cores; "
          f"{args.rounds} interleaved rounds")
    for case, e in result["cases"].items():
        print(f"  {case}: {e['command']}")
        print(f"    without --out: {e['plain']['cpu_median_s']:.3f} s CPU, "
              f"{e['plain']['wall_median_s']:.3f} s wall")
        for s in sides:
            if s == "plain":
                continue
            c, w = e[s]["cpu_ratio"], e[s]["wall_ratio"]
            print(f"    {s:19s}: CPU {c['median']:.3f}x ({c['range'][0]:.3f}-"
                  f"{c['range'][1]:.3f}), wall {w['median']:.3f}x ({w['range'][0]:.3f}-"
                  f"{w['range'][1]:.3f}); {e[s]['cpu_median_s']:.3f} s CPU")
    print("  target of --out: below 1.2x")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
