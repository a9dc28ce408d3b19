"""The flexible UR5 with its two tubes sized: mode 1 above a floor along a workspace motion.

``urdf/ur5_tubes.xml`` is the flexible UR5 of ``ur5_flexible.xml`` with the outer diameters and
walls of its aluminium tubes as parameters. Here the two outer diameters are the design
variables (walls kept at 5 and 4 mm), the payload is 2 kg, and the end effector moves 15 cm
forward and 10 cm down from a reaching pose (inverse kinematics, 20 samples). Mode 1 must stay
at or above 70 Hz along the whole motion with the least tube mass. pinflex sizes the tubes by
Taylor steps with exact verification; the same run solves the problem by SLSQP on the exact
model and by an exact 9 x 9 grid, for time and design quality side by side.

Run: python examples/ur5_tubes.py        (add --json for one JSON object)
"""

import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from pinflex.assignment.sizing import size_for_floors
from pinflex.erls import FlexibleModel
from pinflex.erls.design import design_mass
from pinflex.trajectory.cartesian import path_from_spec

URDF = Path(__file__).resolve().parents[1] / "urdf" / "ur5_tubes.xml"
FLOOR_HZ = 70.0
DESIGN = ["D_upper", "D_fore"]

arm = FlexibleModel(URDF, values={"payload": 2.0})
q_start = [0.0, -1.0, 1.2, 0.3, 0.5, 0.0]
traj = path_from_spec(arm, {"frame": "ee_link", "waypoints": [[0.15, 0.0, -0.1]],
                            "relative": True, "start_q": q_start, "samples": 20})
f_start = arm.frequencies(traj.q, n_modes=1)[:, 0]
mass_start = design_mass(arm, arm.y0)
idx = [arm.design_names.index(n) for n in DESIGN]


def full(x):
    """The design vector with the two diameters set."""
    y = arm.y0.copy()
    y[idx] = x
    return y


def mode1(x):
    """Exact mode-1 frequencies [Hz] along the motion for diameters x."""
    return arm.frequencies(traj.q, full(x), n_modes=1)[:, 0]


t0 = time.perf_counter()
ours = size_for_floors(arm, traj, [(1, FLOOR_HZ)], design=DESIGN, order=3)
t_ours = time.perf_counter() - t0

bounds = [(arm.design[j].lower, arm.design[j].upper) for j in idx]
t0 = time.perf_counter()
ref = minimize(lambda x: design_mass(arm, full(x)), arm.y0[idx], method="SLSQP", bounds=bounds,
               constraints=[{"type": "ineq", "fun": lambda x: mode1(x) - FLOOR_HZ}],
               options={"ftol": 1e-12, "maxiter": 200})
t_ref = time.perf_counter() - t0
ref_margin = float(np.min(mode1(ref.x) - FLOOR_HZ))

t0 = time.perf_counter()
grid = [np.linspace(lo, hi, 9) for lo, hi in bounds]
best = None
for a in grid[0]:
    for b in grid[1]:
        x = np.array([a, b])
        if np.min(mode1(x)) >= FLOOR_HZ:
            m = design_mass(arm, full(x))
            if best is None or m < best[0]:
                best = (m, x)
t_grid = time.perf_counter() - t0

summary = {
    "start": {"design": dict(zip(DESIGN, arm.y0[idx].tolist())), "mass_kg": mass_start,
              "mode1_min_hz": float(f_start.min()), "mode1_max_hz": float(f_start.max())},
    "floor_hz": FLOOR_HZ, "payload_kg": 2.0, "samples": int(traj.q.shape[0]),
    "pinflex": {"design": {n: ours.design[n] for n in DESIGN}, "mass_kg": ours.mass_kg,
                "margin_hz": ours.margin_hz, "expansions": ours.expansions, "time_s": t_ours},
    "scipy_slsqp_exact": {"design": dict(zip(DESIGN, ref.x.tolist())), "mass_kg": float(ref.fun),
                          "margin_hz": ref_margin, "time_s": t_ref},
    "exact_grid_9x9": None if best is None else {
        "design": dict(zip(DESIGN, best[1].tolist())), "mass_kg": float(best[0]),
        "time_s": t_grid},
    "joints": arm.joint_labels(),
}

if __name__ == "__main__":
    if "--json" in sys.argv:
        print(json.dumps(summary))
    else:
        print(f"UR5, 2 kg payload, {traj.q.shape[0]} samples: mode 1 {f_start.min():.2f}-"
              f"{f_start.max():.2f} Hz at the nominal tubes (90/70 mm, tube mass "
              f"{mass_start:.3f} kg); floor {FLOOR_HZ:g} Hz")
        print(f"{'':22s} {'D_upper [mm]':>12s} {'D_fore':>8s} {'mass [kg]':>10s} "
              f"{'margin [Hz]':>12s} {'time [s]':>9s}")
        rows = [("pinflex (Taylor)", ours.y[idx], ours.mass_kg, ours.margin_hz, t_ours),
                ("SLSQP on exact model", ref.x, float(ref.fun), ref_margin, t_ref)]
        if best is not None:
            rows.append(("exact grid 9 x 9", best[1], best[0],
                         float(np.min(mode1(best[1]) - FLOOR_HZ)), t_grid))
        for label, x, m, marg, t in rows:
            print(f"{label:22s} {1e3 * x[0]:12.2f} {1e3 * x[1]:8.2f} {m:10.4f} {marg:12.4f} "
                  f"{t:9.2f}")
        print(f"pinflex: {ours.expansions} expansions (order 3); joints {arm.joint_switch}")
