"""How well the Taylor model's error estimate (the radius warning) tracks the actual error.

Run: ``python benchmarks/bench_radius.py [--quick] [--json]``. On benchmark A (planar, expansion
at q0 = [1.817, 5.312], y0 = [0.125, 0.125]), for orders 1..8, along 40 seeded random
directions in (q1, q2, m1, m2) and the five axis/elbow directions, offsets 0.03..2.5 (designs
kept inside their bounds), it compares the estimate of
:meth:`pinflex.parametric.TaylorModel.error_estimate` with the actual relative error of λ
against the exact model and prints

* ``missed``: sample-modes with an actual error above 1 % whose estimate is at most 1 %
  (a silent large error), and the largest actual/estimate ratio among them;
* ``cautious``: sample-modes with an actual error below 0.1 % whose estimate is above 1 %;
* the largest estimate along benchmark A's 152-sample trajectory for each order;
* the cost of the check: ``evaluate`` of 152 samples with and without it (p = 4, modes 1–3),
  interleaved in one process, median and range over rounds;
* the cost of verifying an assignment on tracked modes: ``verify_tracked`` (eigenpairs, MAC
  tracking from the expansion point) against the sorted exact frequencies
  (``exact_errors``) of the same 152 poses, interleaved likewise.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings

import numpy as np

from pinflex.assignment.study import builtin_path, user_trajectory
from pinflex.erls import FlexibleModel
from pinflex.parametric import expand

Q0 = np.array([1.817, 5.312])
Y0 = np.array([0.125, 0.125])


def sweep(model, orders, ndir, nt):
    """Missed and cautious counts of the error estimate over random directions."""
    rng = np.random.default_rng(1)
    D = rng.normal(size=(ndir, 4))
    D /= np.linalg.norm(D, axis=1)[:, None]
    D = np.vstack([D, [[0, 1, 0, 0], [1, 0, 0, 0], [0.7071, -0.7071, 0, 0], [0, 0, 1, 0],
                       [0, 0, 0, 1]]])
    ts = np.linspace(0.03, 2.5, nt)
    traj = user_trajectory(model, "benchmark_a")
    out = {"orders": list(orders), "samples": 0, "missed": 0, "worst_missed_ratio": 0.0,
           "cautious": 0, "trajectory_max_estimate": {}}
    for p in orders:
        tm = expand(model, Q0, Y0, order=p, modes=(1, 2, 3))
        est_t, _ = tm.error_estimate(tm.offsets(traj.q, warn=False))
        out["trajectory_max_estimate"][p] = float(est_t.max())
        for d in D:
            dx = ts[:, None] * d
            Y = Y0 + dx[:, 2:]
            ok = np.all((Y >= 0) & (Y <= 0.25), axis=1)
            if not ok.any():
                continue
            dx, Y = dx[ok], Y[ok]
            Q = Q0 + dx[:, :2]
            exact = (2 * np.pi * np.array([model.frequencies(q, y, n_modes=3)
                                           for q, y in zip(Q, Y)])) ** 2
            actual = np.abs(tm.evaluate(Q, Y, warn=False) / exact - 1)
            est, _ = tm.error_estimate(tm.offsets(Q, Y, warn=False))
            out["samples"] += actual.size
            miss = (actual > 1e-2) & (est <= 1e-2)
            out["missed"] += int(miss.sum())
            if miss.any():
                ratio = float(np.max(actual[miss] / np.maximum(est[miss], 1e-300)))
                out["worst_missed_ratio"] = max(out["worst_missed_ratio"], ratio)
            out["cautious"] += int(np.sum((actual < 1e-3) & (est > 1e-2)))
    return out


def check_cost(model, rounds):
    """Median and range of evaluate() time with / without the check, interleaved."""
    traj = user_trajectory(model, "benchmark_a")
    tm = expand(model, Q0, Y0, order=4, modes=(1, 2, 3))
    Q = traj.q
    tm.evaluate(Q)
    ratios = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(20):
            tm.evaluate(Q, warn=False)
        off = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(20):
            tm.evaluate(Q, warn=True)
        on = time.perf_counter() - t0
        ratios.append(on / off)
    return {"median": float(np.median(ratios)), "min": float(np.min(ratios)),
            "max": float(np.max(ratios)), "rounds": rounds}


def tracking_cost(model, rounds):
    """Median and range of verify_tracked / exact_errors time on benchmark A, interleaved."""
    from pinflex.assignment import Target, exact_errors
    from pinflex.assignment.targets import target_matrix
    from pinflex.assignment.verify import verify_tracked

    traj = user_trajectory(model, "benchmark_a")
    Q, y = traj.q, np.zeros(2)
    targets = [Target(1, 190.0)]
    tgt = target_matrix(targets, Q.shape[0])
    ref = (Q0, Y0)
    ratios = []
    for _ in range(rounds):
        t0 = time.perf_counter()
        for _ in range(5):
            exact_errors(model, Q, y, targets, [1, 2, 3, 4])
        plain = time.perf_counter() - t0
        t0 = time.perf_counter()
        for _ in range(5):
            verify_tracked(model, Q, y, tgt, [1], [1, 2, 3, 4], ref)
        tracked = time.perf_counter() - t0
        ratios.append(tracked / plain)
    return {"median": float(np.median(ratios)), "min": float(np.min(ratios)),
            "max": float(np.max(ratios)), "rounds": rounds}


def main():
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer directions and orders")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    model = FlexibleModel(builtin_path("two_link.urdf"), planar=True)
    if args.quick:
        res = sweep(model, (2, 4), 6, 10)
        cost = check_cost(model, 5)
    else:
        res = sweep(model, (1, 2, 3, 4, 6, 8), 40, 25)
        cost = check_cost(model, 9)
    res["check_cost_ratio"] = cost
    res["tracking_cost_ratio"] = track = tracking_cost(model, 5 if args.quick else 9)
    if args.json:
        print(json.dumps(res))
        return
    print(f"orders {res['orders']}, {res['samples']} sample-modes")
    print(f"missed (actual > 1 %, estimate <= 1 %): {res['missed']}"
          f" (worst actual/estimate {res['worst_missed_ratio']:.2f})")
    print(f"cautious (actual < 0.1 %, estimate > 1 %): {res['cautious']}")
    for p, e in res["trajectory_max_estimate"].items():
        print(f"  p = {p}: largest estimate along the benchmark A trajectory {100 * e:.3f} %")
    print(f"evaluate() with the check / without, 152 samples, p = 4: median {cost['median']:.2f}"
          f" (range {cost['min']:.2f}-{cost['max']:.2f}, {cost['rounds']} rounds)")
    print(f"tracked verification / sorted exact frequencies, 152 poses: median "
          f"{track['median']:.2f} (range {track['min']:.2f}-{track['max']:.2f}, "
          f"{track['rounds']} rounds)")


if __name__ == "__main__":
    main()
