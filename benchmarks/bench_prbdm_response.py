"""PRBDM dynamic response against the beam's linear FE (paper 001's "up to 10 %" claim).

Run: ``python benchmarks/bench_prbdm_response.py [--quick] [--json | --markdown]``
(``--markdown`` prints the table of README's "PRBDM dynamics").

For paper 001's uniform steel beam, fits nR chains (n = 3, 4, 5; the eigen-only objective and
the combined one, ``fit_prbdm``'s default: frequencies and large tip deflections) and
prints, per chain, the accuracy measures of :mod:`pinflex.dynamics.prbdm`: resonance
frequency and peak receptance errors per mode, the largest |H| error over the band, the static
compliance error and the RMS error of the step response (damping ratio ξ = 0.02 on every mode,
paper 001 eq. 5 with the principal square root). Also Su's classic static 3R PRBM with each
of its published stiffness sets (load-independent Table 1, end moment, end force).

An eigen-only fit of n modes at one pose is exactly determined (2n parameters, n
frequencies): a family of chains matches the frequencies to round-off, and which member the
multistart returns decides its deflection and response. Its rows are therefore one member,
not a property of the method; the combined fits are over-determined and stable.
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
    ap.add_argument("--markdown", action="store_true", help="print a Markdown table")
    ap.add_argument("--xi", type=float, default=0.02, help="damping ratio (default 0.02)")
    args = ap.parse_args(argv)

    from pinflex.dynamics.prbdm import compare
    from pinflex.prbdm import build_chain, fit_prbdm, uniform_beam
    from pinflex.prbdm.classic import SU_3R, SU_3R_FORCE, SU_3R_MOMENT

    pl = uniform_beam()
    su = (SU_3R,) if args.quick else (SU_3R, SU_3R_MOMENT, SU_3R_FORCE)
    rows = {model.name: model.chain(pl) for model in su}
    cases = [(3, "eigen")] if args.quick else [(n, obj) for obj in ("eigen", "combined")
                                               for n in (3, 4, 5)]
    for n, objective in cases:
        fit = fit_prbdm(pl, n, objective=objective, n_starts=4 if args.quick else 16)
        rows[f"{n}R {objective}"] = build_chain(pl, fit.link_fractions, fit.stiffness)
    out = {name: compare(pl, chain, xi=args.xi, periods=5.0) for name, chain in rows.items()}
    if args.json:
        print(json.dumps(out))
        return 0
    if args.markdown:
        print("| chain (fit) | definitions, ε | step response RMS | static | resonance peak of "
              "the receptance, modes 1, 2, 3, … | frequencies |")
        print("|---|---|---|---|---|---|")
        for name, r in out.items():
            freq = np.abs(np.asarray(r["freq_error"]))
            freqs = ("exact" if freq.max() < 1e-6 else f"≤ {100 * freq.max():.2g} %"
                     if "Su" not in name else
                     ", ".join(f"{100 * e:+.1f}" for e in r["freq_error"]) + " %")
            defs = ("Su's published set, scored as the fits" if "Su" in name
                    else "fitted by `pinflex` (θ = 0, no pose sweep: no ε)")
            print(f"| {name} | {defs} | {100 * r['step_rms_error']:.1f} % | "
                  f"{100 * r['static_error']:+.1f} % | "
                  + ", ".join(f"{100 * e:+.1f}" for e in r["peak_error"])
                  + f" % | {freqs} |")
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
