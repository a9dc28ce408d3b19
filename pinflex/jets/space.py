"""The coefficient layout of truncated multivariate Taylor series (jets)."""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from functools import lru_cache
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    import scipy.sparse as sp


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


@lru_cache(maxsize=64)
def _layout(nvars: int, order: int) -> dict[str, Any]:
    """Coefficient layout of a jet space (the arrays of :class:`JetSpace`), built once."""
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

    out: dict[str, Any] = {}
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
        out[name] = _readonly(value)
    out["index"] = index
    return out


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
        # the layout depends only on (nvars, order): built once, shared (read-only arrays)
        for name, value in _layout(nvars, order).items():
            object.__setattr__(self, name, value)

    @property
    def ncoef(self) -> int:
        """Number of coefficients, ``C(nvars + order, order)``."""
        return int(self.degree_offsets[-1])

    @property
    def npairs(self) -> int:
        """Number of coefficient pairs in the product table."""
        return int(self.pair_a.size)

    def degree_slice(self, degree: int) -> slice:
        """Slice of the coefficients of one degree ``|α| = degree``.

        Args:
            degree: Total degree, 0 <= degree <= order.

        Returns:
            The slice of the coefficient axis (length ``ncoef``) holding that degree.

        Raises:
            ValueError: ``degree`` is outside 0..order.
        """
        if not 0 <= degree <= self.order:
            raise ValueError(f"degree {degree} is outside 0..{self.order}")
        return slice(int(self.degree_offsets[degree]), int(self.degree_offsets[degree + 1]))

    def position(self, alpha: Sequence[int]) -> int:
        """Coefficient position of the multi-index ``alpha``.

        Args:
            alpha: Multi-index, one non-negative exponent per variable (length ``nvars``).

        Returns:
            Its index on the coefficient axis, in ``0..ncoef - 1``.

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

    @property
    def monomial_plan(self) -> tuple[tuple[int, int, int, int, int], ...]:
        """Row slices that build the monomials of degree ≥ 2 from those one degree lower.

        In the graded, descending lexicographic order, the degree-``d`` multi-indices with
        ``α_0 = … = α_{k−1} = 0 < α_k`` are ``e_k`` plus the degree-``(d − 1)`` ones with
        ``α_0 = … = α_{k−1} = 0``, which are the *last* of their degree, in the same order. So
        with the monomials stored as rows (``ncoef × nsamples``, row ``1 + k`` holding
        ``δx_k``), every step ``(dst0, dst1, src0, src1, row)`` is one contiguous product
        ``m[dst0:dst1] = m[src0:src1] * m[row]``: ``(order − 1) · nvars`` products in all, no
        gathers and no Python loop over monomials or samples.
        """
        return _monomial_plan(self)

    @property
    def matmul_plan(self) -> tuple[list[tuple[int, int, int, int]], sp.csr_matrix]:
        """Per-degree GEMM blocks and the sparse scatter of their outputs into coefficients.

        For each degree ``d`` of the left factor, every left coefficient of degree ``d`` times
        every right coefficient of degree ≤ ``order - d`` is a valid pair; the pairs are laid
        out as ``(left, right)`` row-major, the order in which one GEMM produces them.
        """
        return _matmul_plan(self)

    def _build_monomial_plan(self) -> tuple[tuple[int, int, int, int, int], ...]:
        steps = []
        off = self.degree_offsets
        for d in range(2, self.order + 1):
            dst = end_prev = int(off[d])  # the degree-(d - 1) block ends where d starts
            for k in range(self.nvars):
                count = math.comb(d - 1 + self.nvars - k - 1, self.nvars - k - 1)
                steps.append((dst, dst + count, end_prev - count, end_prev, 1 + k))
                dst += count
            if dst != int(off[d + 1]):  # pragma: no cover - layout guard
                raise AssertionError("monomial plan does not match the coefficient layout")
        return tuple(steps)

    def _build_matmul_plan(self) -> tuple[list[tuple[int, int, int, int]], sp.csr_matrix]:
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
        import scipy.sparse as sp

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


@lru_cache(maxsize=64)
def _monomial_plan(space: JetSpace) -> tuple[tuple[int, int, int, int, int], ...]:
    return space._build_monomial_plan()


@lru_cache(maxsize=64)
def _matmul_plan(space: JetSpace) -> tuple[list[tuple[int, int, int, int]], sp.csr_matrix]:
    return space._build_matmul_plan()


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
