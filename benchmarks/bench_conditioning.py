"""Fine meshes with joint springs, locks and section parameters: error against references.

Prints, for the cases of ``tests/conditioning_cases.py`` (references with no pinflex code):

* straight chains (a root or elbow spring of 2000 N m/rad, a locked root or elbow, a solid
  circle diameter parameter off its nominal value) at 256 and 1024 elements per refined link:
  the largest relative error of the lowest three modes from ``frequencies()`` and ``modes()``
  against the transfer-matrix solution of the continuous beam (the mesh limit: the mesh error
  of these modes is below 2e-9 at 256 elements), beside the nodal-coordinate pencil of the same
  mesh (``matrices()`` solved by a generalized eigensolver, the route these models took before);
* a bent spatial three-link arm (spring, lock, area parameter on link 2) at 256 and 1024
  elements on link 2 against the Richardson limit of the global frame in extended precision;
* soft root springs (1e-12 to 100 N m/rad): spring mode and next two against the closed form;
* the extreme clamped cantilevers (L 1 mm-100 m, E 1e6-1e12 Pa, tip/beam mass 0-1e6, 1-256
  elements): how many agree with the same mesh's inverse-form reference to 1e-6, the worst
  error, and how many were refused or warned by name.

Run: python benchmarks/bench_conditioning.py [--quick] [--json FILE]
(``--quick``: 256 elements only, no nodal comparison at 1024, a quarter of the cantilevers).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import time
import warnings
from pathlib import Path

import numpy as np

from pinflex.erls import modal

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _rel(a, b) -> float:
    return float(np.max(np.abs(np.asarray(a) / np.asarray(b) - 1.0)))


def _nodal(model, q, y, k):
    """The nodal-coordinate pencil of the same mesh (the route before), lowest k frequencies."""
    M, K = model.matrices(q, y)
    try:
        lam = modal.eigvals_from(model, M, K)[:k]
    except Exception as exc:  # the nodal pencil may refuse ('not restrained')
        return f"refused ({type(exc).__name__})"
    return np.sqrt(np.abs(lam)) / (2.0 * math.pi)


def _row(name, n, model, q, y, ref, nodal):
    t0 = time.perf_counter()
    f = model.frequencies(q, y, n_modes=3)
    t1 = time.perf_counter()
    g = model.modes(q, y, n_modes=3).freq_hz
    t2 = time.perf_counter()
    out = {"case": name, "elements": n, "frequencies": _rel(f, ref), "modes": _rel(g, ref),
           "frequencies_s": t1 - t0, "modes_s": t2 - t1}
    if nodal:
        h = _nodal(model, q, y, 3)
        out["nodal"] = h if isinstance(h, str) else _rel(h, ref)
    return out


def chains(meshes, nodal_upto):
    """Straight chains against the continuous beam."""
    from beam_closed_forms import planar_chain_hz
    from conditioning_cases import CASES, case

    from pinflex.description import parse
    from pinflex.erls import FlexibleModel

    rows = []
    for n in meshes:
        for name in CASES:
            text, joints, y, segments, points, root = case(name, n)
            model = FlexibleModel(parse(text), planar=True, joints=joints)
            ref = planar_chain_hz(segments, points, root, 3, omega_max=4000.0)
            rows.append(_row(name, n, model, np.zeros(model.nv), y, ref, n <= nodal_upto))
    return rows


def arm3(meshes, nodal_upto):
    """The bent spatial three-link arm against its extended-precision limit."""
    from conditioning_cases import A_AT, ARM3_CASES, Q3, arm3_reference, arm3_urdf, richardson

    from pinflex.description import parse
    from pinflex.erls import FlexibleModel

    rows = []
    for name, (joints, ref_kw, area) in ARM3_CASES.items():
        vals = np.array([arm3_reference(Q3, (4, m, 4), **ref_kw) for m in (4, 8, 16)])
        limit = richardson((4, 8, 16), vals)[0]
        for n in meshes:
            model = FlexibleModel(parse(arm3_urdf((4, n, 4), area)), joints=joints)
            y = np.array([A_AT]) if area else None
            rows.append(_row(f"3-link arm, {name}", n, model, Q3, y, limit, n <= nodal_upto))
    return rows


def soft_springs():
    """Soft root springs against the transfer-matrix closed form."""
    from beam_closed_forms import Segment, bending_hz
    from conditioning_cases import EI_A, RHOA_A, chain

    from pinflex.description import parse
    from pinflex.erls import FlexibleModel

    rows = []
    for k in (1e-12, 1e-10, 1e-8, 1e-6, 1e-4, 1e-2, 1.0, 100.0):
        model = FlexibleModel(parse(chain([1.0], [128])), planar=True, joints={"j0": k})
        ref = bending_hz([Segment(1.0, EI_A, RHOA_A)], [None], k, 3, omega_max=1000.0,
                         omega_min=1e-9)
        f = model.frequencies(np.zeros(1), n_modes=3)
        g = model.modes(np.zeros(1), n_modes=3).freq_hz
        rows.append({"k": k, "spring_mode_hz": float(f[0]), "sqrt_3k_over_rhoAL3_hz":
                     math.sqrt(3 * k / RHOA_A) / (2 * math.pi), "spring_mode": _rel(f[:1], ref[:1]),
                     "elastic": _rel(f[1:], ref[1:]), "modes": _rel(g, ref)})
    return rows


def cantilevers(quick):
    """Extreme clamped cantilevers against the same mesh's reference."""
    from conditioning_cases import LENGTHS, MESHES, MODULI, RATIOS, cantilever

    import pinflex.exceptions as pex
    from pinflex.description import parse
    from pinflex.erls import FlexibleModel

    count = {"ok": 0, "wrong_warned": 0, "wrong_silent": 0, "refused": 0}
    refusals: dict[str, int] = {}
    warned: dict[str, int] = {}
    worst = 0.0
    worst_case = None
    cases = [(L, E, r, n) for L in LENGTHS for E in MODULI for r in RATIOS for n in MESHES]
    if quick:
        cases = cases[::4]
    accuracy = (pex.SoftSpringWarning,)  # the named warning that an answer is not exact
    for L, E, r, n in cases:
        text, ref = cantilever(L, E, r, n)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                model = FlexibleModel(parse(text), planar=True, joints="locked")
                f = model.frequencies(np.zeros(1), n_modes=ref.size)
                g = model.modes(np.zeros(1), n_modes=ref.size).freq_hz
            except pex.PinflexError as exc:
                count["refused"] += 1
                refusals[type(exc).__name__] = refusals.get(type(exc).__name__, 0) + 1
                continue
        for w in caught:
            if issubclass(w.category, pex.PinflexWarning):
                warned[w.category.__name__] = warned.get(w.category.__name__, 0) + 1
        err = max(_rel(f, ref), _rel(g, ref)) if np.all(np.isfinite([*f, *g])) else np.inf
        said = any(issubclass(w.category, accuracy) for w in caught)
        count["ok" if err <= 1e-6 else "wrong_warned" if said else "wrong_silent"] += 1
        if err > worst:
            worst, worst_case = err, {"L": L, "E": E, "tip_over_beam": r, "elements": n}
    return {"cases": len(cases), **count, "refusals": refusals, "warnings": warned,
            "worst": worst, "worst_case": worst_case}


def main(argv=None):
    """Print (and optionally write as JSON) every figure."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="256 elements, fewer cantilevers")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    args = parser.parse_args(argv)
    meshes = (256,) if args.quick else (256, 1024)
    warnings.simplefilter("ignore", category=UserWarning)  # cost estimates of large meshes
    out = {"chains": chains(meshes, 256), "arm3": arm3(meshes, 256),
           "soft_springs": soft_springs(), "cantilevers": cantilevers(args.quick)}

    def fmt(v):
        return v if isinstance(v, str) else f"{v:.1e}"

    print("lowest three modes, largest relative error against the reference")
    print(f"{'case':<34}{'elements':>9}{'frequencies()':>15}{'modes()':>10}"
          f"{'nodal pencil':>24}{'s/call':>9}")
    for r in out["chains"] + out["arm3"]:
        print(f"{r['case']:<34}{r['elements']:>9}{fmt(r['frequencies']):>15}"
              f"{fmt(r['modes']):>10}{fmt(r.get('nodal', '-')):>24}{r['frequencies_s']:>9.2f}")
    print("\nsoft root springs (bar, 128 elements)")
    print(f"{'k [N m/rad]':>12}{'f_spring [Hz]':>15}{'sqrt(3k/rhoAL^3)/2pi':>22}"
          f"{'spring mode':>13}{'next two':>10}{'modes()':>10}")
    for r in out["soft_springs"]:
        print(f"{r['k']:>12.0e}{r['spring_mode_hz']:>15.6e}{r['sqrt_3k_over_rhoAL3_hz']:>22.6e}"
              f"{fmt(r['spring_mode']):>13}{fmt(r['elastic']):>10}{fmt(r['modes']):>10}")
    c = out["cantilevers"]
    print(f"\nextreme cantilevers: {c['cases']} cases, {c['ok']} within 1e-6 of the mesh "
          f"reference, {c['wrong_silent']} wrong without a warning, {c['wrong_warned']} wrong "
          f"with an accuracy warning, {c['refused']} refused {c['refusals']}; warnings seen "
          f"{c['warnings']}; worst error of an answer {c['worst']:.1e} at {c['worst_case']}")
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
