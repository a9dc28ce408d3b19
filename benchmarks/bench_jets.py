"""Time of the eigenpair Taylor recursion and of evaluating the Taylor model.

Run: ``python benchmarks/bench_jets.py``. For a 23-dof pencil with two rigid modes (the size of
benchmark A) expanded in 4 variables (2 joints + 2 design variables), prints for orders 1..8
the time of :func:`pinflex.parametric.eigen.eigen_jets` for 3 elastic modes (eigensolve at the
expansion point included), the time of evaluating the 3 eigenvalue polynomials at 152 samples,
and, for comparison, the bare generalized eigensolves ``scipy.linalg.eigh(K, M)`` of 152 matrix
pairs of the same size. The matrix jets are synthetic (random, with coefficients decaying like
``0.3^|α|``): the timing depends on sizes only.
"""

from __future__ import annotations

import argparse

import numpy as np
import scipy.linalg
from timing import best_of

from pinflex import jets
from pinflex.parametric.eigen import eigen_jets

N_DOF = 23
N_RIGID = 2
N_VARS = 4
MODES = [2, 3, 4]
N_SAMPLES = 152


def synthetic_pencil(space, rng):
    """Jets of a symmetric M (positive definite at x0) and K (two rigid modes at x0)."""
    n, ne = N_DOF, N_DOF - N_RIGID
    decay = 0.3**space.degrees
    a = rng.standard_normal((space.ncoef, n, n)) * decay[:, None, None] / n
    b = rng.standard_normal((space.ncoef, ne, ne)) * decay[:, None, None]
    M = a + a.transpose(0, 2, 1)
    M[0] = np.eye(n) + a[0] @ a[0].T
    K = np.zeros((space.ncoef, n, n))
    K[:, :ne, :ne] = 10.0 * (b + b.transpose(0, 2, 1))
    K[0, :ne, :ne] = b[0] @ b[0].T + np.diag(np.linspace(1.0, 1e3, ne))
    return M, K


def main():
    """Print the timing table."""
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    rng = np.random.default_rng(0)
    pairs = []
    for _ in range(N_SAMPLES):
        M, K = synthetic_pencil(jets.JetSpace(N_VARS, 0), rng)
        pairs.append((M[0], K[0]))
    t_eigh = best_of(lambda: [scipy.linalg.eigh(K, M) for M, K in pairs], repeat=5)

    print(f"n = {N_DOF} dof, {N_VARS} variables, modes {MODES}, {N_SAMPLES} samples")
    print(f"bare eigh of {N_SAMPLES} matrix pairs: {t_eigh * 1e3:.2f} ms")
    print(f"{'order':>5} {'ncoef':>6} {'npairs':>7} {'recursion [ms]':>15} {'eval [us]':>10}")
    for order in range(1, 9):
        space = jets.JetSpace(N_VARS, order)
        M, K = synthetic_pencil(space, rng)
        lam, _ = eigen_jets(space, M, K, MODES)  # warm the per-space plan cache
        number = 20 if order <= 4 else 3
        t_rec = best_of(lambda: eigen_jets(space, M, K, MODES), number=number)
        dx = rng.uniform(-0.1, 0.1, (N_SAMPLES, N_VARS))
        t_eval = best_of(lambda: jets.evaluate(space, lam, dx), number=200)
        print(
            f"{order:>5} {space.ncoef:>6} {space.npairs:>7} {t_rec * 1e3:>15.2f} "
            f"{t_eval * 1e6:>10.1f}"
        )


if __name__ == "__main__":
    main()
