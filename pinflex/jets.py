"""Truncated multivariate Taylor ("jet") arithmetic, vectorised with NumPy.

This module carries the Taylor polynomials of paper 000, eq. (3)–(4), through exact
arithmetic, so that the coefficients of M(q, y) and K(q, y) are exact to round-off rather
than finite differences, and it splits a jet into the partially linear polynomial of
eq. (7)–(9).

Conventions:
    A *jet* of a function ``f: R^nvars -> R^shape`` at an expansion point ``x0``, truncated at
    order ``p``, is a plain ndarray of shape ``(ncoef, *shape)``. Its row ``c`` holds the
    Taylor coefficient ``∂^α f(x0) / α!`` (not the raw derivative) of the multi-index
    ``α = space.multi_indices[c]``, so that ``f(x0 + δx) ≈ Σ_c jet[c] · δx^α``.

    Coefficients are in *graded* order: every ``|α| = 0``, then every ``|α| = 1``, ...,
    then every ``|α| = p``. Within one degree the multi-indices are in *descending
    lexicographic* order, i.e. the exponent of the first variable is largest first. For two
    variables and order 2 the order is ``(0,0), (1,0), (0,1), (2,0), (1,1), (0,2)``. Because
    the order is graded, the jet of a lower order (same variables) is a prefix of the jet.

    Linear operations act coefficient by coefficient, so sums, scalings and products with a
    constant matrix are plain NumPy (``a + b``, ``2.0 * a``, ``C @ a``,
    ``a.swapaxes(-1, -2)``); only products of two jets need :func:`mul` or :func:`matmul`.
    Add a constant through :func:`constant` (``a + constant(space, 2.0)``): a bare scalar
    added to a jet would be added to every coefficient.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
import scipy.sparse as sp

__all__ = [
    "JetSpace",
    "constant",
    "derivative",
    "design_split",
    "evaluate",
    "matmul",
    "monomials",
    "mul",
    "partially_linear",
    "partially_linear_mask",
    "ray_coefficients",
    "restrict",
    "sin_cos_of_variable",
    "sqrt",
    "truncate",
    "variable",
]


def _compositions(degree: int, nvars: int) -> Iterator[tuple[int, ...]]:
    """Yield the multi-indices of one degree in descending lexicographic order."""
    if nvars == 1:
        yield (degree,)
        return
    for first in range(degree, -1, -1):
        for rest in _compositions(degree - first, nvars - 1):
            yield (first, *rest)


def _readonly(array: np.ndarray) -> np.ndarray:
    array.setflags(write=False)
    return array


@dataclass(frozen=True, eq=False)
class JetSpace:
    """The coefficient layout of jets in ``nvars`` variables truncated at ``order``.

    Two spaces compare equal (and hash equal) when ``nvars`` and ``order`` agree.

    Attributes:
        nvars: Number of variables of the expansion.
        order: Truncation order ``p``: coefficients with ``|α| ≤ p`` are kept.
        multi_indices: Exponents α, shape ``(ncoef, nvars)``, graded then descending
            lexicographic (see the module docstring).
        degrees: ``|α|`` of every coefficient, shape ``(ncoef,)``.
        degree_offsets: Coefficients of degree ``d`` occupy
            ``degree_offsets[d]:degree_offsets[d + 1]``; shape ``(order + 2,)``.
        factorials: ``α!`` of every coefficient, shape ``(ncoef,)``.
        index: Map from an exponent tuple α to its coefficient position.
        pair_a: First factor of every product pair, sorted by ``pair_c``; shape ``(npairs,)``.
        pair_b: Second factor of every product pair; shape ``(npairs,)``.
        pair_c: Position of ``α_a + α_b`` (all pairs with ``|α_a| + |α_b| ≤ order``),
            non-decreasing; shape ``(npairs,)``.
        pair_starts: First pair of every target coefficient, shape ``(ncoef,)`` (every target
            has at least the pair ``(0, c)``), for ``np.add.reduceat``.
        parent: For ``|α| ≥ 1``, the position of ``α - e_k`` where ``k`` is
            ``parent_var``; ``-1`` for the constant term. Shape ``(ncoef,)``.
        parent_var: The variable ``k`` removed to get ``parent``; ``-1`` for the constant.
    """

    nvars: int
    order: int
    multi_indices: np.ndarray = field(init=False, repr=False)
    degrees: np.ndarray = field(init=False, repr=False)
    degree_offsets: np.ndarray = field(init=False, repr=False)
    factorials: np.ndarray = field(init=False, repr=False)
    index: dict[tuple[int, ...], int] = field(init=False, repr=False)
    pair_a: np.ndarray = field(init=False, repr=False)
    pair_b: np.ndarray = field(init=False, repr=False)
    pair_c: np.ndarray = field(init=False, repr=False)
    pair_starts: np.ndarray = field(init=False, repr=False)
    parent: np.ndarray = field(init=False, repr=False)
    parent_var: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if isinstance(self.nvars, bool) or not isinstance(self.nvars, (int, np.integer)):
            raise TypeError(f"nvars must be an int, got {self.nvars!r}")
        if isinstance(self.order, bool) or not isinstance(self.order, (int, np.integer)):
            raise TypeError(f"order must be an int, got {self.order!r}")
        if self.nvars < 1:
            raise ValueError(f"nvars = {self.nvars}: a jet space needs at least one variable")
        if self.order < 0:
            raise ValueError(f"order = {self.order}: the truncation order must be ≥ 0")
        nvars, order = int(self.nvars), int(self.order)
        object.__setattr__(self, "nvars", nvars)
        object.__setattr__(self, "order", order)

        alphas = [a for d in range(order + 1) for a in _compositions(d, nvars)]
        mi = np.array(alphas, dtype=np.int64).reshape(len(alphas), nvars)
        degrees = mi.sum(axis=1)
        offsets = np.searchsorted(degrees, np.arange(order + 2), side="left")
        index = {a: i for i, a in enumerate(alphas)}
        fact = np.array([math.prod(math.factorial(int(k)) for k in a) for a in alphas], float)

        # Product table: every pair (i, j) with |α_i| + |α_j| ≤ order.
        pa_list, pb_list, pc_list = [], [], []
        for i, ai in enumerate(alphas):
            jmax = int(offsets[order - sum(ai) + 1])
            js = np.arange(jmax)
            sums = mi[js] + mi[i]
            pa_list.append(np.full(jmax, i))
            pb_list.append(js)
            pc_list.append(np.array([index[tuple(s)] for s in sums.tolist()], dtype=np.int64))
        pa, pb, pc = (np.concatenate(x) for x in (pa_list, pb_list, pc_list))
        perm = np.lexsort((pb, pa, pc))
        pa, pb, pc = pa[perm], pb[perm], pc[perm]
        starts = np.searchsorted(pc, np.arange(len(alphas)), side="left")

        parent = np.full(len(alphas), -1, dtype=np.int64)
        parent_var = np.full(len(alphas), -1, dtype=np.int64)
        for i, a in enumerate(alphas[1:], start=1):
            k = next(k for k, ak in enumerate(a) if ak > 0)
            parent_var[i] = k
            parent[i] = index[a[:k] + (a[k] - 1,) + a[k + 1 :]]

        for name, value in (
            ("multi_indices", mi),
            ("degrees", degrees),
            ("degree_offsets", offsets),
            ("factorials", fact),
            ("pair_a", pa),
            ("pair_b", pb),
            ("pair_c", pc),
            ("pair_starts", starts),
            ("parent", parent),
            ("parent_var", parent_var),
        ):
            object.__setattr__(self, name, _readonly(value))
        object.__setattr__(self, "index", index)

    @property
    def ncoef(self) -> int:
        """Number of coefficients, ``C(nvars + order, order)``."""
        return int(self.degree_offsets[-1])

    @property
    def npairs(self) -> int:
        """Number of coefficient pairs in the product table."""
        return int(self.pair_a.size)

    def degree_slice(self, degree: int) -> slice:
        """Slice of the coefficients of one degree ``|α| = degree``."""
        if not 0 <= degree <= self.order:
            raise ValueError(f"degree {degree} is outside 0..{self.order}")
        return slice(int(self.degree_offsets[degree]), int(self.degree_offsets[degree + 1]))

    def position(self, alpha: Sequence[int]) -> int:
        """Coefficient position of the multi-index ``alpha``.

        Raises:
            ValueError: ``alpha`` has the wrong length, a negative entry or ``|α| > order``.
        """
        key = tuple(int(a) for a in alpha)
        if len(key) != self.nvars or key not in self.index:
            raise ValueError(
                f"multi-index {key} is not in the jet space (nvars = {self.nvars}, order = "
                f"{self.order}): give {self.nvars} non-negative integers summing to ≤ {self.order}"
            )
        return self.index[key]

    @cached_property
    def _matmul_plan(self) -> tuple[list[tuple[int, int, int, int]], sp.csr_matrix]:
        """Per-degree GEMM blocks and the sparse scatter of their outputs into coefficients.

        For each degree ``d`` of the left factor, every left coefficient of degree ``d`` times
        every right coefficient of degree ≤ ``order - d`` is a valid pair; the pairs are laid
        out as ``(left, right)`` row-major, the order in which one GEMM produces them.
        """
        blocks, targets = [], []
        off = self.degree_offsets
        for d in range(self.order + 1):
            a0, a1, b1 = int(off[d]), int(off[d + 1]), int(off[self.order - d + 1])
            blocks.append((a0, a1, 0, b1))
            ai = np.repeat(np.arange(a0, a1), b1)
            bj = np.tile(np.arange(b1), a1 - a0)
            sums = self.multi_indices[ai] + self.multi_indices[bj]
            targets.append(np.array([self.index[tuple(s)] for s in sums.tolist()], np.int64))
        tgt = np.concatenate(targets)
        scatter = sp.csr_matrix(
            (np.ones(tgt.size), (tgt, np.arange(tgt.size))), shape=(self.ncoef, tgt.size)
        )
        return blocks, scatter

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, JetSpace):
            return NotImplemented
        return (self.nvars, self.order) == (other.nvars, other.order)

    def __hash__(self) -> int:
        return hash((JetSpace, self.nvars, self.order))


def _check_jet(space: JetSpace, jet: np.ndarray, name: str = "jet") -> np.ndarray:
    jet = np.asarray(jet)
    if jet.ndim == 0 or jet.shape[0] != space.ncoef:
        raise ValueError(
            f"{name} has shape {jet.shape}; a jet of this space needs shape "
            f"({space.ncoef}, ...) with the coefficient axis first"
        )
    return jet


def _check_var(space: JetSpace, k: int) -> int:
    if not 0 <= int(k) < space.nvars:
        raise ValueError(f"variable index {k} is outside 0..{space.nvars - 1}")
    return int(k)


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
    blocks, scatter = space._matmul_plan
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


def truncate(space: JetSpace, jet: np.ndarray, new_space: JetSpace) -> np.ndarray:
    """Drop the coefficients of degree above ``new_space.order``.

    Args:
        space: Space of ``jet``.
        jet: Jet of shape ``(ncoef, *shape)``.
        new_space: Target space, same ``nvars`` and an order ≤ ``space.order``.

    Returns:
        Jet of shape ``(new_space.ncoef, *shape)`` (a copy).

    Raises:
        ValueError: The spaces are incompatible.
    """
    jet = _check_jet(space, jet)
    if new_space.nvars != space.nvars or new_space.order > space.order:
        raise ValueError(
            f"cannot truncate a jet of (nvars={space.nvars}, order={space.order}) to "
            f"(nvars={new_space.nvars}, order={new_space.order}): keep nvars and lower the order"
        )
    return jet[: new_space.ncoef].copy()


def restrict(space: JetSpace, jet: np.ndarray, keep: Sequence[int]) -> tuple[JetSpace, np.ndarray]:
    """Freeze every variable not in ``keep`` at its expansion point.

    Args:
        space: Space of ``jet``.
        jet: Jet of shape ``(ncoef, *shape)``.
        keep: Indices of the variables to keep, in the order of the new space.

    Returns:
        ``(sub_space, sub_jet)`` with ``sub_space = JetSpace(len(keep), order)``.

    Raises:
        ValueError: ``keep`` is empty, repeats a variable or is out of range.
    """
    jet = _check_jet(space, jet)
    keep = [_check_var(space, k) for k in keep]
    if not keep or len(set(keep)) != len(keep):
        raise ValueError(f"keep = {keep}: give distinct variable indices, at least one")
    sub = JetSpace(len(keep), space.order)
    full = np.zeros((sub.ncoef, space.nvars), dtype=np.int64)
    full[:, keep] = sub.multi_indices
    pos = [space.index[tuple(row)] for row in full.tolist()]
    return sub, jet[pos].copy()


def derivative(space: JetSpace, jet: np.ndarray, alpha: Sequence[int]) -> np.ndarray:
    """Raw partial derivative ``∂^α f(x0)`` at the expansion point.

    Args:
        space: Jet space.
        jet: Jet of ``f``, shape ``(ncoef, *shape)``.
        alpha: Multi-index, ``nvars`` non-negative integers with ``|α| ≤ order``.

    Returns:
        Array of shape ``shape``: the stored coefficient times ``α!``.

    Raises:
        ValueError: ``alpha`` is not in the space.
    """
    jet = _check_jet(space, jet)
    pos = space.position(alpha)
    return jet[pos] * space.factorials[pos]


def monomials(space: JetSpace, dx: np.ndarray) -> np.ndarray:
    """Monomials ``δx^α`` of every coefficient at every sample.

    Args:
        space: Jet space.
        dx: Offsets from the expansion point, shape ``(nsamples, nvars)`` (or ``(nvars,)``).

    Returns:
        Array of shape ``(nsamples, ncoef)`` (``(ncoef,)`` for a single offset).

    Raises:
        ValueError: ``dx`` does not have ``nvars`` columns.
    """
    dx = np.asarray(dx)
    single = dx.ndim == 1
    dx2 = dx[None, :] if single else dx
    if dx2.ndim != 2 or dx2.shape[1] != space.nvars:
        raise ValueError(f"dx has shape {dx.shape}; expected (nsamples, {space.nvars})")
    # a table of powers δx_k^j, then one gather per variable (fewer, larger NumPy calls than
    # a degree-by-degree build; this runs once per evaluation of a Taylor model)
    n, nv = dx2.shape
    powers = np.empty((n, nv, space.order + 1), dtype=np.result_type(dx2, float))
    powers[:, :, 0] = 1.0
    if space.order:
        np.cumprod(np.broadcast_to(dx2[:, :, None], (n, nv, space.order)), axis=2,
                   out=powers[:, :, 1:])
    mi = space.multi_indices
    mon = powers[:, 0, mi[:, 0]]
    for k in range(1, space.nvars):
        mon = mon * powers[:, k, mi[:, k]]
    return mon[0] if single else mon


def evaluate(space: JetSpace, jet: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """Evaluate the Taylor polynomial ``Σ_α jet[α] δx^α`` at many offsets.

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)``.
        dx: Offsets from the expansion point, shape ``(nsamples, nvars)`` (or ``(nvars,)``).

    Returns:
        Values of shape ``(nsamples, *shape)`` (``shape`` for a single offset).
    """
    jet = _check_jet(space, jet)
    mon = monomials(space, dx)
    if mon.ndim == 1:
        return np.tensordot(mon, jet, axes=(0, 0))
    return (mon @ jet.reshape(space.ncoef, -1)).reshape(mon.shape[0], *jet.shape[1:])


def ray_coefficients(space: JetSpace, jet: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Univariate Taylor coefficients along rays ``t ↦ f(x0 + t v)``.

    ``c_k(v) = Σ_{|α|=k} jet[α] v^α``.

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)``.
        directions: Ray directions ``v``, shape ``(ndir, nvars)``.

    Returns:
        Array of shape ``(ndir, order + 1, *shape)``.
    """
    jet = _check_jet(space, jet)
    mon = monomials(space, np.atleast_2d(directions))
    weighted = mon.reshape(*mon.shape, *((1,) * (jet.ndim - 1))) * jet[None]
    return np.add.reduceat(weighted, space.degree_offsets[:-1], axis=1)


def partially_linear_mask(space: JetSpace, design: Sequence[int]) -> np.ndarray:
    """Coefficients kept by the partial linearization of eq. (7): ``|β| ≤ 1``.

    Args:
        space: Jet space.
        design: Indices of the design variables ``y`` (the others are the joints ``q``).

    Returns:
        Boolean mask of shape ``(ncoef,)``.
    """
    design = [_check_var(space, k) for k in design]
    return space.multi_indices[:, design].sum(axis=1) <= 1


def partially_linear(space: JetSpace, jet: np.ndarray, design: Sequence[int]) -> np.ndarray:
    """Jet with every coefficient of degree ≥ 2 in the design variables set to zero (eq. 7).

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)``.
        design: Indices of the design variables ``y``.

    Returns:
        Jet of the same shape, linear in ``δy`` (a copy).
    """
    jet = _check_jet(space, jet)
    mask = partially_linear_mask(space, design)
    return jet * mask.reshape(-1, *((1,) * (jet.ndim - 1)))


def design_split(
    space: JetSpace, jet: np.ndarray, design: Sequence[int]
) -> tuple[JetSpace, np.ndarray, np.ndarray]:
    """Split a jet into the polynomials ``l_0(q)`` and ``l_j(q)`` of eq. (9).

    ``f̂(q, y) = l_0(δq) + Σ_j l_j(δq) δy_j`` where ``l_0`` has order ``p`` and each ``l_j``
    order ``p − 1`` (its degree-``p`` coefficients are zero).

    Args:
        space: Jet space in all variables.
        jet: Jet of shape ``(ncoef, *shape)``.
        design: Indices of the design variables ``y``, in the order of the output ``j`` axis.
            The remaining variables, in increasing index order, are the joints ``q``.

    Returns:
        ``(q_space, l0, l1)`` with ``q_space = JetSpace(nq, order)``, ``l0`` of shape
        ``(q_space.ncoef, *shape)`` and ``l1`` of shape ``(ny, q_space.ncoef, *shape)``; both
        evaluate with :func:`monomials` of ``q_space``.

    Raises:
        ValueError: ``design`` repeats a variable, is out of range or leaves no joint.
    """
    jet = _check_jet(space, jet)
    design = [_check_var(space, k) for k in design]
    if len(set(design)) != len(design):
        raise ValueError(f"design = {design} repeats a variable")
    joints = [k for k in range(space.nvars) if k not in design]
    if not joints:
        raise ValueError("design_split needs at least one joint variable besides the design")
    q_space = JetSpace(len(joints), space.order)
    full = np.zeros((q_space.ncoef, space.nvars), dtype=np.int64)
    full[:, joints] = q_space.multi_indices
    l0 = jet[[space.index[tuple(row)] for row in full.tolist()]]
    l1 = np.zeros((len(design), *l0.shape), dtype=jet.dtype)
    n_low = int(q_space.degree_offsets[space.order]) if space.order >= 1 else 0
    for j, k in enumerate(design):
        rows = full[:n_low].copy()
        rows[:, k] += 1
        l1[j, :n_low] = jet[[space.index[tuple(row)] for row in rows.tolist()]]
    return q_space, l0.copy(), l1
