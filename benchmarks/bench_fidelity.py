"""Speed against accuracy of the element count: error, its estimate, time per evaluation.

For benchmark A (q0) and the flexible UR5 (a general pose), every flexible link's element
count is multiplied by 1, 2, 4, ...; each level's lowest three frequencies are compared with
a much finer mesh (64x for benchmark A, 16x for the UR5: its own error is far below the
levels shown), next to the Richardson estimate that ``pinflex.erls.fidelity`` uses to pick a
mesh for a tolerance, and the time of one ``frequencies()`` call (median of interleaved rounds,
single-thread BLAS; the machine may be loaded). Writes ``fidelity_elements.png`` with
``--out``.

Run: ``python benchmarks/bench_fidelity.py [--quick] [--json FILE] [--out docs]``.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from interleave import blas_threads, interleaved, pin_single_thread

pin_single_thread()

import numpy as np  # noqa: E402

from pinflex.description import load  # noqa: E402
from pinflex.erls import FlexibleModel  # noqa: E402
from pinflex.erls.fidelity import refined  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
CASES = {
    "benchmark A": (ROOT / "urdf" / "two_link.urdf", np.array([1.817, 5.312]), True, 64),
    "flexible UR5": (ROOT / "urdf" / "ur5_flexible.xml",
                     np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0]), False, 16),
}


def study(name, factors, rounds):
    """Rows (factor, dof, time, error, estimate) of one arm."""
    path, q, planar, fine = CASES[name]
    desc = load(path)
    ref = FlexibleModel(refined(desc, fine), planar=planar).frequencies(q, n_modes=3)
    rows, prev = [], []
    for f in factors:
        model = FlexibleModel(refined(desc, f), planar=planar)
        t = np.median(interleaved({"f": lambda: model.frequencies(q, n_modes=3)},
                                  rounds=rounds, number=3)["f"])
        fr = model.frequencies(q, n_modes=3)
        prev.append(fr)
        est = np.full(3, np.nan)
        if len(prev) >= 3:
            d1, d2 = np.abs(prev[-2] - prev[-3]), np.abs(prev[-1] - prev[-2])
            p = np.clip(np.log2(d1 / d2), 1.0, 8.0)
            est = d2 / (2.0**p - 1.0) / np.abs(fr)
        err = np.abs(fr / ref - 1)
        rows.append((f, model.ndof, float(t), err.max(), float(np.max(est))))
    return rows


def main(argv=None):
    """Run the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0], epilog=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="fewer levels and rounds")
    parser.add_argument("--json", metavar="FILE", help="also write the figures as JSON")
    parser.add_argument("--out", metavar="DIR", help="folder for fidelity_elements.png")
    args = parser.parse_args(argv)
    rounds = 3 if args.quick else 5
    print(f"bench_fidelity: {blas_threads()}; time = median of {rounds} interleaved rounds")
    out = {}
    for name, factors in (("benchmark A", (1, 2, 4, 8) if args.quick else (1, 2, 4, 8, 16, 32)),
                          ("flexible UR5", (1, 2, 4) if args.quick else (1, 2, 4, 8))):
        rows = study(name, factors, rounds)
        print(f"\n{name}: elements x factor | dof | time per frequencies() [ms] | max error "
              "modes 1-3 | Richardson estimate")
        for f, nd, t, e, est in rows:
            print(f"  x{f:<3d} {nd:6d} {1e3 * t:10.2f} {e:12.2e} {est:12.2e}")
        out[name] = [dict(zip(("factor", "ndof", "time_s", "error", "estimate"), r))
                     for r in rows]
    if args.json:
        Path(args.json).write_text(json.dumps(out, indent=2))
        print(f"wrote {args.json}")
    if args.out:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        fig, ax = plt.subplots(figsize=(6.5, 4.2))
        for name, rows in out.items():
            t = [r["time_s"] for r in rows]
            ax.loglog(t, [r["error"] for r in rows], "o-", label=f"{name}: error")
            ax.loglog(t, [r["estimate"] for r in rows], "x--", label=f"{name}: estimate")
        ax.set_xlabel("time per frequencies() call [s]")
        ax.set_ylabel("relative error, modes 1-3 (max)")
        ax.set_title("Elements per link: speed against accuracy")
        ax.grid(alpha=0.3, which="both")
        ax.legend(fontsize=8)
        fig.tight_layout()
        Path(args.out).mkdir(parents=True, exist_ok=True)
        path = Path(args.out) / "fidelity_elements.png"
        fig.savefig(path, dpi=110)
        print(f"wrote {path}")


if __name__ == "__main__":
    main()
