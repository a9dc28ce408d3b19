"""Fidelity of lumped models against the segment count, beside MuJoCo's own rod, in one run.

Two cases, every number measured in this process:

* **link**: benchmark A's first link (L = 0.6 m, EI = 69e9 x 3.97e-8 N m^2, rhoA = 1.9 kg/m)
  clamped at its root, against the closed-form cantilever (Euler-Bernoulli roots). For each
  segment count n: pinflex's fitted lumped link (modes 1-2 matched, with its ERLS model at 40
  elements), the equal-segment chain with k = EI/l, and MuJoCo's own 1-D flex (a discrete
  elastic rod, ``<flexcomp dim="1">``) of n edges with the same E, I (``young`` scaled so that
  the rod's circle of radius 15 mm has I = 3.97e-8 m^4) and rhoA (``mass`` = rhoA L, which
  MuJoCo spreads equally over the n + 1 points; the two points of the clamped first edge are
  pinned). The rod's frequencies are read off 0.4 s of its free vibration after a tip kick
  (least-squares sinusoids started at the spectrum's peak; RK4, 2e-5 s, stiff edge equality
  constraints); the lumped models' from MuJoCo's own mass matrix and joint stiffness of the
  exported MJCF. Only the rod's mode 1 is read (its mode 2 is barely excited by the kick).
* **static tip deflection** of the same clamped link under a transverse tip force (Euler-
  Bernoulli deflection 1e-3 L), relative to the closed form P L^3 / 3 EI: the definition of
  MuJoCo's stated accuracy for its flexible models ("within about 10 % of Euler-Bernoulli tip
  deflection"), here on the same beam for the three models. The lumped MJCFs' from MuJoCo's
  own model (``mj_jac`` at the tip, joint stiffness); the rod's at rest under the load
  (damped, same RK4 step).
* **arm**: benchmark A straight with free joints against its ERLS model (= the global FE of
  the same mesh): fitted and naive lumped arms, modes 1-2, own joints.

MuJoCo step time: this thread's CPU time per ``mj_step`` (``time.thread_time``; MuJoCo steps
in the calling thread, so other processes on a loaded machine do not inflate it) of each model
(lumped MJCF with its hinges; the rod), same integrator (RK4) and step (2e-5 s), median and
range over interleaved rounds. The machine's load is printed.

Run: ``python benchmarks/bench_lumped.py [--quick] [--counts N ...] [--out FILE.png]
[--json FILE] [--csv FILE]``.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from interleave import blas_threads, interleaved, pin_single_thread  # noqa: E402

pin_single_thread()

import numpy as np  # noqa: E402
import scipy.linalg as sla  # noqa: E402
from lumped_ring import (  # noqa: E402
    clamped_link_urdf,
    mujoco_tip_deflection,
    ring_frequencies,
)
from reference_fe import cantilever_hz  # noqa: E402

from pinflex.description import parse  # noqa: E402
from pinflex.erls import FlexibleModel  # noqa: E402
from pinflex.exceptions import LinkTooShort  # noqa: E402
from pinflex.lumped import fit_lumped, lumped_mjcf  # noqa: E402

E, I2, RHOA, L, R = 69e9, 3.97e-8, 1.9, 0.6, 0.015
DT = 2e-5
#: Transverse tip force [N] of the static case: Euler-Bernoulli tip deflection 1e-3 L.
TIP_FORCE = 3.0 * E * I2 * 1e-3 / L**2

LINK_URDF = clamped_link_urdf(L, E, I2, RHOA, 40)


def mujoco_frequencies(mujoco, m, d):
    """Non-rigid frequencies [Hz] from mj_fullM and jnt_stiffness (free joints condensed)."""
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    k = np.array(m.jnt_stiffness[m.dof_jntid])
    e, r = k > 0, k == 0
    Mc = M[np.ix_(e, e)]
    if r.any():
        Mc = Mc - M[np.ix_(e, r)] @ np.linalg.solve(M[np.ix_(r, r)], M[np.ix_(r, e)])
    return np.sqrt(sla.eigh(np.diag(k[e]), Mc, eigvals_only=True)) / (2 * np.pi)


def rod_xml(n: int) -> str:
    """MuJoCo's 1-D flex rod of n edges, first edge clamped."""
    young = E * I2 / (np.pi * R**4 / 4)
    return f"""<mujoco><option gravity="0 0 0" timestep="{DT}" integrator="RK4"/>
<worldbody>
 <flexcomp name="rod" type="grid" count="{n + 1} 1 1" spacing="{L / n} 1 1" dim="1"
           radius="{R}" mass="{RHOA * L}">
   <elasticity young="{young}" poisson="0.3"/>
   <edge equality="true" solref="{2 * DT} 1"/>
   <pin id="0 1"/>
 </flexcomp>
</worldbody></mujoco>"""


def rod_frequencies(mujoco, n: int, guess, duration: float) -> np.ndarray:
    """Modes 1-2 of the rod from its free vibration after a tip velocity kick [Hz]."""
    m = mujoco.MjModel.from_xml_string(rod_xml(n))
    d = mujoco.MjData(m)
    zj = [j for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
          and abs(m.jnt_axis[j][2]) > 0.5]
    tip = zj[int(np.argmax([m.body_pos[m.jnt_bodyid[j]][0] for j in zj]))]
    d.qvel[m.jnt_dofadr[tip]] = 1e-3
    t, y = [], []
    while d.time < duration:
        mujoco.mj_step(m, d)
        t.append(d.time)
        y.append(d.qpos[m.jnt_qposadr[tip]])
    t, y = np.array(t), np.array(y)
    # start mode 1 at the spectrum's peak below 1.5 x the guess (the rod can be far off)
    spec = np.abs(np.fft.rfft((y - y.mean()) * np.hanning(y.size)))
    freq = np.fft.rfftfreq(y.size, t[1] - t[0])
    low = freq < 1.5 * guess[0]
    start = [float(freq[low][np.argmax(spec[low])]), float(guess[1])]
    # mode 2 is fitted only to keep it out of mode 1's reading: a tip kick excites it too
    # little (and a rod of two edges has no second transverse mode) to read it reliably
    return np.array([ring_frequencies(t, y, start)[0], np.nan])


def rod_tip_deflection(mujoco, n: int, force: float, duration: float = 0.1) -> float:
    """Static tip deflection [m] of the clamped rod under a transverse tip force [N].

    The rod is loaded at its tip point and brought to rest by damping on every point's
    degrees of freedom (mass-proportional, critical for the first mode); its tip deflection
    at rest is its static answer (the damping does not change the equilibrium).
    """
    m = mujoco.MjModel.from_xml_string(rod_xml(n))
    m.dof_damping[:] = 2.0 * 2.0 * np.pi * cantilever_hz(L, E * I2, RHOA, 1)[0] * RHOA * L / (n + 1)
    d = mujoco.MjData(m)
    zj = [j for j in range(m.njnt) if m.jnt_type[j] == mujoco.mjtJoint.mjJNT_SLIDE
          and abs(m.jnt_axis[j][2]) > 0.5]
    tip = zj[int(np.argmax([m.body_pos[m.jnt_bodyid[j]][0] for j in zj]))]
    d.xfrc_applied[m.jnt_bodyid[tip], 2] = force
    last = []
    while d.time < duration:
        mujoco.mj_step(m, d)
        last.append(d.qpos[m.jnt_qposadr[tip]])
    if abs(last[-1] - last[-len(last) // 10]) > 1e-6 * abs(last[-1]):
        raise RuntimeError(f"rod of {n} edges not at rest after {duration} s")
    return float(last[-1])


def lumped_tip_deflection(mujoco, m, force: float) -> float:
    """Static tip deflection [m] of a lumped link MJCF from MuJoCo (``mj_jac``, stiffness)."""
    return mujoco_tip_deflection(mujoco, m, force, L)


def stepper(mujoco, m):
    """A function stepping ``m`` 200 times from its current state."""
    d = mujoco.MjData(m)

    def run():
        for _ in range(200):
            mujoco.mj_step(m, d)
    return run


def main(argv=None) -> int:
    """Run the study; print, and write what is asked."""
    import mujoco

    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="fewer segment counts and rounds")
    p.add_argument("--counts", type=int, nargs="+", metavar="N",
                   help="segment counts to run (default 2 3 4 5 6 8 10 12 16)")
    p.add_argument("--out", default=None, help="chart (PNG); none unless given")
    p.add_argument("--json", default=None, help="write the results as JSON")
    p.add_argument("--csv", default=None, help="write the results as CSV")
    args = p.parse_args(argv)
    counts = args.counts or ([2, 3, 4, 6] if args.quick else [2, 3, 4, 5, 6, 8, 10, 12, 16])
    rounds = 3 if args.quick else 7
    load = os.getloadavg()
    print(f"BLAS threads: {blas_threads()}; load average before: "
          f"{load[0]:.1f} {load[1]:.1f} {load[2]:.1f}; mujoco {mujoco.__version__}")
    exact = cantilever_hz(L, E * I2, RHOA, 2)
    tip_exact = TIP_FORCE * L**3 / (3.0 * E * I2)  # Euler-Bernoulli cantilever, tip force
    link = FlexibleModel(parse(LINK_URDF), planar=True)
    arm = FlexibleModel(Path(__file__).resolve().parents[1] / "urdf" / "two_link.urdf",
                        planar=True, joints="free")
    erls_arm = arm.frequencies([0.0, 0.0])[:2]
    rows = []
    for n in counts:
        c0 = time.process_time()
        fit = fit_lumped(link, n, n_modes=min(2, n - 1))
        fit_cpu = time.process_time() - c0
        m_fit = mujoco.MjModel.from_xml_string(
            lumped_mjcf(fit.lumped, [0.0], gravity=(0, 0, 0), timestep=DT).text)
        m_fit.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        f_fit = mujoco_frequencies(mujoco, m_fit, mujoco.MjData(m_fit))[:2]
        f_naive = fit.naive.frequencies([0.0], "own")[:2]
        f_rod = rod_frequencies(mujoco, n, exact, 0.4)
        m_rod = mujoco.MjModel.from_xml_string(rod_xml(n))
        m_naive = mujoco.MjModel.from_xml_string(
            lumped_mjcf(fit.naive, [0.0], gravity=(0, 0, 0), timestep=DT).text)
        tip = {"fit": lumped_tip_deflection(mujoco, m_fit, TIP_FORCE),
               "naive": lumped_tip_deflection(mujoco, m_naive, TIP_FORCE),
               "rod": rod_tip_deflection(mujoco, n, TIP_FORCE)}
        times = interleaved({"lumped": stepper(mujoco, m_fit), "rod": stepper(mujoco, m_rod)},
                            rounds=rounds, clock=time.thread_time)
        try:  # benchmark A's link 2 (0.45 m, 30 mm section) holds at most 14 segments
            fit_arm = fit_lumped(arm, n, poses=[0.0, 0.0], warn_above=None)
            f_arm = fit_arm.lumped.frequencies([0.0, 0.0])[:2]
            f_arm_naive = fit_arm.naive.frequencies([0.0, 0.0])[:2]
        except LinkTooShort:
            f_arm = f_arm_naive = np.array([])

        def err(f, ref):
            out = np.full(2, np.nan)
            out[:f.size] = np.abs(f / ref[:f.size] - 1.0)
            return out

        row = {"n": n, "link_fit_error": err(f_fit, exact).tolist(),
               "link_naive_error": err(f_naive, exact).tolist(),
               "link_rod_error": err(f_rod, exact).tolist(),
               "tip_fit_error": tip["fit"] / tip_exact - 1.0,
               "tip_naive_error": tip["naive"] / tip_exact - 1.0,
               "tip_rod_error": tip["rod"] / tip_exact - 1.0,
               "fit_reported_compliance_error": fit.compliance_error,
               "link_fit_cpu_s": fit_cpu,
               "step_lumped_s": float(np.median(times["lumped"])) / 200,
               "step_lumped_range_s": [float(times["lumped"].min()) / 200,
                                       float(times["lumped"].max()) / 200],
               "step_rod_s": float(np.median(times["rod"])) / 200,
               "step_rod_range_s": [float(times["rod"].min()) / 200,
                                    float(times["rod"].max()) / 200],
               "lumped_nv": int(m_fit.nv), "rod_nv": int(m_rod.nv),
               "arm_fit_error": err(f_arm, erls_arm).tolist(),
               "arm_naive_error": err(f_arm_naive, erls_arm).tolist()}
        rows.append(row)
        print(f"n={n:2d}  link mode1/2: fitted {row['link_fit_error'][0]:.2e}/"
              f"{row['link_fit_error'][1]:.2e}  naive {row['link_naive_error'][0]:.2e}/"
              f"{row['link_naive_error'][1]:.2e}  MuJoCo rod {row['link_rod_error'][0]:.2e}/"
              f"{row['link_rod_error'][1]:.2e}  | tip deflection: fitted "
              f"{row['tip_fit_error']:+.2e} naive {row['tip_naive_error']:+.2e} MuJoCo rod "
              f"{row['tip_rod_error']:+.2e}  | step lumped {1e6 * row['step_lumped_s']:.1f} us"
              f" (nv {row['lumped_nv']}), rod {1e6 * row['step_rod_s']:.1f} us (nv "
              f"{row['rod_nv']})  | arm fitted {row['arm_fit_error'][0]:.1e}/"
              f"{row['arm_fit_error'][1]:.1e} naive {row['arm_naive_error'][0]:.1e}/"
              f"{row['arm_naive_error'][1]:.1e}", flush=True)
    load = os.getloadavg()
    print(f"load average after: {load[0]:.1f} {load[1]:.1f} {load[2]:.1f}")
    result = {"exact_link_hz": exact.tolist(), "tip_force_n": TIP_FORCE,
              "tip_deflection_exact_m": tip_exact, "erls_arm_hz": erls_arm.tolist(),
              "timestep_s": DT, "integrator": "RK4", "rows": rows,
              "blas_threads": blas_threads()}
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
    if args.csv:
        with open(args.csv, "w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["n", "link_fit_mode1", "link_fit_mode2", "link_naive_mode1",
                        "link_naive_mode2", "link_rod_mode1", "link_rod_mode2",
                        "tip_fit", "tip_naive", "tip_rod", "step_lumped_us", "step_rod_us",
                        "arm_fit_mode1", "arm_fit_mode2", "arm_naive_mode1", "arm_naive_mode2"])
            for r in rows:
                w.writerow([r["n"], *r["link_fit_error"], *r["link_naive_error"],
                            *r["link_rod_error"], r["tip_fit_error"], r["tip_naive_error"],
                            r["tip_rod_error"], 1e6 * r["step_lumped_s"],
                            1e6 * r["step_rod_s"], *r["arm_fit_error"], *r["arm_naive_error"]])
    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        from pinflex.outputs import save_figure

        ns = [r["n"] for r in rows]
        fig, (a1, a3, a2) = plt.subplots(1, 3, figsize=(16, 4.2))
        for key, label, style in (("link_fit_error", "pinflex fitted", "o-"),
                                  ("link_naive_error", "equal segments, k = EI/l", "s--"),
                                  ("link_rod_error", "MuJoCo 1-D flex rod", "^-")):
            for mode, alpha in ((0, 1.0), (1, 0.45)):
                if key == "link_rod_error" and mode == 1:
                    continue
                a1.semilogy(ns, [max(r[key][mode], 1e-12) for r in rows], style,
                            alpha=alpha, label=f"{label}, mode {mode + 1}")
        a1.set_xlabel("segments (edges) n")
        a1.set_ylabel("relative frequency error vs closed form")
        a1.set_title("clamped link (benchmark A link 1)")
        a1.legend(fontsize=7)
        a1.grid(True, which="both", alpha=0.3)
        for key, label, style in (("tip_fit_error", "pinflex fitted", "o-"),
                                  ("tip_naive_error", "equal segments, k = EI/l", "s--"),
                                  ("tip_rod_error", "MuJoCo 1-D flex rod", "^-")):
            a3.semilogy(ns, [max(abs(r[key]), 1e-12) for r in rows], style, label=label)
        a3.axhline(0.10, color="grey", lw=0.8, ls=":")
        a3.text(ns[0], 0.11, "10 %", color="grey", fontsize=8)
        a3.set_xlabel("segments (edges) n")
        a3.set_ylabel("|relative error| of the static tip deflection")
        a3.set_title("tip force, vs Euler-Bernoulli PL³/3EI")
        a3.legend(fontsize=7)
        a3.grid(True, which="both", alpha=0.3)
        a2.plot(ns, [1e6 * r["step_lumped_s"] for r in rows], "o-", label="lumped MJCF")
        a2.plot(ns, [1e6 * r["step_rod_s"] for r in rows], "^-", label="MuJoCo flex rod")
        a2.set_xlabel("segments (edges) n")
        a2.set_ylabel(f"CPU time per mj_step [us] (RK4, {DT:g} s)")
        a2.set_title("MuJoCo step time")
        a2.legend()
        a2.grid(True, alpha=0.3)
        fig.tight_layout()
        save_figure(fig, args.out, dpi=120)
        print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
