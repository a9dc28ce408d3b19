"""Compiled evaluation of two-joint Taylor models (see ``evaluation.PowerGrid``).

Imported only by :func:`pinflex.parametric.evaluation.prepare_kernel`, which
:meth:`pinflex.parametric.TaylorModel.evaluate` runs in a background thread after a process's
first ``KERNEL_AFTER`` two-joint evaluations (or a caller runs at once), so nothing else pays
for numba. One call builds the powers of both offsets, contracts them with the coefficient
grid and, when asked, returns the largest ``τ² = dxᵀ A dx`` of the samples for the first
radius screen. Cached on disk (next to this file, or numba's user cache directory when this
one is not writable).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, nogil=True)
def grid_values(Q, q0, coef, form, k, checked):  # pragma: no cover - compiled
    """Values (n, k) of ``Σ_a x^a Σ_b C_ab y^b`` at the samples ``Q`` (n, 2), and max ``τ²``.

    ``coef`` (k (p+1), p+1): rows (mode, a), columns b, zero where ``a + b > p``. ``form``:
    ``(2 A_01, A_00, A_11)``. The powers follow ``P[j] = P[j // 2] P[j − j // 2]`` like the
    NumPy path. ``τ²`` is NaN as soon as one sample's is not finite (so a non-finite offset never
    passes the screen); 0 when ``checked`` is false.
    """
    n = Q.shape[0]
    p1 = coef.shape[1]
    # powers (p+1, n) of both offsets, samples innermost (independent: vectorized)
    px = np.empty((p1, n))
    py = np.empty((p1, n))
    for s in range(n):
        px[0, s] = 1.0
        py[0, s] = 1.0
    if p1 > 1:
        for s in range(n):
            px[1, s] = Q[s, 0] - q0[0]
            py[1, s] = Q[s, 1] - q0[1]
    for j in range(2, p1):
        h = j // 2
        for s in range(n):
            px[j, s] = px[h, s] * px[j - h, s]
            py[j, s] = py[h, s] * py[j - h, s]
    out = np.empty((k, n))  # returned transposed: (n, k)
    g = np.empty(n)
    for m in range(k):
        for s in range(n):
            out[m, s] = 0.0
        for a in range(p1):
            row = m * p1 + a
            for s in range(n):
                g[s] = 0.0
            for b in range(p1):
                c = coef[row, b]  # (zero where a + b > p, multiplied as in the NumPy path)
                for s in range(n):
                    g[s] += c * py[b, s]
            for s in range(n):
                out[m, s] += g[s] * px[a, s]
    t2max = 0.0
    if checked and p1 > 1:
        f0, f1, f2 = form[0], form[1], form[2]
        finite = 0.0  # stays 0 while every τ² is finite (NaN after an inf or a NaN)
        for s in range(n):
            x = px[1, s]
            y = py[1, s]
            t2 = f0 * (x * y) + f1 * (x * x) + f2 * (y * y)
            finite += t2 - t2
            t2max = t2 if t2 > t2max else t2max
        if finite != 0.0:  # a non-finite offset never passes the screen
            t2max = np.nan
    return out.T, t2max
