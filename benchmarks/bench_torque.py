"""Cost of the torque drive on benchmark A: CPU seconds per simulated second.

The prescribed drive on the same motion is timed beside it.

Run: ``python benchmarks/bench_torque.py [--duration 0.1] [--kp 3000] [--kd 30]``. Simulates the
first ``--duration`` seconds of benchmark A's pick-and-place (baseline design, planar), once
with the prescribed drive and once with the torque drive (rigid computed torque plus a PD servo
on the motor angles, adaptive generalized-α), interleaved in one process, single-thread BLAS
(``interleave.pin_single_thread``), and prints for each: process CPU time per simulated second,
steps, and the largest tip deflection. The torque drive's adaptive steps resolve the stiff
elastic modes the motor torques excite at the parent attachment: this is the cost the issue's
"≤ 1 CPU-s per simulated second" is measured on.
"""

from __future__ import annotations

import argparse
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))


def main() -> int:
    """Run the benchmark."""
    from interleave import blas_threads, pin_single_thread

    pin_single_thread()
    import numpy as np

    from pinflex.cases.benchmark_a import benchmark_model, benchmark_trajectory
    from pinflex.dynamics import ErlsDynamics, simulate_prescribed, simulate_torque
    from pinflex.dynamics.motion import JointMotion
    from pinflex.trajectory import Trajectory

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--duration", type=float, default=0.1)
    parser.add_argument("--kp", type=float, default=3000.0)
    parser.add_argument("--kd", type=float, default=30.0)
    args = parser.parse_args()
    model = benchmark_model()
    full = benchmark_trajectory(model)
    keep = full.times_s <= args.duration + 1e-12
    traj = Trajectory(full.times_s[keep], full.q[keep], full.joint_names)
    dyn = ErlsDynamics(model)
    rows = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        tic = time.process_time()
        sp = simulate_prescribed(dyn, traj, after_s=1e-3, sample_hz=2000.0)
        rows.append(("prescribed", time.process_time() - tic, sp.steps, sp))
        motion = JointMotion(traj)
        tic = time.process_time()
        st = simulate_torque(dyn, q0=motion.q_start, trajectory=motion,
                             duration_s=args.duration, kp=args.kp, kd=args.kd,
                             sample_hz=2000.0)
        rows.append(("torque", time.process_time() - tic, st.steps, st))
    print(f"benchmark A, first {args.duration:g} s of the motion, BLAS threads "
          f"{blas_threads()}, kp = {args.kp:g} N m/rad, kd = {args.kd:g} N m s/rad")
    for name, cpu, steps, sim in rows:
        print(f"  {name:10s} {cpu / args.duration:9.2f} CPU-s per simulated s, {steps:7d} "
              f"steps, max |x| {np.abs(sim.x).max():.3e}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
