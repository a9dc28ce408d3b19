"""Speed against accuracy of the PRBDM link count, and what ``tol=`` picks.

For each beam (paper 001's uniform beam and a random planform), nR chains with n = k..N are
fitted (combined objective, the k lowest modes judged, loads alpha = 0.5 1 2 5); each chain's
error is its combined loss against the converged beam truth (the estimator of
``pinflex.prbdm.fidelity.links_for_tolerance``), and its evaluation times are one call of the
chain's frequencies at the straight pose (Pinocchio CRBA + eigh; the chart's x axis) and,
beside it, the tip statics at the four loads (batched planar Newton, four load steps, from
rest), measured in interleaved rounds in one process, in CPU time (single-thread BLAS; the
machine may be loaded, the output says how much). The chart goes to ``--out`` (default
``prbdm_links.png``); the tolerances listed are resolved from the same levels, and each fit's
CPU time is printed (the cost that does grow with n).

Run: ``python benchmarks/bench_prbdm_links.py [--quick] [--json FILE] [--out FILE]``.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, pin_single_thread

pin_single_thread()

import numpy as np  # noqa: E402

from pinflex.prbdm.beams import random_beam, uniform_beam  # noqa: E402
from pinflex.prbdm.chain import chain_frequencies, solve_tip_statics  # noqa: E402
from pinflex.prbdm.fidelity import links_for_tolerance  # noqa: E402
from pinflex.prbdm.mapping import fit_prbdm  # noqa: E402
from pinflex.prbdm.planar import planar_statics  # noqa: E402
from pinflex.prbdm.problem import compute_truth  # noqa: E402

TOLERANCES = (1e-2, 3e-3, 1e-3, 5e-4)


def study(label, beam, n_modes, max_links, starts, rounds):
    """Levels n = k..max_links of one beam: errors, evaluation times, tolerance choices."""
    truth = compute_truth(beam, n_modes)
    # The fits links_for_tolerance makes (same objective, modes, starts and seed).
    fits, fit_cpu = {}, {}
    for n in range(n_modes, max_links + 1):
        c0 = time.process_time()
        fits[n] = fit_prbdm(beam, n, n_modes, "combined", n_starts=starts, truth=truth)
        fit_cpu[n] = time.process_time() - c0
    chains = {n: f.chain(beam) for n, f in fits.items()}
    datas = {n: c.model.createData() for n, c in chains.items()}

    def frequencies(n):
        def run():
            chain_frequencies(chains[n], None, datas[n])
        return run

    def statics(n):
        chain = chains[n]
        ell, zeros = chain.link_lengths_m[1:], np.zeros((truth.forces_n.shape[0], n))

        def run():
            planar_statics(chain.stiffness_nm_rad, ell, truth.forces_n, zeros, 4)
        return run

    # The batched planar Newton is the chain's own statics (same checks as
    # solve_tip_statics); check it against the Pinocchio path once.
    for n, chain in chains.items():
        theta, ok = planar_statics(chain.stiffness_nm_rad, chain.link_lengths_m[1:],
                                   truth.forces_n, np.zeros((truth.forces_n.shape[0], n)), 4)
        ref = np.array([solve_tip_statics(chain, f, load_steps=4).theta for f in truth.forces_n])
        assert ok.all() and np.max(np.abs(theta - ref)) < 1e-8

    sides = {("f", n): frequencies(n) for n in fits} | {("s", n): statics(n) for n in fits}
    times = _interleaved_cpu(sides, rounds=rounds, number=200)
    rows = []
    for n, fit in fits.items():
        t, ts = times[("f", n)], times[("s", n)]
        rows.append({"n": n, "error": fit.combined_error, "eigen": fit.eigen_error,
                     "deflection": fit.deflection_error, "time_s": float(np.median(t)),
                     "time_min_s": float(t.min()), "time_max_s": float(t.max()),
                     "statics_s": float(np.median(ts)), "fit_evaluations": fit.n_evaluations,
                     "fit_cpu_s": fit_cpu[n]})
    picks = {}
    for tol in TOLERANCES:
        ok = [r for r in rows if r["error"] <= tol]
        picks[tol] = ok[0]["n"] if ok else None
    # One tolerance through the library call itself: it must pick the same chain.
    middle = TOLERANCES[2]
    if picks[middle] is not None:
        assert links_for_tolerance(beam, middle, n_modes=n_modes, max_links=max_links,
                                   n_starts=starts, truth=truth).n_joints == picks[middle]
    print(f"== {label}: k = {n_modes} modes judged, {starts} starts, {rounds} interleaved "
          f"rounds ({_load()}; {blas_threads()})")
    print("   n   error (combined)   eigen       deflection   frequencies [us] median (range)"
          "   statics, 4 loads from rest [us]   fit [CPU s]")
    for r in rows:
        print(f"   {r['n']}R  {r['error']:.3e}          {r['eigen']:.3e}   "
              f"{r['deflection']:.3e}    {1e6 * r['time_s']:7.1f} ({1e6 * r['time_min_s']:.1f}-"
              f"{1e6 * r['time_max_s']:.1f})       {1e6 * r['statics_s']:8.1f}"
              f"                    {r['fit_cpu_s']:.2f}")
    print("   tol -> n: " + ", ".join(f"{tol:g} -> {f'{n}R' if n else 'none up to the largest'}"
                                      for tol, n in picks.items()))
    return {"beam": label, "n_modes": n_modes, "rows": rows,
            "picks": {str(k): v for k, v in picks.items()}}


def _interleaved_cpu(sides: dict, rounds: int, number: int) -> dict:
    """Like ``interleave.interleaved`` but in CPU time of this process (robust to load)."""
    out: dict = {n: [] for n in sides}
    for fn in sides.values():
        fn()
    names = list(sides)
    for r in range(rounds):
        for n in names if r % 2 == 0 else names[::-1]:
            t0 = time.process_time()
            for _ in range(number):
                sides[n]()
            out[n].append((time.process_time() - t0) / number)
    return {n: np.asarray(v) for n, v in out.items()}


def _load() -> str:
    load = os.getloadavg()
    return f"load average {load[0]:.1f} on {os.cpu_count()} cores"


def chart(results, out):
    """Error against evaluation time, one line per beam."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    for res in results:
        t = np.array([r["time_s"] for r in res["rows"]]) * 1e6
        e = np.array([r["error"] for r in res["rows"]])
        ax.loglog(t, e, "o-", label=f"{res['beam']} (k = {res['n_modes']} modes)")
        for r, ti, ei in zip(res["rows"], t, e):
            ax.annotate(f"{r['n']}R", (ti, ei), fontsize=7)
    for tol in TOLERANCES:
        ax.axhline(tol, color="gray", ls=":", lw=0.8)
    ax.set_xlabel("one evaluation of the chain's frequencies (CRBA + eigh) [us]")
    ax.set_ylabel("combined error against the converged beam truth [-]")
    ax.set_title("PRBDM link count: speed against accuracy")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    print(f"   chart written to {out}")


def main() -> None:
    """Run the sweep and write the chart."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="up to 4R, fewer starts/rounds")
    parser.add_argument("--json", default=None, metavar="FILE", help="write the numbers")
    parser.add_argument("--out", default="prbdm_links.png", help="chart file")
    parser.add_argument("--modes", type=int, default=2, help="modes judged, k (default 2)")
    args = parser.parse_args()
    max_links, starts, rounds = (4, 3, 3) if args.quick else (8, 8, 7)
    beams = [("uniform beam", uniform_beam())]
    if not args.quick:
        beams.append(("random beam seed 0", random_beam(0)))
    results = [study(label, beam, args.modes, max_links, starts, rounds)
               for label, beam in beams]
    chart(results, args.out)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
