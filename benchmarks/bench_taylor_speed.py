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
     times the assignment reports) [target <= 30 ms]

Run: ``python benchmarks/bench_taylor_speed.py [--quick] [--cpu] [--json FILE]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, fmt_ratio, interleaved, pin_single_thread, ratio_stats

pin_single_thread()

import numpy as np  # noqa: E402
import scipy.linalg as sla  # noqa: E402

from pinflex.assignment.benchmark_a import (  # noqa: E402
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
                        "machine then inflates neither side by waiting; sections 1-2)")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    rounds = 5 if args.quick else 7
    clock = time.thread_time if args.cpu else time.perf_counter
    print(f"bench_taylor_speed: {blas_threads()}; {rounds} interleaved rounds per ratio; "
          f"{'thread CPU' if args.cpu else 'wall'} time")
    out = {"blas": blas_threads(), "rounds": rounds, "clock": "cpu" if args.cpu else "wall"}

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

    a = benchmark_model()
    traj = benchmark_trajectory(a)
    Q = traj.q
    tm = expand(a, Q0, np.zeros(2), order=4, design=[])
    exact = a.frequencies(Q, np.zeros(2), n_modes=1)[:, 0]
    err = float(np.max(np.abs(tm.evaluate(Q, quantity="freq_hz", warn=False)[:, 0] / exact - 1)))
    reps = 200  # the polynomial side is ~1000x faster: time 200 calls per round, report one
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
    out["evaluation"] = {**s_eval, "max_error": err}
    out["radius_check"] = s_check

    runs = []
    for _ in range(rounds):
        runs.append(assign_mode1(a, traj, report_modes=()).timings_s)
    keys = ("expansion_and_build", "qp", "exact_verification")
    total = np.array([sum(r[k] for k in keys) for r in runs])
    stages = ", ".join(f"{k} {1e3 * np.median([r[k] for r in runs]):.1f}" for k in keys)
    print(f"\n3. benchmark A end to end: median {1e3 * np.median(total):.1f} ms (range "
          f"{1e3 * total.min():.1f}-{1e3 * total.max():.1f}) over {rounds} runs (target <= 30 ms); "
          f"stages [ms]: {stages}")
    out["end_to_end"] = {"median_s": float(np.median(total)), "min_s": float(total.min()),
                         "max_s": float(total.max())}
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
