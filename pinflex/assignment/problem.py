"""The eigenfrequency-assignment QP of paper 000 (Belotti et al. 2021, Sec. 2.4, eq. 10–14).

The QP (eq. 12–14) and its solution, built from sampled polynomials.

With the partially linearised model of eq. (9), mode ``i`` at sample ``k`` is predicted as
``l_{i,0}(q_k) + Σ_j l_{i,j}(q_k) δy_j``. The cost (10), summed over modes with weights
``w_i`` and integrated by a quadrature rule with weights ``ω_k`` (the trapezoidal rule on the
trajectory grid, as in the paper's Sec. 3.3), is

.. math::

    f(δy) = ½ Σ_i w_i Σ_k ω_k (l_{i,0,k} + L_{i,k} δy − λ_{i,d,k})²
          = ½ δyᵀ R δy + hᵀ δy + c,

with :math:`R = Σ_i w_i L_iᵀ Ω L_i` (eq. 13), :math:`h = Σ_i w_i L_iᵀ Ω (l_{i,0} − λ_{i,d})`
(eq. 14) and :math:`c = ½ Σ_i w_i (l_{i,0} − λ_{i,d})ᵀ Ω (l_{i,0} − λ_{i,d})`, so that
:meth:`AssignmentQP.cost` is the cost itself, not just up to a constant.

Units: this module is agnostic. It minimises the squared mismatch of whatever quantity the
``l`` arrays and the targets represent — eigenvalues ``λ = ω²`` [rad²/s²] or frequencies
[Hz] — as long as ``l0``, ``L``, ``targets``, ``floors`` and ``bands`` use the same one. The
cost then has units [quantity² · s] and ``δy`` the units of the design variables.

This module builds and solves the QP only; evaluating the modal model and verifying the
answer with the exact model belongs to the assignment driver.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from pinflex.exceptions import InvalidAssignmentProblem
from pinflex.linalg import readonly as _readonly


@dataclass(frozen=True)
class AssignmentQP:
    """An assignment QP ``min ½ δyᵀRδy + hᵀδy + c`` s.t. ``Aδy = b``, ``l <= Cδy <= u``, box.

    Attributes:
        R: Hessian, symmetric positive semidefinite, shape (ny, ny).
        h: Linear term, shape (ny,).
        c: Constant term, so that :meth:`cost` is the exact cost (10).
        A: Equality rows, shape (n_eq, ny).
        b: Equality right-hand side, shape (n_eq,).
        C: Inequality rows, shape (n_in, ny): the user's ``A_ineq`` rows, then floor rows,
            then band rows.
        l: Lower bounds of ``Cδy``, shape (n_in,) (``-inf`` where absent).
        u: Upper bounds of ``Cδy``, shape (n_in,) (``+inf`` where absent).
        lower: Box lower bounds on δy, shape (ny,) (may be ``-inf``).
        upper: Box upper bounds on δy, shape (ny,) (may be ``+inf``).
        names: Names of the design-variable steps, length ny.
        constraint_names: One name per row of ``C``, e.g. ``"inequality[0]"``,
            ``"floor[mode 0, sample 12]"``, ``"band[0] above, sample 3"``.
        constraint_groups: Group of each row of ``C``: ``"inequality"``, ``"floor"``, ``"band"``.
        band_sides: For each band, shape (ns,): +1 where the prediction must stay above the
            band, −1 where it must stay below.
        n_modes: Number of modes in the cost.
        n_samples: Number of trajectory samples.
    """

    R: np.ndarray
    h: np.ndarray
    c: float
    A: np.ndarray
    b: np.ndarray
    C: np.ndarray
    l: np.ndarray  # noqa: E741  (the QP literature's name)
    u: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    names: tuple[str, ...]
    constraint_names: tuple[str, ...]
    constraint_groups: tuple[str, ...]
    band_sides: tuple[np.ndarray, ...]
    n_modes: int
    n_samples: int

    @property
    def ny(self) -> int:
        """Number of design variables."""
        return self.h.size

    @property
    def box(self) -> tuple[np.ndarray, np.ndarray]:
        """Box bounds ``(lower, upper)`` on δy."""
        return self.lower, self.upper

    def cost(self, dy: np.ndarray) -> float:
        """Exact value of the cost (10) at ``dy`` (shape (ny,)).

        Args:
            dy: Design step δy (ny,) from the expansion design [kg].

        Returns:
            ``½ δyᵀRδy + hᵀδy + c`` (units of the cost: [Hz²·s] for frequency targets).
        """
        dy = np.asarray(dy, dtype=float)
        return float(0.5 * dy @ self.R @ dy + self.h @ dy + self.c)

    def max_violation(self, dy: np.ndarray) -> float:
        """Largest violation of any constraint at ``dy`` (0 if feasible), in each row's units.

        Args:
            dy: Design step δy (ny,) from the expansion design [kg].

        Returns:
            The largest violation of the box [kg], the equalities and the inequalities (each
            in its row's units), 0.0 when all hold.
        """
        dy = np.asarray(dy, dtype=float)
        parts = [np.maximum(self.lower - dy, 0.0), np.maximum(dy - self.upper, 0.0)]
        if self.A.shape[0]:
            parts.append(np.abs(self.A @ dy - self.b))
        if self.C.shape[0]:
            Cy = self.C @ dy
            parts += [np.maximum(self.l - Cy, 0.0), np.maximum(Cy - self.u, 0.0)]
        return float(max(np.max(p) if p.size else 0.0 for p in parts))


@dataclass(frozen=True)
class QPSolution:
    """Answer of an assignment-QP solver.

    Attributes:
        found: True if the solver reports an optimum that satisfies the constraints.
        dy: Optimal step of the design variables, shape (ny,).
        iterations: Solver iterations.
        time_s: Solver time (setup + solve, as the solver measures it) [s].
        status: Solver status text.
        objective: Exact cost :meth:`AssignmentQP.cost` at ``dy``.
        max_violation: Largest constraint violation at ``dy``.
        dual_eq: Multipliers of the equality rows, shape (n_eq,) (empty if unknown).
        dual_in: Multipliers of the rows of ``C``, shape (n_in,) (> 0 at an active upper
            bound, < 0 at an active lower bound).
        dual_box: Multipliers of the box bounds, shape (ny,), same sign convention.
        polished: True if ``dy`` was refined on the active set (see
            :func:`solve_assignment_qp`).
    """

    found: bool
    dy: np.ndarray
    iterations: int
    time_s: float
    status: str
    objective: float
    max_violation: float = 0.0
    dual_eq: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dual_in: np.ndarray = field(default_factory=lambda: np.zeros(0))
    dual_box: np.ndarray = field(default_factory=lambda: np.zeros(0))
    polished: bool = False


def _as_modes(name: str, value, ndim: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.ndim == ndim - 1:
        array = array[None]
    if array.ndim != ndim:
        raise InvalidAssignmentProblem(
            f"{name} must have {ndim - 1} (one mode) or {ndim} (several modes) dimensions, "
            f"got shape {array.shape}"
        )
    if not np.all(np.isfinite(array)):
        raise InvalidAssignmentProblem(f"{name} has non-finite entries")
    return array


def build_assignment_qp(
    l0,
    L,
    targets,
    weights_t,
    *,
    lower,
    upper,
    A_eq=None,
    b_eq=None,
    A_ineq=None,
    b_ineq=None,
    floors=None,
    bands: Sequence[tuple[int, float, float]] | None = None,
    mode_weights=None,
    band_reference_dy=None,
    names: Sequence[str] | None = None,
) -> AssignmentQP:
    """Build the assignment QP (12)–(14) from sampled polynomial values.

    Args:
        l0: ``l_{i,0}(q(t_k))``, shape (ns,) for one mode or (nm, ns).
        L: ``l_{i,j}(q(t_k))``, shape (ns, ny) or (nm, ns, ny).
        targets: Targets ``λ_{i,d}(t_k)``, broadcastable to (nm, ns) (a scalar is a constant
            target, shape (ns,) the same target history for every mode, (nm, 1) one
            constant per mode), in the units of ``l0``.
        weights_t: Quadrature weights ω_k on the time grid, shape (ns,) [s]
            (:meth:`pinflex.trajectory.Trajectory.trapezoid_weights`).
        lower: Box lower bounds on δy, broadcastable to (ny,) (``-inf`` for none).
        upper: Box upper bounds on δy, broadcastable to (ny,) (``+inf`` for none).
        A_eq: Equality rows ``A_eq δy = b_eq``, shape (n_eq, ny).
        b_eq: Shape (n_eq,).
        A_ineq: Inequality rows ``A_ineq δy <= b_ineq`` (e.g. a mass budget
            ``Σ δm <= budget − Σ m0``), shape (n_ineq, ny).
        b_ineq: Shape (n_ineq,).
        floors: Frequency floors, broadcastable to (nm, ns) (a scalar for all, (nm, 1) one
            per mode): the prediction must satisfy ``l_{i,0,k} + L_{i,k} δy >= floor_{i,k}``;
            ``-inf`` entries add no row.
        bands: Forbidden bands ``(mode, a, b)`` with ``a < b``: the prediction of ``mode``
            must avoid ``(a, b)`` at every sample. Avoiding an interval is not convex, so each
            sample gets one linear row chosen from the side the prediction is on at
            ``band_reference_dy`` (default δy = 0): ``>= b`` if it is at or above the band
            middle ``(a + b)/2``, ``<= a`` otherwise. A prediction inside the band is thus
            pushed to the nearer edge. Rebuild with a new reference to let a sample cross.
        mode_weights: Weights ``w_i`` of the modes, shape (nm,); default ones.
        band_reference_dy: δy at which band sides are chosen, shape (ny,).
        names: Names of the design variables; default ``dy[0]``, ``dy[1]``, ...

    Returns:
        The :class:`AssignmentQP`.

    Raises:
        InvalidAssignmentProblem: Inconsistent shapes, non-finite data, negative weights or a
            band with ``a >= b``.
    """
    l0 = _as_modes("l0", l0, 2)
    L = _as_modes("L", L, 3)
    nm, ns = l0.shape
    if L.shape[:2] != (nm, ns):
        raise InvalidAssignmentProblem(
            f"L must have shape ({nm}, {ns}, ny) to match l0 {l0.shape}, got {L.shape}"
        )
    ny = L.shape[2]
    try:
        d = np.broadcast_to(np.asarray(targets, dtype=float), (nm, ns))
    except ValueError as err:
        raise InvalidAssignmentProblem(
            f"targets must broadcast to (n_modes, n_samples) = ({nm}, {ns}), got "
            f"{np.shape(targets)}"
        ) from err
    if not np.all(np.isfinite(d)):
        raise InvalidAssignmentProblem("targets have non-finite entries")
    w_t = np.asarray(weights_t, dtype=float)
    if w_t.shape != (ns,) or np.any(w_t < 0.0) or not np.all(np.isfinite(w_t)):
        raise InvalidAssignmentProblem(
            f"weights_t must be ({ns},) finite and >= 0 (trapezoidal weights), got {w_t.shape}"
        )
    w_m = np.ones(nm) if mode_weights is None else np.asarray(mode_weights, dtype=float)
    if w_m.shape != (nm,) or np.any(w_m < 0.0) or not np.all(np.isfinite(w_m)):
        raise InvalidAssignmentProblem(f"mode_weights must be ({nm},) finite and >= 0")

    W = w_m[:, None] * w_t[None, :]  # (nm, ns)
    res0 = l0 - d
    R = np.einsum("ik,ikj,ikl->jl", W, L, L)
    R = 0.5 * (R + R.T)
    h = np.einsum("ik,ikj,ik->j", W, L, res0)
    c = 0.5 * float(np.sum(W * res0**2))

    lo = _vector("lower", lower, ny)
    hi = _vector("upper", upper, ny)
    A, b = _rows("A_eq", "b_eq", A_eq, b_eq, ny)
    G, g = _rows("A_ineq", "b_ineq", A_ineq, b_ineq, ny)

    rows, row_l, row_u, row_names, groups = [G], [np.full(len(g), -np.inf)], [g], [], []
    row_names += [f"inequality[{r}]" for r in range(len(g))]
    groups += ["inequality"] * len(g)
    if floors is not None:
        try:
            fl = np.broadcast_to(np.asarray(floors, dtype=float), (nm, ns))
        except ValueError as err:
            raise InvalidAssignmentProblem(
                f"floors must broadcast to ({nm}, {ns}), got {np.shape(floors)}"
            ) from err
        if np.any(np.isnan(fl)) or np.any(fl == np.inf):
            raise InvalidAssignmentProblem("floors must be finite, or -inf for no floor")
        i_idx, k_idx = np.nonzero(np.isfinite(fl))
        rows.append(L[i_idx, k_idx])
        row_l.append(fl[i_idx, k_idx] - l0[i_idx, k_idx])
        row_u.append(np.full(i_idx.size, np.inf))
        row_names += [f"floor[mode {i}, sample {k}]" for i, k in zip(i_idx, k_idx)]
        groups += ["floor"] * i_idx.size
    sides = []
    ref = np.zeros(ny) if band_reference_dy is None else _vector("band_reference_dy",
                                                                  band_reference_dy, ny)
    for n, band in enumerate(bands or ()):
        mode, a, bb = int(band[0]), float(band[1]), float(band[2])
        if not 0 <= mode < nm or not a < bb:
            raise InvalidAssignmentProblem(
                f"band {n} = {band!r}: need 0 <= mode < {nm} and a < b (mode, a, b)"
            )
        value = l0[mode] + L[mode] @ ref
        side = np.where(value >= 0.5 * (a + bb), 1, -1)
        sides.append(side)
        rows.append(L[mode])
        row_l.append(np.where(side > 0, bb - l0[mode], -np.inf))
        row_u.append(np.where(side > 0, np.inf, a - l0[mode]))
        row_names += [
            f"band[{n}] {'above' if s > 0 else 'below'}, mode {mode}, sample {k}"
            for k, s in enumerate(side)
        ]
        groups += ["band"] * ns

    if names is None:
        names = tuple(f"dy[{j}]" for j in range(ny))
    elif len(names) != ny:
        raise InvalidAssignmentProblem(f"{len(names)} names given for {ny} design variables")
    return AssignmentQP(
        R=_readonly(R), h=_readonly(h), c=c, A=_readonly(A), b=_readonly(b),
        C=_readonly(np.vstack(rows).reshape(-1, ny)),
        l=_readonly(np.concatenate(row_l)), u=_readonly(np.concatenate(row_u)),
        lower=_readonly(lo), upper=_readonly(hi), names=tuple(names),
        constraint_names=tuple(row_names), constraint_groups=tuple(groups),
        band_sides=tuple(_readonly(s) for s in sides), n_modes=nm, n_samples=ns,
    )


def _vector(name: str, value, n: int) -> np.ndarray:
    try:
        v = np.array(np.broadcast_to(np.asarray(value, dtype=float), (n,)))
    except ValueError as err:
        raise InvalidAssignmentProblem(
            f"{name} must be a scalar or have shape ({n},), got {np.shape(value)}"
        ) from err
    if np.any(np.isnan(v)):
        raise InvalidAssignmentProblem(f"{name} has NaN entries")
    return v


def _rows(name_m: str, name_v: str, M, v, ny: int) -> tuple[np.ndarray, np.ndarray]:
    if M is None and v is None:
        return np.zeros((0, ny)), np.zeros(0)
    if M is None or v is None:
        raise InvalidAssignmentProblem(f"give both {name_m} and {name_v}, or neither")
    M = np.atleast_2d(np.asarray(M, dtype=float))
    v = np.atleast_1d(np.asarray(v, dtype=float))
    if M.shape[1] != ny or v.shape != (M.shape[0],):
        raise InvalidAssignmentProblem(
            f"{name_m} must be (m, {ny}) and {name_v} (m,), got {M.shape} and {v.shape}"
        )
    if not (np.all(np.isfinite(M)) and np.all(np.isfinite(v))):
        raise InvalidAssignmentProblem(f"{name_m} / {name_v} have non-finite entries")
    return M, v


# --------------------------------------------------------------------------- solving
