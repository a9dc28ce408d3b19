"""PRBDM dynamic response against the beam's linear FE (paper 001's "up to 10 %" claim).

Run: ``python benchmarks/bench_prbdm_response.py [--quick] [--json]``.

For paper 001's uniform steel beam, fits nR chains (n = 3, 4, 5; the eigen-only objective and
the combined one, ``fit_prbdm``'s default: frequencies and large tip deflections) and
prints, per chain, the accuracy measures of :mod:`pinflex.dynamics.prbdm`: resonance
frequency and peak receptance errors per mode, the largest |H| error over the band, the static
compliance error and the RMS error of the step response (damping ratio ξ = 0.02 on every mode,
paper 001 eq. 5 with the principal square root). Also Su's classic static 3R PRBM.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))


def main(argv=None) -> int:
    """Run the comparison."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="3R eigen-only fit and Su's 3R only")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--xi", type=float, default=0.02, help="damping ratio (default 0.02)")
    args = ap.parse_args(argv)

    from pinflex.dynamics.prbdm import compare
    from pinflex.prbdm import build_chain, fit_prbdm, uniform_beam

    pl = uniform_beam()
    EI = 205e9 * 0.3624 * 0.040532**3 / 12.0
    rows = {"Su 3R (static PRBM)": build_chain(pl, np.array([0.10, 0.35, 0.40, 0.15]),
                                               np.array([3.51, 2.99, 2.58]) * EI)}
    cases = [(3, "eigen")] if args.quick else [(n, obj) for obj in ("eigen", "combined")
                                               for n in (3, 4, 5)]
    for n, objective in cases:
        fit = fit_prbdm(pl, n, objective=objective, n_starts=4 if args.quick else 16)
        rows[f"{n}R {objective}"] = build_chain(pl, fit.link_fractions, fit.stiffness)
    out = {name: compare(pl, chain, xi=args.xi, periods=5.0) for name, chain in rows.items()}
    if args.json:
        print(json.dumps(out))
        return 0
    for name, r in out.items():
        print(f"{name}: modes {r['modes']}, frequency errors "
              f"{', '.join(f'{100 * e:+.3f}' for e in r['freq_error'])} %; peak |H| errors "
              f"{', '.join(f'{100 * e:+.1f}' for e in r['peak_error'])} %; static "
              f"{100 * r['static_error']:+.1f} %; max |H| error in band "
              f"{100 * r['max_abs_H_error_band']:.0f} %; step response RMS error "
              f"{100 * r['step_rms_error']:.1f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
