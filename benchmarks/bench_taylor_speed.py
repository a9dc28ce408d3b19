"""Speed of the Taylor modal model: expansion, evaluation, radius check, end to end.

Every ratio is measured interleaved in this one process (median and range over the rounds),
single-thread BLAS unless you set a count; the machine may be loaded, so read the ranges.

  1  expansion of the flexible UR5 (6 joints + payload), p = 4: pinflex.parametric.expand
     (solver coordinates, pinflex.parametric.conditioned) against the nodal-coordinate route
     it replaced (matrix_jets + eigh + eigen_jets + spectrum slopes), same process; p = 6 time
     [target: >= 10x faster, <= 0.1 s]
  2  benchmark A, p = 4: evaluation at new poses (monomials rebuilt each call) along the 152
     samples against the exact model on the same samples, and the error [target >= 1000x at
     <= 0.1 %]; with the radius check on against off [target <= 1.5x]
  3  benchmark A end to end: expansion and QP build, ProxQP, exact verification (the stage
     times the assignment reports, wall and thread CPU) [target <= 30 ms]; beside it the exact
     frequencies of the same 152 poses, the floor of any exact verification

Run: ``python benchmarks/bench_taylor_speed.py [--quick] [--cpu] [--sections 123]
[--rounds N] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, fmt_ratio, interleaved, pin_single_thread, ratio_stats

pin_single_thread()

import numpy as np  # noqa: E402
import scipy.linalg as sla  # noqa: E402

from pinflex.cases.benchmark_a import (  # noqa: E402
    Q0,
    assign_mode1,
    benchmark_model,
    benchmark_trajectory,
)
from pinflex.erls import FlexibleModel  # noqa: E402
from pinflex.parametric import expand, matrix_jets  # noqa: E402
from pinflex.parametric.eigen import eigen_jets, spectrum_slopes  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
QU = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])


def nodal_expand(model, q0, order):
    """The replaced route: nodal-coordinate jets, eigh at q0, recursion, spectrum slopes."""
    space, M, K, _, _ = matrix_jets(model, q0, order=order)
    w, V = sla.eigh(K[0], M[0], check_finite=False)
    lam, _ = eigen_jets(space, M, K, [model.n_rigid], eigvals0=w, eigvecs0=V)
    spectrum_slopes(space, M, K, w[model.n_rigid:], V[:, model.n_rigid:])
    return lam


def main(argv=None):
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer rounds")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    parser.add_argument("--cpu", action="store_true",
                        help="time this thread's CPU time instead of wall time (a loaded "
                        "machine then inflates neither side by waiting; sections 1-2; "
                        "section 3 always prints both)")
    parser.add_argument("--sections", default="123", help="which sections to run (default 123)")
    parser.add_argument("--rounds", type=int, default=None,
                        help="interleaved rounds per ratio (default 7, --quick 5)")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    rounds = args.rounds or (5 if args.quick else 7)
    clock = time.thread_time if args.cpu else time.perf_counter
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"bench_taylor_speed: {blas_threads()}; {rounds} interleaved rounds per ratio; "
          f"{'thread CPU' if args.cpu else 'wall'} time; load average {load:.2f} at the start")
    out = {"blas": blas_threads(), "rounds": rounds, "clock": "cpu" if args.cpu else "wall",
           "load_average_start": load}

    if "1" in args.sections:
        section_expansion(out, rounds, clock)
    a = benchmark_model()
    traj = benchmark_trajectory(a)
    Q = traj.q
    if "2" in args.sections:
        section_evaluation(out, a, Q, rounds, clock)
    if "3" in args.sections:
        section_end_to_end(out, a, traj, rounds)
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")


def section_expansion(out, rounds, clock):
    """Section 1: UR5 expansion against the nodal route, and p = 6."""
    ur5 = FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml")
    new = expand(ur5, QU, order=4)
    old = nodal_expand(ur5, QU, 4)
    agree = float(np.max(np.abs(new.eigval_jets[:, 0] - old[:, 0])) / np.max(np.abs(old)))
    t = interleaved({"new": lambda: expand(ur5, QU, order=4),
                     "old": lambda: nodal_expand(ur5, QU, 4)}, rounds=max(3, rounds - 2),
                    clock=clock)
    s = ratio_stats(t["old"], t["new"])
    print(f"\n1. UR5 expansion, p = 4, {new.space.nvars} variables: "
          f"{1e3 * s['den_median_s']:.0f} ms "
          f"vs the nodal route {1e3 * s['num_median_s']:.0f} ms -> {fmt_ratio(s)} faster "
          f"(target >= 10x, <= 100 ms); coefficients agree to {agree:.1e} (relative)")
    t6 = interleaved({"p6": lambda: expand(ur5, QU, order=6)}, rounds=3, clock=clock)["p6"]
    print(f"   p = 6: {1e3 * np.median(t6):.0f} ms (median of 3)")
    out["expansion"] = {**s, "speedup_median": s["ratio_median"], "coef_agreement": agree,
                        "p6_median_s": float(np.median(t6))}



def section_evaluation(out, a, Q, rounds, clock):
    """Section 2: evaluation at new poses against the exact model; the radius check."""
    from pinflex.parametric import evaluation as taylor

    tm = expand(a, Q0, np.zeros(2), order=4, design=[])
    exact = a.frequencies(Q, np.zeros(2), n_modes=1)[:, 0]
    err = float(np.max(np.abs(tm.evaluate(Q, quantity="freq_hz", warn=False)[:, 0] / exact - 1)))
    reps = 200  # the polynomial side is ~1000x faster: time 200 calls per round, report one
    # the NumPy path first: what a process's first KERNEL_AFTER two-joint evaluations take
    kept, taylor._KERNEL[:] = list(taylor._KERNEL), [None]
    t_np = interleaved({
        "exact": lambda: a.frequencies(Q, np.zeros(2), n_modes=1),
        "taylor": lambda: [tm.evaluate(Q, quantity="freq_hz", warn=False) for _ in range(reps)],
    }, rounds=rounds, number=1, clock=clock)
    t_np["taylor"] = t_np["taylor"] / reps
    taylor._KERNEL[:] = kept
    s_np = ratio_stats(t_np["exact"], t_np["taylor"])
    c0 = time.perf_counter()
    ready = taylor.prepare_kernel()
    prep = time.perf_counter() - c0
    t = interleaved({
        "exact": lambda: a.frequencies(Q, np.zeros(2), n_modes=1),
        "taylor": lambda: [tm.evaluate(Q, quantity="freq_hz", warn=False) for _ in range(reps)],
    }, rounds=rounds, number=1, clock=clock)
    t["taylor"] = t["taylor"] / reps
    t_fast = interleaved({"taylor": lambda: tm.evaluate(Q, quantity="freq_hz", warn=False),
                          "checked": lambda: tm.evaluate(Q, quantity="freq_hz", warn=True)},
                         rounds=rounds, number=reps, clock=clock)
    s_eval = ratio_stats(t["exact"], t["taylor"])
    s_check = ratio_stats(t_fast["checked"], t_fast["taylor"])
    print(f"\n2. benchmark A, p = 4, 152 new poses: exact model (FlexibleModel.frequencies, "
          f"batched, mode 1) {1e3 * s_eval['num_median_s']:.2f} ms, polynomial (monomials "
          f"rebuilt, radius check off) {1e6 * s_eval['den_median_s']:.1f} us -> "
          f"{fmt_ratio(s_eval)} (target >= 1000x), max error {100 * err:.3f} % (target <= 0.1 %)")
    print(f"   radius check on vs off: {1e6 * s_check['num_median_s']:.1f} us vs "
          f"{1e6 * s_check['den_median_s']:.1f} us -> {fmt_ratio(s_check)} (target <= 1.5x)")
    print(f"   (compiled kernel: {'prepared' if ready else 'NOT AVAILABLE (no numba)'} in "
          f"{prep:.2f} s wall before timing; a process prepares it in the background after "
          f"{taylor.KERNEL_AFTER} two-joint evaluations. Before that, the NumPy path: "
          f"{1e6 * s_np['den_median_s']:.1f} us -> {fmt_ratio(s_np)} the exact model)")
    out["evaluation"] = {**s_eval, "max_error": err, "kernel": bool(ready),
                         "kernel_prepare_s": prep}
    out["evaluation_numpy_path"] = s_np
    out["radius_check"] = s_check


def section_end_to_end(out, a, traj, rounds):
    """Section 3: benchmark A end to end, wall and CPU stage clocks."""
    Q = traj.q
    # every round: one assignment (its stage clocks: wall and this thread's CPU), then the
    # exact frequencies of the same 152 poses at its design (the floor of any verification)
    runs, cpus, floor = [], [], []
    for r in range(rounds + 1):
        res = assign_mode1(a, traj, report_modes=())
        c0 = time.thread_time()
        a.frequencies(Q, res.y, n_modes=4)
        if r:  # round 0 warms the caches
            floor.append(time.thread_time() - c0)
            runs.append(res.timings_s)
            cpus.append(res.cpu_timings_s)
    keys = ("expansion_and_build", "qp", "exact_verification")
    e2e = {}
    for label, rows in (("wall", runs), ("cpu", cpus)):
        total = np.array([sum(r[k] for k in keys) for r in rows])
        stages = ", ".join(f"{k} {1e3 * np.median([r[k] for r in rows]):.1f}" for k in keys)
        head = "\n3. " if label == "wall" else "   "
        print(f"{head}benchmark A end to end ({label} time): median "
              f"{1e3 * np.median(total):.1f} ms (range {1e3 * total.min():.1f}-"
              f"{1e3 * total.max():.1f}) over {rounds} runs "
              f"(target <= 30 ms); stages [ms]: {stages}")
        e2e[label] = {"median_s": float(np.median(total)), "min_s": float(total.min()),
                      "max_s": float(total.max()),
                      "stages_median_s": {k: float(np.median([r[k] for r in rows]))
                                          for k in keys}}
    ratio = e2e["cpu"]["median_s"] / float(np.median(floor))
    print(f"   exact frequencies of the same 152 poses (FlexibleModel.frequencies, 4 modes, "
          f"CPU): {1e3 * np.median(floor):.1f} ms median; end to end / that sweep "
          f"{ratio:.2f}x, exact verification / that sweep "
          f"{e2e['cpu']['stages_median_s']['exact_verification'] / float(np.median(floor)):.2f}x"
          " (CPU medians)")
    out["end_to_end"] = {**e2e["wall"], "cpu": e2e["cpu"],
                         "frequencies_152_cpu_median_s": float(np.median(floor)),
                         "cpu_ratio_to_frequencies": ratio}


if __name__ == "__main__":
    main()
