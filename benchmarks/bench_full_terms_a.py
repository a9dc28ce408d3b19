"""What eq. (1) leaves out on benchmark A's own pick-and-place: eq. (1) against ``terms="full"``.

Run: ``python benchmarks/bench_full_terms_a.py [--speedups 1 3 10] [--tol 1e-5] [--json]``.

Benchmark A's elbow sits on the flexible first link, so its full terms are the locked system's
second variation with the joint's elastic offset (``pinflex.dynamics.speed``; a beam split at
such a joint equals the one beam to 1e-9, ``tests/test_speed_joints.py``). For the motion run
as published and run ``k`` times faster (the same path in ``1/k`` of the time), prints the
validity indicator of eq. (1) (``max |ω|²/ω₁²``, ``max |α|/ω₁²`` against the locked modes), the
peak tip deflection during the motion and the residual amplitude after it with each set of
terms, their relative differences, the Richardson error estimates of both runs (the
difference is a finding only where it is well above them) and the CPU times. Baseline design,
no gravity, 0.3 s held after the stop, ``tol`` on the fixed-step integrator.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
import warnings
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def run(speedups, tol):
    """One row per speed-up (dictionaries)."""
    import numpy as np

    from pinflex.assignment.study import user_trajectory
    from pinflex.dynamics import ErlsDynamics, simulate_prescribed, vibration_report
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import ModelValidityWarning
    from pinflex.trajectory import Trajectory

    model = FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    base = user_trajectory(model, "benchmark_a")
    dyn = ErlsDynamics(model, y=np.zeros(model.ny))
    rows = []
    for k in speedups:
        traj = Trajectory(np.asarray(base.times_s) / k, base.q, base.joint_names)
        out: dict = {"speedup": k, "duration_s": traj.duration_s}
        for terms in ("eq1", "full"):
            tic = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ModelValidityWarning)
                sim = simulate_prescribed(dyn, traj, after_s=0.3, terms=terms, tol=tol)
            rep = vibration_report(dyn, sim)
            out[terms] = {"tip_peak_m": rep.tip_peak_m,
                          "residual_amplitude_m": rep.residual_amplitude_m,
                          "error_estimate": sim.error_estimate,
                          "cpu_s": time.process_time() - tic}
            v = sim.validity
            out["indicator"] = v.indicator
            out["max_speed_ratio"], out["max_accel_ratio"] = v.max_speed_ratio, v.max_accel_ratio
        e, f = out["eq1"], out["full"]
        out["peak_difference"] = abs(e["tip_peak_m"] / f["tip_peak_m"] - 1.0)
        out["residual_difference"] = abs(e["residual_amplitude_m"]
                                         / f["residual_amplitude_m"] - 1.0)
        rows.append(out)
    return rows


def main(argv=None) -> int:
    """Run the benchmark and print a table (or JSON)."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--speedups", type=float, nargs="+", default=[1.0, 3.0, 10.0])
    ap.add_argument("--tol", type=float, default=1e-5, help="Richardson tolerance of both runs")
    ap.add_argument("--json", action="store_true", help="print the rows as JSON")
    args = ap.parse_args(argv)
    rows = run(args.speedups, args.tol)
    if args.json:
        print(json.dumps(rows, indent=1))
        return 0
    print(f"benchmark A, baseline design; tol {args.tol:g}; load average "
          f"{os.getloadavg()[0]:.1f} on {os.cpu_count()} cores")
    print(" speed-up | indicator (speed, accel) | tip peak eq1 / full [mm] | diff    | "
          "residual eq1 / full [mm] | diff    | estimates eq1 / full | CPU eq1 / full [s]")
    for r in rows:
        e, f = r["eq1"], r["full"]
        print(f" {r['speedup']:8g} | {r['indicator']:.2e} ({r['max_speed_ratio']:.1e}, "
              f"{r['max_accel_ratio']:.1e}) | {1e3 * e['tip_peak_m']:.5f} / "
              f"{1e3 * f['tip_peak_m']:.5f} | {100 * r['peak_difference']:.4f} % | "
              f"{1e3 * e['residual_amplitude_m']:.5f} / {1e3 * f['residual_amplitude_m']:.5f} | "
              f"{100 * r['residual_difference']:.4f} % | {e['error_estimate']:.1e} / "
              f"{f['error_estimate']:.1e} | {e['cpu_s']:.1f} / {f['cpu_s']:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
