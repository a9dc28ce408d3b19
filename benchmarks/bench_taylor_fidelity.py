"""Speed against accuracy of the Taylor order and of the number of expansion points.

Same work for every setting, in one run: modes 1-3 of benchmark A along its 152-sample
trajectory (nominal design, joints expanded), and of the flexible UR5 at 40 samples within
±0.1 rad of a general pose (three joints). Error: the largest relative frequency error over
samples and modes against the exact model at the same samples (the value the series
converges to). Estimate: the two-term estimate ``max(e_p, e_(p+1))``, ``e_p = |T_(p+1) - T_p|
/ |T_(p+1)|`` (the larger of the next two orders' relative terms), that ``expand(tol=...)`` /
``pinflex assign --tol`` use to pick the order; the single next-order term ``e_p`` beside it
(it vanishes where a coefficient does). Time: one evaluation of
every sample (monomials rebuilt, radius check off; this thread's CPU time, median of
interleaved rounds, single-thread BLAS, so a loaded machine inflates it less than wall time),
and the expansion time (wall).

1  Taylor order p = 1..8, one expansion point (benchmark A at q0; the UR5 at its pose).
2  Expansion points: benchmark A's trajectory cut into K equal runs of samples, each covered
   by an expansion at its middle sample, p = 2 and 4 (K = 1, 2, 3, 4, 6, 8).

Writes ``fidelity_taylor.png`` with ``--out``.

Run: ``python benchmarks/bench_taylor_fidelity.py [--quick] [--json FILE] [--out docs]``.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, interleaved, pin_single_thread

pin_single_thread()

import numpy as np  # noqa: E402

from pinflex.cases.benchmark_a import Q0, benchmark_model, benchmark_trajectory  # noqa: E402
from pinflex.erls import FlexibleModel  # noqa: E402
from pinflex.parametric import expand  # noqa: E402
from pinflex.parametric.fidelity import next_order_estimates, two_term_estimates  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
MODES = (1, 2, 3)
UR5_Q = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
UR5_JOINTS = ["shoulder_lift_joint", "elbow_joint", "wrist_1_joint"]


def _cases():
    a = benchmark_model()
    Qa = benchmark_trajectory(a).q
    ur5 = FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml")
    Qu = np.repeat(UR5_Q[None], 40, axis=0)
    Qu[:, 1:4] += 0.1 * np.random.default_rng(1).uniform(-1, 1, size=(40, 3))
    return {"benchmark A": (a, Q0, Qa, None), "flexible UR5": (ur5, UR5_Q, Qu, UR5_JOINTS)}


def _exact(model, Q):
    return model.frequencies(Q, n_modes=max(MODES))[:, [m - 1 for m in MODES]]


def order_study(model, q0, Q, joints, orders, rounds):
    """Rows (order, error, estimate, single term, eval time, expansion time) at one point."""
    exact = _exact(model, Q)
    top = expand(model, q0, order=max(orders) + 2, modes=MODES, joints=joints, design=[])
    est = two_term_estimates(top, Q)
    single = next_order_estimates(top, Q)
    rows = []
    for p in orders:
        t0 = time.perf_counter()
        tm = expand(model, q0, order=p, modes=MODES, joints=joints, design=[])
        t_exp = time.perf_counter() - t0
        err = float(np.max(np.abs(tm.evaluate(Q, quantity="freq_hz", warn=False) / exact - 1)))
        t = interleaved({"e": lambda: tm.evaluate(Q, quantity="freq_hz", warn=False)},
                        rounds=rounds, number=200, clock=time.thread_time)["e"]
        rows.append((p, err, float(np.max(est[p])), float(np.max(single[p])),
                     float(np.median(t)), t_exp))
    return rows


def points_study(model, Q, order, counts, rounds):
    """Rows (K, error, eval time, expansion time) for K equal runs of samples."""
    exact = _exact(model, Q)
    ns = Q.shape[0]
    rows = []
    for K in counts:
        edges = np.linspace(0, ns, K + 1).round().astype(int)
        t0 = time.perf_counter()
        parts = [(expand(model, Q[(a + b) // 2], order=order, modes=MODES, design=[]), a, b)
                 for a, b in zip(edges[:-1], edges[1:])]
        t_exp = time.perf_counter() - t0

        def run(parts=parts):
            return [tm.evaluate(Q[a:b], quantity="freq_hz", warn=False) for tm, a, b in parts]

        err = float(np.max(np.abs(np.concatenate(run()) / exact - 1)))
        t = interleaved({"e": run}, rounds=rounds, number=100, clock=time.thread_time)["e"]
        rows.append((K, err, float(np.median(t)), t_exp))
    return rows


def main(argv=None):
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer settings and rounds")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    parser.add_argument("--out", metavar="DIR", help="folder for fidelity_taylor.png")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    rounds = 3 if args.quick else 5
    print(f"bench_taylor_fidelity: {blas_threads()}; evaluation times = thread CPU time, median "
          f"of {rounds} interleaved rounds")
    cases = _cases()
    out: dict = {"blas": blas_threads(), "rounds": rounds, "order": {}, "points": {}}
    for name, (model, q0, Q, joints) in cases.items():
        orders = (1, 2, 4, 6) if args.quick else tuple(range(1, 9))
        if name == "flexible UR5":
            orders = (1, 2, 3, 4) if args.quick else (1, 2, 3, 4, 5)
        rows = order_study(model, q0, Q, joints, orders, rounds)
        print(f"\n1. {name}, {Q.shape[0]} samples, modes 1-3: order | max error | two-term "
              "estimate | estimate / error | single next-order term | evaluation [us] | "
              "expansion [ms]")
        for p, e, est, one, t, te in rows:
            print(f"  p={p:<2d} {e:11.2e} {est:11.2e} {est / e:8.2f} {one:11.2e} "
                  f"{1e6 * t:10.1f} {1e3 * te:10.1f}")
        ratios = [r[2] / r[1] for r in rows]
        print(f"  two-term estimate / error: {min(ratios):.2f}-{max(ratios):.2f}")
        out["order"][name] = [dict(zip(("order", "error", "estimate", "single_term", "eval_s",
                                        "expand_s"), r)) for r in rows]
    model, _, Q, _ = cases["benchmark A"]
    counts = (1, 2, 4, 8) if args.quick else (1, 2, 3, 4, 6, 8)
    for order in (2, 4):
        rows = points_study(model, Q, order, counts, rounds)
        print(f"\n2. benchmark A, p = {order}: expansion points | max error | evaluation [us] | "
              "expansions [ms]")
        for K, e, t, te in rows:
            print(f"  K={K:<2d} {e:11.2e} {1e6 * t:10.1f} {1e3 * te:10.1f}")
        out["points"][f"p={order}"] = [dict(zip(("points", "error", "eval_s", "expand_s"), r))
                                       for r in rows]
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")
    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, 2, figsize=(10, 4.2))
        ax = axes[0]
        for name, rows in out["order"].items():
            t = [r["eval_s"] for r in rows]
            ax.loglog(t, [r["error"] for r in rows], "o-", label=f"{name}: error")
            ax.loglog(t, [r["estimate"] for r in rows], "x--", label=f"{name}: estimate")
            for r in rows:
                ax.annotate(f"p={r['order']}", (r["eval_s"], r["error"]), fontsize=7)
        ax.set_xlabel("CPU time per evaluation of all samples [s]")
        ax.set_ylabel("relative frequency error, modes 1-3 (max)")
        ax.set_title("Taylor order (one expansion point)")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
        ax = axes[1]
        for key, rows in out["points"].items():
            t = [r["eval_s"] for r in rows]
            ax.loglog(t, [r["error"] for r in rows], "o-", label=f"benchmark A, {key}")
            for r in rows:
                ax.annotate(f"K={r['points']}", (r["eval_s"], r["error"]), fontsize=7)
        ax.set_xlabel("CPU time per evaluation of all 152 samples [s]")
        ax.set_title("Expansion points along the trajectory")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=7)
        fig.tight_layout()
        Path(args.out).mkdir(parents=True, exist_ok=True)
        path = Path(args.out) / "fidelity_taylor.png"
        fig.savefig(path, dpi=110)
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
