"""Benchmark A with tube sections as design variables: mode 1 10 % up, least link mass.

The original arm has solid 30 mm aluminium rods (a tube with a 15 mm wall) and the paper's
0.125 kg masses at the elbow and the tip. The design variables are the outer diameter and
the wall thickness of each link's tube. pinflex sizes them by Taylor steps with exact
verification (pinflex.assignment.sizing); the same problem is solved in the same run by
SLSQP on the exact model, for time and design quality side by side.

Run: python examples/benchmark_a_tubes.py        (add --json for one JSON object)
"""

import json
import sys
import time

import numpy as np
from scipy.optimize import minimize

from pinflex.assignment.sizing import size_for_floors
from pinflex.assignment.study import user_trajectory
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.erls.design import design_mass

LINK = """<pinflex:flexible link="{link}" elements="{n}" normal="0 0 1">
    <pinflex:material E="69e9" density="2687"/>
    <pinflex:section shape="hollow_circle" outer_diameter="{{D{i}}}" wall="{{t{i}}}"/>
  </pinflex:flexible>"""
URDF = f"""<robot name="benchmark_a_tubes" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="tool"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-6.2832" upper="6.2832" effort="1" velocity="1"/></joint>
  <joint name="q2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-6.2832" upper="6.2832" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="link2"/><child link="tool"/>
    <origin xyz="0.45 0 0"/></joint>
  <pinflex:coordinates convention="absolute"/>
  <pinflex:parameter name="D1" value="0.03" lower="0.02" upper="0.06" design="true"/>
  <pinflex:parameter name="t1" value="0.015" lower="0.001" upper="0.015" design="true"/>
  <pinflex:parameter name="D2" value="0.03" lower="0.02" upper="0.06" design="true"/>
  <pinflex:parameter name="t2" value="0.015" lower="0.001" upper="0.015" design="true"/>
  {LINK.format(link="link1", n=4, i=1)}
  {LINK.format(link="link2", n=3, i=2)}
  <pinflex:point_mass name="m1" link="link1" xyz="0.6 0 0" mass="0.125"/>
  <pinflex:point_mass name="m2" link="link2" xyz="0.45 0 0" mass="0.125"/>
</robot>"""

arm = FlexibleModel(parse(URDF), planar=True)
traj = user_trajectory(arm, "benchmark_a")
f_orig = arm.frequencies(traj.q, n_modes=1)[:, 0]
floor = 1.10 * f_orig.min()
mass_orig = design_mass(arm, arm.y0)

t0 = time.perf_counter()
ours = size_for_floors(arm, traj, [(1, floor)], order=4)
t_ours = time.perf_counter() - t0

lo = [d.lower for d in arm.design]
hi = [d.upper for d in arm.design]


def valid(x):
    """Walls at most half the diameter (difference steps may cross the solid-rod limit)."""
    x = np.array(x, dtype=float)
    x[1], x[3] = min(x[1], x[0] / 2), min(x[3], x[2] / 2)
    return x


cons = [
    {"type": "ineq",
     "fun": lambda x: arm.frequencies(traj.q, valid(x), n_modes=1)[:, 0] - floor},
    {"type": "ineq", "fun": lambda x: np.array([x[0] - 2 * x[1], x[2] - 2 * x[3]])},  # tubes
]
t0 = time.perf_counter()
ref = minimize(lambda x: design_mass(arm, valid(x)), arm.y0, method="SLSQP",
               bounds=list(zip(lo, hi)), constraints=cons, options={"ftol": 1e-12, "maxiter": 300})
t_ref = time.perf_counter() - t0
ref_margin = float(np.min(arm.frequencies(traj.q, ref.x, n_modes=1)[:, 0] - floor))

summary = {
    "original": {"design": dict(zip(arm.design_names, arm.y0.tolist())), "mass_kg": mass_orig,
                 "mode1_min_hz": float(f_orig.min()), "mode1_max_hz": float(f_orig.max())},
    "floor_hz": floor,
    "pinflex": {"design": ours.design, "mass_kg": ours.mass_kg,
                "added_mass_kg": ours.added_mass_kg, "margin_hz": ours.margin_hz,
                "expansions": ours.expansions, "time_s": t_ours},
    "scipy_slsqp_exact": {"design": dict(zip(arm.design_names, ref.x.tolist())),
                          "mass_kg": float(ref.fun), "added_mass_kg": float(ref.fun - mass_orig),
                          "margin_hz": ref_margin, "iterations": int(ref.nit), "time_s": t_ref},
    "joints": arm.joint_labels(),
}

if __name__ == "__main__":
    if "--json" in sys.argv:
        print(json.dumps(summary))
    else:
        print(f"original: solid 30 mm rods, mode 1 {f_orig.min():.2f}-{f_orig.max():.2f} Hz "
              f"along the motion, link mass {mass_orig:.4f} kg; floor {floor:.2f} Hz (+10 %)")
        print(f"{'':22s} {'D1 [mm]':>8s} {'t1':>6s} {'D2':>6s} {'t2':>6s} {'mass [kg]':>10s} "
              f"{'added':>8s} {'margin [Hz]':>12s} {'time [s]':>9s}")
        for label, y, m, marg, t in (
            ("pinflex (Taylor)", ours.y, ours.mass_kg, ours.margin_hz, t_ours),
            ("SLSQP on exact model", ref.x, float(ref.fun), ref_margin, t_ref),
        ):
            print(f"{label:22s} {1e3 * y[0]:8.2f} {1e3 * y[1]:6.2f} {1e3 * y[2]:6.2f} "
                  f"{1e3 * y[3]:6.2f} {m:10.4f} {m - mass_orig:+8.4f} {marg:12.4f} {t:9.2f}")
        print(f"pinflex: {ours.expansions} expansions; joints {arm.joint_switch}")
    if "--history" in sys.argv:
        for y, m, marg in ours.history:
            print(np.round(1e3 * y, 3).tolist(), round(m, 5), round(marg, 5))
