"""Start-up of the ``pinflex`` command against the import of Pinocchio alone.

Run: ``python benchmarks/bench_startup.py``. Each round starts fresh Python processes, in
alternating order, for

* ``python -c "import pinocchio"`` (the floor: plain modal analysis needs Pinocchio),
* ``python -m pinflex modes urdf/two_link.urdf --planar`` (the whole command: imports, model
  set-up, one modal analysis, printing),
* ``python -c "import pinflex.jets"`` (the Taylor arithmetic, which needs no Pinocchio),

and prints the median and range over the rounds of each wall time and of the ratio
``pinflex modes / import pinocchio`` measured within the same round (target: at most 1.5).
It also lists which heavy modules a plain ``pinflex modes`` run loads. BLAS threads are set to
one in the child processes.

Like with like: every side runs in a fresh interpreter with the same environment and finds
compiled bytecode for every module, pinflex's included, as after ``pip install`` (which
byte-compiles, as it did for NumPy and Pinocchio). The children drop
``PYTHONDONTWRITEBYTECODE`` and write their bytecode under a temporary
``PYTHONPYCACHEPREFIX`` during an untimed warm-up run, so the checkout is not touched. A second
figure, ``pinflex modes`` with ``PYTHONDONTWRITEBYTECODE=1`` and no bytecode of its own (a
source checkout with bytecode writing off: its modules are compiled on every run, while
NumPy's and Pinocchio's installed bytecode is still read), is printed beside it for reference;
it is not like with like and is not the target figure.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
URDF = ROOT / "urdf" / "two_link.urdf"
HEAVY = ("scipy.optimize", "scipy.sparse", "matplotlib", "meshcat", "dask", "proxsuite")

COMMANDS = {
    "import pinocchio": [sys.executable, "-c", "import pinocchio"],
    "pinflex modes": [sys.executable, "-m", "pinflex", "modes", str(URDF), "--planar"],
    "import pinflex.jets": [sys.executable, "-c", "import pinflex.jets"],
}


def _env(pycache: str | None) -> dict[str, str]:
    """Child environment: BLAS threads 1, this checkout first on the path.

    With ``pycache`` a folder, bytecode is written there and read back (the installed case);
    with None, bytecode writing is off and no prefix is set (a checkout compiled per run).
    """
    env = dict(os.environ, OMP_NUM_THREADS="1", OPENBLAS_NUM_THREADS="1", MKL_NUM_THREADS="1")
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT), env.get("PYTHONPATH")) if p)
    env.pop("PYTHONPYCACHEPREFIX", None)
    if pycache is None:
        env["PYTHONDONTWRITEBYTECODE"] = "1"
    else:
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = pycache
    return env


def _checkout_has_bytecode() -> bool:
    """Whether ``pinflex/`` here holds ``__pycache__`` folders (read even with writing off)."""
    return any((ROOT / "pinflex").rglob("__pycache__"))


def wall_time(cmd: list[str], env: dict[str, str]) -> float:
    """Wall time [s] of one fresh process running ``cmd`` (its output discarded)."""
    t0 = time.perf_counter()
    subprocess.run(cmd, env=env, check=True, stdout=subprocess.DEVNULL, cwd=ROOT)
    return time.perf_counter() - t0


def loaded_modules(env: dict[str, str]) -> dict[str, bool]:
    """Which heavy modules a ``pinflex modes`` run has imported when it finishes."""
    code = ("import runpy, sys\n"
            f"sys.argv = ['pinflex', 'modes', {str(URDF)!r}, '--planar']\n"
            "try:\n    runpy.run_module('pinflex', run_name='__main__')\n"
            "except SystemExit:\n    pass\n"
            f"print(' '.join(m for m in {HEAVY!r} if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                         capture_output=True, text=True, cwd=ROOT).stdout.strip().splitlines()
    loaded = set(out[-1].split()) if out else set()
    return {m: m in loaded for m in HEAVY}


def jets_needs_pinocchio(env: dict[str, str]) -> bool:
    """Whether ``import pinflex.jets`` loads Pinocchio."""
    code = "import sys, pinflex.jets; print('pinocchio' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], env=env, check=True,
                         capture_output=True, text=True, cwd=ROOT).stdout.strip()
    return out == "True"


NO_BYTECODE = "pinflex modes, no bytecode"


def _stats(v: list[float]) -> dict[str, float]:
    return {"median": statistics.median(v), "min": min(v), "max": max(v)}


def run(rounds: int) -> dict:
    """Interleaved rounds; medians and ranges of the wall times and of the ratios."""
    with tempfile.TemporaryDirectory(prefix="pinflex-pycache-") as pycache:
        env = _env(pycache)
        bare = _env(None)
        sides = [(n, cmd, env) for n, cmd in COMMANDS.items()]
        sides.append((NO_BYTECODE, COMMANDS["pinflex modes"], bare))
        for _, cmd, e in sides:  # write the bytecode, warm the file cache; not timed
            wall_time(cmd, e)
        times: dict[str, list[float]] = {n: [] for n, _, _ in sides}
        ratios: list[float] = []
        ratios_bare: list[float] = []
        for r in range(rounds):
            order = sides if r % 2 == 0 else sides[::-1]
            got = {n: wall_time(cmd, e) for n, cmd, e in order}
            for n in times:
                times[n].append(got[n])
            ratios.append(got["pinflex modes"] / got["import pinocchio"])
            ratios_bare.append(got[NO_BYTECODE] / got["import pinocchio"])
        summary = {n: {"median_s": statistics.median(v), "min_s": min(v), "max_s": max(v)}
                   for n, v in times.items()}
        heavy = loaded_modules(env)
        jets = jets_needs_pinocchio(env)
    return {
        "rounds": rounds,
        "blas_threads": 1,
        "bytecode": "cached for every module (as installed), written to a temporary prefix",
        "times": summary,
        "ratio_modes_over_pinocchio": _stats(ratios),
        "ratio_no_bytecode_over_pinocchio": _stats(ratios_bare),
        "checkout_has_bytecode": _checkout_has_bytecode(),
        "target_ratio": 1.5,
        "load_average": list(os.getloadavg()) if hasattr(os, "getloadavg") else None,
        "heavy_modules_loaded_by_modes": heavy,
        "jets_imports_pinocchio": jets,
    }


def main(argv: list[str] | None = None) -> int:
    """Command line of the benchmark."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=9, help="interleaved rounds (default 9)")
    parser.add_argument("--quick", action="store_true", help="5 rounds (for CI smoke runs)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    out = run(5 if args.quick else max(args.rounds, 1))
    if args.json:
        print(json.dumps(out))
        return 0
    print(f"start-up, {out['rounds']} interleaved rounds, BLAS threads 1, bytecode cached for "
          "every module (median [min, max]):")
    for name, t in out["times"].items():
        print(f"  {name:28s} {1e3 * t['median_s']:8.0f} ms  [{1e3 * t['min_s']:.0f}, "
              f"{1e3 * t['max_s']:.0f}]")
    r = out["ratio_modes_over_pinocchio"]
    print(f"  ratio pinflex modes / import pinocchio: {r['median']:.2f} "
          f"[{r['min']:.2f}, {r['max']:.2f}] (target <= {out['target_ratio']})")
    b = out["ratio_no_bytecode_over_pinocchio"]
    note = ("; this checkout has __pycache__ folders, so it was read" if
            out["checkout_has_bytecode"] else "")
    print(f"  for reference, pinflex compiled from source on every run / import pinocchio: "
          f"{b['median']:.2f} [{b['min']:.2f}, {b['max']:.2f}] (not like with like{note})")
    if out["load_average"] is not None:
        print("  load average at the end (1, 5, 15 min): "
              + ", ".join(f"{x:.1f}" for x in out["load_average"]))
    heavy = [m for m, v in out["heavy_modules_loaded_by_modes"].items() if v]
    print(f"  heavy modules loaded by pinflex modes: {', '.join(heavy) or 'none'}")
    print(f"  import pinflex.jets loads Pinocchio: {out['jets_imports_pinocchio']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
