r"""Tip statics of the planar chain, batched over loads, and their design derivatives.

:func:`planar_statics` is the closed form of :func:`~pinflex.prbdm.chain.solve_tip_statics`
(the same residual :math:`K\theta - J^T F`, tangent, tolerance and acceptance checks) for
several dead loads at once. At a converged equilibrium :math:`R(\theta, c) = 0`,
:math:`d\theta/dc = -T^{-1}\partial R/\partial c` with T the Newton tangent, and the tip moves
by :math:`J\,d\theta/dc + \partial P/\partial c` (:func:`tip_derivative`).
"""

from __future__ import annotations

from functools import cache

import numpy as np

from .massmatrix import chain_indices


def tip_derivative(k_static: np.ndarray, theta: np.ndarray, forces: np.ndarray,
                    lengths: np.ndarray, k_ref: np.ndarray, dk_ref: np.ndarray,
                    factors: np.ndarray, ds_dx: np.ndarray, law_segment: bool,
                    n1: int) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of the tips (x, z) and of the angles with respect to x at equilibria.

    Returns:
        (d tip / d x of shape (l, 2, n_params), d theta / d x of shape (l, n, n_params)).

    Args:
        k_static: Static spring stiffness (n,).
        theta: Converged angles, one row per load (l, n).
        forces: The loads (l, 2).
        lengths: Lengths of links 0..n.
        k_ref: Uncorrected stiffness (n,) and ``dk_ref`` its derivative (n, n) by s.
        dk_ref: See ``k_ref``.
        factors: Correction factors.
        ds_dx: Joint positions' derivative by the fractions (n, n + 1).
        law_segment: Whether the law is ``"segment"``.
        n1: n + 1.
    """
    n_l, n = theta.shape
    ix = chain_indices(n)
    n_p = ds_dx.shape[1] + factors.size
    planar = planar_indices(n)
    q = theta @ planar.prefix
    ell = lengths[1:]
    c, sn = np.cos(q), np.sin(q)
    fx, fz = forces[:, :1], forces[:, 1:]
    s_mat = ix.tri
    # Tip Jacobian rows: d x_tip / d q_a = -l_a sin q_a, d z_tip / d q_a = -l_a cos q_a.
    tip_jac = np.empty((n_l, 2, n))
    tip_jac[:, 0] = (-ell * sn) @ s_mat
    tip_jac[:, 1] = (-ell * c) @ s_mat
    work = -sn * fx - c * fz                               # u'(q_a) . F
    idx = ix.idx
    arm = ell * (c * fx - sn * fz)                         # l_a u(q_a) . F
    tangent = (arm @ planar.suffix)[:, planar.top] + planar.eye * k_static
    dl_dx = ix.dl @ ds_dx                                  # (n, n1)
    scale = factors if law_segment else np.full(n, float(np.mean(factors)))
    dk_dx = np.zeros((n, n_p))
    dk_dx[:, :n1] = scale[:, None] * dk_ref @ ds_dx
    if law_segment:
        dk_dx[idx, n1 + idx] = k_static
    else:
        dk_dx[:, n1:] = k_ref[:, None] * (factors / factors.size)[None, :]
    dr = dk_dx[None, :, :] * theta[:, :, None]
    # (J^T F)_i = sum_{a >= i} l_a u'(q_a) . F depends on the lengths directly.
    dr[:, :, :n1] -= s_mat.T @ (work[:, :, None] * dl_dx[None, :, :])
    dtheta = -np.linalg.solve(tangent, dr)
    dtip = tip_jac @ dtheta
    # Direct dependence on the geometry: P = (s_1, 0) + sum_a l_a u(q_a).
    dtip[:, 0, :n1] += c @ dl_dx + ds_dx[0]
    dtip[:, 1, :n1] += -sn @ dl_dx
    return dtip, dtheta



class PlanarIndices:
    """Index and summation matrices of the planar Newton for n joints (built once per n)."""

    def __init__(self, n: int):
        idx = np.arange(n)
        self.top = np.maximum.outer(idx, idx)          # max(i, j)
        self.prefix = np.triu(np.ones((n, n)))         # (x @ prefix)_j = sum_{a <= j} x_a
        self.suffix = np.ascontiguousarray(self.prefix.T)  # (x @ suffix)_i = sum_{a >= i} x_a
        self.eye = np.eye(n)


@cache
def planar_indices(n: int) -> PlanarIndices:
    """The :class:`PlanarIndices` of an n-joint chain (one per n)."""
    return PlanarIndices(n)


def planar_tip(root_m: float, ell: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Tip (x, z) of the chain: link 0 of length root_m along +X, links 1..n of lengths ell."""
    q = np.cumsum(theta)
    return np.array([root_m + np.sum(ell * np.cos(q)), -np.sum(ell * np.sin(q))])


def planar_statics(k: np.ndarray, ell: np.ndarray, forces: np.ndarray, theta0: np.ndarray,
                   load_steps: int, max_iter: int = 30, tol: float = 1e-10
                   ) -> tuple[np.ndarray, np.ndarray]:
    r"""Newton's method for :math:`K\theta = J^T F` on several dead loads at once.

    The planar closed form of :func:`~pinflex.prbdm.chain.solve_tip_statics` (the same
    residual, tangent, tolerance and acceptance checks: converged, tangent positive definite,
    every absolute link angle between the axis and the force), vectorised over loads.

    Args:
        k: Spring stiffness (n,), or one row per load (l, n) [N m/rad].
        ell: Lengths of links 1..n (n,), or one row per load (l, n) [m].
        forces: Tip forces (l, 2) [N].
        theta0: Starting angles (l, n) [rad].
        load_steps: Equal load increments.
        max_iter: Newton iterations allowed per load step.
        tol: Convergence tolerance on the residual relative to its terms' norms.

    Returns:
        (theta (l, n), ok (l,)) with ok False where a check failed.
    """
    theta = np.array(theta0, dtype=float)
    n_l, n = theta.shape
    ix = planar_indices(n)
    top, prefix, suffix_sum = ix.top, ix.prefix, ix.suffix
    ok = np.ones(n_l, dtype=bool)
    k = np.asarray(k, dtype=float)
    k_diag = ix.eye * (k[:, None, :] if k.ndim == 2 else k)
    fx_all, fz_all = forces[:, :1], forces[:, 1:]
    # Rows: the residual K theta - tau, then its two terms K theta and tau (one reduction
    # gives the three norms of the convergence test).
    terms = np.empty((3, n_l, n))
    residual, kt, tau = terms[0], terms[1], terms[2]

    steps = max(1, int(load_steps))
    for step in range(1, steps + 1):
        if step == steps:
            fx, fz = fx_all, fz_all
        else:
            fx, fz = fx_all * (step / steps), fz_all * (step / steps)
        active = ok.copy()
        for iteration in range(max_iter + 1):
            q = theta @ prefix
            lc, ls = ell * np.cos(q), ell * np.sin(q)
            # tau_i = sum_{a >= i} l_a u'(q_a) . F; the tangent's (i, j) entry is the suffix
            # sum from max(i, j) of l_a u(q_a) . F, plus k on the diagonal.
            np.matmul(-ls * fx - lc * fz, suffix_sum, out=tau)
            tangent = ((lc * fx - ls * fz) @ suffix_sum)[:, top] + k_diag
            np.multiply(k, theta, out=kt)
            np.subtract(kt, tau, out=residual)
            norms = np.sqrt((terms * terms).sum(2))
            finite = np.isfinite(norms[0])
            ok &= finite
            active &= (norms[0] > tol * (norms[1] + norms[2] + 1e-300)) & finite
            if not active.any():
                break
            if iteration == max_iter:
                ok &= ~active
                break
            try:
                if active.all():
                    theta -= np.linalg.solve(tangent, residual[:, :, None])[:, :, 0]
                else:
                    theta[active] -= np.linalg.solve(tangent[active],
                                                     residual[active][:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                ok &= ~active
                break
    # The last tangent was formed at the final angles and the full load (symmetric): it is
    # positive definite exactly when its Cholesky factorisation exists (per load on failure).
    try:
        np.linalg.cholesky(tangent)
    except np.linalg.LinAlgError:
        ok &= np.linalg.eigvalsh(tangent)[:, 0] > 0.0
    angle = np.arctan2(-forces[:, 1], forces[:, 0])
    absolute = q  # every exit of the Newton loop leaves q = theta @ prefix of the final angles
    low, high = np.minimum(0.0, angle), np.maximum(0.0, angle)
    slack = 1e-9 + 1e-12 * np.abs(absolute).max(axis=1, initial=0.0)
    inside = (absolute >= (low - slack)[:, None]) & (absolute <= (high + slack)[:, None])
    ok &= inside.all(axis=1) & np.isfinite(theta).all(axis=1)
    return theta, ok

