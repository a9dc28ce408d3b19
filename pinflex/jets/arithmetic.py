"""Arithmetic on jets: constants, variables, sin/cos, products, square root."""

from __future__ import annotations

import math

import numpy as np

from pinflex.jets.space import JetSpace, _check_jet, _check_var


def constant(space: JetSpace, value: np.ndarray | float) -> np.ndarray:
    """Jet of a constant.

    Args:
        space: Jet space.
        value: The constant, any shape.

    Returns:
        Jet of shape ``(ncoef, *value.shape)`` with only the constant coefficient set.
    """
    value = np.asarray(value, dtype=float)
    jet = np.zeros((space.ncoef, *value.shape))
    jet[0] = value
    return jet


def variable(space: JetSpace, k: int, value0: np.ndarray | float = 0.0) -> np.ndarray:
    """Jet of the variable ``x_k = x0_k + δx_k``.

    Args:
        space: Jet space.
        k: Variable index, ``0 ≤ k < nvars``.
        value0: Expansion point ``x0_k`` (scalar or array; an array gives a jet of that shape
            whose every entry is the same variable).

    Returns:
        Jet of shape ``(ncoef, *shape(value0))``.

    Raises:
        ValueError: ``k`` is out of range.
    """
    k = _check_var(space, k)
    jet = constant(space, value0)
    if space.order >= 1:
        jet[space.index[tuple(int(i == k) for i in range(space.nvars))]] = 1.0
    return jet


def sin_cos_of_variable(
    space: JetSpace, k: int, x0: np.ndarray | float
) -> tuple[np.ndarray, np.ndarray]:
    """Jets of ``sin(x0 + δx_k)`` and ``cos(x0 + δx_k)`` (exact univariate series).

    The coefficient of ``δx_k^j`` is ``sin^{(j)}(x0)/j!`` (resp. ``cos^{(j)}(x0)/j!``); every
    other coefficient is zero.

    Args:
        space: Jet space.
        k: Variable index (an angle [rad]).
        x0: Expansion point [rad], scalar or array.

    Returns:
        ``(sin_jet, cos_jet)``, each of shape ``(ncoef, *shape(x0))``.

    Raises:
        ValueError: ``k`` is out of range.
    """
    k = _check_var(space, k)
    x0 = np.asarray(x0, dtype=float)
    s, c = np.sin(x0), np.cos(x0)
    cycle_sin, cycle_cos = (s, c, -s, -c), (c, -s, -c, s)
    sin_jet = np.zeros((space.ncoef, *x0.shape))
    cos_jet = np.zeros((space.ncoef, *x0.shape))
    for j in range(space.order + 1):
        pos = space.index[tuple(j if i == k else 0 for i in range(space.nvars))]
        sin_jet[pos] = cycle_sin[j % 4] / math.factorial(j)
        cos_jet[pos] = cycle_cos[j % 4] / math.factorial(j)
    return sin_jet, cos_jet


def _align(a: np.ndarray, ndim: int) -> np.ndarray:
    """Insert unit axes after the coefficient axis so that trailing shapes broadcast."""
    missing = ndim - (a.ndim - 1)
    return a.reshape(a.shape[0], *((1,) * missing), *a.shape[1:]) if missing > 0 else a


def mul(space: JetSpace, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Elementwise product of two jets, truncated at the space's order.

    ``(ab)_γ = Σ_{α+β=γ} a_α b_β`` (Cauchy product of Taylor coefficients). Trailing shapes
    broadcast as in NumPy.

    Args:
        space: Jet space.
        a: Jet of shape ``(ncoef, *sa)``.
        b: Jet of shape ``(ncoef, *sb)``.

    Returns:
        Jet of shape ``(ncoef, *broadcast(sa, sb))``.
    """
    a = _check_jet(space, a, "a")
    b = _check_jet(space, b, "b")
    nd = max(a.ndim, b.ndim) - 1
    a, b = _align(a, nd), _align(b, nd)
    prod = a[space.pair_a] * b[space.pair_b]
    return np.add.reduceat(prod, space.pair_starts, axis=0)


def matmul(space: JetSpace, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Matrix product of two jets of matrices, truncated at the space's order.

    Args:
        space: Jet space.
        a: Jet of shape ``(ncoef, ..., n, m)``.
        b: Jet of shape ``(ncoef, ..., m, r)``, or ``(ncoef, m)`` for a vector.

    Returns:
        Jet of shape ``(ncoef, ..., n, r)`` (``(ncoef, ..., n)`` for a vector ``b``).

    Raises:
        ValueError: The shapes do not chain.
    """
    a = _check_jet(space, a, "a")
    b = _check_jet(space, b, "b")
    if a.ndim < 3 or b.ndim < 2:
        raise ValueError(
            f"matmul needs a matrix jet (ncoef, ..., n, m) and a matrix or vector jet; got "
            f"shapes {a.shape} and {b.shape}"
        )
    if b.ndim == 2:
        return matmul(space, a, b[:, :, None])[..., 0]
    if a.shape[-1] != b.shape[-2]:
        raise ValueError(f"matmul: inner dimensions differ, {a.shape} @ {b.shape}")
    if a.ndim == 3 and b.ndim == 3:
        return _matmul_gemm(space, a, b)
    nd = max(a.ndim, b.ndim) - 1
    a, b = _align(a, nd), _align(b, nd)
    prod = np.matmul(a[space.pair_a], b[space.pair_b])
    return np.add.reduceat(prod, space.pair_starts, axis=0)


def _matmul_gemm(space: JetSpace, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Unbatched matrix jets: one GEMM per degree of ``a``, then one sparse scatter."""
    blocks, scatter = space.matmul_plan
    _, n, m = a.shape
    r = b.shape[2]
    dtype = np.result_type(a, b)
    parts = []
    for a0, a1, b0, b1 in blocks:
        na, nb = a1 - a0, b1 - b0
        lhs = a[a0:a1].reshape(na * n, m)
        rhs = b[b0:b1].transpose(1, 0, 2).reshape(m, nb * r)
        parts.append((lhs @ rhs).reshape(na, n, nb, r).transpose(0, 2, 1, 3).reshape(-1, n * r))
    stacked = np.concatenate(parts, axis=0)
    if np.iscomplexobj(stacked):
        out = scatter @ stacked.real + 1j * (scatter @ stacked.imag)
    else:
        out = scatter @ stacked
    return np.asarray(out, dtype=dtype).reshape(space.ncoef, n, r)


def sqrt(space: JetSpace, a: np.ndarray) -> np.ndarray:
    """Jet of ``sqrt(f)`` from the jet of ``f``, for ``f(x0) > 0`` (e.g. ω = √λ).

    Solves ``s² = f`` degree by degree: ``s_0 = √f_0`` and
    ``s_γ = (f_γ − Σ_{α+β=γ, α,β≠0} s_α s_β) / (2 s_0)``.

    Args:
        space: Jet space.
        a: Jet of ``f``, shape ``(ncoef, *shape)``, with a positive constant term.

    Returns:
        Jet of ``√f``, same shape.

    Raises:
        ValueError: A constant term is not positive.
    """
    a = _check_jet(space, a, "a")
    if np.any(~(a[0] > 0)):
        raise ValueError("sqrt of a jet needs a positive constant term f(x0) > 0")
    s = np.zeros(a.shape)
    s[0] = np.sqrt(a[0])
    inner = (space.pair_a != 0) & (space.pair_b != 0)
    for d in range(1, space.order + 1):
        sl = space.degree_slice(d)
        sel = inner & (space.pair_c >= sl.start) & (space.pair_c < sl.stop)
        acc = np.zeros((sl.stop - sl.start, *a.shape[1:]))
        if np.any(sel):
            terms = s[space.pair_a[sel]] * s[space.pair_b[sel]]
            np.add.at(acc, space.pair_c[sel] - sl.start, terms)
        s[sl] = (a[sl] - acc) / (2.0 * s[0])
    return s
