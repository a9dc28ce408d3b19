"""Expansion time with section, material and joint-stiffness variables against mass variables.

Every case expands all joints at order 4 (``pinflex.expand``); each design case is paired with
a mass case of the same variable count on the same arm, and both are timed in the same rounds
(interleaved, one process, single-thread BLAS unless set), by this thread's CPU time and by
wall time per call; ratios are per round (median and range).

* benchmark A (planar, 2 joints): point masses m1, m2 against rod diameters d1, d2;
* flexible UR5 (6 joints; the base pan joint does not enter the pencil and is left out of the
  recursion): payload against one tube diameter, one Young's modulus (both tubes), one joint
  stiffness (elbow spring), and the payload with wrist 1 locked; payload + an elbow mass
  against the two tube diameters and against a tube diameter + the elbow stiffness. Without
  ``--quick`` the nodal-coordinate route that section variables took before (``matrix_jets``
  + eigh + recursion) is timed for the two tube diameters, and its coefficients are compared
  with the solver route's.

Run: python benchmarks/bench_sections.py [--quick] [--json] [--order P]
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, pin_single_thread, ratio_stats  # noqa: E402

pin_single_thread()

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
QA = np.array([1.817, 5.312])
QU = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])


def _ur5_variants(folder: Path):
    """UR5 variants: two design masses; tubes with a modulus and an elbow spring; a lock."""
    import pinflex

    flex = (ROOT / "urdf" / "ur5_flexible.xml").read_text()
    flex = flex.replace("</pinflex:overlay>",
                        '<pinflex:point_mass name="elbow_mass" link="forearm_link" '
                        'xyz="0 0 0.2" mass="0.5" design="true" lower="0" upper="3"/>'
                        "</pinflex:overlay>")
    tubes = (ROOT / "urdf" / "ur5_tubes.xml").read_text()
    tubes = tubes.replace('E="70e9"', 'E="{E_tube}"')
    tubes = tubes.replace(
        '<pinflex:parameter name="payload"',
        '<pinflex:parameter name="E_tube" value="70e9" lower="50e9" upper="90e9" '
        'design="true"/><pinflex:parameter name="k_elbow" value="1e5" lower="1e4" '
        'upper="1e6" design="true"/><pinflex:parameter name="payload"')
    tubes = tubes.replace("</pinflex:overlay>",
                          '<pinflex:joint name="elbow_joint" stiffness="{k_elbow}"/>'
                          "</pinflex:overlay>")
    (folder / "ur5_two_masses.xml").write_text(flex)
    (folder / "ur5_tubes_k.xml").write_text(tubes)
    return (pinflex.FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml"),
            pinflex.FlexibleModel(folder / "ur5_two_masses.xml"),
            pinflex.FlexibleModel(ROOT / "urdf" / "ur5_tubes.xml", values={"payload": 2.0}),
            pinflex.FlexibleModel(folder / "ur5_tubes_k.xml", values={"payload": 2.0}),
            pinflex.FlexibleModel(folder / "ur5_tubes_k.xml", values={"payload": 2.0},
                                  joints="annotated"),
            pinflex.FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml",
                                  joints={"wrist_1_joint": "locked"}))


def _bench_a():
    from arms import two_link

    import pinflex
    from pinflex.description import parse

    rods = two_link(
        'shape="solid_circle" diameter="{d1}"', 'shape="solid_circle" diameter="{d2}"',
        params='<pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/><pinflex:parameter name="d2" value="0.03" lower="0.02" upper="0.06" '
        'design="true"/>',
        extra='<pinflex:point_mass name="m1" link="link1" xyz="0.6 0 0" mass="0.125"/>'
        '<pinflex:point_mass name="m2" link="link2" xyz="0.45 0 0" mass="0.125"/>')
    return (pinflex.FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True),
            pinflex.FlexibleModel(parse(rods), planar=True))


def nodal_expand(model, q0, order, design):
    """The nodal-coordinate route: jets of the nodal pencil, eigh at q0, the recursion."""
    import scipy.linalg as sla

    from pinflex.parametric import matrix_jets
    from pinflex.parametric.eigen import eigen_jets

    space, M, K, _, _ = matrix_jets(model, q0, order=order, design=design)
    w, V = sla.eigh(K[0], M[0], check_finite=False)
    return eigen_jets(space, M, K, [model.n_rigid], eigvals0=w, eigvecs0=V)[0]


def _timed(fn):
    c0, w0 = time.thread_time(), time.perf_counter()
    fn()
    return time.thread_time() - c0, time.perf_counter() - w0


def main(argv=None) -> int:
    """Run the benchmark."""
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0], epilog=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--quick", action="store_true", help="3 rounds, no nodal-route timing")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--order", type=int, default=4, help="Taylor order (default 4)")
    args = p.parse_args(argv)
    import os

    import pinflex

    order = args.order
    bench_mass, bench_sec = _bench_a()
    tmp = tempfile.TemporaryDirectory()
    ur5, ur5_2m, tubes, tubes_e, tubes_k, ur5_lock = _ur5_variants(Path(tmp.name))

    def ex(model, q, design=None):
        return lambda: pinflex.expand(model, q, order=order, design=design)

    pairs = [  # (label, mass side, design side, variables)
        ("benchmark A: d1, d2 vs m1, m2", ex(bench_mass, QA), ex(bench_sec, QA), 4),
        ("UR5: D_upper vs payload", ex(ur5, QU), ex(tubes, QU, ["D_upper"]), 7),
        ("UR5: E (both tubes) vs payload", ex(ur5, QU), ex(tubes_e, QU, ["E_tube"]), 7),
        ("UR5: k_elbow vs payload", ex(ur5, QU), ex(tubes_k, QU, ["k_elbow"]), 7),
        ("UR5 payload: wrist 1 locked vs free", ex(ur5, QU), ex(ur5_lock, QU), 7),
        ("UR5: D_upper, D_fore vs payload, elbow mass", ex(ur5_2m, QU),
         ex(tubes, QU, ["D_upper", "D_fore"]), 8),
        ("UR5: D_upper, k_elbow vs payload, elbow mass", ex(ur5_2m, QU),
         ex(tubes_k, QU, ["D_upper", "k_elbow"]), 8),
    ]
    sides = {}
    for label, mass_fn, design_fn, _ in pairs:
        sides[label + " [mass]"] = mass_fn
        sides[label + " [design]"] = design_fn
    nodal_label = "UR5: D_upper, D_fore, nodal route"
    if not args.quick:
        sides[nodal_label] = lambda: nodal_expand(tubes, QU, order, ["D_upper", "D_fore"])
    rounds = 3 if args.quick else 5
    for fn in sides.values():  # warm-up (caches, plans)
        fn()
    cpu = {n: [] for n in sides}
    wall = {n: [] for n in sides}
    names = list(sides)
    for r in range(rounds):  # interleaved, alternating order
        for n in names if r % 2 == 0 else names[::-1]:
            c, w = _timed(sides[n])
            cpu[n].append(c)
            wall[n].append(w)
    cpu = {n: np.asarray(v) for n, v in cpu.items()}
    wall = {n: np.asarray(v) for n, v in wall.items()}
    out: dict = {"rounds": rounds, "order": order, "blas": blas_threads(),
                 "load_average": list(os.getloadavg()), "pairs": {}}
    for label, _, _, nv in pairs:
        m, d = label + " [mass]", label + " [design]"
        out["pairs"][label] = {"variables": nv, "cpu": ratio_stats(cpu[d], cpu[m]),
                               "wall": ratio_stats(wall[d], wall[m])}
    if not args.quick:
        new = pinflex.expand(tubes, QU, order=order, design=["D_upper", "D_fore"])
        old = nodal_expand(tubes, QU, order, ["D_upper", "D_fore"])
        agree, sp = 0.0, new.space
        for deg in range(order + 1):
            s = sp.degree_slice(deg)
            agree = max(agree, float(np.max(np.abs(new.eigval_jets[s, 0] - old[s, 0]))
                                     / np.max(np.abs(old[s, 0]))))
        d = "UR5: D_upper, D_fore vs payload, elbow mass [design]"
        out["nodal_route"] = {"cpu": ratio_stats(cpu[nodal_label], cpu[d]),
                              "wall": ratio_stats(wall[nodal_label], wall[d]),
                              "coef_agreement_per_degree": agree}
    if args.json:
        print(json.dumps(out))
        return 0
    la = out["load_average"]
    print(f"expansion time, order {order}, all joints; {rounds} interleaved rounds; {out['blas']}; "
          f"load average {la[0]:.1f} {la[1]:.1f} {la[2]:.1f}")
    print("design / mass at the same variable count: thread CPU time (median ms) and ratio "
          "median (range); wall ratio")
    for label, v in out["pairs"].items():
        c, w = v["cpu"], v["wall"]
        print(f"  {label:46s} {v['variables']} vars  {1e3 * c['num_median_s']:7.1f} vs "
              f"{1e3 * c['den_median_s']:6.1f} ms  {c['ratio_median']:.2f}x "
              f"({c['ratio_min']:.2f}-{c['ratio_max']:.2f}); wall {w['ratio_median']:.2f}x "
              f"({w['ratio_min']:.2f}-{w['ratio_max']:.2f})")
    if not args.quick:
        v = out["nodal_route"]
        c, w = v["cpu"], v["wall"]
        print(f"  nodal route, D_upper and D_fore: {1e3 * c['num_median_s']:.0f} ms CPU, "
              f"{c['ratio_median']:.1f}x ({c['ratio_min']:.1f}-{c['ratio_max']:.1f}) the "
              f"solver route (wall {w['ratio_median']:.1f}x); mode 1 coefficients agree to "
              f"{v['coef_agreement_per_degree']:.1e} (relative to each degree's largest)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
