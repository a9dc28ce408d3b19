"""Batch PRBDM throughput on a local Dask cluster with 1 and 2 workers.

Run: ``python benchmarks/bench_batch.py [--preset small|paper] [--beams N]``. The same random
beams are fitted twice into fresh stores, once on one worker process and once on two. Prints
the throughput [beams/s] of each run (from the first submission to the last stored row, worker
start-up excluded), the parallel efficiency eta = r2 / (2 r1), the per-beam split between the
truth (beam FE and elastica) and the fits, in wall and CPU seconds, and what the measured CPU
time per beam means for paper 001's 50,000-beam study, and the overhead of the client loop per
task. The machine's load average is printed before and after: on a shared machine the
wall-clock numbers (and the efficiency) suffer, the CPU times much less; the share of each
run's worker-seconds spent computing (task CPU time / (wall time x workers)) says how much.

Presets: ``small`` (default) is one 4R model (4 modes, 4 multistarts) per p = 10 beam; ``paper``
fits the 4R and 5R models of paper 001 (4 and 5 modes, 16 multistarts) to each beam.
"""

from __future__ import annotations

import argparse
import os
import tempfile
from pathlib import Path

import numpy as np

from pinflex.batch.runner import run_prbdm
from pinflex.batch.store import ResultStore
from pinflex.batch.tasks import PrbdmStudy

PRESETS = {
    "small": dict(links=(4,), modes=(4,), n_starts=4),
    "paper": dict(links=(4, 5), modes=(4, 5), n_starts=16),
}


def per_beam_times(path: Path) -> dict[str, float]:
    """Mean truth and fit time per beam (fits summed over the beam's models) [s]."""
    beams: dict[int, dict[str, float]] = {}
    with ResultStore(path) as store:
        for row in store.rows(status="ok"):
            t = beams.setdefault(row.item, {"truth_s": row.timings["truth_s"],
                                            "truth_cpu_s": row.timings["truth_cpu_s"],
                                            "fit_s": 0.0, "fit_cpu_s": 0.0})
            t["fit_s"] += row.timings["fit_s"]
            t["fit_cpu_s"] += row.timings["fit_cpu_s"]
    return {k: float(np.mean([b[k] for b in beams.values()])) for k in
            ("truth_s", "fit_s", "truth_cpu_s", "fit_cpu_s")} | {"beams": len(beams)}


def loop_overhead(n_tasks: int = 300) -> float:
    """Wall time per task of the client loop (submit, collect, store a row) [s].

    Each task returns a ready-made row of about 3 kB (``list([row])`` on the worker), so the
    time is Dask's round trip plus the SQLite write, with no computation.
    """
    from pinflex.batch.runner import Task, run_tasks

    def row(i: int) -> dict:
        return {"seed": 0, "item": i, "config_hash": "overhead", "kind": "prbdm",
                "status": "ok", "params": {"x_m": [0.1] * 12}, "result": {"v": [0.5] * 200},
                "metrics": {"eigen_error": 1e-4}, "timings": {"task_s": 0.0}}

    tasks = [Task(f"noop-{i}", ((0, i, "overhead"),), list, ([row(i)],), "prbdm")
             for i in range(n_tasks)]
    with tempfile.TemporaryDirectory() as tmp, ResultStore(Path(tmp) / "o.db") as store:
        summary = run_tasks(store, tasks, n_tasks, 0, workers=2, progress=False)
    return summary.wall_s / summary.tasks


def main(argv=None) -> None:
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--preset", choices=sorted(PRESETS), default="small")
    parser.add_argument("--beams", type=int, default=6)
    parser.add_argument("--seed", type=int, default=2020)
    args = parser.parse_args(argv)
    study = PrbdmStudy(seed=args.seed, n_beams=args.beams, **PRESETS[args.preset])
    print(f"preset {args.preset}: {args.beams} random beams (p = {study.n_sections}), models "
          f"{', '.join(f'{n}R/{m} modes' for n, m in zip(study.links, study.modes))}, "
          f"{study.n_starts} multistarts, truth {study.truth_modes} modes + "
          f"{len(study.alphas)} elastica loads; {os.cpu_count()} cores")
    print(f"load average before: {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    rates, splits = {}, {}
    with tempfile.TemporaryDirectory() as tmp:
        for workers in (1, 2):
            path = Path(tmp) / f"w{workers}.db"
            summary = run_prbdm(study, path, workers=workers, progress=False)
            if summary.failed:
                print(f"  ({summary.failed} beams failed)")
            rates[workers] = summary.rate_per_s
            splits[workers] = per_beam_times(path)
            busy = summary.stage_s["task_cpu_s"] * summary.tasks / (summary.wall_s * workers)
            print(f"{workers} worker(s): {summary.tasks} beams in {summary.wall_s:.1f} s -> "
                  f"{summary.rate_per_s:.4f} beams/s ({1 / summary.rate_per_s:.2f} s per beam); "
                  f"workers computed {100 * busy:.0f} % of the time")
    print(f"load average after:  {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    eff = rates[2] / (2 * rates[1])
    print(f"parallel efficiency r2 / (2 r1) = {eff:.2f}")
    s = splits[1]
    wall = s["truth_s"] + s["fit_s"]
    cpu = s["truth_cpu_s"] + s["fit_cpu_s"]
    print(f"per beam (1 worker, mean of {s['beams']}): truth {s['truth_s']:.2f} s "
          f"({100 * s['truth_s'] / wall:.0f} %), fit {s['fit_s']:.2f} s "
          f"({100 * s['fit_s'] / wall:.0f} %) wall; truth {s['truth_cpu_s']:.2f} s, fit "
          f"{s['fit_cpu_s']:.2f} s CPU")
    print(f"client loop overhead: {1e3 * loop_overhead():.1f} ms per task (no-op tasks, "
          "2 workers)")
    total_h = 50_000 * cpu / 3600
    print(f"paper's 50,000 beams at {cpu:.2f} CPU s per beam: {total_h:.0f} core-hours; "
          f"{total_h / 64:.1f} h on 64 cores, {total_h / 256:.1f} h on 256 cores "
          "(at full efficiency)")


if __name__ == "__main__":
    main()
