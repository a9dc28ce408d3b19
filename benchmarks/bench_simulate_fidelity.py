"""Speed-accuracy of a simulation's fidelity knobs: time step and retained modes (benchmark A).

Run: ``python benchmarks/bench_simulate_fidelity.py [--quick] [--json] [--out DIR]``.

One process, one motion (benchmark A's pick-and-place, baseline design, 0.1 s held), one
converged reference: the default integrator with ``tol`` = 1e-4 (``--quick``: 1e-3) and 8 exact
coefficient evaluations per sample interval. For every setting: the tip-deflection error
``max |δ − δ_ref| / max |δ_ref|`` and the CPU time (``time.process_time``, median of
``--rounds``) of the simulation plus its report.

* time step: the default integrator at ``N`` coarse steps (one pair N, 2N; Richardson
  extrapolated), with its own error estimate beside the true error; also ``tol`` ladders;
* retained modes: the reduced simulation on the k lowest locked-joint modes of 3 poses
  (start, middle, end; up to 3k vectors) at the default step settings, k = 1 ... nx/3.

``--out DIR`` writes ``simulate_fidelity.png`` (error against CPU time, both knobs).
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
sys.path.insert(0, str(ROOT / "benchmarks"))


def main(argv=None) -> int:
    """Run the benchmark."""
    from interleave import blas_threads, pin_single_thread

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer settings, looser reference")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--out", default=None, help="folder for simulate_fidelity.png")
    ap.add_argument("--rounds", type=int, default=None, help="timing rounds (default 3, 1 quick)")
    args = ap.parse_args(argv)
    if "numpy" not in sys.modules:
        pin_single_thread()
    import numpy as np

    from pinflex.assignment.study import user_trajectory
    from pinflex.dynamics import ErlsDynamics, simulate_prescribed, vibration_report
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import PinflexWarning

    rounds = args.rounds or (1 if args.quick else 3)
    model = FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    traj = user_trajectory(model, "benchmark_a")
    dyn = ErlsDynamics(model, y=np.zeros(model.ny))
    after = 0.1

    def run(**kw):
        best = []
        for _ in range(rounds):
            c0 = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", PinflexWarning)
                sim = simulate_prescribed(dyn, traj, after_s=after, **kw)
            rep = vibration_report(dyn, sim)
            best.append(time.process_time() - c0)
        return sim, rep, float(np.median(best))

    ref_sim, ref, ref_cpu = run(tol=1e-3 if args.quick else 1e-4, grid_per_interval=8)
    scale = float(np.abs(ref.deflection_m).max())

    def err(rep):
        return float(np.abs(rep.deflection_m - ref.deflection_m).max() / scale)

    n_default = int(np.ceil(traj.duration_s * 5000.0 / 2.0))
    steps_list = ([n_default // 4, n_default // 2, n_default, 2 * n_default] if args.quick else
                  [n_default // 8, n_default // 4, n_default // 2, n_default, 2 * n_default,
                   4 * n_default])
    step_rows = []
    for n in steps_list:
        sim, rep, cpu = run(steps=n)
        step_rows.append({"setting": f"steps N={n}", "steps": n, "h_ms": 1e3 * traj.duration_s / n,
                          "error": err(rep), "estimate": sim.error_estimate, "cpu_s": cpu})
    tol_rows = []
    for tol in ([1e-2] if args.quick else [3e-2, 1e-2, 3e-3]):
        sim, rep, cpu = run(tol=tol, steps=n_default // 4)
        tol_rows.append({"setting": f"tol={tol:g}", "tol": tol, "fine_steps": sim.steps,
                         "error": err(rep), "estimate": sim.error_estimate,
                         "observed_order": sim.observed_order, "cpu_s": cpu})
    ks = [1, 2, 4, 7] if args.quick else list(range(1, model.nx // 3 + 1))
    mode_rows = []
    _, _, full_cpu = run()
    for k in ks:
        sim, rep, cpu = run(modes=k)
        mode_rows.append({"setting": f"k={k}", "k": k, "error": err(rep), "cpu_s": cpu,
                          "speedup": full_cpu / cpu})
    out = {
        "blas_threads": blas_threads(), "load_average": list(os.getloadavg()),
        "rounds": rounds, "simulated_s": traj.duration_s + after,
        "reference": {"tol": 1e-3 if args.quick else 1e-4, "estimate": ref_sim.error_estimate,
                      "fine_steps": ref_sim.steps, "cpu_s": ref_cpu},
        "default_cpu_s": full_cpu, "time_step": step_rows, "tol": tol_rows, "modes": mode_rows,
    }
    if args.out:
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        from matplotlib.figure import Figure

        fig = Figure(figsize=(7.0, 4.2), layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        ax.loglog([r["cpu_s"] for r in step_rows], [max(r["error"], 1e-9) for r in step_rows],
                  "o-", label="time step (N, 2N; extrapolated): true error")
        ax.loglog([r["cpu_s"] for r in step_rows], [r["estimate"] for r in step_rows], "o:",
                  color="C0", alpha=0.5, label="its Richardson estimate (finer run)")
        for r in step_rows:
            ax.annotate(f"h={r['h_ms']:.2g} ms", (r["cpu_s"], max(r["error"], 1e-9)), fontsize=7)
        ax.loglog([r["cpu_s"] for r in mode_rows], [max(r["error"], 1e-9) for r in mode_rows],
                  "s-", color="C1", label="retained locked modes k per pose (3 poses)")
        for r in mode_rows:
            ax.annotate(f"k={r['k']}", (r["cpu_s"], max(r["error"], 1e-9)), fontsize=7)
        ax.set_xlabel("CPU time of simulation + report [s] (1.61 s simulated)")
        ax.set_ylabel("tip deflection error / peak (vs converged)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
        ax.set_title("benchmark A, prescribed motion: speed-accuracy of step and modes",
                     fontsize=9)
        Path(args.out).mkdir(parents=True, exist_ok=True)
        p = Path(args.out) / "simulate_fidelity.png"
        fig.savefig(p, dpi=120)
        out["chart"] = str(p)
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"benchmark A, {out['simulated_s']:.2f} s simulated; {out['blas_threads']}; load "
          f"average {out['load_average'][0]:.1f}; reference tol {out['reference']['tol']:g} "
          f"({ref_sim.steps} fine steps, {ref_cpu:.2f} s CPU)")
    print("time step (one pair N, 2N, extrapolated):")
    for r in step_rows:
        print(f"  N = {r['steps']:6d} (h = {r['h_ms']:.3f} ms): error {100 * r['error']:.4f} %, "
              f"estimate {100 * r['estimate']:.4f} %, {r['cpu_s']:.3f} s CPU")
    print("tol ladder:")
    for r in tol_rows:
        print(f"  tol = {r['tol']:g}: {r['fine_steps']} fine steps, error {100 * r['error']:.4f} "
              f"%, estimate {100 * r['estimate']:.4f} %, order {r['observed_order']:.2f}, "
              f"{r['cpu_s']:.3f} s CPU")
    print(f"retained modes (default steps; full model {full_cpu:.3f} s CPU):")
    for r in mode_rows:
        print(f"  k = {r['k']:2d}: error {100 * r['error']:.4f} %, {r['cpu_s']:.3f} s CPU, "
              f"speed-up {r['speedup']:.2f}")
    if "chart" in out:
        print(f"wrote {out['chart']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
