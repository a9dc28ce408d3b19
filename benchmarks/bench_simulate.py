"""Time simulation of benchmark A's pick-and-place: cost, accuracy, modal truncation.

Run: ``python benchmarks/bench_simulate.py [--quick] [--json] [--out DIR]``.

Measures, in one process (BLAS threads as set in the environment; use
``OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1``):

* the prescribed-motion simulation of benchmark A (baseline design, 1.51 s of motion and
  ``--after`` s held) at the default tolerances: compute time, steps, cost per simulated second
  (SPEC §7 target: one second of motion in under one second of compute), median and range over
  ``--rounds`` rounds;
* its error against a tight reference (``rtol = 1e-6``, 4 exact coefficient evaluations per
  sample interval): max |δ_tip − δ_ref| / max |δ_ref|;
* the reduced simulation on the k lowest locked-joint modes of 3 poses along the motion
  (start, middle, end; up to 3k basis vectors), k = 1 .. nx/3: error against the full
  simulation at the same tolerances and speed-up, charted with ``--out``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def _basis_size(dyn, traj, k: int) -> int:
    from pinflex.dynamics.motion import JointMotion
    from pinflex.dynamics.simulate import PrescribedSystem, _ReducedSystem

    return _ReducedSystem(PrescribedSystem(dyn, JointMotion(traj)), k).nx


def main(argv=None) -> int:
    """Run the benchmark."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="0.1 s after the stop, k in {1, 2, 4}")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--out", default=None, help="folder for the truncation chart")
    ap.add_argument("--after", type=float, default=None, help="held time after the stop [s]")
    ap.add_argument("--rounds", type=int, default=None, help="timing rounds (default 5, 1 quick)")
    args = ap.parse_args(argv)

    from pinflex.assignment.study import user_trajectory
    from pinflex.dynamics import ErlsDynamics, simulate_prescribed, vibration_report
    from pinflex.erls import FlexibleModel

    after = args.after if args.after is not None else (0.1 if args.quick else 0.5)
    rounds = args.rounds or (1 if args.quick else 5)
    model = FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    traj = user_trajectory(model, "benchmark_a")
    dyn = ErlsDynamics(model, y=np.zeros(model.ny))
    simulated = traj.duration_s + after

    def run(**kw):
        t0 = time.perf_counter()
        sim = simulate_prescribed(dyn, traj, after_s=after, **kw)
        rep = vibration_report(dyn, sim)
        return sim, rep, time.perf_counter() - t0

    ref_sim, ref, t_ref = run(rtol=1e-6, grid_per_interval=4)
    times, reps = [], []
    for _ in range(rounds):
        sim, rep, _ = run()
        times.append(sim.time_s)
        reps.append((sim, rep))
    sim, rep = reps[-1]
    scale = np.abs(ref.deflection_m).max()
    err_default = float(np.abs(rep.deflection_m - ref.deflection_m).max() / scale)
    ks = [1, 2, 4] if args.quick else list(range(1, model.nx // 3 + 1))
    trunc = []
    for k in ks:
        s_k, r_k, _ = run(modes=k)
        trunc.append({"k": k, "basis": _basis_size(dyn, traj, k),
                      "error": float(np.abs(r_k.deflection_m - rep.deflection_m).max()
                                              / np.abs(rep.deflection_m).max()),
                      "time_s": s_k.time_s, "speedup": float(np.median(times)) / s_k.time_s,
                      "steps": s_k.steps})
    out = {
        "blas_threads": {k: __import__("os").environ.get(k) for k in
                         ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS")},
        "simulated_s": simulated, "motion_s": traj.duration_s, "after_s": after,
        "time_s_median": float(np.median(times)), "time_s_range": [min(times), max(times)],
        "cost_per_simulated_s": float(np.median(times)) / simulated,
        "steps": sim.steps, "error_default_vs_tight": err_default,
        "reference": {"time_s": ref_sim.time_s, "steps": ref_sim.steps},
        "tip_peak_m": rep.tip_peak_m, "residual_amplitude_m": rep.residual_amplitude_m,
        "dominant_frequency_hz": rep.dominant_frequency_hz,
        "locked_mode1_hz": rep.reference_hz[0], "truncation": trunc,
        "peer": "not measured (see the module doc)",
    }
    if args.out:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.5, 4.0), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        kk = [t["k"] for t in trunc]
        ax.semilogy(kk, [max(t["error"], 1e-16) for t in trunc], "o-", label="error vs full")
        ax.set_xlabel("locked-joint modes kept per pose, k (3 poses)")
        ax.set_ylabel("max |δ_k − δ_full| / max |δ_full|")
        ax2 = ax.twinx()
        ax2.plot(kk, [t["speedup"] for t in trunc], "s--", color="C1", label="speed-up")
        ax2.set_ylabel("speed-up (full time / reduced time)")
        ax.grid(alpha=0.3, which="both")
        ax.set_title("benchmark A, tip deflection: modal truncation", fontsize=9)
        Path(args.out).mkdir(parents=True, exist_ok=True)
        p = Path(args.out) / "simulate_truncation.png"
        fig.savefig(p, dpi=120)
        out["chart"] = str(p)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"benchmark A prescribed motion: {simulated:.2f} s simulated in "
          f"{out['time_s_median']:.3f} s (median of {rounds}; range "
          f"{min(times):.3f}-{max(times):.3f} s) = {out['cost_per_simulated_s']:.3f} s of "
          f"compute per simulated second ({sim.steps} steps); target < 1")
    print(f"  error at default tolerances vs rtol 1e-6: {100 * err_default:.3f} % of the peak")
    print(f"  tip peak {1e3 * rep.tip_peak_m:.4f} mm, residual {1e3 * rep.residual_amplitude_m:.4f}"
          f" mm at {rep.dominant_frequency_hz:.3f} Hz (locked mode 1 {rep.reference_hz[0]:.3f} Hz)")
    for t in trunc:
        print(f"  k = {t['k']:2d} ({t['basis']:2d} vectors): error {100 * t['error']:8.4f} %, "
              f"{t['time_s']:.3f} s, speed-up {t['speedup']:.2f}")
    if "chart" in out:
        print(f"wrote {out['chart']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
