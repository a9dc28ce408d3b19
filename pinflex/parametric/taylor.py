"""Taylor models of eigenvalues and frequencies: the read-only model, evaluation, radius checks.

Built by :func:`pinflex.parametric.expand`; evaluated through the plan of
:mod:`pinflex.parametric.evaluation`.
"""

from __future__ import annotations

import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from types import MappingProxyType

import numpy as np

from pinflex import jets
from pinflex.exceptions import (
    ConfigurationError,
    TaylorRadiusExceeded,
    TaylorRadiusWarning,
)
from pinflex.jets import JetSpace
from pinflex.jets.evaluation import monomial_rows
from pinflex.linalg import readonly as _readonly
from pinflex.parametric import evaluation
from pinflex.parametric.evaluation import RADIUS_TOL, EvaluationPlan
from pinflex.summaries import taylor_summary
from pinflex.validation import float_array, require_bool

_TINY = np.finfo(float).tiny
_MAX = np.maximum.reduce  # the ufunc itself: ndarray.max adds a Python-level wrapper per call
_dot, _abs, _mul, _sub, _matmul = np.dot, np.abs, np.multiply, np.subtract, np.matmul


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

    A Taylor model never changes after construction: every array is a read-only copy, and
    the derived fields (private: the coefficient matrices :meth:`coefficients` returns, the
    per-degree blocks of the error estimate, the spectral neighbours' rates of the radius
    check and the evaluation plan) are computed once, when it is built. It pickles (process
    pools, Dask batches): only the defining fields are stored, the derived ones are rebuilt
    on loading.
    Unpickling runs code named in the file (that is how pickle works, not a pinflex choice):
    load pickled models only from files you trust.
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
    _coefficient_matrices: Mapping[tuple[str, bool], np.ndarray] = field(
        init=False, repr=False, compare=False)
    _degree_blocks: Mapping[str, np.ndarray] = field(init=False, repr=False, compare=False)
    _spectral_weights: np.ndarray | None = field(init=False, repr=False, compare=False)
    _evaluation_plan: EvaluationPlan = field(init=False, repr=False, compare=False)

    def __repr__(self) -> str:
        return taylor_summary(self)  # order, variables, modes, radius: no array dumps

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
        object.__setattr__(self, "_coefficient_matrices", MappingProxyType(coef))
        object.__setattr__(self, "_degree_blocks", MappingProxyType(blocks))
        W = spectral_weights(self.modes, self.spectrum, self.spectrum_slopes)
        object.__setattr__(self, "_spectral_weights", None if W is None else _readonly(W))
        object.__setattr__(self, "_evaluation_plan", EvaluationPlan.build(self))

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
        return self._estimate_from(dx, mon @ self._degree_blocks[quantity])[:2]

    def _estimate_from(self, dx: np.ndarray, con: np.ndarray):
        """(estimate, ratio, value) from ``mon @ _degree_blocks[quantity]``."""
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
        W = self._spectral_weights
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
        return meeting_distance(self._spectral_weights, rays, len(self.modes))

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
        if not isinstance(quantity, str) or quantity not in ("eigval", "freq_hz"):
            raise ConfigurationError(f"quantity = {quantity!r}: expected 'eigval' or 'freq_hz'")
        if not (type(Q) is np.ndarray and Q.dtype == np.float64):
            Q = float_array(Q, "joint values Q")  # finiteness: checked with warn/strict
        linear_in_design = require_bool(linear_in_design, "linear_in_design")
        warn, strict = require_bool(warn, "warn"), require_bool(strict, "strict")
        if isinstance(tol, bool) or not isinstance(tol, int | float | np.number) or \
                not tol > 0.0:  # inf: no tolerance; NaN refused
            raise ConfigurationError(f"tol must be a positive number, got {tol!r}")
        plan = self._evaluation_plan
        grid = plan.grid
        if grid is not None and Y is None:
            # one or two joints, all expanded, no design (see PowerGrid)
            coef = grid.values.get((quantity, linear_in_design))
            Qa = np.asarray(Q, dtype=float)
            if coef is not None and Qa.ndim == 2 and Qa.shape[1] == 2 and Qa.shape[0]:
                checked = True if warn or strict else False
                kernels = evaluation._KERNEL
                kernel = kernels[0] if kernels else evaluation.kernel_when_ready()
                if kernel is not None:  # one compiled call (output of its own: no lock)
                    value, t2 = kernel(Qa, grid.q0, coef, grid.form, grid.k, checked)
                    if not checked or t2 <= grid.limits.get(
                            (quantity, linear_in_design, tol), -1.0):
                        return value  # (screen 1, see PowerGrid)
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
                            return value  # screen 1 (see PowerGrid)
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
        """The radius check of a :class:`PowerGrid` evaluation (``t2``: largest τ²)."""
        plan = self._evaluation_plan
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
        plan = self._evaluation_plan
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
        est, ratio, value = self._estimate_from(dx, mon @ self._degree_blocks[quantity])
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
        return self._coefficient_matrices[quantity, bool(linear_in_design)]

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

