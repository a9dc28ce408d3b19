"""Which expanded quantity is nearly linear in which design variable: λ, Hz or 1/λ.

Benchmark A at q0 = (1.817, 5.312) (absolute angles), mode 1, Taylor order 4 in both joints
and two design variables, expanded at the middle of the design box:

* mass variables: the point masses m1, m2 over [0, 0.25]² kg (paper 000's box);
* section variables: the diameters d1, d2 of solid aluminium rods (ρ = 2687 kg/m³, E = 69
  GPa, the 0.125 kg masses kept) over [0.025, 0.035]² m (±17 % around 30 mm; a wider box
  leaves the series' convergence radius in d).

For each quantity (λ = ω², f [Hz], 1/λ) the full Taylor polynomial and the partially linear
one (paper 000 eq. 7–9: linear in δy) are evaluated on an 11 × 11 design grid and compared
with the exact model; errors are reported as the largest relative error of the *frequency*
each polynomial implies (f = √λ / 2π, or 1 / (2π √(1/λ))), so the columns compare like with
like.

Run: python benchmarks/bench_linearity.py [--quick] [--json]
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _jets(tm):
    from pinflex import jets
    from pinflex.jets.scalar import Scalar

    lam = tm.eigval_jets[:, 0]
    inv = (Scalar(tm.space, lam).reciprocal()).c
    freq = jets.sqrt(tm.space, lam) / (2 * np.pi)
    return {"lambda": lam, "Hz": freq, "1/lambda": inv}


def _to_hz(name, v):
    if name == "lambda":
        return np.sqrt(np.maximum(v, 0.0)) / (2 * np.pi)
    if name == "1/lambda":
        return 1.0 / (2 * np.pi * np.sqrt(np.maximum(v, 1e-300)))
    return v


def study(model, q0, box, n):
    """Largest frequency errors of full and partially linear polynomials per quantity."""
    from pinflex import jets
    from pinflex.parametric import expand

    y_mid = np.array([0.5 * (lo + hi) for lo, hi in box])
    tm = expand(model, q0, y_mid, order=4, modes=(1,))
    grid = [np.linspace(lo, hi, n) for lo, hi in box]
    Y = np.array([[a, b] for a in grid[0] for b in grid[1]])
    Q = np.tile(q0, (len(Y), 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exact = model.frequencies(Q, Y, n_modes=1)[:, 0]
    dx = np.hstack([Q - tm.q0, Y - tm.y0])
    mon = jets.monomials(tm.space, dx)
    design_vars = [2, 3]
    out = {}
    for name, jet in _jets(tm).items():
        full = mon @ jet
        lin = mon @ jets.partially_linear(tm.space, jet, design_vars)
        out[name] = {
            "full_percent": 100 * float(np.max(np.abs(_to_hz(name, full) / exact - 1))),
            "linear_percent": 100 * float(np.max(np.abs(_to_hz(name, lin) / exact - 1))),
        }
    return out


def main(argv=None) -> int:
    """Print the table."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="a 5 x 5 design grid")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    from test_sizing import RODS

    import pinflex
    from pinflex.description import parse

    n = 5 if args.quick else 11
    q0 = np.array([1.817, 5.312])
    masses = pinflex.FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    rods = pinflex.FlexibleModel(parse(RODS), planar=True)
    res = {
        "mass m1, m2 in [0, 0.25]^2 kg": study(masses, q0, [(0.0, 0.25)] * 2, n),
        "rod diameters d1, d2 in [0.025, 0.035]^2 m": study(rods, q0, [(0.025, 0.035)] * 2,
                                                           n),
    }
    if args.json:
        print(json.dumps(res))
        return 0
    print(f"benchmark A, mode 1 at q0, order 4, expanded at the box middle, {n} x {n} grid;")
    print("largest relative error of the implied frequency [%]: full Taylor / linear in y")
    print(f"{'design variables':42s} {'lambda':>16s} {'Hz':>16s} {'1/lambda':>16s}")
    for k, v in res.items():
        cells = [f"{v[q]['full_percent']:.4f} / {v[q]['linear_percent']:.3f}"
                 for q in ("lambda", "Hz", "1/lambda")]
        print(f"{k:42s} " + " ".join(f"{c:>16s}" for c in cells))
    return 0


if __name__ == "__main__":
    sys.exit(main())
