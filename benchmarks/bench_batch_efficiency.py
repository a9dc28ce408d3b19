"""Parallel efficiency of batch PRBDM fits at 2 workers: warm workers, tasks of many beams.

One local Dask cluster with two single-threaded worker processes is started and warmed (the
PRBDM modules imported and one beam fitted on each worker). Each round then runs the same
tasks twice, in alternating order: all of them on one worker, and split evenly over both
(a static split, so both halves hold the same number of beams). A task fits several beams
(``run_prbdm_beam``: truth and fits, as ``pinflex batch prbdm`` does), so Dask's per-task
overhead is small against the work. The efficiency of a round is ``T1 / (2 T2)`` with T1 and
T2 the wall times of the one- and two-worker runs; median and range over the rounds are
printed, with the load average before and after (other work on the machine takes cores from
the two-worker run first, so a loaded machine lowers the figure) and the CPU time the tasks
report (the same work in both runs).

Run: ``python benchmarks/bench_batch_efficiency.py [--quick] [--rounds R] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import os
import time


def fit_beams(study: dict, seed: int, items: list[int], configs: list) -> float:
    """Fit every beam of ``items`` on this worker; return the CPU seconds spent."""
    from pinflex.batch.tasks import run_prbdm_beam

    c0 = time.process_time()
    for item in items:
        rows = run_prbdm_beam(study, seed, item, configs)
        if any(r["status"] != "ok" for r in rows):
            raise RuntimeError(f"beam {item} failed: {[r['error'] for r in rows]}")
    return time.process_time() - c0


def _load() -> float:
    return os.getloadavg()[0]


def main() -> None:
    """Run the rounds and print the efficiency."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="3R fits, 2 starts, 2 tasks of 2 beams, 3 rounds")
    parser.add_argument("--rounds", type=int, default=None, help="rounds (default 5)")
    parser.add_argument("--beams-per-task", type=int, default=None)
    parser.add_argument("--tasks", type=int, default=None, help="tasks per run (even)")
    parser.add_argument("--json", default=None, metavar="FILE", help="write the numbers")
    args = parser.parse_args()
    from distributed import Client, LocalCluster, wait

    from pinflex.batch.tasks import PrbdmStudy

    links, starts = ((3,), 2) if args.quick else ((4,), 4)
    per_task = args.beams_per_task or (2 if args.quick else 3)
    n_tasks = args.tasks or (2 if args.quick else 4)
    rounds = args.rounds or (3 if args.quick else 5)
    if n_tasks % 2:
        raise SystemExit("--tasks must be even (the two-worker run splits them in halves)")
    study = PrbdmStudy(seed=15, n_beams=per_task * n_tasks, links=links, n_starts=starts)
    payload = {"beam": study.beam_settings(), "truth": study.truth_settings()}
    configs = [(f"c{i}", c) for i, c in enumerate(study.configs())]
    groups = [list(range(k * per_task, (k + 1) * per_task)) for k in range(n_tasks)]
    load_before = _load()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None,
                      host="127.0.0.1") as cluster, Client(cluster) as client:
        workers = sorted(client.scheduler_info()["workers"])
        # Warm-up: import and one full beam on each worker.
        wait([client.submit(fit_beams, payload, 15, [1000 + i], configs, workers=[w],
                            allow_other_workers=False, pure=False)
              for i, w in enumerate(workers)])

        def run(split: bool) -> tuple[float, float]:
            t0 = time.perf_counter()
            futures = [client.submit(fit_beams, payload, 15, g, configs,
                                     workers=[workers[k % 2 if split else 0]],
                                     allow_other_workers=False, pure=False)
                       for k, g in enumerate(groups)]
            cpu = sum(f.result() for f in futures)
            return time.perf_counter() - t0, cpu

        t1s, t2s, c1s, c2s, eff = [], [], [], [], []
        for r in range(rounds):
            order = (False, True) if r % 2 == 0 else (True, False)
            res = {split: run(split) for split in order}
            (t1, c1), (t2, c2) = res[False], res[True]
            t1s.append(t1)
            t2s.append(t2)
            c1s.append(c1)
            c2s.append(c2)
            eff.append(t1 / (2.0 * t2))
            print(f"   round {r + 1}: 1 worker {t1:.1f} s, 2 workers {t2:.1f} s -> efficiency "
                  f"{eff[-1]:.3f} (task CPU {c1:.1f} / {c2:.1f} s; load {_load():.1f})",
                  flush=True)
    load_after = _load()
    e = sorted(eff)
    beams = per_task * n_tasks
    print(f"== batch efficiency at 2 workers: {n_tasks} tasks of {per_task} beams "
          f"({links[0]}R combined fits, {starts} starts, truth included) per run, {rounds} "
          f"rounds, warm workers, one thread each")
    print(f"   efficiency T1 / (2 T2): median {e[len(e) // 2]:.3f}, range {e[0]:.3f}-{e[-1]:.3f}"
          f" (target >= 0.9)")
    print(f"   wall per beam: 1 worker {sorted(t1s)[rounds // 2] / beams:.2f} s, 2 workers "
          f"{sorted(t2s)[rounds // 2] / beams:.2f} s; task CPU per beam "
          f"{sorted(c1s)[rounds // 2] / beams:.2f} s")
    print(f"   load average (1 min) before {load_before:.1f}, after {load_after:.1f} on "
          f"{os.cpu_count()} cores")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"efficiency": eff, "t1_s": t1s, "t2_s": t2s, "cpu1_s": c1s,
                       "cpu2_s": c2s, "tasks": n_tasks, "beams_per_task": per_task,
                       "links": list(links), "starts": starts, "load_before": load_before,
                       "load_after": load_after}, fh, indent=1)


if __name__ == "__main__":
    main()
