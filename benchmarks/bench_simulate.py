"""Time simulation of benchmark A's pick-and-place: cost per simulated second and accuracy.

Run: ``python benchmarks/bench_simulate.py [--quick] [--json] [--rounds N] [--peer]``.

Measures, in one process (single-thread BLAS unless the environment sets it), on benchmark A
(baseline design, 1.51 s of motion and ``--after`` s held):

* the prescribed-motion simulation with the default integrator (``"fixed"``: trapezoidal rule
  at two uniform step sizes, Richardson extrapolation) and with the adaptive generalized-α
  (``"newmark"``, the previous default), timed round by round interleaved: CPU time of the
  process (``time.process_time``; the machine may be shared) and wall time, median and range
  over ``--rounds`` rounds, per simulated second (target: under 1 s of compute per second);
  the report (tip deflection and metrics) is timed with it;
* the error of each against a converged run (``"fixed"`` with ``tol`` 1e-4, 8 coefficient
  evaluations per sample interval; ``--quick``: ``tol`` 1e-3): max |δ − δ_ref| / max |δ_ref| of
  the tip deflection, and the Richardson estimate the default run reports;
* with ``--peer`` (needs the ``peers`` extra, Exudyn): the same motion in Exudyn
  (``benchmarks/peer_exudyn.py``: ANCF cable elements, the same element counts, the same
  physical joint motion), at each step of ``--peer-steps``: its CPU time per simulated second and
  its tip deflection against our converged run, in the same run.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))


def main(argv=None) -> int:
    """Run the benchmark."""
    from interleave import blas_threads, pin_single_thread

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="0.1 s after the stop, 3 rounds, "
                    "looser reference")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--after", type=float, default=None, help="held time after the stop [s]")
    ap.add_argument("--rounds", type=int, default=None, help="timing rounds (default 5, 3 quick)")
    ap.add_argument("--peer", action="store_true", help="also run the Exudyn model")
    ap.add_argument("--peer-steps", type=float, nargs="+", default=None, metavar="H",
                    help="Exudyn time steps [s] (default 2e-4; without --quick 2e-4 1e-4 5e-5)")
    args = ap.parse_args(argv)
    if "numpy" not in sys.modules:
        pin_single_thread()
    import numpy as np

    from pinflex.assignment.study import user_trajectory
    from pinflex.dynamics import ErlsDynamics, simulate_prescribed, vibration_report
    from pinflex.erls import FlexibleModel

    after = args.after if args.after is not None else (0.1 if args.quick else 0.5)
    rounds = args.rounds or (3 if args.quick else 5)
    model = FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    traj = user_trajectory(model, "benchmark_a")
    dyn = ErlsDynamics(model, y=np.zeros(model.ny))
    simulated = traj.duration_s + after

    def run(**kw):
        c0, w0 = time.process_time(), time.perf_counter()
        sim = simulate_prescribed(dyn, traj, after_s=after, **kw)
        rep = vibration_report(dyn, sim)
        return sim, rep, time.process_time() - c0, time.perf_counter() - w0

    ref_tol = 1e-3 if args.quick else 1e-4
    ref_sim, ref, _, _ = run(tol=ref_tol, grid_per_interval=8)
    scale = float(np.abs(ref.deflection_m).max())
    sides = {"fixed": {}, "newmark": {"method": "newmark"}}
    cpu: dict = {k: [] for k in sides}
    wall: dict = {k: [] for k in sides}
    last: dict = {}
    for r in range(rounds):
        for name in (list(sides) if r % 2 == 0 else list(sides)[::-1]):
            sim, rep, c, w = run(**sides[name])
            cpu[name].append(c / simulated)
            wall[name].append(w / simulated)
            last[name] = (sim, rep)
    out: dict = {
        "blas_threads": blas_threads(), "load_average": list(os.getloadavg()),
        "simulated_s": simulated, "motion_s": traj.duration_s, "after_s": after,
        "rounds": rounds,
        "reference": {"tol": ref_tol, "estimate": ref_sim.error_estimate,
                      "steps": ref_sim.steps},
    }
    for name in sides:
        sim, rep = last[name]
        out[name] = {
            "cpu_per_simulated_s_median": float(np.median(cpu[name])),
            "cpu_per_simulated_s_range": [float(min(cpu[name])), float(max(cpu[name]))],
            "wall_per_simulated_s_median": float(np.median(wall[name])),
            "wall_per_simulated_s_range": [float(min(wall[name])), float(max(wall[name]))],
            "steps": sim.steps,
            "tip_error_vs_converged": float(np.abs(rep.deflection_m - ref.deflection_m).max()
                                            / scale),
            "error_estimate": (None if not np.isfinite(sim.error_estimate)
                               else sim.error_estimate),
        }
    ratio = np.array(cpu["newmark"]) / np.array(cpu["fixed"])
    out["speedup_cpu_vs_newmark"] = {"median": float(np.median(ratio)),
                                     "range": [float(ratio.min()), float(ratio.max())]}
    sim, rep = last["fixed"]
    out["tip_peak_m"] = rep.tip_peak_m
    out["residual_amplitude_m"] = rep.residual_amplitude_m
    out["dominant_frequency_hz"] = rep.dominant_frequency_hz
    out["locked_mode1_hz"] = rep.reference_hz[0]
    out["peer"] = None
    if args.peer:
        from peer_exudyn import compare_with_exudyn

        steps = args.peer_steps or ([2e-4] if args.quick else [2e-4, 1e-4, 5e-5])
        out["peer"] = compare_with_exudyn(traj, ref, after_s=after, steps_s=steps)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"benchmark A prescribed motion, {simulated:.2f} s simulated; {out['blas_threads']}; "
          f"load average {out['load_average'][0]:.1f} on {os.cpu_count()} cores; "
          f"{rounds} interleaved rounds")
    for name in sides:
        d = out[name]
        est = d["error_estimate"]
        print(f"  {name:8s}: {d['cpu_per_simulated_s_median']:.3f} s CPU per simulated s "
              f"(range {d['cpu_per_simulated_s_range'][0]:.3f}-"
              f"{d['cpu_per_simulated_s_range'][1]:.3f}), wall "
              f"{d['wall_per_simulated_s_median']:.3f} ({d['wall_per_simulated_s_range'][0]:.3f}-"
              f"{d['wall_per_simulated_s_range'][1]:.3f}); {d['steps']} steps; tip error vs "
              f"converged {100 * d['tip_error_vs_converged']:.3f} % of the peak"
              + ("" if est is None else f" (Richardson estimate {100 * est:.2f} %)"))
    s = out["speedup_cpu_vs_newmark"]
    print(f"  fixed vs newmark: {s['median']:.1f}x less CPU ({s['range'][0]:.1f}-"
          f"{s['range'][1]:.1f}); target < 1 s CPU per simulated s")
    print(f"  tip peak {1e3 * rep.tip_peak_m:.4f} mm, residual {1e3 * rep.residual_amplitude_m:.4f}"
          f" mm at {rep.dominant_frequency_hz:.3f} Hz (locked mode 1 {rep.reference_hz[0]:.3f} Hz)")
    for p in out["peer"] or []:
        ch = p["change_from_coarser"]
        print(f"  peer ({p['model']}): {p['cpu_per_simulated_s']:.3f} s CPU per simulated s; "
              f"tip deflection vs our converged run {100 * p['tip_difference']:.2f} % of the "
              "peak" + ("" if ch is None else f" (change from the coarser step "
                                              f"{100 * ch:.2f} %)"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
