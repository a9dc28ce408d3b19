"""A 3 x 2 assignment sweep with one shared Taylor expansion vs one expansion per case.

Run: ``python benchmarks/bench_sweep_share.py [--quick] [--json] [--rounds N]``.

The study: the UR5 of ``urdf/ur5_flexible.xml`` (two aluminium tubes, a payload design mass)
moving its shoulder and elbow along 40 samples; mode 1 is assigned. The sweep is
``targets.0.freq_hz`` (3 values) x ``constraints.mass_budget_kg`` (2 values), cases that differ
only in targets and budgets. Both ways run in this process on one core, interleaved round by
round:

* ``per case``: :func:`pinflex.batch.sweep.run_assign_case` for each case (what the batch
  runner did before: model, trajectory, expansion, exact verification, every time);
* ``shared``: :func:`pinflex.batch.sweep.run_assign_group` on all six (one model, trajectory
  and expansion, the exact frequencies before computed once).

Both give the same designs (checked). Prints the median and range of each over the rounds and
of their ratio. BLAS threads are pinned to 1; on a loaded machine the times vary, the ratio
less. ``--quick`` uses order 3 and two rounds.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from pinflex.batch.sweep import (  # noqa: E402
    parse_sweeps,
    plan_cases,
    run_assign_case,
    run_assign_group,
)

ROOT = Path(__file__).resolve().parents[1]
STUDY = """robot = "{robot}"
[trajectory]
csv = "traj.csv"
[expansion]
order = {order}
[[targets]]
mode = 1
freq_hz = 60.0
[options]
baseline = {{ payload = 0.0 }}
report_modes = [2]
"""


def write_study(folder: Path, order: int) -> Path:
    """The study file and its trajectory in ``folder``."""
    from pinflex.erls import FlexibleModel
    from pinflex.trajectory import Trajectory

    robot = ROOT / "urdf" / "ur5_flexible.xml"
    model = FlexibleModel(robot)
    q0 = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0])
    s = np.linspace(0.0, 1.0, 40)[:, None]
    q = q0 + s * np.array([0.0, 0.25, -0.3, 0.0, 0.0, 0.0])
    Trajectory(s[:, 0] * 2.0, q, model.joint_names).to_csv(folder / "traj.csv")
    path = folder / "study.toml"
    path.write_text(STUDY.format(robot=robot.as_posix(), order=order))
    return path


def main() -> None:
    """Run the benchmark."""
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="order 3, two rounds")
    ap.add_argument("--json", action="store_true", help="print one JSON object")
    ap.add_argument("--rounds", type=int, default=None, help="rounds (default 5, quick 2)")
    args = ap.parse_args()
    order = 3 if args.quick else 4
    rounds = args.rounds or (2 if args.quick else 5)
    with tempfile.TemporaryDirectory() as tmp:
        study = write_study(Path(tmp), order)
        sweeps = parse_sweeps(["targets.0.freq_hz=55,60,65",
                               "constraints.mass_budget_kg=0.5,3.0"])
        cases = plan_cases(study, sweeps)
        items = [(cfg, ov, h, i) for i, (h, _, cfg, ov) in enumerate(cases)]
        t_case, t_shared = [], []
        for _ in range(rounds):
            t0 = time.perf_counter()
            alone = [run_assign_case(cfg, ov, h, i)[0] for cfg, ov, h, i in items]
            t_case.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            shared = run_assign_group(items)
            t_shared.append(time.perf_counter() - t0)
        for a, b in zip(alone, shared):
            assert a["status"] == b["status"] == "ok", (a["error"], b["error"])
            assert np.allclose(a["result"]["y"], b["result"]["y"], atol=1e-9)
    t_case, t_shared = np.array(t_case), np.array(t_shared)
    ratio = t_case / t_shared
    out = {
        "cases": len(items), "order": order, "rounds": rounds, "blas_threads": 1,
        "load_average": os.getloadavg()[0],
        "per_case_s": {"median": float(np.median(t_case)), "min": float(t_case.min()),
                       "max": float(t_case.max())},
        "shared_s": {"median": float(np.median(t_shared)), "min": float(t_shared.min()),
                     "max": float(t_shared.max())},
        "speedup": {"median": float(np.median(ratio)), "min": float(ratio.min()),
                    "max": float(ratio.max())},
    }
    if args.json:
        print(json.dumps(out))
        return
    print(f"3 x 2 sweep on the UR5 (order {order}), {rounds} interleaved rounds, 1 BLAS thread, "
          f"load average {out['load_average']:.2f}")
    print(f"  one expansion per case: median {out['per_case_s']['median']:.2f} s "
          f"(range {t_case.min():.2f}-{t_case.max():.2f})")
    print(f"  one shared expansion:   median {out['shared_s']['median']:.2f} s "
          f"(range {t_shared.min():.2f}-{t_shared.max():.2f})")
    print(f"  speed-up: median {out['speedup']['median']:.2f} x "
          f"(range {ratio.min():.2f}-{ratio.max():.2f})")


if __name__ == "__main__":
    main()
