"""Speed against accuracy of eq. (1): Kane's spin-up beam, eq. (1) against ``terms="full"``.

Run: ``python benchmarks/bench_spin_up.py [--speeds 1 2 4 6 10] [--out DIR]``. For each final
hub speed Ωs [rad/s] prints the validity indicator of eq. (1) along the motion
(``max |ω|²/ω₁²``, ``max |α|/ω₁²``, :mod:`pinflex.erls.validity`), the peak tip deflection
during the spin-up with eq. (1) and with the full terms (centrifugal, Euler and geometric
stiffness; equal to a rotating-frame FE to 1e-4 in tests/test_dynamics_speed.py), their
relative difference and the run times, and writes ``spin_up.json`` and, with ``--out``,
``spin_up_validity.png`` (the relative difference against the indicator) into DIR.
"""

from __future__ import annotations

import argparse
import json
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from pinflex.cases.spin_up import OMEGA1_RAD_S, SPIN_UP_S, SpinUp, spin_up_model
from pinflex.dynamics import ErlsDynamics, simulate_prescribed
from pinflex.exceptions import ModelValidityWarning


def run(speeds, tol=1e-6):
    """One row per speed (dictionaries)."""
    with tempfile.TemporaryDirectory() as tmp:
        dyn = ErlsDynamics(spin_up_model(Path(tmp) / "kane.urdf"))
    rows = []
    for omega_s in speeds:
        motion = SpinUp(omega_s)
        peaks, times = {}, {}
        validity = None
        for terms in ("eq1", "full"):
            tic = time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", ModelValidityWarning)
                sim = simulate_prescribed(dyn, motion, after_s=0.01, sample_hz=20.0,
                                          terms=terms, start="rest", grid_per_interval=4,
                                          tol=tol)
            times[terms] = time.process_time() - tic
            during = sim.times_s <= SPIN_UP_S
            peaks[terms] = float(np.abs(sim.x[during, -2]).max())  # tip transverse
            validity = sim.validity
        assert validity is not None
        rows.append({
            "omega_s_rad_s": omega_s, "omega_s_over_omega1": omega_s / OMEGA1_RAD_S,
            "indicator": validity.indicator, "max_speed_ratio": validity.max_speed_ratio,
            "max_accel_ratio": validity.max_accel_ratio,
            "peak_eq1_m": peaks["eq1"], "peak_full_m": peaks["full"],
            "relative_difference": abs(peaks["eq1"] / peaks["full"] - 1.0),
            "cpu_s_eq1": times["eq1"], "cpu_s_full": times["full"],
        })
    return rows


def main():
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--speeds", type=float, nargs="+", default=[1.0, 2.0, 4.0, 6.0, 10.0])
    parser.add_argument("--out", metavar="DIR", default=None)
    args = parser.parse_args()
    rows = run(args.speeds)
    print(f"Kane's spin-up beam, Ts = {SPIN_UP_S:g} s, omega_1 = {OMEGA1_RAD_S:.4f} rad/s "
          "(clamped); peak tip deflection during the spin-up")
    print(f"{'Ωs':>6} {'Ωs/ω1':>6} {'|ω|²/ω1²':>9} {'|α|/ω1²':>8} {'eq1 [m]':>10} "
          f"{'full [m]':>10} {'diff':>7} {'cpu eq1':>8} {'cpu full':>8}")
    for r in rows:
        print(f"{r['omega_s_rad_s']:6.2f} {r['omega_s_over_omega1']:6.3f} "
              f"{r['max_speed_ratio']:9.4f} {r['max_accel_ratio']:8.4f} "
              f"{r['peak_eq1_m']:10.5f} {r['peak_full_m']:10.5f} "
              f"{100 * r['relative_difference']:6.2f}% {r['cpu_s_eq1']:7.2f}s "
              f"{r['cpu_s_full']:7.2f}s")
    out = Path(args.out) if args.out else Path(".")
    if args.out:
        out.mkdir(parents=True, exist_ok=True)
        (out / "spin_up.json").write_text(json.dumps(rows, indent=1))
        from matplotlib.figure import Figure

        fig = Figure(figsize=(6.0, 3.8), dpi=110)
        ax = fig.add_subplot()
        x = [r["indicator"] for r in rows]
        ax.loglog(x, [r["relative_difference"] for r in rows], "o-",
                  label="|peak eq. (1) / peak full − 1|")
        ax.axvline(0.1, color="0.4", ls="--", lw=0.9, label="warning threshold 0.1")
        ax.set_xlabel("validity indicator max(|ω|²/ω₁², |α|/ω₁²)")
        ax.set_ylabel("relative difference of the peak tip deflection")
        ax.set_title("Kane's spin-up beam: eq. (1) against the full terms", fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(out / "spin_up_validity.png")
        print(f"wrote {out / 'spin_up.json'} and {out / 'spin_up_validity.png'}")


if __name__ == "__main__":
    main()
