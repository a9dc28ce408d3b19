"""Interleaved timing: both sides of a ratio measured round by round in one process."""

from __future__ import annotations

import os
import time

# no NumPy import at module level: pin_single_thread() must run before NumPy loads its BLAS


def blas_threads() -> str:
    """The BLAS thread setting this process runs with (environment variables)."""
    names = ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS")
    found = [f"{n}={os.environ[n]}" for n in names if n in os.environ]
    return ", ".join(found) if found else "BLAS threads not set (library default)"


def pin_single_thread() -> None:
    """Ask for single-thread BLAS unless the caller set a count (call before importing numpy).

    Raises:
        RuntimeError: NumPy is already imported (the setting would not take effect).
    """
    import sys

    if "numpy" in sys.modules:
        raise RuntimeError("pin_single_thread() must run before NumPy is imported")
    for name in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(name, "1")


def _once(fn, number: int, clock=time.perf_counter) -> float:
    t0 = clock()
    for _ in range(number):
        fn()
    return (clock() - t0) / number


def interleaved(sides: dict, rounds: int = 7, number: int = 1, clock=time.perf_counter) -> dict:
    """Time every side once per round, in turn, for ``rounds`` rounds [s per call].

    The order of the sides alternates between rounds so that neither always runs first.
    ``clock``: wall time by default; ``time.thread_time`` counts only this thread's CPU time
    (with single-thread BLAS, all of the work), which other processes on a loaded machine do
    not inflate. Returns ``{name: array of per-round times}``.
    """
    import numpy as np

    names = list(sides)
    out = {n: [] for n in names}
    for fn in sides.values():  # warm-up (caches, lazy set-up)
        fn()
    for r in range(rounds):
        for n in names if r % 2 == 0 else names[::-1]:
            out[n].append(_once(sides[n], number, clock))
    return {n: np.asarray(v) for n, v in out.items()}


def ratio_stats(num, den) -> dict:
    """Median and range of the per-round ratios ``num / den``, and the median times [s]."""
    import numpy as np

    r = num / den
    return {
        "ratio_median": float(np.median(r)),
        "ratio_min": float(r.min()),
        "ratio_max": float(r.max()),
        "num_median_s": float(np.median(num)),
        "den_median_s": float(np.median(den)),
        "rounds": int(r.size),
    }


def fmt_ratio(s: dict) -> str:
    """``1.23x (1.10-1.40)`` from :func:`ratio_stats`."""
    return f"{s['ratio_median']:.2f}x ({s['ratio_min']:.2f}-{s['ratio_max']:.2f})"
