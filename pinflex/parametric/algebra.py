"""Jet algebras: the arithmetic of Taylor coefficients on the leading axis.

Both follow the :class:`pinflex.erls.Algebra` protocol of the assembly (``size``,
``const_at``, ``const``, ``mm``), as :class:`pinflex.erls.BatchAlgebra` does for poses.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
import scipy.sparse as sp

from pinflex import jets
from pinflex.jets import JetSpace


class JetAlgebra:
    """Taylor coefficients on the leading axis (the :class:`pinflex.erls.Algebra` protocol).

    Constants enter the constant coefficient only (``const_at = 0``); the product of two
    jets is the truncated Cauchy product.
    """

    const_at: int | slice = 0

    def __init__(self, space: JetSpace):
        """Algebra of the jets of ``space``.

        Args:
            space: The jet space (variables and truncation order) of every operand.
        """
        self.space = space
        self.size = space.ncoef

    def const(self, c: np.ndarray) -> np.ndarray:
        """Jet of a constant array.

        Args:
            c: The constant, any shape.

        Returns:
            Jet (ncoef, *c.shape) with only the constant coefficient set.
        """
        return jets.constant(self.space, c)

    def mm(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Truncated product of two matrix jets.

        Args:
            a: Jet (ncoef, ..., n, m).
            b: Jet (ncoef, ..., m, r), or (ncoef, m) for a vector.

        Returns:
            Jet of ``a @ b`` (ncoef, ..., n, r), truncated at the space's order.
        """
        return jets.matmul(self.space, a, b)



@lru_cache(maxsize=16)
def _lookup(space: JetSpace):
    """Position of every multi-index by its base-(p+1) code, and the codes of the space."""
    base = space.order + 1
    weights = base ** np.arange(space.nvars, dtype=np.int64)
    codes = space.multi_indices @ weights
    table = np.full(base**space.nvars, -1, dtype=np.int64)
    table[codes] = np.arange(space.ncoef)
    return table, codes


class SparseJetAlgebra(JetAlgebra):
    """Jet algebra whose products skip coefficients that are zero.

    The factors of the assembly depend on few joints each (a link's root twist only on the
    joints upstream of it), so most of their Taylor coefficients vanish; the truncated product
    multiplies only the nonzero ones, one GEMM per degree of the left factor, and scatters the
    pairs into their target coefficients. Exact: the same sums as :func:`pinflex.jets.matmul`.
    """

    def mm(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Truncated product of two matrix jets (ncoef, n, m) @ (ncoef, m, r)."""
        nc, n, m = a.shape
        r = b.shape[2]
        nz_a = np.any(a.reshape(nc, -1) != 0.0, axis=1)
        nz_b = np.any(b.reshape(nc, -1) != 0.0, axis=1)
        blocks, scatter = _product_plan(self.space, nz_a.tobytes(), nz_b.tobytes())
        if not blocks:
            return np.zeros((nc, n, r))
        parts = []
        for la, rb in blocks:
            lhs = a[la].reshape(la.size * n, m)
            rhs = b[rb].transpose(1, 0, 2).reshape(m, rb.size * r)
            prod = (lhs @ rhs).reshape(la.size, n, rb.size, r).transpose(0, 2, 1, 3)
            parts.append(prod.reshape(-1, n * r))
        stacked = parts[0] if len(parts) == 1 else np.concatenate(parts, axis=0)
        return np.asarray(scatter @ stacked).reshape(nc, n, r)


@lru_cache(maxsize=256)
def _product_plan(space: JetSpace, nz_a: bytes, nz_b: bytes):
    """GEMM blocks and scatter of a truncated product, per pattern of nonzero coefficients.

    The factors of one assembly share few patterns (a factor's pattern is set by the joints
    it depends on), so the pairs, their targets and the sparse scatter are built once per
    pattern: ``blocks`` lists, per degree of the left factor, its nonzero coefficients and
    the right factor's nonzero ones it can pair with; ``scatter`` (ncoef × npairs) sums the
    pair products into their target coefficients.
    """
    deg = space.degrees
    table, codes = _lookup(space)
    ia = np.flatnonzero(np.frombuffer(nz_a, dtype=bool))
    ib = np.flatnonzero(np.frombuffer(nz_b, dtype=bool))
    blocks, targets = [], []
    for d in np.unique(deg[ia]):
        la = ia[deg[ia] == d]
        rb = ib[deg[ib] <= space.order - d]
        if not rb.size:
            continue
        blocks.append((la, rb))
        targets.append(table[(codes[la][:, None] + codes[rb][None, :]).ravel()])
    if not blocks:
        return (), None
    tgt = np.concatenate(targets)
    scatter = sp.csr_matrix((np.ones(tgt.size), (tgt, np.arange(tgt.size))),
                            shape=(space.ncoef, tgt.size))
    return tuple(blocks), scatter
