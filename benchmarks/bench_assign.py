"""Benchmark A assignment: stage times, and the QP's answer against exact searches.

Run: ``python benchmarks/bench_assign.py``. Prints the compute time of each stage (Taylor
expansion and QP build, ProxQP solve, exact verification along 152 poses) and the end-to-end
time (SPEC §7 target: under 0.5 s), the difference between ProxQP's and SciPy's answers to the
same QP, and the best designs on the exact model from a zooming grid search over [0, 0.25]²,
by the QP's cost and by the largest error, beside the QP's design.
"""

from __future__ import annotations

import argparse
import time
import warnings
from pathlib import Path

import numpy as np

from pinflex.assignment import (
    Target,
    brute_force,
    build_assignment,
    exact_cost,
    solve_assignment_qp,
    solve_assignment_qp_scipy,
)
from pinflex.cases.benchmark_a import Q0, assign_mode1, benchmark_model, benchmark_trajectory

ROOT = Path(__file__).resolve().parents[1]


def main():
    """Run the benchmark."""
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    warnings.simplefilter("ignore")
    model = benchmark_model()
    traj = benchmark_trajectory(model)
    target = [Target(1, 190.0)]
    runs = []
    for _ in range(5):
        r = assign_mode1(model, traj, report_modes=())
        runs.append(r.timings_s)
    best = {k: min(t[k] for t in runs) for k in runs[0]}
    stages = ", ".join(f"{k} {1e3 * v:.1f}" for k, v in best.items())
    print(f"stage times (best of 5) [ms]: {stages}")
    end_to_end = best["expansion_and_build"] + best["qp"] + best["exact_verification"]
    print("benchmark A end to end (expansion + QP + exact verification): "
          f"{1e3 * end_to_end:.1f} ms "
          "(target < 500 ms)")
    print(f"design m1 = {r.design['m1']:.5f} kg, m2 = {r.design['m2']:.5f} kg; max error "
          f"{100 * r.max_error_before:.2f} % -> {100 * r.max_error_after:.2f} % (exact), "
          f"{r.solution.iterations} ProxQP iterations")
    problem, _ = build_assignment(model, traj, target, q0=Q0)
    a, b = solve_assignment_qp(problem), solve_assignment_qp_scipy(problem)
    print(f"ProxQP vs SciPy on the same QP: |dy difference| = {np.abs(a.dy - b.dy).max():.2e} kg")
    t0 = time.perf_counter()
    bf = brute_force(model, traj, target, points=21, zoom_levels=2)
    ours_cost, ours_err = exact_cost(model, traj, target, r.y[None])
    print(f"exact grid search ({bf.evaluations} designs, final spacing {bf.spacing[0]:.2e} kg, "
          f"{time.perf_counter() - t0:.1f} s):")
    print(f"  best cost      at m1, m2 = {np.round(bf.y_best_cost, 5).tolist()}: cost "
          f"{bf.best_cost:.4f} vs QP design {ours_cost[0]:.4f} "
          f"(gap {100 * (ours_cost[0] / bf.best_cost - 1):.2f} %)")
    print(f"  best max error at m1, m2 = {np.round(bf.y_best_max_error, 5).tolist()}: "
          f"{100 * bf.best_max_error:.2f} % vs QP design {100 * ours_err[0]:.2f} %")


if __name__ == "__main__":
    main()
