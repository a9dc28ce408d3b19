"""Taylor models of eigenvalues and frequencies: building, evaluating, radius checks."""

from __future__ import annotations

import threading
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from types import MappingProxyType

import numpy as np
import scipy.linalg as sla

from pinflex import jets
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    ConfigurationError,
    EigenSolverError,
    RepeatedEigenvalue,
    TaylorRadiusExceeded,
    TaylorRadiusWarning,
)
from pinflex.jets import JetSpace
from pinflex.jets.evaluation import monomial_rows
from pinflex.linalg import readonly as _readonly
from pinflex.parametric import solver_design
from pinflex.parametric.conditioned import embed, expansion_eigenpairs, reduced_solver_jets
from pinflex.parametric.eigen import eigen_jets, radius_estimate, spectrum_slopes
from pinflex.parametric.matrices import matrix_jets

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


def _kernel_when_ready():
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
class TaylorModel:
    """Taylor polynomials of eigenvalues around ``(q0, y0)`` (paper 000 eq. 4 and 7–9).

    Attributes:
        space: Jet space (variables: expanded joints, then expanded design variables).
        q0: Expansion pose, user coordinates, (nv,).
        y0: Expansion design values [kg], (ny,).
        modes: Non-rigid mode numbers (1 = lowest), (k,).
        joint_idx: User indices of the expanded joints.
        design_idx: Indices of the expanded design variables.
        eigval_jets: Jets of λ_i = ω_i² [rad²/s²], (ncoef, k).
        radius: Estimated convergence radius along each variable axis, (nvars, k), in the
            variables' own units [rad, m or kg] (see :meth:`error_estimate`).
        spectrum: All non-rigid eigenvalues at the expansion point [rad²/s²], (m,).
        spectrum_slopes: Their first derivatives along each variable, (nvars, m).
        freq_jets: Jets of the frequencies [Hz] (derived from ``eigval_jets`` by default).
        joints: The model's joint conditions ``{joint: 'free' | 'locked' | 'k=...'}``; the
            mode numbers count the non-rigid modes under these conditions.
        order_choice: How the order was picked when :func:`expand` got a ``tol``:
            ``{"tol", "order", "estimate", "estimates", "method"}`` (None otherwise).
        coefficient_matrices: ``{(quantity, linear_in_design): (ncoef, k)}`` coefficients of
            the four polynomials :meth:`evaluate` uses (derived).
        degree_blocks: ``{quantity: (ncoef, k·(p+1) + k)}``: per mode one column per degree
            holding that degree's coefficients only, then the full coefficients (derived).
        spectral_weights: ``(nvars, k·w)`` rates ``2 (∇λ_j − ∇λ_i) / |λ_j − λ_i|`` of each
            mode against its spectral neighbours, or None without a spectrum (derived).

    A Taylor model never changes after construction: every array is a read-only copy, and
    the derived fields are computed once, when it is built. It pickles (process pools, Dask
    batches): only the defining fields are stored, the derived ones are rebuilt on loading.
    """

    space: JetSpace
    q0: np.ndarray
    y0: np.ndarray
    modes: tuple[int, ...]
    joint_idx: tuple[int, ...]
    design_idx: tuple[int, ...]
    eigval_jets: np.ndarray
    radius: np.ndarray
    freq_jets: np.ndarray | None = None
    spectrum: np.ndarray | None = None
    spectrum_slopes: np.ndarray | None = None
    joints: dict[str, str] | None = None
    order_choice: Mapping[str, object] | None = None
    coefficient_matrices: Mapping[tuple[str, bool], np.ndarray] = field(
        init=False, repr=False, compare=False)
    degree_blocks: Mapping[str, np.ndarray] = field(init=False, repr=False, compare=False)
    spectral_weights: np.ndarray | None = field(init=False, repr=False, compare=False)
    evaluation_plan: _EvaluationPlan = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if self.freq_jets is None:
            object.__setattr__(self, "freq_jets",
                               jets.sqrt(self.space, self.eigval_jets) / (2.0 * np.pi))
        for name in ("q0", "y0", "eigval_jets", "radius", "freq_jets", "spectrum",
                     "spectrum_slopes"):
            if getattr(self, name) is not None:
                object.__setattr__(self, name, _readonly(getattr(self, name)))
        ncoef, p, off = self.space.ncoef, self.order, self.space.degree_offsets
        coef, blocks = {}, {}
        for quantity, jet in (("eigval", self.eigval_jets), ("freq_hz", self.jet("freq_hz"))):
            full = np.ascontiguousarray(jet.reshape(ncoef, -1))
            lin = jets.partially_linear(self.space, jet, self.design_vars)
            coef[quantity, False] = _readonly(full)
            coef[quantity, True] = _readonly(np.ascontiguousarray(lin.reshape(ncoef, -1)))
            # per mode one column per degree holding that degree's coefficients only, then the
            # full coefficients: one product with the monomials gives both
            k = full.shape[1]
            B = np.zeros((ncoef, k * (p + 1) + k))
            for c in range(k):
                for d in range(p + 1):
                    B[off[d]:off[d + 1], c * (p + 1) + d] = full[off[d]:off[d + 1], c]
            B[:, k * (p + 1):] = full
            blocks[quantity] = _readonly(B)
        object.__setattr__(self, "coefficient_matrices", MappingProxyType(coef))
        object.__setattr__(self, "degree_blocks", MappingProxyType(blocks))
        W = spectral_weights(self.modes, self.spectrum, self.spectrum_slopes)
        object.__setattr__(self, "spectral_weights", None if W is None else _readonly(W))
        object.__setattr__(self, "evaluation_plan", _EvaluationPlan.build(self))

    def __reduce__(self):
        """Pickle the defining fields only (for process pools, Dask, files).

        The derived fields (coefficient matrices, degree blocks, the evaluation plan with its
        lock and scratch rows) are rebuilt by the constructor on loading, and
        ``order_choice`` is read-only again.
        """
        kw = {f.name: getattr(self, f.name) for f in fields(self) if f.init}
        kw["order_choice"] = _plain(self.order_choice)
        return (_rebuild_taylor_model, (kw,))

    @property
    def order(self) -> int:
        """Truncation order p."""
        return self.space.order

    def jet(self, quantity: str = "eigval") -> np.ndarray:
        """Coefficients of λ (``eigval``, [rad²/s²]) or of the frequency (``freq_hz``, [Hz]).

        Args:
            quantity: ``'eigval'`` (default) or ``'freq_hz'``.

        Returns:
            The jet (ncoef, k): one row per monomial of :attr:`space`, one column per mode.

        Raises:
            ConfigurationError: ``quantity`` is neither name.
        """
        if quantity == "eigval":
            return self.eigval_jets
        if quantity == "freq_hz" and self.freq_jets is not None:
            return self.freq_jets
        raise ConfigurationError(f"quantity='{quantity}': expected 'eigval' or 'freq_hz'")

    def offsets(self, Q, Y=None, *, warn: bool = True) -> np.ndarray:
        """Offsets (n, nvars) of samples from the expansion point; checks fixed joints.

        Args:
            Q: Joint coordinates of the samples, (nv,) or (n, nv), user convention
                [rad or m]; joints that are not expanded must stay at ``q0`` (to 1e-12).
            Y: Design values [kg], (ny,) or (n, ny), over all design variables; those that
                are not expanded must stay at ``y0`` (to 1e-12 relative); None keeps them
                all at ``y0``.
            warn: Run :meth:`check_radius` on the offsets (warns
                :class:`TaylorRadiusWarning` beyond the estimated tolerance).

        Returns:
            Offsets (n, nvars): expanded joints first [rad or m], then expanded design
            variables (in their own units, [kg] for point masses).

        Raises:
            ConfigurationError: ``Q`` or ``Y`` has the wrong shape, ``Y`` is not finite, or
                they move a joint or a design variable that is not expanded.
        """
        Q = np.asarray(Q, dtype=float)
        if Q.ndim == 1:
            Q = Q[None]
        if Q.ndim != 2 or Q.shape[1] != self.q0.size:
            raise ConfigurationError(
                f"expected {self.q0.size} joint values per sample, got shape {Q.shape}"
            )
        jidx = np.asarray(self.joint_idx, dtype=int)
        if len(jidx) < self.q0.size:
            fixed = [i for i in range(self.q0.size) if i not in self.joint_idx]
            if np.any(np.abs(Q[:, fixed] - self.q0[fixed]) > 1e-12):
                raise ConfigurationError(
                    f"joints {fixed} are not expanded in this Taylor model; keep them at q0 "
                    f"({self.q0[fixed].tolist()}) or expand them"
                )
        if Y is not None:
            Y = _checked_design(self, Y, Q.shape[0])
        if not self.design_idx:
            dx = Q[:, jidx] - self.q0[jidx]
        else:
            dx = np.empty((Q.shape[0], self.space.nvars))
            nj = len(jidx)
            dx[:, :nj] = Q[:, jidx] - self.q0[jidx]
            if Y is None:
                dx[:, nj:] = 0.0
            else:
                didx = list(self.design_idx)
                dx[:, nj:] = Y[..., didx] - self.y0[didx]
        if warn:
            self.check_radius(dx)
        return dx

    def error_estimate(self, dx: np.ndarray, *, quantity: str = "eigval",
                       mon: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        r"""Estimated relative truncation error and distance/radius at offsets ``dx``.

        Along each sample's own ray ``x0 + t v`` (``t = |dx|``, ``v = dx / t``) the polynomial
        is ``Σ_k c_k t^k``; its order-``k`` contributions ``c_k t^k`` come from the same
        monomials as the value. Two distances limit the series:

        * ``R_c``: the root test on the upper half of the orders,
          ``min_{j ≥ ⌈p/2⌉} t (|c_0| / |c_j t^j|)^{1/j}``, the distance at which an order
          alone would reach the value (:func:`pinflex.parametric.eigen.root_test`);
        * ``R_s``: half the distance at which the eigenvalue would meet another one of the
          expansion point's spectrum if both moved at their rates at ``x0``,
          ``½ min_j |λ_j − λ_i| / |v·(∇λ_j − ∇λ_i)|`` over the four nearest non-rigid
          eigenvalues on each side. The
          branch points of ``λ_i`` sit near its crossing or veering partners; this brings in
          what low orders cannot show (at ``p = 2`` two coefficients say little about the
          radius). The first-order meeting distance ignores the coupling that turns a
          crossing into a veering, whose branch points lie closer, hence the half.

        With ``R = min(R_c, R_s)`` and ``ρ = t / R``, the omitted terms are estimated as a
        geometric tail after the last order: ``e = T ρ / (1 − ρ) / |c_0|`` with
        ``T = max(|c_p| t^p, ρ |c_{p−1}| t^{p−1})`` (the second guards against a last
        coefficient that happens to be small), and ``e = ∞`` for ``ρ ≥ 1``. Round-off along
        directions that change nothing (turning the whole arm) gives ``ρ`` of order
        ``ε^{1/p}`` and a negligible estimate.

        This is an estimate, not a rigorous bound. On benchmark A (orders 1–8, 45 joint and
        design directions, offsets 0.03–2.5, 4194 sample-modes) the actual error exceeded 1 %
        where the estimate stayed below 1 % twice (actual at most 2.2× the estimate); the
        estimate flags 51 sample-modes whose actual error is below 0.1 % (cautious). Along
        benchmark A's trajectory at ``p = 4`` it stays below 0.8 %
        (``python benchmarks/bench_radius.py``).

        Where the series along a ray has vanishing terms it knows only what the model's own
        orders show. At a pose where the frequency is even in a joint offset (benchmark A
        stretched, q = (0.7, 0.7), elbow offsets) the odd coefficients and the first-order
        spectrum rates are zero. An order-1 model has then nothing to judge its error by
        (it is off by 2.4 % at ±0.4 rad and 6.2 % at ±0.8 rad there): where its first-order
        part vanishes along a non-zero offset the estimate is ``inf`` with ratio NaN, and
        :meth:`check_radius` / :meth:`evaluate` warn that the error cannot be estimated (also
        along directions the quantity does not depend on at all; use order ≥ 2 there).
        Orders 2–6 are judged by their even coefficients and warn there wherever the error
        exceeds 1 % (``tests/test_taylor_fidelity.py``). Near such poses use order ≥ 2, or
        pick the order with :func:`pinflex.parametric.fidelity.order_for_tolerance`, whose
        two-term estimate sees the next non-vanishing order.

        Args:
            dx: Offsets (n, nvars) from the expansion point.
            quantity: 'eigval' or 'freq_hz': whose series is judged.
            mon: Monomials of ``dx`` when the caller has them.

        Returns:
            ``(estimate, ratio)``: relative error estimates and ``t / R``, each (n, k)
            (``inf`` and NaN where an order-1 model cannot estimate its error, see above).
        """
        dx = np.atleast_2d(np.asarray(dx, dtype=float))
        if mon is None:
            mon = jets.monomials(self.space, dx)
        return self._estimate_from(dx, mon @ self.degree_blocks[quantity])[:2]

    def _estimate_from(self, dx: np.ndarray, con: np.ndarray):
        """(estimate, ratio, value) from ``mon @ degree_blocks[quantity]``."""
        p, k = self.order, len(self.modes)
        n = dx.shape[0]
        value = con[:, k * (p + 1):]
        a = np.abs(con[:, :k * (p + 1)]).reshape(n, k, p + 1)  # (sample, mode, degree)
        c0 = np.maximum(a[:, :, 0], _TINY)
        if p >= 1:
            j0 = max(1, (p + 1) // 2)
            r = a[:, :, j0:] / c0[:, :, None]
            np.power(r, (1.0 / np.arange(j0, p + 1, dtype=float))[None, None, :], out=r)
            rho = r.max(axis=2)
        else:
            rho = np.zeros((n, k))
        W = self.spectral_weights
        if W is not None:  # twice the meeting rate: half the meeting distance
            np.maximum(rho, np.abs(dx @ W).reshape(n, k, -1).max(axis=2), out=rho)
        tail = np.maximum(a[:, :, p], rho * a[:, :, p - 1]) if p >= 1 else rho * c0
        # no errstate context here (it costs more than the arithmetic): guard the divisions
        est = tail * rho / (np.maximum(1.0 - rho, 1e-12) * c0)
        est[rho >= 1.0] = np.inf
        if p == 1:
            # an order-1 model whose first-order part vanishes along a sample's offset (a pose
            # where the quantity is even in it) has nothing to judge its error by: unknown,
            # reported as such (ratio NaN) instead of an estimate of 0
            blind = (rho <= 1e-12) & np.any(dx != 0.0, axis=1)[:, None]
            if blind.any():
                est[blind] = np.inf
                rho = np.where(blind, np.nan, rho)
        return est, rho, value

    def _spectral_radius(self, rays: np.ndarray) -> np.ndarray:
        """Distance along unit rays (n, nvars) at which the nearest eigenvalue would meet."""
        return meeting_distance(self.spectral_weights, rays, len(self.modes))

    def check_radius(self, dx: np.ndarray, tol: float = RADIUS_TOL, *,
                     quantity: str = "eigval", mon: np.ndarray | None = None,
                     strict: bool = False) -> float:
        """Warn (or raise, ``strict``) where the estimated truncation error exceeds ``tol``.

        The estimate is :meth:`error_estimate` along each sample's own direction from the
        expansion point, so joint and design offsets are judged together.

        Args:
            dx: Offsets (n, nvars) from the expansion point (:meth:`offsets`).
            tol: Largest acceptable estimated relative error (default 1e-2).
            quantity: ``'eigval'`` or ``'freq_hz'``: whose series is judged.
            mon: Monomials of ``dx`` when the caller has them.
            strict: Raise instead of warning :class:`TaylorRadiusWarning`.

        Raises:
            ConfigurationError: Some offset is not finite.
            TaylorRadiusExceeded: ``strict`` and some sample is beyond the estimated radius or
                its estimated relative error exceeds ``tol``.

        Returns:
            The largest estimated relative error over samples and modes (``inf`` beyond the
            estimated radius).
        """
        if not np.all(np.isfinite(dx)):
            raise ConfigurationError("offsets that are not finite: the Taylor model has no "
                                     "value there")
        est, ratio = self.error_estimate(dx, quantity=quantity, mon=mon)
        return self._report(est, ratio, tol, strict)

    def _report(self, est: np.ndarray, ratio: np.ndarray, tol: float, strict: bool,
                stacklevel: int = 3) -> float:
        worst = float(np.max(est)) if est.size else 0.0
        if worst > tol:
            s, c = np.unravel_index(int(np.argmax(est)), est.shape)
            if np.isnan(ratio[s, c]):
                where = ("where it cannot estimate its error (its first-order part vanishes "
                         "along the offset: use order >= 2)")
            elif not np.isfinite(worst):
                where = (f"beyond its estimated convergence radius (distance "
                         f"{ratio[s, c]:.2f}x the radius)")
            else:
                where = f"where its estimated truncation error is {100 * worst:.3g} %"
            text = (f"Taylor model of mode {self.modes[c]} (order {self.order}) evaluated "
                    f"{where} at sample {s} (tolerance {100 * tol:.3g} %): expand closer, "
                    "raise the order, or use several expansion points "
                    "(pinflex.parametric.expand_along)")
            if strict:
                raise TaylorRadiusExceeded(text)
            warnings.warn(text, TaylorRadiusWarning, stacklevel=stacklevel)
        return worst

    def evaluate(self, Q, Y=None, *, quantity: str = "eigval", linear_in_design=False,
                 warn: bool = True, strict: bool = False, tol: float = RADIUS_TOL
                 ) -> np.ndarray:
        """Polynomial values at samples: (n, k) eigenvalues [rad²/s²] or frequencies [Hz].

        Args:
            Q: Joint values (n, nv) in user coordinates.
            Y: Design values (n, ny) or (ny,) [kg] (default y0).
            quantity: 'eigval' or 'freq_hz'.
            linear_in_design: Use the partially linear polynomial λ̂ (eq. 7) instead of λ^p.
            warn: Warn where the estimated truncation error exceeds ``tol``
                (:meth:`check_radius`); joint values that are not finite are then refused.
                With ``warn=False`` and ``strict=False`` nothing is checked: a NaN or an
                infinite joint value gives a NaN or infinite value.
            strict: Raise :class:`~pinflex.exceptions.TaylorRadiusExceeded` there instead.
            tol: Relative error level of the check.

        Returns:
            Values (n, k) of the expanded modes.

        Raises:
            ConfigurationError: ``Q`` or ``Y`` has the wrong shape, moves a joint or design
                variable the model does not expand, or (with the check on) is not finite.
            TaylorRadiusExceeded: ``strict`` and some sample's estimated error exceeds ``tol``.
        """
        plan = self.evaluation_plan
        grid = plan.grid
        if grid is not None and Y is None:
            # one or two joints, all expanded, no design (see _PowerGrid)
            coef = grid.values.get((quantity, linear_in_design))
            Qa = np.asarray(Q, dtype=float)
            if coef is not None and Qa.ndim == 2 and Qa.shape[1] == 2 and Qa.shape[0]:
                checked = True if warn or strict else False
                kernel = _KERNEL[0] if _KERNEL else _kernel_when_ready()
                if kernel is not None:  # one compiled call (output of its own: no lock)
                    value, t2 = kernel(Qa, grid.q0, coef, grid.form, grid.k, checked)
                    if not checked or t2 <= grid.limits.get(
                            (quantity, linear_in_design, tol), -1.0):
                        return value  # (screen 1, see _PowerGrid)
                    # screen 1 not passed (or its level not yet known): the NumPy path
                    # below finds the level, runs screen 2 and the per-sample estimate
                n = Qa.shape[0]
                if plan.lock.acquire(False):  # this thread owns the kept arrays
                    try:
                        run, P = (grid.scratch[checked].get(n)
                                  or grid.new_scratch(n, checked))
                        if not checked:
                            return run(Qa.T, coef)
                        value, t2 = run(Qa.T, coef)
                        if t2 <= grid.limits.get((quantity, linear_in_design, tol), -1.0):
                            return value  # screen 1 (see _PowerGrid)
                        return self._grid_checked(value, t2, P, Qa, quantity, linear_in_design,
                                                  strict, tol)
                    finally:
                        plan.lock.release()
                # another thread evaluates: arrays of its own
                run, P = grid.new_scratch(n, checked, keep=False)
                if not checked:
                    return run(Qa.T, coef)
                value, t2 = run(Qa.T, coef)
                return self._grid_checked(value, t2, P, Qa, quantity, linear_in_design,
                                          strict, tol)
        key = (quantity, bool(linear_in_design))
        if key not in plan.values:
            self.jet(quantity)  # names the bad quantity
        Qa = np.asarray(Q, dtype=float)
        if plan.q0_col is not None and Y is None and Qa.ndim == 2 and Qa.shape[1] == plan.nq:
            # all joints expanded, in order, no design: the offsets go straight into the rows
            n = Qa.shape[0]
            if plan.lock.acquire(blocking=False):  # this thread owns the scratch rows
                try:
                    scratch = plan.scratch.get(n) or plan.new_scratch(n)
                    rows, first, views = scratch
                    if first is not None:
                        np.subtract(Qa.T, plan.q0_col, out=first)
                    for src, row, dst in views:
                        np.multiply(src, row, out=dst)
                    return self._finish(rows, None, Qa, Y, key, warn, strict, tol)
                finally:
                    plan.lock.release()
            rows = np.empty((plan.ncoef, n))  # another thread evaluates: rows of its own
            rows[0] = 1.0
            if plan.ncoef > 1:
                np.subtract(Qa.T, plan.q0_col, out=rows[1 : 1 + plan.nvars])
            for d0, d1, s0, s1, r in plan.steps:
                np.multiply(rows[s0:s1], rows[r], out=rows[d0:d1])
            return self._finish(rows, None, Qa, Y, key, warn, strict, tol)
        dx = self.offsets(Qa, Y, warn=False)
        return self._finish(monomial_rows(self.space, dx.T), dx, Qa, Y, key, warn, strict, tol)

    def _grid_checked(self, value, t2, P, Qa, quantity, linear, strict, tol):
        """The radius check of a :class:`_PowerGrid` evaluation (``t2``: largest τ²)."""
        plan = self.evaluation_plan
        grid = plan.grid
        key = (quantity, bool(linear))
        # screen 1: the largest A-norm of the offsets against the norm at which the bound
        # of the estimate reaches tol (the caller tried the cached level)
        if t2 <= grid.limit(key, tol, plan.screen_passes):
            return value
        # screen 2: every check row at every sample, the column-maximum screen
        rows = grid.checked.get(key)
        if rows is not None:
            S = _dot(rows, grid.products(P))
            _abs(S, out=S)
            if plan.screen_passes(_MAX(S, axis=1).tolist(), tol):
                return value
        return self._checked_slow(None, None, Qa, None, key, tol, strict)

    def _finish(self, rows, dx, Qa, Y, key, warn, strict, tol):
        """Values from the monomial rows (ncoef, n), with the radius check when asked."""
        plan = self.evaluation_plan
        if not (warn or strict) or not rows.shape[1]:  # (no sample: nothing to judge)
            return (plan.values[key] @ rows).T
        checked = plan.checked.get(key)
        if checked is None:  # no screen (order 0 or 1, a vanishing eigenvalue)
            return self._checked_slow(rows.T, dx, Qa, Y, key, tol, strict)
        # one product: the value and, per check row, every sample's order-j part or rate
        S = checked @ rows
        k = plan.k
        if plan.screen_passes(_MAX(np.abs(S[k:]), axis=1).tolist(), tol):
            return S[:k].T
        return self._checked_slow(rows.T, dx, Qa, Y, key, tol, strict)

    def _checked_slow(self, mon, dx, Q, Y, key, tol, strict):
        """The per-sample estimate and report (:meth:`error_estimate`) and the value."""
        if dx is None:
            dx = self.offsets(Q, Y, warn=False)
        if not np.all(np.isfinite(dx)):  # the screens send every non-finite sample here
            bad = int(np.flatnonzero(~np.all(np.isfinite(dx), axis=1))[0])
            raise ConfigurationError(
                f"joint values of sample {bad} are not finite ({np.asarray(Q)[bad].tolist()}): "
                "the Taylor model has no value there")
        if mon is None:
            mon = monomial_rows(self.space, dx.T).T
        quantity, linear = key
        est, ratio, value = self._estimate_from(dx, mon @ self.degree_blocks[quantity])
        self._report(est, ratio, tol, strict, stacklevel=5)
        if linear:
            return mon @ self.coefficients(quantity, linear_in_design=True)
        return value

    def coefficients(self, quantity: str = "eigval", *,
                     linear_in_design: bool = False) -> np.ndarray:
        """Coefficient matrix (ncoef, k) of a polynomial (read-only).

        Args:
            quantity: 'eigval' (λ [rad²/s²]) or 'freq_hz' (f [Hz]).
            linear_in_design: The partially linear polynomial λ̂ of eq. (7) instead of λ^p.
        """
        self.jet(quantity)  # checks the name
        return self.coefficient_matrices[quantity, bool(linear_in_design)]

    @property
    def design_vars(self) -> list[int]:
        """Jet-variable indices of the expanded design variables."""
        n = len(self.joint_idx)
        return list(range(n, n + len(self.design_idx)))

    def linear_parts(self, Q, *, quantity: str = "eigval"):
        """Values of l_{i,0}(q) and l_{i,j}(q) of eq. (9) at samples.

        Args:
            Q: Joint coordinates (nv,) or (n, nv) of the samples, user convention [rad or m].
            quantity: ``'eigval'`` ([rad²/s²]; ``L`` per unit of each design variable) or
                ``'freq_hz'`` ([Hz]).

        Raises:
            ConfigurationError: The model expands no design variable, ``Q`` has the wrong
                shape or moves a joint that is not expanded, or ``quantity`` is unknown.

        Returns:
            ``(l0, L)``: l0 (n, k) and L (n, k, ny_expanded), so that
            ``λ̂_i = l0[:, i] + L[:, i, :] @ δy``.
        """
        if not self.design_idx:
            raise ConfigurationError("the Taylor model expands no design variable")
        if not self.joint_idx:
            jet = self.jet(quantity)
            l0 = np.repeat(jet[:1], np.atleast_2d(Q).shape[0], axis=0)
            grads = jet[1 : 1 + len(self.design_idx)]
            return l0, np.repeat(grads.T[None], l0.shape[0], axis=0)
        qspace, l0, l1 = jets.design_split(self.space, self.jet(quantity), self.design_vars)
        dq = self.offsets(Q, None)[:, : len(self.joint_idx)]
        mon = jets.monomials(qspace, dq)
        return mon @ l0, np.einsum("nc,jck->nkj", mon, l1)


def _checked_design(tm: TaylorModel, Y, n: int) -> np.ndarray:
    """Design values ``Y`` as a float array (ny,) or (n, ny), checked against the model.

    Raises:
        ConfigurationError: not numbers, not finite, a wrong shape, or a design variable that
            is not expanded moved from ``y0`` (the polynomial does not depend on it: its value
            there would be the value at ``y0``).
    """
    ny = tm.y0.size
    try:
        Y = np.asarray(Y, dtype=float)
    except (TypeError, ValueError) as exc:
        raise ConfigurationError(f"design values Y must be numbers, got {Y!r}") from exc
    if not (Y.shape == (ny,) or (Y.ndim == 2 and Y.shape[1] == ny and Y.shape[0] in (1, n))):
        raise ConfigurationError(
            f"expected design values of shape ({ny},) or ({n}, {ny}), got shape {Y.shape}")
    if not np.all(np.isfinite(Y)):
        raise ConfigurationError("design values Y must be finite numbers (no NaN or inf)")
    fixed = [i for i in range(ny) if i not in tm.design_idx]
    if fixed:
        moved = np.abs(Y[..., fixed] - tm.y0[fixed]) > 1e-12 * np.maximum(1.0,
                                                                        np.abs(tm.y0[fixed]))
        if np.any(moved):
            bad = sorted({fixed[j] for j in np.nonzero(moved)[-1].tolist()})
            raise ConfigurationError(
                f"design variables {bad} are not expanded in this Taylor model; keep them at "
                f"y0 ({tm.y0[bad].tolist()}) or expand them")
    return Y


def _plain(value):
    """Read-only mappings as plain dicts, recursively (they do not pickle)."""
    if isinstance(value, Mapping):
        return {k: _plain(v) for k, v in value.items()}
    return value


def _frozen(value):
    """Plain dicts as read-only mappings, recursively (the inverse of :func:`_plain`)."""
    if isinstance(value, dict):
        return MappingProxyType({k: _frozen(v) for k, v in value.items()})
    return value


def _rebuild_taylor_model(kw: dict) -> TaylorModel:
    """A pickled :class:`TaylorModel` from its defining fields."""
    kw = dict(kw)
    kw["order_choice"] = _frozen(kw["order_choice"])
    return TaylorModel(**kw)


@dataclass(frozen=True)
class _EvaluationPlan:
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
    grid: _PowerGrid | None = None
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
    def build(cls, tm: TaylorModel) -> _EvaluationPlan:
        space, p, k = tm.space, tm.order, len(tm.modes)
        nq = tm.q0.size
        direct = not tm.design_idx and tuple(tm.joint_idx) == tuple(range(nq))
        q0_col = np.ascontiguousarray(tm.q0[:, None]) if direct else None
        values = {key: _readonly(np.ascontiguousarray(c.T))
                  for key, c in tm.coefficient_matrices.items()}
        checked: dict[tuple[str, bool], np.ndarray] = {}
        off = space.degree_offsets
        j0 = max(1, (p + 1) // 2)
        orders = sorted(set(range(j0, p + 1)) | {p - 1} - {0}) if p >= 1 else []
        W = tm.spectral_weights
        w = 0 if W is None else W.shape[1] // k
        groups = len(orders) + w
        root = tuple((g, 1.0 / j) for g, j in enumerate(orders) if j >= j0)
        spec = tuple(range(len(orders), groups))
        for (quantity, linear), value in values.items():
            full = tm.coefficient_matrices[quantity, False]
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
            grid=_PowerGrid.build(tm, values, checked) if direct and nq == 2 and p >= 2
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
class _PowerGrid:
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

    1. every check row ``r`` of :class:`_EvaluationPlan` is a homogeneous polynomial of
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
       :meth:`_EvaluationPlan.screen_passes`.
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
    def build(cls, tm: TaylorModel, values, checked) -> _PowerGrid:
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


def expand(model: FlexibleModel, q0, y0=None, *, order: int = 4, modes: Sequence[int] = (1,),
           joints: Sequence[str] | None = None, design: Sequence[str] | None = None,
           tol: float | None = None, over=None) -> TaylorModel:
    """Build the Taylor model of the given non-rigid modes at ``(q0, y0)``.

    The eigenvalues ``λ_i(q, y) = ω_i²`` of ``K φ = λ M φ`` are expanded to order ``p`` in the
    listed joints and design variables, exactly (jets of M and K through the joint kinematics,
    then the eigenpair recursion of paper 000 eq. 5–6).

    Args:
        model: The flexible model.
        q0: Expansion pose, one value per moving joint (nv,), user coordinates [rad or m].
        y0: Expansion design values (ny,) [kg] or ``{name: value}`` (default: nominal).
        order: Truncation order p (>= 0).
        modes: Non-rigid mode numbers to expand, 1 = lowest (default: mode 1).
        joints: Names of the joints to expand (default: all moving joints).
        design: Names of the design variables to expand (default: all).
        tol: Pick the order instead: the lowest order up to ``order`` (at least 1, at most
            10) whose two-term estimate of the relative frequency error over ``over`` (the
            larger of the next two orders' relative terms) meets ``tol``
            (:func:`pinflex.parametric.fidelity.order_for_tolerance`); the choice and its
            estimate are in ``order_choice``.
        over: With ``tol``: the samples where the model will be used, joint values (n, nv)
            or ``(Q, Y)`` with design values (n, ny) or (ny,).

    Returns:
        A read-only :class:`TaylorModel`: jets of λ [rad²/s²] and of f [Hz], shape (ncoef, k)
        with ``k = len(modes)``, and the estimated convergence radius (nvars, k).

    Raises:
        ConfigurationError: Modes outside 1..n_elastic, unknown names, a bad order or pose.
        RepeatedEigenvalue: a requested mode is (nearly) repeated at the expansion point.
    """
    if tol is not None:
        return _expand_for_tolerance(model, q0, y0, order, modes, joints, design, tol, over)
    if model.n_elastic == 0:
        model.check_n_modes(None)  # raises NoFlexibleLink, naming the robot
    raw = [modes] if isinstance(modes, int | np.integer | str) else list(np.ravel(modes))
    if not raw or any(isinstance(m, bool | str | np.bool_)
                      or not isinstance(m, int | np.integer | float | np.floating)
                      or not float(m).is_integer() for m in raw):
        raise ConfigurationError(f"modes must be whole mode numbers 1..{model.n_elastic}, "
                                 f"got {modes!r}")
    modes = tuple(int(m) for m in raw)
    if min(modes) < 1 or max(modes) > model.n_elastic:
        raise ConfigurationError(f"modes {modes} must lie in 1..{model.n_elastic}")
    from pinflex.resources import check_order, check_taylor

    order = check_order(order)  # bounded before any work, whichever jet path runs
    n_design = model.ny if design is None else len(design)
    check_taylor((model.nv if joints is None else len(joints)) + n_design, order, model.ndof,
                 n_design)
    idx = [model.n_rigid + m - 1 for m in modes]
    solver = solver_design.covered(model)
    try:
        space, lam, w, slopes, jidx, didx = _expansion_jets(model, q0, y0, order, joints,
                                                            design, idx, solver)
    except _SolverRefused as refused:
        # A joint spring much stiffer (or softer) than the beams scales the solver-coordinate
        # pencil badly: its bordered matrices fail the condition check or its highest modes
        # the resolution check, where the nodal pencil still resolves them. Such refusals
        # are taken again on the nodal pencil, which raises its own error if it refuses too.
        if not model.plan.conditions.spring_joints:
            raise refused.error from None
        space, lam, w, slopes, jidx, didx = _expansion_jets(model, q0, y0, order, joints,
                                                            design, idx, False)
    elastic = slice(model.n_rigid, None)
    spectrum = w[elastic].copy()
    # estimated radius (nvars, k) along each variable axis: min of coefficient and spectrum
    W = spectral_weights(modes, spectrum, slopes)
    r_c = radius_estimate(space, lam)  # (nvars, k)
    radius = np.minimum(r_c, 0.5 * meeting_distance(W, np.eye(space.nvars), len(modes)))
    return TaylorModel(
        space=space,
        q0=np.asarray(q0, dtype=float),
        y0=model.check_y(y0),
        modes=modes,
        joint_idx=tuple(jidx),
        design_idx=tuple(didx),
        eigval_jets=lam,
        radius=radius,
        spectrum=spectrum,
        spectrum_slopes=slopes,
        joints=model.joint_labels(),
    )


def _expansion_jets(model, q0, y0, order, joints, design, idx, solver):
    """One route of :func:`expand`: space, λ jets, eigenvalues at x0, slopes, joints, design.

    ``solver``: the solver-coordinate jets (:func:`reduced_solver_jets`), else the nodal ones
    (:func:`matrix_jets`).

    Raises:
        _SolverRefused: On the solver route, its eigenpairs or the eigenpair recursion refused
            the point (a :class:`~pinflex.exceptions.RepeatedEigenvalue` or an unresolved
            mode).
    """
    if solver:  # solver coordinates: only the joints that change the pencil, design terms
        space, rspace, keep, M, K, jidx, didx = reduced_solver_jets(
            model, q0, y0, order=order, joints=joints, design=design)
    else:
        space, M, K, jidx, didx = matrix_jets(model, q0, y0, order=order, joints=joints,
                                              design=design)
        rspace, keep = space, list(range(space.nvars))
    try:
        if solver and K.ndim == 2 and not model.plan.conditions.locked_joints:
            w, V = expansion_eigenpairs(model, M[0])
        elif solver:  # design-dependent stiffness, springs or locks: not the plain layout
            w, V = solver_design.expansion_eigenpairs(model, K if K.ndim == 2 else K[0], M[0])
        else:
            w, V = sla.eigh(K[0], M[0], check_finite=False)
    except np.linalg.LinAlgError as exc:
        raise EigenSolverError(
            "the generalized eigenproblem at the expansion point failed: M(x0) must be "
            "symmetric positive definite"
        ) from exc
    except (RepeatedEigenvalue, ConfigurationError) as exc:  # (the solver pairs only)
        if not solver:
            raise
        raise _SolverRefused(exc) from exc
    big = np.argmax(np.abs(V), axis=0)
    V = V * np.sign(V[big, np.arange(V.shape[1])])
    try:
        lam, _ = eigen_jets(rspace, M, K, idx, eigvals0=w, eigvecs0=V)
    except RepeatedEigenvalue as exc:
        if solver:
            raise _SolverRefused(exc) from exc
        raise
    lam = embed(space, rspace, keep, lam)
    elastic = slice(model.n_rigid, None)
    slopes = np.zeros((space.nvars, model.ndof - model.n_rigid))
    slopes[keep] = spectrum_slopes(rspace, M, K, w[elastic], V[:, elastic])
    return space, lam, w, slopes, jidx, didx


class _SolverRefused(Exception):
    """The solver-coordinate pencil refused the expansion point (``error``: its refusal)."""

    def __init__(self, error: Exception):
        super().__init__(str(error))
        self.error = error


def _expand_for_tolerance(model, q0, y0, order, modes, joints, design, tol, over):
    """:func:`expand` with ``tol``: the order from two-term estimates over ``over``."""
    import dataclasses

    from pinflex.parametric.fidelity import TWO_TERM_RULE, order_for_tolerance

    if over is None:
        raise ConfigurationError("expand(tol=...) needs over=Q (or (Q, Y)): the samples where "
                                 "the model will be used")
    Q, Y = over if isinstance(over, tuple) else (over, None)
    cap = max(1, int(order)) if order is not None else 8
    choice = order_for_tolerance(model, q0, y0, Q=Q, Y=Y, tol=tol, modes=modes,
                                 orders=range(1, cap + 1), joints=joints, design=design)
    info = MappingProxyType({"tol": choice.tol, "order": choice.order,
                             "estimate": choice.estimate,
                             "estimates": MappingProxyType(dict(choice.estimates)),
                             "method": f"{TWO_TERM_RULE}, frequency [Hz], max over "
                                       "samples and modes"})
    return dataclasses.replace(choice.model, order_choice=info)


def spectral_weights(modes: Sequence[int], spectrum: np.ndarray | None,
                     slopes: np.ndarray | None) -> np.ndarray | None:
    """(nvars, k·w): ``2 (∇λ_j − ∇λ_i) / |λ_j − λ_i|`` for each mode i and neighbour j.

    Args:
        modes: Mode numbers (1 = lowest non-rigid).
        spectrum: Non-rigid eigenvalues at the expansion point [rad²/s²], (m,), or None.
        slopes: Their first derivatives along each variable, (nvars, m), or None.

    Returns:
        The rates, or None without a spectrum of at least two eigenvalues.
    """
    if spectrum is None or slopes is None or spectrum.size < 2:
        return None
    blocks = []
    for m in modes:
        i = m - 1
        # the nearest eigenvalues (four on each side) are the possible partners
        near = [j for j in range(max(0, i - 4), min(spectrum.size, i + 5)) if j != i]
        gap = np.abs(spectrum[near] - spectrum[i])
        blocks.append((slopes[:, near] - slopes[:, [i]]) / gap[None, :])
    width = max(b.shape[1] for b in blocks)
    blocks = [np.pad(b, ((0, 0), (0, width - b.shape[1]))) for b in blocks]
    return np.ascontiguousarray(2.0 * np.concatenate(blocks, axis=1))


def meeting_distance(W: np.ndarray | None, rays: np.ndarray, k: int) -> np.ndarray:
    """Distance (n, k) along unit rays (n, nvars) at which the nearest eigenvalue would meet."""
    if W is None:
        return np.full((rays.shape[0], k), np.inf)
    with np.errstate(divide="ignore"):
        return 2.0 / np.abs(rays @ W).reshape(rays.shape[0], k, -1).max(axis=2)
