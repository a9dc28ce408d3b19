"""Expansion time with section design variables against mass design variables, one run.

Benchmark A (planar, order 4, both joints expanded): two design variables either as the point
masses m1, m2 (linear in M) or as the diameters d1, d2 of solid rods (A ∝ d², I ∝ d⁴ through
the section formulas in jet arithmetic); and the flexible UR5 (all six joints, order 4): the
payload against the two tube diameters. Both sides are timed interleaved in one process,
median and range over rounds; BLAS threads are reported.

Run: python benchmarks/bench_sections.py [--quick] [--json]
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def _models():
    from test_parameters import two_link

    import pinflex
    from pinflex.description import parse

    rods = two_link(
        'shape="solid_circle" diameter="{d1}"', 'shape="solid_circle" diameter="{d2}"',
        params='<pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/><pinflex:parameter name="d2" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/>',
        extra='<pinflex:point_mass name="m1" link="link1" xyz="0.6 0 0" mass="0.125"/>'
        '<pinflex:point_mass name="m2" link="link2" xyz="0.45 0 0" mass="0.125"/>')
    bench_mass = pinflex.FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    bench_sec = pinflex.FlexibleModel(parse(rods), planar=True)
    ur5_mass = pinflex.FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml")
    ur5_sec = pinflex.FlexibleModel(ROOT / "urdf" / "ur5_tubes.xml", values={"payload": 2.0})
    return bench_mass, bench_sec, ur5_mass, ur5_sec


def main(argv=None) -> int:
    """Run the benchmark."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--quick", action="store_true", help="fewer rounds, benchmark A only")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    args = p.parse_args(argv)
    import pinflex

    bench_mass, bench_sec, ur5_mass, ur5_sec = _models()
    qa = np.array([1.817, 5.312])
    qu = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
    cases = [
        ("benchmark A: m1, m2 (mass)", lambda: pinflex.expand(bench_mass, qa, order=4)),
        ("benchmark A: d1, d2 (rod diameters)",
         lambda: pinflex.expand(bench_sec, qa, order=4)),
    ]
    if not args.quick:
        cases += [
            ("UR5: payload (mass)", lambda: pinflex.expand(ur5_mass, qu, order=4)),
            ("UR5: D_upper, D_fore (tube diameters)",
             lambda: pinflex.expand(ur5_sec, qu, order=4, design=["D_upper", "D_fore"])),
        ]
    rounds = 3 if args.quick else 5
    times = {name: [] for name, _ in cases}
    for _ in range(rounds):  # interleaved
        for name, fn in cases:
            t0 = time.perf_counter()
            fn()
            times[name].append(time.perf_counter() - t0)
    out = {"rounds": rounds, "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS", "default"),
           "cases": {k: {"median_s": float(np.median(v)), "min_s": float(np.min(v)),
                         "max_s": float(np.max(v))} for k, v in times.items()}}
    names = [n for n, _ in cases]
    ratios = {}
    for a, b in zip(names[::2], names[1::2]):
        r = np.array(times[b]) / np.array(times[a])
        ratios[b] = {"median": float(np.median(r)), "min": float(np.min(r)),
                     "max": float(np.max(r))}
    out["section_over_mass"] = ratios
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"expansion time, {rounds} interleaved rounds, BLAS threads {out['blas_threads']} "
          "(shared machine: absolute times vary, ratios are per round)")
    for k, v in out["cases"].items():
        print(f"  {k:42s} median {1e3 * v['median_s']:9.1f} ms "
              f"[{1e3 * v['min_s']:.1f}, {1e3 * v['max_s']:.1f}]")
    for k, r in ratios.items():
        print(f"  ratio {k:36s} {r['median']:.2f} [{r['min']:.2f}, {r['max']:.2f}]")
    return 0


if __name__ == "__main__":
    sys.exit(main())
