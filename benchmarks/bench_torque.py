"""Cost of the torque drive on benchmark A: CPU seconds per simulated second, both routes.

Run: ``python benchmarks/bench_torque.py [--duration 0.02] [--rounds 3] [--after 0.5]
[--kp 3000] [--kd 30] [--json]``. Benchmark A's pick-and-place (baseline design, no point
masses, planar) driven by the rigid computed torque plus a PD servo on the motor angles, in one
process with single-thread BLAS (``interleave.pin_single_thread``), rounds interleaved (the
order alternates):

* ``nonlinear`` (``route="nonlinear"``, adaptive generalized-α on the nonlinear equations, its
  servo implicit, with its error estimate from a second run at 10x ``rtol``) on the first
  ``--duration`` seconds (the servo's start, its most expensive part); with
  ``--nonlinear-full`` also once on the whole motion plus ``--after`` (at ``--nonlinear-rtol``),
  and the linear route's runs compared with it;
* ``linear`` (``route="linear"``, the default: linearised about the rigid computed-torque
  motion, :mod:`pinflex.dynamics.torque_linear`) on the same first seconds, and on the whole
  motion plus ``--after`` seconds held.

Printed: process CPU time per simulated second (median and range over the rounds), steps, the
load average, the linear route's two estimates (Richardson step error, linearisation error),
its difference from the nonlinear route on the short horizon and from a converged linear run
(8x the steps) on the whole run (largest elastic coordinate and tip deflection, relative to
their peaks). With ``--peer`` (the ``peers`` extra): the same servo run in Exudyn
(``peer_exudyn.exudyn_servo_tip_deflection``: ANCF cables, torsional spring-damper motors fed
the same computed torque) at each ``--peer-steps``, its CPU per simulated second and its tip
deflection (against the rigid arm at the measured motor angles) against our converged run.
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


def main(argv=None) -> int:
    """Run the benchmark."""
    from interleave import blas_threads, pin_single_thread

    pin_single_thread()
    import numpy as np

    from pinflex.cases.benchmark_a import benchmark_model, benchmark_trajectory
    from pinflex.dynamics import ErlsDynamics
    from pinflex.dynamics.motion import JointMotion
    from pinflex.dynamics.torque import simulate_torque

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=0.02,
                        help="short horizon of the nonlinear route [s] (default 0.02)")
    parser.add_argument("--after", type=float, default=0.5,
                        help="held time after the motion, linear route [s] (default 0.5)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--kp", type=float, default=3000.0)
    parser.add_argument("--kd", type=float, default=30.0)
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--peer", action="store_true",
                        help="also run the PD servo in Exudyn (the peers extra)")
    parser.add_argument("--peer-steps", type=float, nargs="+", default=[1e-4, 5e-5, 2.5e-5],
                        metavar="H", help="Exudyn time steps [s] (default 1e-4 5e-5 2.5e-5)")
    parser.add_argument("--nonlinear-rtol", type=float, default=1e-5,
                        help="rtol of the nonlinear route (default 1e-5)")
    parser.add_argument("--nonlinear-full", action="store_true",
                        help="also run the nonlinear route on the whole motion (once)")
    args = parser.parse_args(argv)
    model = benchmark_model()
    motion = JointMotion(benchmark_trajectory(model))
    dyn = ErlsDynamics(model, y=np.zeros(model.ny))
    full_s = motion.t1 + args.after
    tip = dyn.frame_map("tool")

    def tip_deflection(sim):
        return np.array([(tip(q)[0] @ x)[:2] for q, x in zip(sim.q, sim.x)])

    def run(route, duration, **kw):
        if route == "nonlinear":
            kw.setdefault("rtol", args.nonlinear_rtol)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            c0 = time.process_time()
            sim = simulate_torque(dyn, q0=motion.q_start, trajectory=motion,
                                  duration_s=duration, kp=args.kp, kd=args.kd,
                                  sample_hz=5000.0, route=route, **kw)
            return sim, (time.process_time() - c0) / duration

    sides = {"nonlinear_short": ("nonlinear", args.duration),
             "linear_short": ("linear", args.duration),
             "linear_full": ("linear", full_s)}
    cpu: dict = {k: [] for k in sides}
    last: dict = {}
    for r in range(args.rounds):
        for name in (list(sides) if r % 2 == 0 else list(sides)[::-1]):
            sim, c = run(*sides[name])
            cpu[name].append(c)
            last[name] = sim
    ref, _ = run("linear", full_s, steps=8 * int(np.ceil(motion.duration_s * 5000.0 / 2.0)))

    def rel(a, b):
        return float(np.abs(a - b).max() / np.abs(b).max())

    short_l, short_n, full = last["linear_short"], last["nonlinear_short"], last["linear_full"]
    out: dict = {
        "blas_threads": blas_threads(), "load_average": list(os.getloadavg()),
        "rounds": args.rounds, "kp": args.kp, "kd": args.kd,
        "short_s": args.duration, "full_s": full_s,
        "routes": {k: {"cpu_per_simulated_s_median": float(np.median(v)),
                       "cpu_per_simulated_s_range": [float(min(v)), float(max(v))],
                       "steps": last[k].steps}
                   for k, v in cpu.items()},
        "short_linear_vs_nonlinear": {"x": rel(short_l.x, short_n.x),
                                      "tip": rel(tip_deflection(short_l),
                                                 tip_deflection(short_n))},
        "full_linear_vs_converged": {"x": rel(full.x, ref.x),
                                     "tip": rel(tip_deflection(full), tip_deflection(ref))},
        "full_error_estimate": full.error_estimate,
        "full_linearisation_error": full.linearisation_error,
        "full_tip_peak_m": float(np.linalg.norm(tip_deflection(full), axis=1).max()),
        "full_joint_deviation_rad": float(np.abs(
            full.q_physical - motion.sample(full.times_s)[0]).max()),
    }
    out["nonlinear_full"] = None
    if args.nonlinear_full:
        nl, c = run("nonlinear", full_s)
        out["nonlinear_full"] = {
            "rtol": args.nonlinear_rtol, "cpu_per_simulated_s": c, "steps": nl.steps,
            "error_estimate": nl.error_estimate,
            "linear_vs_nonlinear": {"x": rel(full.x, nl.x),
                                    "tip": rel(tip_deflection(full), tip_deflection(nl))},
            "linear_8x_vs_nonlinear": {"x": rel(ref.x, nl.x),
                                       "tip": rel(tip_deflection(ref), tip_deflection(nl))}}
    out["peer"] = None
    if args.peer:
        from peer_exudyn import compare_servo_with_exudyn

        from pinflex.dynamics import vibration_report
        from pinflex.dynamics.torque_linear import computed_torque

        rep = vibration_report(dyn, ref)
        out["peer"] = compare_servo_with_exudyn(
            motion, computed_torque(dyn, motion), rep.times_s, rep.deflection_m[:, :2],
            kp=args.kp, kd=args.kd, after_s=args.after, steps_s=args.peer_steps)
        ours = vibration_report(dyn, full)
        out["linear_full_tip_vs_converged_report"] = float(
            np.abs(ours.deflection_m - rep.deflection_m).max()
            / np.abs(rep.deflection_m).max())
    ratio = np.array(cpu["nonlinear_short"]) / np.array(cpu["linear_full"])
    out["speedup_vs_nonlinear"] = {"median": float(np.median(ratio)),
                                   "range": [float(ratio.min()), float(ratio.max())]}
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"benchmark A, computed torque + PD (kp = {args.kp:g} N m/rad, kd = {args.kd:g} N m "
          f"s/rad), baseline design; BLAS threads {out['blas_threads']}; load average "
          f"{out['load_average'][0]:.1f} on {os.cpu_count()} cores; {args.rounds} interleaved "
          "rounds")
    for name, d in out["routes"].items():
        lo, hi = d["cpu_per_simulated_s_range"]
        span = args.duration if name.endswith("short") else full_s
        print(f"  {name:16s} {span:6.3f} s simulated: {d['cpu_per_simulated_s_median']:9.3f} "
              f"CPU-s per simulated s ({lo:.3f}-{hi:.3f}), {d['steps']} steps")
    s = out["speedup_vs_nonlinear"]
    print(f"  linear (whole run) vs nonlinear (first {args.duration:g} s): {s['median']:.0f}x "
          f"less CPU per simulated s ({s['range'][0]:.0f}-{s['range'][1]:.0f})")
    d = out["short_linear_vs_nonlinear"]
    print(f"  first {args.duration:g} s, linear vs nonlinear route: elastic coordinates "
          f"{d['x']:.2e}, tip deflection {d['tip']:.2e} of their peaks")
    d = out["full_linear_vs_converged"]
    print(f"  whole run vs a converged linear run (8x steps): {d['x']:.2e} (tip {d['tip']:.2e})"
          f"; Richardson estimate {out['full_error_estimate']:.2e}, linearisation estimate "
          f"{out['full_linearisation_error']:.2e}; tip peak "
          f"{1e3 * out['full_tip_peak_m']:.4f} mm, joint deviation "
          f"{out['full_joint_deviation_rad']:.2e} rad")
    d = out["nonlinear_full"]
    if d is not None:
        print(f"  nonlinear route, whole run (rtol {d['rtol']:g}, one run): "
              f"{d['cpu_per_simulated_s']:.2f} CPU-s per simulated s, {d['steps']} steps, "
              f"estimate {d['error_estimate']:.2e}; linear route vs it: "
              f"{d['linear_vs_nonlinear']['x']:.2e} (tip {d['linear_vs_nonlinear']['tip']:.2e}), "
              f"linear 8x steps vs it: {d['linear_8x_vs_nonlinear']['x']:.2e} "
              f"(tip {d['linear_8x_vs_nonlinear']['tip']:.2e})")
    for p in out["peer"] or []:
        ch = p["change_from_coarser"]
        print(f"  peer ({p['model']}): {p['cpu_per_simulated_s']:.3f} CPU-s per simulated s; "
              f"tip deflection vs our converged run {100 * p['tip_difference']:.3f} % of the "
              "peak" + ("" if ch is None else f" (change from the coarser step "
                                              f"{100 * ch:.3f} %)"))
    if args.peer:
        print(f"  ours (default steps) vs our converged run, same measure: "
              f"{100 * out['linear_full_tip_vs_converged_report']:.3f} % of the peak")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
