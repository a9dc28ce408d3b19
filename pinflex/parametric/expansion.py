"""Expansion of chosen modes at one point: jets of M and K, eigenpair jets, radius estimate."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import scipy.linalg as sla

from pinflex.checks import check_n_modes, check_y
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    ConfigurationError,
    EigenSolverError,
    RepeatedEigenvalue,
)
from pinflex.parametric import solver_design
from pinflex.parametric.conditioned import embed, expansion_eigenpairs, reduced_solver_jets
from pinflex.parametric.eigen import eigen_jets, radius_estimate, spectrum_slopes
from pinflex.parametric.matrices import matrix_jets
from pinflex.parametric.taylor import TaylorModel, meeting_distance, spectral_weights


def expand_at_order(model: FlexibleModel, q0, y0=None, *, order: int = 4,
                    modes: Sequence[int] = (1,), joints: Sequence[str] | None = None,
                    design: Sequence[str] | None = None) -> TaylorModel:
    """:func:`pinflex.parametric.expand` at a given order (arguments and result as there)."""
    if model.n_elastic == 0:
        check_n_modes(model, None)  # raises NoFlexibleLink, naming the robot
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
    _check_expansion_point(model, q0, y0, modes, lam[0])
    elastic = slice(model.n_rigid, None)
    spectrum = w[elastic].copy()
    # estimated radius (nvars, k) along each variable axis: min of coefficient and spectrum
    W = spectral_weights(modes, spectrum, slopes)
    r_c = radius_estimate(space, lam)  # (nvars, k)
    radius = np.minimum(r_c, 0.5 * meeting_distance(W, np.eye(space.nvars), len(modes)))
    return TaylorModel(
        space=space,
        q0=np.asarray(q0, dtype=float),
        y0=check_y(model, y0),
        modes=modes,
        joint_idx=tuple(jidx),
        design_idx=tuple(didx),
        eigval_jets=lam,
        radius=radius,
        spectrum=spectrum,
        spectrum_slopes=slopes,
        joints=model.joint_labels(),
    )


#: Largest relative difference between a Taylor model's eigenvalue at its expansion point and
#: the exact modal solve's before the expansion is refused (see :func:`_check_expansion_point`).
EXPANSION_POINT_RTOL = 1e-6


def _check_expansion_point(model, q0, y0, modes, lam0: np.ndarray) -> None:
    """Refuse an expansion whose eigenvalues at ``x0`` differ from the exact modal solve.

    The expansion's eigenpairs come from its own pencil (the solver-coordinate jets, or the
    nodal ones when those refuse). On models with joint springs, locks or section design that
    pencil is not the conditioned form of :mod:`pinflex.erls.solve_conditions`: a spring far
    softer than the beams (k = 1e-4 N m/rad on a 1 m bar: the spring mode 0.86 % off, 1e-6: a
    negative eigenvalue) or a fine mesh on the nodal fallback loses digits there. The exact
    solve (``frequencies()``) keeps them, so a difference above :data:`EXPANSION_POINT_RTOL`
    means the Taylor model would be wrong from its first coefficient: refused by name. Models
    with free joints only expand on the same conditioned form as the exact solve (not checked).
    """
    from pinflex.erls import solve

    if solve.supported(model):
        return
    exact_hz = model.frequencies(q0, y0, n_modes=max(modes), check_bounds=False)
    exact = (2.0 * np.pi * exact_hz[np.asarray(modes) - 1]) ** 2
    lam0 = np.asarray(lam0, dtype=float)
    rel = np.abs(lam0 - exact) / exact
    bad = ~(rel <= EXPANSION_POINT_RTOL)
    if np.any(bad):
        i = int(np.argmax(np.where(np.isfinite(rel), rel, np.inf)))
        raise EigenSolverError(
            f"mode {modes[i]} at the expansion point: the Taylor route's eigenvalue "
            f"{lam0[i]:.6g} rad²/s² differs from the exact modal solve's {exact[i]:.6g} by "
            f"{rel[i]:.2g} (relative; tolerance {EXPANSION_POINT_RTOL:g}): its pencil loses "
            "digits at this point (a joint spring far softer than the beams, or a fine mesh); "
            "use the exact model (frequencies(), modes()) for this mode, stiffen or free the "
            "spring, or use fewer elements"
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
            w, V = solver_design.expansion_eigenpairs(model, K if K.ndim == 2 else K[0], M[0],
                                                      idx)
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
        lam, _ = eigen_jets(rspace, M, K, idx, eigvals0=w, eigvecs0=V, n_rigid=model.n_rigid)
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


