"""Taylor model of benchmark A's first mode along its pick-and-place path (paper 000, Fig. 3).

Run ``python examples/benchmark_a_taylor.py``: prints the largest error of the p = 4 frequency
polynomial along the 152-sample trajectory and how long one evaluation takes.
"""

import time
from pathlib import Path

import numpy as np

import pinflex
from pinflex.assignment.study import user_trajectory

URDF = Path(__file__).resolve().parents[1] / "urdf" / "two_link.urdf"

arm = pinflex.FlexibleModel(URDF, planar=True)  # absolute link angles, as in the paper
traj = user_trajectory(arm, "benchmark_a")
taylor = pinflex.expand(arm, [1.817, 5.312], order=4)  # joints q1, q2 and masses m1, m2
exact_hz = arm.frequencies(traj.q, [0.0, 0.0], n_modes=1)[:, 0]
poly_hz = taylor.evaluate(traj.q, [0.0, 0.0], quantity="freq_hz")[:, 0]
max_error = float(np.max(np.abs(poly_hz / exact_hz - 1)))

if __name__ == "__main__":
    t0 = time.perf_counter()
    for _ in range(100):
        taylor.evaluate(traj.q, [0.0, 0.0], quantity="freq_hz", warn=False)
    t_poly = (time.perf_counter() - t0) / 100
    print(f"p = 4, mode 1, y = 0: max error {100 * max_error:.3f} % along {len(traj.q)} samples")
    print(f"polynomial: {1e6 * t_poly:.0f} us for all samples")
