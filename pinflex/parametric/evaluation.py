"""Evaluation of Taylor models: monomial plans, the two-joint power grid, the compiled kernel.

:class:`EvaluationPlan` is what :meth:`pinflex.parametric.TaylorModel.evaluate` precomputes
when a Taylor model is built; :class:`PowerGrid` evaluates models of two joints without design
variables on the NumPy path or, after ``KERNEL_AFTER`` calls, with the compiled kernel
(:func:`prepare_kernel`, numba imported here only).
"""

from __future__ import annotations

import threading
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING

import numpy as np
import scipy.linalg as sla

from pinflex import jets
from pinflex.linalg import readonly as _readonly

if TYPE_CHECKING:
    from pinflex.parametric.taylor import TaylorModel

RADIUS_TOL = 1e-2
"""Default warning level of the estimated relative truncation error (1 %)."""
_TINY = np.finfo(float).tiny
_MAX = np.maximum.reduce  # the ufunc itself: ndarray.max adds a Python-level wrapper per call
_dot, _abs, _mul, _sub, _matmul = np.dot, np.abs, np.multiply, np.subtract, np.matmul


_KERNEL: list = []  # [the compiled two-joint evaluation, or None without numba], once ready
KERNEL_AFTER = 500
"""Two-joint evaluations in one process after which the compiled kernel is prepared.

Importing numba and compiling (or loading the cached compilation of) the kernel costs
1.2–2.7 s once per process, the NumPy path ~20 µs per call: a process that evaluates a few
times never pays for numba. After this many calls the kernel is prepared in a background
thread while the NumPy path keeps answering (same values to round-off, same radius decisions);
calls take the kernel once it is ready. :func:`prepare_kernel` prepares it at once."""
_KERNEL_LOCK = threading.Lock()
_KERNEL_STATE = {"calls": 0, "started": False}


def _grid_kernel():
    """The compiled :class:`_PowerGrid` evaluation, prepared now (numba imported here only).

    Returns None when numba is not available (the NumPy path is then used).
    """
    if not _KERNEL:
        with _KERNEL_LOCK:
            if not _KERNEL:
                try:
                    from pinflex.parametric._grid_kernel import grid_values
                except ImportError:  # numba missing or broken on this platform: NumPy path
                    grid_values = None
                if grid_values is not None:  # compile (or load) both sample layouts now,
                    q = np.zeros((2, 2))  # with the argument types of _PowerGrid's fields
                    coef = _readonly(np.zeros((3, 3)))
                    form = _readonly(np.zeros(3))
                    for sample in (q, np.asfortranarray(q)):  # C and F, writeable or not
                        for s in (sample, _readonly(sample.copy(order="A"))):
                            grid_values(s, np.zeros(2), coef, form, 1, True)
                _KERNEL.append(grid_values)
    return _KERNEL[0]


def prepare_kernel() -> bool:
    """Prepare the compiled two-joint Taylor evaluation now.

    Otherwise it is prepared in the background after :data:`KERNEL_AFTER` evaluations in a
    process.

    Returns:
        True when the compiled evaluation is available (numba installed), else False.
    """
    return _grid_kernel() is not None


def kernel_when_ready():
    """The kernel once prepared, else None (counting calls; preparing it in the background)."""
    state = _KERNEL_STATE
    state["calls"] += 1
    if state["calls"] >= KERNEL_AFTER and not state["started"]:
        with _KERNEL_LOCK:
            if not state["started"]:
                state["started"] = True
                threading.Thread(target=_grid_kernel, name="pinflex-taylor-kernel",
                                 daemon=True).start()
    return None



@dataclass(frozen=True)
class EvaluationPlan:
    """What :meth:`TaylorModel.evaluate` precomputes: monomial steps, coefficient matrices.

    ``values[(quantity, linear)]`` is the transposed (k, ncoef) coefficient matrix of the
    value; the monomials are rows (ncoef, nsamples), so one GEMM gives all values.
    ``checked[(quantity, linear)]`` stacks below it the rows of the radius screen: for every
    order ``j`` the check reads (the upper half and ``p − 1``), the order-``j`` coefficients
    divided by ``|c_0|`` (a row of ``checked @ mon`` is ``c_j t^j / |c_0|`` at each sample),
    and the spectral meeting rates ``v·(∇λ_j − ∇λ_i)·2/|λ_j − λ_i|`` on the first-order
    monomials.

    The screen (:meth:`screen_passes`) takes the largest magnitude of each row over the
    samples and evaluates the estimate of :meth:`TaylorModel.error_estimate` on them. The
    estimate grows with each of them, so this is an upper bound of the worst per-sample
    estimate: when it meets ``tol`` no sample can fail and the per-sample estimate is skipped;
    otherwise the per-sample estimate runs and decides (and words the warning) exactly as
    before. Same decisions, same messages.
    """

    ncoef: int
    nvars: int
    nq: int
    k: int
    q0_col: np.ndarray | None
    steps: tuple[tuple[int, int, int, int, int], ...]
    values: Mapping[tuple[str, bool], np.ndarray]
    checked: Mapping[tuple[str, bool], np.ndarray]
    root: tuple[tuple[int, float], ...]  # (group, 1/j) of the root-test orders
    spec: tuple[int, ...]  # groups of the spectral rates
    last: int  # group of order p
    before_last: int  # group of order p - 1 (-1: the constant, ratio 1)
    ncheck: int
    grid: PowerGrid | None = None
    lock: threading.Lock = field(default_factory=threading.Lock, repr=False, compare=False)
    scratch: dict = field(default_factory=dict, repr=False, compare=False)

    def new_scratch(self, n: int):
        """Monomial rows for ``n`` samples, kept for the next calls (a few sizes, bounded).

        Returns ``(rows, first, views)``: the rows (ncoef, n) with the constant row set, the
        view the offsets go into, and the ``(source, row, target)`` views of the steps.
        Callers hold :attr:`lock`.
        """
        rows = np.empty((self.ncoef, n))
        rows[0] = 1.0
        first = rows[1 : 1 + self.nvars] if self.ncoef > 1 else None
        views = tuple((rows[s0:s1], rows[r], rows[d0:d1]) for d0, d1, s0, s1, r in self.steps)
        if len(self.scratch) >= 4 or rows.nbytes > 8 << 20:
            self.scratch.clear()
        if rows.nbytes <= 8 << 20:
            self.scratch[n] = (rows, first, views)
        return rows, first, views

    @classmethod
    def build(cls, tm: TaylorModel) -> EvaluationPlan:
        """The plan of a Taylor model (called once, when it is built)."""
        space, p, k = tm.space, tm.order, len(tm.modes)
        nq = tm.q0.size
        direct = not tm.design_idx and tuple(tm.joint_idx) == tuple(range(nq))
        q0_col = np.ascontiguousarray(tm.q0[:, None]) if direct else None
        values = {key: _readonly(np.ascontiguousarray(c.T))
                  for key, c in tm._coefficient_matrices.items()}
        checked: dict[tuple[str, bool], np.ndarray] = {}
        off = space.degree_offsets
        j0 = max(1, (p + 1) // 2)
        orders = sorted(set(range(j0, p + 1)) | {p - 1} - {0}) if p >= 1 else []
        W = tm._spectral_weights
        w = 0 if W is None else W.shape[1] // k
        groups = len(orders) + w
        root = tuple((g, 1.0 / j) for g, j in enumerate(orders) if j >= j0)
        spec = tuple(range(len(orders), groups))
        for (quantity, linear), value in values.items():
            full = tm._coefficient_matrices[quantity, False]
            c0 = np.abs(full[0])
            if (p < 2 or not np.all(c0 > 1e-250) or not np.all(np.isfinite(full))
                    or (W is not None and not np.all(np.isfinite(W)))):
                continue
            cols = np.zeros((space.ncoef, k, groups))  # mode-major: a mode's rows together
            for g, j in enumerate(orders):
                cols[off[j] : off[j + 1], :, g] = full[off[j] : off[j + 1]] / c0
            if W is not None and w:
                cols[1 : 1 + space.nvars, :, len(orders):] = W.reshape(-1, k, w)
            checked[quantity, linear] = _readonly(np.ascontiguousarray(
                np.concatenate([value, cols.reshape(space.ncoef, groups * k).T], axis=0)))
        return cls(
            ncoef=space.ncoef, nvars=space.nvars, nq=nq, k=k, q0_col=q0_col,
            steps=space.monomial_plan if space.order else (),
            values=MappingProxyType(values), checked=MappingProxyType(checked),
            root=root, spec=spec, last=orders.index(p) if p >= 1 else -1,
            before_last=orders.index(p - 1) if p - 1 in orders else -1,
            ncheck=groups * k,
            grid=PowerGrid.build(tm, values, checked) if direct and nq == 2 and p >= 2
            else None,
        )

    def screen_passes(self, colmax: list[float], tol: float) -> bool:
        """True when the bound of the estimate over all samples meets ``tol`` (see above).

        ``colmax``: largest magnitude over the samples of each check row of
        ``checked @ mon``.
        """
        G = self.ncheck // self.k
        spec0 = self.spec[0] if self.spec else G
        bound = tol * (1.0 - 1e-9)  # rounding margin: undecided cases go per sample
        for base in range(0, self.ncheck, G):
            rho = 0.0
            for g, inv_j in self.root:
                r = colmax[base + g] ** inv_j
                if not r <= rho:  # NaN propagates: the per-sample path then decides
                    rho = r
            if spec0 < G:  # (a NaN offset already made the root rows NaN)
                rho = max(rho, max(colmax[base + spec0 : base + G]))
            if not rho < 1.0:
                return False
            tail = colmax[base + self.last]
            if self.before_last >= 0:
                tail = max(tail, rho * colmax[base + self.before_last])
            else:
                tail = max(tail, rho)
            if not tail * rho / max(1.0 - rho, 1e-12) <= bound:
                return False
        return True


@dataclass(frozen=True)
class PowerGrid:
    """The evaluation of two-joint models (both joints expanded, no design), ``p ≥ 2``.

    Per call: the powers of the offsets ``(x, y)``, ``P[j] = P[⌊j/2⌋] · P[j − ⌊j/2⌋]``
    (``p − 1`` products of contiguous blocks, both variables at once); the value factored
    as ``Σ_a x^a (Σ_b C_ab y^b)``: one small GEMM of the coefficient grid ``C_ab`` (zero
    where ``a + b > p``) with the y-powers, one elementwise product with the x-powers (laid
    out so that both operands are contiguous: the product also runs over the y-rows,
    against zeros) and one matrix-vector product summing over ``a``. Five NumPy calls and
    one subtraction, against ``2 (p − 1)`` row-slice products and a GEMM of the general
    monomial rows. When numba is available, :meth:`TaylorModel.evaluate` runs all of it (and
    ``τ²`` of screen 1) as one compiled call instead (``_grid_kernel.grid_values``: the same
    products, equal to round-off); this NumPy form stays the fallback and computes the powers
    screen 2 needs.

    The radius check is screened in two steps before the per-sample estimate, each an
    upper bound of every sample's estimate (so the decisions are those of the per-sample
    estimate):

    1. every check row ``r`` of :class:`EvaluationPlan` is a homogeneous polynomial of
       degree ``d_r`` (the order-``j`` parts and the linear spectral rates), so
       ``|row_r(dx)| ≤ K_r τ^{d_r}`` with ``τ² = dxᵀ A dx`` for a fixed ``A ≻ 0`` and
       ``K_r`` the largest ``|row_r|`` on the ellipse ``τ = 1``. The estimate's bound grows
       with each row, so it is below ``tol`` for every sample when ``max τ² ≤ T(tol)²``,
       ``T`` found once per tolerance by bisection. Per call: ``τ²`` of all samples (one
       product of three rows ``xy, x², y²``, the first computed for the check) and its
       maximum. ``A`` is built from the check rows' own linear and quadratic forms (so the
       directions in which the model does not change do not count), plus ``10⁻⁴`` of the
       identity; ``K_r`` comes from 2048 points on the ellipse, raised by Bernstein's
       inequality for trigonometric polynomials (``|f'| ≤ d ‖f‖``) to a rigorous bound.
    2. when 1 fails: every check row at every sample and the column-maximum screen of
       :meth:`EvaluationPlan.screen_passes`.
    """

    order: int
    k: int
    values: dict[tuple[str, bool], np.ndarray]
    checked: dict[tuple[str, bool], np.ndarray]
    bounds: dict[tuple[str, bool], tuple[tuple[float, ...], tuple[int, ...]]]
    form: np.ndarray
    q0: np.ndarray
    limits: dict = field(default_factory=dict, repr=False, compare=False)
    scratch: dict = field(default_factory=lambda: {False: {}, True: {}}, repr=False,
                          compare=False)  # {checked: {n: arrays}}

    @classmethod
    def build(cls, tm: TaylorModel, values, checked) -> PowerGrid:
        """The grid of a two-joint Taylor model without design variables."""
        p, k = tm.order, len(tm.modes)
        mi = tm.space.multi_indices
        degree = mi.sum(axis=1)
        vals = {}
        for key, v in values.items():  # v: (k, ncoef) -> rows (mode, a), columns b
            g = np.zeros((k, p + 1, p + 1))
            g[:, mi[:, 0], mi[:, 1]] = v
            vals[key] = _readonly(g.reshape(k * (p + 1), p + 1))
        chk, rows_of = {}, {}
        for key, c in checked.items():
            rows = c[k:]
            g = np.zeros((rows.shape[0], (p + 1) ** 2))
            g[:, mi[:, 0] * (p + 1) + mi[:, 1]] = rows
            chk[key] = _readonly(g)
            rows_of[key] = rows
        # A from the check rows' linear forms w (w wᵀ / |w|²) and quadratic forms H (|H|/‖H‖)
        A0 = np.zeros((2, 2))
        for rows in rows_of.values():
            for row in rows:
                d = set(degree[row != 0].tolist())
                if d == {1}:
                    w = row[1:3]
                    A0 += np.outer(w, w) / (w @ w)
                elif d == {2}:
                    lam, V = np.linalg.eigh(np.array([[row[3], row[4] / 2],
                                                      [row[4] / 2, row[5]]]))
                    A0 += (V * np.abs(lam)) @ V.T / np.max(np.abs(lam))
        top = np.max(np.linalg.eigvalsh(A0)) if np.all(np.isfinite(A0)) else 0.0
        A = (A0 / top if top > 0 else np.eye(2)) + 1e-4 * np.eye(2)
        A = 0.5 * (A + A.T)
        # points of the ellipse dxᵀ A dx = 1: dx = L⁻ᵀ (cos θ, sin θ), A = L Lᵀ
        theta = np.linspace(0.0, 2.0 * np.pi, 2048, endpoint=False)
        circle = np.stack([np.cos(theta), np.sin(theta)])
        ellipse = sla.solve_triangular(np.linalg.cholesky(A), circle, lower=True, trans="T")
        mon = jets.monomials(tm.space, ellipse.T)
        bounds = {}
        for key, rows in rows_of.items():
            K, deg = [], []
            for row in rows:
                d = set(degree[row != 0].tolist()) or {1}  # (a zero row: K = 0)
                if len(d) != 1 or not np.all(np.isfinite(row)):
                    K, deg = [np.inf], [1]  # not homogeneous: screen 1 never passes
                    break
                dr = d.pop()
                # the largest |row| on the grid raised by Bernstein's inequality, and round-off
                kr = float(np.max(np.abs(mon @ row))) / (1.0 - dr * np.pi / 2048)
                K.append(kr * (1.0 + 1e-10))
                deg.append(int(dr))
            bounds[key] = (tuple(K), tuple(deg))
        form = _readonly(np.array([2.0 * A[0, 1], A[0, 0], A[1, 1]]))  # · (xy, x², y²)
        return cls(order=p, k=k, values=vals, checked=chk, bounds=bounds, form=form,
                   q0=tm.q0.copy())

    def limit(self, key, tol: float, screen) -> float:
        """Largest ``max τ²`` that passes screen 1 at ``tol``.

        Cached in :attr:`limits` as ``{(quantity, linear, tol): level}`` (-1: never passes).
        """
        found = self.limits.get((*key, tol))
        if found is not None:
            return found
        bound = self.bounds.get(key)
        limit = -1.0
        if bound is not None and all(np.isfinite(bound[0])):
            K, deg = bound

            def passes(T: float) -> bool:
                return bool(screen([kr * T ** d for kr, d in zip(K, deg)], tol))

            lo, hi = 0.0, 1.0
            if passes(lo):
                while passes(hi) and hi < 1e300:
                    lo, hi = hi, 2.0 * hi
                if hi >= 1e300:
                    limit = np.inf
                else:
                    for _ in range(200):
                        mid = 0.5 * (lo + hi)
                        if mid in (lo, hi):
                            break
                        lo, hi = (mid, hi) if passes(mid) else (lo, mid)
                    limit = lo * lo * (1.0 - 1e-9)
        if len(self.limits) >= 32:
            self.limits.clear()
        self.limits[(*key, tol)] = limit
        return limit

    def new_scratch(self, n: int, checked: bool, keep: bool = True):
        """The evaluation of ``n`` samples on arrays of its own: ``(run, P)``.

        ``run(Qa.T, coef)`` fills the powers ``P`` (p+1, rows, n) and returns the values
        (n, k), and with ``checked`` also the largest ``τ²`` of the samples. Kept for the next
        calls (a few sizes, bounded) when ``keep``; callers then hold the plan's lock.
        """
        p, k = self.order, self.k
        W = 3 if checked else 2  # rows per power: x, y (and xy for the check)
        P = np.zeros((p + 1, W, n))
        P[0] = 1.0
        q0 = np.repeat(self.q0[:, None], n, axis=1)
        first, Y = P[1, :2], P[:, 1, :]
        steps = tuple((P[j // 2], P[j - j // 2], P[j]) for j in range(2, p + 1))
        G2 = np.zeros((k * (p + 1), W * n))  # G = C Y in the first n columns, zeros after
        H2 = np.empty_like(G2)
        G, P2, H = G2[:, :n], P.reshape(p + 1, W * n), H2[:, :n]
        Gm: np.ndarray
        Hm: np.ndarray
        S: np.ndarray
        if k == 1:
            Gm, Hm, S = G2, H2, np.ones(p + 1)
        else:
            Gm, Hm = G2.reshape(k, p + 1, W * n), H2.reshape(k, p + 1, W * n)
            S = np.kron(np.eye(k), np.ones((1, p + 1)))  # Σ_a per mode
        sub, mul, mm, dot, mx = _sub, _mul, _matmul, _dot, _MAX
        if not checked:
            def run(QT, coef):
                sub(QT, q0, first)
                for a, b, out in steps:
                    mul(a, b, out)
                mm(coef, Y, out=G)  # G = C Y
                mul(Gm, P2, Hm)  # H = G ⊙ X (and zeros ⊙ Y)
                if k == 1:
                    return dot(S, H)[:, None]  # Σ_a H[a]
                return dot(S, H).T
        else:
            x, y, xy = P[1, 0], P[1, 1], P[1, 2]
            form, tau2 = self.form, np.empty(n)
            block = P.reshape(-1)[5 * n : 8 * n].reshape(3, n)  # xy, x², y²
            # the powers of x and y only (the third rows above the first stay zero)
            steps2 = tuple((a[:2], b[:2], out[:2]) for a, b, out in steps)

            def run(QT, coef):
                sub(QT, q0, first)
                mul(x, y, xy)
                for a, b, out in steps2:
                    mul(a, b, out)
                mm(coef, Y, out=G)
                mul(Gm, P2, Hm)
                value = dot(S, H)[:, None] if k == 1 else dot(S, H).T
                return value, mx(dot(form, block, out=tau2))
        entry = (run, P)
        if keep:
            kept = self.scratch[checked]
            nbytes = (4 + 2 * k) * P.nbytes
            if len(kept) >= 4 or nbytes > 8 << 20:
                kept.clear()
            if nbytes <= 8 << 20:
                kept[n] = entry
        return entry

    def products(self, P: np.ndarray) -> np.ndarray:
        """Every monomial ``x^a y^b`` (``a, b ≤ p``) of the samples whose powers are ``P``."""
        n = P.shape[2]
        return (P[:, 0, None, :] * P[None, :, 1, :]).reshape(-1, n)


