"""PRBDM chains under more load cases: tip moments, inclined and combined end loads, guided ends.

Run: ``python benchmarks/bench_prbdm_loads.py [--beams uniform random1] [--starts 4]
[--json FILE]`` (prints Markdown tables).

For each beam, the tip error of each chain under each case of
:data:`pinflex.prbdm.loads.EXTENDED_CASES`, over the elastica's tip displacement (the
deflection measure of pinflex's fits), every chain solved by its own statics
(:func:`pinflex.prbdm.chain.solve_tip_statics`) and every truth by
:func:`pinflex.prbdm.elastica.end_load_equilibrium`. Chains: Howell's 1R (gamma = 0.85,
K_Theta = 2.65) and, on guided ends, Howell's fixed-guided 2R (pivots (1 - gamma) L / 2 from
each end, K = 2 gamma K_Theta EI / L); Su's 3R end-force and end-moment sets; pinflex's
combined 3R fitted on paper 001's loads (transverse forces alpha = 0.5, 1, 2, 5), and the
combined 1R and 3R fitted on the extended cases themselves (1R: the cantilever cases only).
Also Howell and Midha's (gamma, Theta_max) table of the 1R path, recomputed from the elastica.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

HOWELL_TABLE = [(0.0, 0.8517, 64.3), (0.5, 0.8430, 81.8), (1.0, 0.8360, 94.8)]


def howell_limits(beam) -> list[dict]:
    """Theta where the 1R path error reaches 0.5 % of the deflection, per Howell's n."""
    from scipy.optimize import brentq

    from pinflex.prbdm.loads import LoadCase, case_truth

    length = beam.length_m
    rows = []
    for n, gamma, published in HOWELL_TABLE:
        angle = math.degrees(math.atan2(1.0, -n))

        def error(alpha, gamma=gamma, angle=angle):
            tip = case_truth(beam, LoadCase(alpha=alpha, angle_deg=angle)).tip_m
            theta = math.atan2(-tip[1], tip[0] - (1.0 - gamma) * length)
            radius = math.hypot(tip[0] - (1.0 - gamma) * length, tip[1])
            return math.degrees(theta), abs(radius - gamma * length) / np.linalg.norm(
                tip - [length, 0.0])

        alpha = brentq(lambda a: error(a)[1] - 0.005, 6.0, 8.5, xtol=1e-7)
        rows.append({"n": n, "gamma": gamma, "alpha": alpha, "theta_max_deg": error(alpha)[0],
                     "published_deg": published})
    return rows


def main(argv=None) -> int:
    """Run the comparison."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--beams", nargs="*", default=["uniform", "random1"],
                    help="'uniform' or 'randomSEED' (default: uniform random1)")
    ap.add_argument("--starts", type=int, default=4, help="multistarts per fit (default 4)")
    ap.add_argument("--json", default=None, metavar="FILE", help="also write the numbers")
    args = ap.parse_args(argv)

    from pinflex.prbdm import build_chain, fit_prbdm, random_beam, uniform_beam
    from pinflex.prbdm.beams import equivalent_bending_stiffness
    from pinflex.prbdm.classic import HOWELL_1R, SU_3R_FORCE, SU_3R_MOMENT
    from pinflex.prbdm.loads import EXTENDED_CASES, case_errors, case_truth

    out: dict = {"cases": [c.to_dict() for c in EXTENDED_CASES], "beams": {}}
    for name in args.beams:
        beam = uniform_beam() if name == "uniform" else random_beam(int(name[len("random"):]))
        tips = np.array([case_truth(beam, c).tip_m for c in EXTENDED_CASES])
        ei, length, gamma = equivalent_bending_stiffness(beam), beam.length_m, 0.85
        guided_2r = build_chain(beam, np.array([(1 - gamma) / 2, gamma, (1 - gamma) / 2]),
                                np.full(2, 2 * gamma * 2.65 * ei / length))
        cantilever = tuple(c for c in EXTENDED_CASES if c.boundary == "cantilever")
        chains: dict = {}
        howell = case_errors(beam, HOWELL_1R.chain(beam), EXTENDED_CASES, tips)
        guided = np.array([c.boundary == "fixed-guided" for c in EXTENDED_CASES])
        howell[guided] = case_errors(beam, guided_2r, [c for c in EXTENDED_CASES
                                                       if c.boundary == "fixed-guided"],
                                     tips[guided])
        chains["Howell 1R (guided: 2R)"] = (howell, None)
        chains["Su 3R end force"] = (case_errors(beam, SU_3R_FORCE.chain(beam), EXTENDED_CASES,
                                                 tips), None)
        chains["Su 3R end moment"] = (case_errors(beam, SU_3R_MOMENT.chain(beam),
                                                  EXTENDED_CASES, tips), None)
        fits = [("3R fit, paper loads", 3, None), ("1R fit, these loads", 1, cantilever),
                ("3R fit, these loads", 3, EXTENDED_CASES)]
        for label, n, loads in fits:
            start = time.process_time()
            fit = fit_prbdm(beam, n, n_starts=args.starts, loads=loads)
            cpu = time.process_time() - start
            chains[label] = (case_errors(beam, fit.chain(beam), EXTENDED_CASES, tips),
                             {"eigen_error": fit.eigen_error, "cpu_s": cpu,
                              "link_fractions": fit.link_fractions})
        out["beams"][name] = {k: {"errors": v[0].tolist(), "fit": v[1]}
                              for k, v in chains.items()}
        print(f"\n{name} beam: tip error under each case, % of the tip displacement "
              "(each chain by its own statics; '-' the chain cannot take the case)\n")
        print("| case | " + " | ".join(chains) + " |")
        print("|---" * (len(chains) + 1) + "|")
        for i, case in enumerate(EXTENDED_CASES):
            cells = [("-" if not np.isfinite(v[0][i]) else f"{100 * v[0][i]:.3g}")
                     for v in chains.values()]
            print(f"| {case.label} | " + " | ".join(cells) + " |")
        rms = [np.sqrt(np.nanmean(np.square(v[0]))) for v in chains.values()]
        print("| RMS over the cases it takes | " + " | ".join(f"{100 * r:.3g}" for r in rms)
              + " |")
        freq = [("-" if v[1] is None else f"{100 * v[1]['eigen_error']:.3g}")
                for v in chains.values()]
        print("| fit's frequency error (modes 1..n) | " + " | ".join(freq) + " |")
    rows = howell_limits(uniform_beam())
    out["howell"] = rows
    print("\nHowell and Midha's 1R characteristic radius: Theta where the path error reaches "
          "0.5 % of the deflection (uniform beam)\n")
    print("| n | gamma | alpha | Theta_max, pinflex [deg] | published [deg] |")
    print("|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['n']:g} | {r['gamma']} | {r['alpha']:.4f} | {r['theta_max_deg']:.2f} | "
              f"{r['published_deg']} |")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
