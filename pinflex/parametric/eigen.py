r"""Taylor coefficients of eigenvalues and eigenvectors of a parametric eigenproblem.

Implements the recursion of paper 000, eq. (5)–(6), generalised to any order ``p`` and any
number of variables, for the symmetric generalized problem

.. math:: K(x)\,\phi(x) = \lambda(x)\,M(x)\,\phi(x),

given the jets (see :mod:`pinflex.jets`) of ``M`` (symmetric positive definite) and ``K``
(symmetric positive semidefinite) at an expansion point ``x0``.

The expanded quantity is the eigenvalue ``λ = ω²`` [rad²/s²] (not a frequency in Hz); use
:func:`pinflex.jets.sqrt` for the jet of ``ω`` [rad/s] and divide by ``2π`` for Hz.

Normalisation and sign:
    Eigenvectors are **mass-normalised at every x**: ``φ(x)ᵀ M(x) φ(x) = 1``. In jet
    coefficients this is ``Σ_{a+b+c=γ} φ_aᵀ M_b φ_c = δ_{γ0}``. The sign is fixed at the
    expansion point only: the entry of ``φ(x0)`` with the largest magnitude (the first one on
    ties) is positive, unless eigenvectors are supplied, whose signs are kept. Away from
    ``x0`` the sign follows by continuity.

Recursion:
    Collecting the coefficient of ``δx^γ`` (``|γ| = d ≥ 1``) in ``Kφ = λMφ`` and in the
    normalisation condition gives, with ``u = Mφ``,

    .. math::

        \begin{bmatrix} K_0 - \lambda_0 M_0 & -M_0\phi_0 \\ -\phi_0^T M_0 & 0
        \end{bmatrix}
        \begin{bmatrix} \phi_\gamma \\ \lambda_\gamma \end{bmatrix} =
        \begin{bmatrix} -\sum_{a\neq 0} K_a\phi_{\gamma-a}
            + \lambda_0 \hat u_\gamma + \sum_{a\neq 0,\gamma} \lambda_a u_{\gamma-a} \\
            \tfrac12\big(\phi_0^T \hat u_\gamma
            + \sum_{a\neq 0,\gamma} \phi_a^T u_{\gamma-a}\big) \end{bmatrix},
        \qquad \hat u_\gamma = \sum_{a\neq 0} M_a \phi_{\gamma-a},

    whose right-hand side only holds coefficients of degree < d. The bordered matrix is
    square, symmetric and regular when ``λ0`` is a simple eigenvalue; it is LU-factorised once
    per mode (its border scaled to the size of ``K0 − λ0 M0``) and reused for every
    multi-index and order. Products of ``M_a, K_a`` with known ``φ_b`` are pushed forward
    one GEMM per degree.

Failure detection:
    A mode whose eigenvalue belongs to a cluster of (nearly) equal eigenvalues has no
    analytic eigenvector branch and the bordered matrix is singular: :func:`eigen_jets`
    raises :class:`~pinflex.exceptions.RepeatedEigenvalue` instead of returning numbers. Two
    eigenvalues are clustered when ``|λ_i − λ_j| ≤ rtol·max(|λ_i|, |λ_j|) + atol``; the
    default ``atol`` is the rounding level of the pair, relative to the elastic spectrum
    (``100·n·ε·λ_i·λ_j/λ_e`` when the number of rigid modes is given, rigid zeros
    ``100·n·ε·max|λ|``) so that multiple rigid
    (zero) eigenvalues form a cluster. A simple non-zero mode next to a multiple zero
    eigenvalue is fine. The bordered matrix's reciprocal condition number is checked too.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
from scipy.linalg import lapack

from pinflex.exceptions import EigenSolverError, RepeatedEigenvalue
from pinflex.jets import JetSpace, ray_coefficients

__all__ = ["eigen_jets", "find_cluster", "radius_estimate", "root_test", "spectrum_slopes"]

_EPS = np.finfo(float).eps
# LAPACK routines called directly: the scipy.linalg wrappers cost more than the work at n ≈ 20.
_GETRF, _GETRS, _GECON = lapack.dgetrf, lapack.dgetrs, lapack.dgecon


@lru_cache(maxsize=32)
def _recursion_plan(space: JetSpace) -> tuple[list, list]:
    """Per-degree pair sets of the recursion, cached per jet space.

    Returns:
        ``push[e]`` for ``e = 0..p-1``: ``(a_stop, b_slice, scatter)`` where every ``a`` in
        ``1..a_stop-1`` (degrees 1..p-e) times every ``b`` of degree ``e`` is a valid pair,
        laid out ``(a, b)`` row-major, and ``scatter`` (ncoef × npairs, sparse) sums them into
        their target coefficients. ``inner[d]`` for ``d = 1..p`` (index ``d-1``):
        ``(pa, pc, scatter)`` over pairs ``a + c = γ`` with ``|γ| = d``, ``a ≠ 0``, ``c ≠ 0``;
        ``scatter`` (n_γ × npairs) sums them into the degree-``d`` coefficients.
    """
    p, off, mi = space.order, space.degree_offsets, space.multi_indices
    push = []
    for e in range(p):
        a_stop = int(off[p - e + 1])
        b0, b1 = int(off[e]), int(off[e + 1])
        ai = np.repeat(np.arange(1, a_stop), b1 - b0)
        bj = np.tile(np.arange(b0, b1), a_stop - 1)
        tgt = [space.index[tuple(s)] for s in (mi[ai] + mi[bj]).tolist()]
        scatter = sp.csr_matrix(
            (np.ones(len(tgt)), (tgt, np.arange(len(tgt)))), shape=(space.ncoef, len(tgt))
        )
        push.append((a_stop, slice(b0, b1), scatter))
    inner = []
    for d in range(1, p + 1):
        lo, hi = int(off[d]), int(off[d + 1])
        sel = (space.pair_c >= lo) & (space.pair_c < hi) & (space.pair_a != 0)
        sel &= space.pair_b != 0
        pa, pc, tg = space.pair_a[sel], space.pair_b[sel], space.pair_c[sel] - lo
        scatter = sp.csr_matrix(
            (np.ones(tg.size), (tg, np.arange(tg.size))), shape=(hi - lo, tg.size)
        )
        inner.append((pa, pc, scatter))
    return push, inner


def find_cluster(
    eigvals: np.ndarray, mode: int, *, rtol: float = 1e-6, atol: float | None = None,
    n_rigid: int | None = None,
) -> list[int]:
    """Indices of the eigenvalues that are (nearly) equal to ``eigvals[mode]``.

    Args:
        eigvals: All eigenvalues ``λ`` [rad²/s²], ascending, shape ``(n,)``.
        mode: Index of the mode of interest.
        rtol: Relative tolerance.
        atol: Absolute tolerance [rad²/s²]; default the rounding level of the pair
            (:func:`_pair_levels`).
        n_rigid: Number of rigid (zero) modes first in ``eigvals``, when the caller knows it:
            they form a cluster among themselves and never with an elastic mode, and the
            elastic modes' levels are relative to the elastic spectrum. None: the level is
            ``100·n·ε·max|λ|`` for every eigenvalue.

    Returns:
        Sorted indices ``j`` with ``|λ_j − λ_mode| ≤ rtol·max(|λ_j|, |λ_mode|) + atol``,
        including ``mode`` itself.
    """
    w = np.asarray(eigvals, dtype=float)
    lam = w[mode]
    if atol is not None:
        tol = np.full(w.shape, float(atol))
    else:
        tol = _pair_levels(w, mode, n_rigid)
    close = np.abs(w - lam) <= rtol * np.maximum(np.abs(w), abs(lam)) + tol
    if n_rigid is not None:  # rigid and elastic modes are told apart by count
        rigid = np.arange(w.size) < n_rigid
        close &= rigid == rigid[mode]
    return [int(j) for j in np.flatnonzero(close)]


def _pair_levels(eigvals: np.ndarray, mode: int, n_rigid: int | None = None) -> np.ndarray:
    """Rounding level [rad²/s²] of ``λ_j − λ_mode`` for every ``j``.

    Without ``n_rigid``: ``100·n·ε·max|λ|`` (a direct solve's absolute level, which also makes
    several rigid zeros one cluster). With the number of rigid modes known, the rigid zeros
    keep that level and two elastic modes get ``100·n·ε·min(λ_j·λ_mode/λ_e, max|λ|)``
    (``λ_e`` the lowest elastic eigenvalue): the inverse (solver-coordinate) form gives
    ``μ = 1/λ`` to an absolute ``~n·ε/λ_e``, so its low modes keep their relative accuracy on
    any mesh, and modes it resolves worse than a direct solve (above a spring mode far below
    the beams') come from the direct solve, absolute ``~n·ε·max|λ|``. The absolute level alone
    put well-separated low modes of a fine mesh in one cluster (benchmark A with 224 + 224
    elements: λ up to ~2e17, modes 1.47e6 and 7.19e6 rad²/s² 'repeated'); the relative one
    alone every mode above a 1e-8 N m/rad spring. Where the eigenvalues are less accurate than
    that, a true double root is still caught by the condition check of the bordered matrix.
    """
    a = np.abs(eigvals)
    level = 100.0 * eigvals.size * _EPS
    out = np.full(a.shape, level * float(np.max(a, initial=0.0)))
    if n_rigid is not None and n_rigid <= mode:
        low = max(float(np.min(a[n_rigid:])), np.finfo(float).tiny)
        out[n_rigid:] = level * np.minimum(a[n_rigid:] * (a[mode] / low), np.max(a))
    return out


def _default_atol(eigvals: np.ndarray, mode: int, n_rigid: int | None = None) -> float:
    """The rounding level of ``eigvals[mode]`` itself (:func:`_pair_levels`) [rad²/s²]."""
    return float(_pair_levels(eigvals, mode, n_rigid)[mode])


def _relative_gap(w: np.ndarray, mode: int, atol: float) -> float:
    """Smallest ``|λ_j − λ_i| / max(|λ_i|, |λ_j|, atol)`` over the other modes."""
    others = np.delete(w, mode)
    if others.size == 0:
        return np.inf
    diff = np.abs(others - w[mode])
    scale = np.maximum(np.maximum(np.abs(others), abs(w[mode])), atol)
    rel = np.divide(diff, scale, out=np.zeros_like(diff), where=scale > 0)
    return float(rel.min())


def _check_pencil(space: JetSpace, M_jet: np.ndarray, K_jet: np.ndarray) -> int:
    jets = (("M_jet", M_jet), ("K_jet", K_jet)) if K_jet.ndim != 2 else (("M_jet", M_jet),)
    for name, jet in jets:
        if jet.ndim != 3 or jet.shape[0] != space.ncoef or jet.shape[1] != jet.shape[2]:
            raise ValueError(
                f"{name} has shape {jet.shape}; expected ({space.ncoef}, n, n): a jet of square "
                "matrices on this space"
            )
    if K_jet.shape[-2:] != M_jet.shape[1:] or (K_jet.ndim == 3 and M_jet.shape != K_jet.shape):
        raise ValueError(f"M_jet {M_jet.shape} and K_jet {K_jet.shape} differ in shape")
    n = M_jet.shape[1]
    for name, mat in (("M", M_jet[0]), ("K", K_jet if K_jet.ndim == 2 else K_jet[0])):
        scale = max(float(np.max(np.abs(mat))), np.finfo(float).tiny)
        if np.max(np.abs(mat - mat.T)) > 1e-10 * scale:
            raise ValueError(f"{name}(x0) is not symmetric; the recursion needs symmetric M, K")
    return n


def _bordered_lu(
    K0: np.ndarray, M0: np.ndarray, lam0: float, phi0: np.ndarray
) -> tuple[np.ndarray, np.ndarray, float, float]:
    """LU of ``[[K0 − λ0 M0, −σ M0φ0], [−σ φ0ᵀM0, 0]]``; returns (lu, piv, σ, rcond)."""
    n = K0.shape[0]
    A = K0 - lam0 * M0
    b = M0 @ phi0
    sigma = max(float(np.max(np.abs(A))), np.finfo(float).tiny) / float(np.max(np.abs(b)))
    B = np.empty((n + 1, n + 1))
    B[:n, :n] = A
    B[:n, n] = -sigma * b
    B[n, :n] = -sigma * b
    B[n, n] = 0.0
    anorm = float(np.abs(B).sum(axis=0).max())
    lu, piv, info = _GETRF(B, overwrite_a=True)
    if info > 0:  # exactly singular pivot
        return lu, piv, sigma, 0.0
    rcond, _ = _GECON(lu, anorm, norm="1")
    return lu, piv, sigma, float(rcond)


def eigen_jets(
    space: JetSpace,
    M_jet: np.ndarray,
    K_jet: np.ndarray,
    modes: int | Sequence[int],
    *,
    eigvals0: np.ndarray | None = None,
    eigvecs0: np.ndarray | None = None,
    cluster_rtol: float = 1e-6,
    cluster_atol: float | None = None,
    cond_max: float = 1e13,
    n_rigid: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Jets of chosen eigenvalues and mass-normalised eigenvectors of ``K φ = λ M φ``.

    Args:
        space: Jet space of the expansion (``nvars`` variables, order ``p``).
        M_jet: Jet of the mass matrix, shape ``(ncoef, n, n)``; ``M(x0)`` symmetric
            positive definite.
        K_jet: Jet of the stiffness matrix, shape ``(ncoef, n, n)``; ``K(x0)`` symmetric. A
            single ``(n, n)`` matrix is a stiffness that does not depend on the variables
            (its products in the recursion are skipped).
        modes: Index or indices into the ascending eigenvalues of ``(K(x0), M(x0))``.
        eigvals0: All eigenvalues at ``x0`` [rad²/s²], ascending, shape ``(n,)``; computed
            with ``scipy.linalg.eigh`` when omitted. Give it together with ``eigvecs0``.
        eigvecs0: Eigenvectors at ``x0``: shape ``(n, n)`` (all, columns in the order of
            ``eigvals0``) or ``(n, len(modes))`` (the chosen modes). They are rescaled to
            ``φᵀ M0 φ = 1``; their signs are kept.
        cluster_rtol: Relative tolerance of :func:`find_cluster`.
        cluster_atol: Absolute tolerance of :func:`find_cluster` [rad²/s²].
        cond_max: Largest accepted 1-norm condition number of the (scaled) bordered matrix.
        n_rigid: Number of rigid (zero) modes first in the spectrum, if known: the cluster
            test is then relative to the elastic spectrum (:func:`find_cluster`).

    Returns:
        ``(lam_jets, phi_jets)``: eigenvalue jets of shape ``(ncoef, nmodes)`` [rad²/s²] and
        eigenvector jets of shape ``(ncoef, n, nmodes)``, in the coefficient order of
        ``space`` (coefficients ``∂^α/α!``).

    Raises:
        RepeatedEigenvalue: A chosen mode is (nearly) repeated at ``x0``, or its bordered
            matrix is too ill-conditioned.
        EigenSolverError: ``M(x0)`` is not positive definite, or the supplied eigenpairs do
            not solve the eigenproblem at ``x0``.
        ValueError: Shapes or mode indices are wrong.
    """
    M_jet = np.asarray(M_jet, dtype=float)
    K_jet = np.asarray(K_jet, dtype=float)
    n = _check_pencil(space, M_jet, K_jet)
    M0, K0 = M_jet[0], (K_jet if K_jet.ndim == 2 else K_jet[0])
    mode_list = [int(m) for m in np.atleast_1d(modes)]
    if not mode_list or any(not 0 <= m < n for m in mode_list):
        raise ValueError(f"modes = {mode_list}: give indices in 0..{n - 1}")
    if (eigvals0 is None) != (eigvecs0 is None):
        raise ValueError("give eigvals0 and eigvecs0 together, or neither")

    if eigvals0 is None:
        try:
            w, V = sla.eigh(K0, M0, check_finite=False)
        except np.linalg.LinAlgError as exc:
            raise EigenSolverError(
                "the generalized eigenproblem at the expansion point failed: M(x0) must be "
                "symmetric positive definite"
            ) from exc
        phi0 = V[:, mode_list]
        big = np.argmax(np.abs(phi0), axis=0)
        phi0 = phi0 * np.sign(phi0[big, np.arange(len(mode_list))])
    else:
        w = np.asarray(eigvals0, dtype=float)
        V = np.asarray(eigvecs0, dtype=float)
        if w.shape != (n,) or np.any(np.diff(w) < 0):
            raise ValueError(f"eigvals0 must be all {n} eigenvalues in ascending order")
        if V.shape == (n, n):
            phi0 = V[:, mode_list]
        elif V.shape == (n, len(mode_list)):
            phi0 = V
        else:
            raise ValueError(f"eigvecs0 has shape {V.shape}; expected ({n}, {n}) or ({n}, nmodes)")
        phi0 = phi0 / np.sqrt(np.einsum("im,ij,jm->m", phi0, M0, phi0))
    lam0 = w[mode_list]

    # Detection: clusters first, then a residual check of supplied pairs.
    for m in mode_list:
        atol = _default_atol(w, m, n_rigid) if cluster_atol is None else float(cluster_atol)
        cluster = find_cluster(w, m, rtol=cluster_rtol, atol=cluster_atol, n_rigid=n_rigid)
        if len(cluster) > 1:
            raise RepeatedEigenvalue(m, cluster, w[cluster], _relative_gap(w, m, atol))
    residual = K0 @ phi0 - (M0 @ phi0) * lam0
    scale = np.abs(K0).max() * np.abs(phi0).max(axis=0) + np.abs(lam0) * np.abs(M0 @ phi0).max(
        axis=0
    )
    if np.any(np.abs(residual).max(axis=0) > 1e-8 * np.maximum(scale, np.finfo(float).tiny)):
        raise EigenSolverError(
            "the eigenpairs at the expansion point do not satisfy K φ = λ M φ (relative "
            "residual above 1e-8): pass eigvals0/eigvecs0 from scipy.linalg.eigh(K(x0), M(x0))"
        )

    factors = []
    for j, m in enumerate(mode_list):
        lu, piv, sigma, rcond = _bordered_lu(K0, M0, float(lam0[j]), phi0[:, j])
        if not rcond * cond_max >= 1.0:
            nearest = int(np.delete(np.arange(n), m)[np.argmin(np.abs(np.delete(w, m) - w[m]))])
            cluster = sorted({m, nearest})
            atol = _default_atol(w, m, n_rigid) if cluster_atol is None else float(cluster_atol)
            raise RepeatedEigenvalue(m, cluster, w[cluster], _relative_gap(w, m, atol))
        factors.append((lu, piv, sigma))

    return _recursion(space, M_jet, K_jet, lam0, phi0, factors)


def _recursion(
    space: JetSpace,
    M_jet: np.ndarray,
    K_jet: np.ndarray,
    lam0: np.ndarray,
    phi0: np.ndarray,
    factors: list[tuple[np.ndarray, np.ndarray, float]],
) -> tuple[np.ndarray, np.ndarray]:
    """Degree-by-degree solve of the bordered systems (see the module docstring)."""
    ncoef, n = space.ncoef, M_jet.shape[1]
    nm = phi0.shape[1]
    p, off = space.order, space.degree_offsets
    lam = np.zeros((ncoef, nm))
    phi = np.zeros((ncoef, n, nm))
    u = np.zeros((ncoef, n, nm))  # (Mφ)_γ; for unsolved γ only the a ≠ 0 part
    v = np.zeros((ncoef, n, nm))  # (Kφ)_γ, a ≠ 0 part
    lam[0], phi[0] = lam0, phi0
    u[0] = M_jet[0] @ phi0
    if p == 0:
        return lam, phi
    push, inner = _recursion_plan(space)
    M0 = M_jet[0]
    M_rows = M_jet.reshape(ncoef * n, n)  # views: the a ≠ 0 factors of a push are rows
    # n .. a_stop·n; a constant stiffness (2-D) has no a ≠ 0 factor: v stays zero
    pushed = [(u, M_rows)] if K_jet.ndim == 2 else [(u, M_rows), (v, K_jet.reshape(ncoef * n, n))]

    for d in range(p + 1):
        if d >= 1:
            lo, hi = int(off[d]), int(off[d + 1])
            ng = hi - lo
            pa, pc, scatter = inner[d - 1]
            u_hat = u[lo:hi]
            rhs = lam0 * u_hat - v[lo:hi]
            s = (phi0 * u_hat).sum(axis=1)
            if pa.size:
                u_c = u[pc]
                lam_u = lam[pa][:, None, :] * u_c
                rhs += (scatter @ lam_u.reshape(pa.size, n * nm)).reshape(ng, n, nm)
                s += scatter @ (phi[pa] * u_c).sum(axis=1)
            s *= 0.5
            for j, (lu, piv, sigma) in enumerate(factors):
                block = np.empty((n + 1, ng))
                block[:n] = rhs[:, :, j].T
                block[n] = sigma * s[:, j]
                sol, info = _GETRS(lu, piv, block, overwrite_b=True)
                phi[lo:hi, :, j] = sol[:n].T
                lam[lo:hi, j] = sigma * sol[n]
            u[lo:hi] += np.matmul(M0, phi[lo:hi])
        if d < p:
            a_stop, bsl, scatter = push[d]
            na, nb = a_stop - 1, bsl.stop - bsl.start
            phis = phi[bsl].transpose(1, 0, 2).reshape(n, nb * nm)
            for acc, rows in pushed:
                prod = (rows[n : a_stop * n] @ phis).reshape(na, n, nb, nm)
                prod = prod.transpose(0, 2, 1, 3).reshape(na * nb, n * nm)
                acc += (scatter @ prod).reshape(ncoef, n, nm)
    return lam, phi


def radius_estimate(
    space: JetSpace,
    jet: np.ndarray,
    direction: np.ndarray | None = None,
    *,
    noise_rtol: float = 1e-12,
) -> np.ndarray:
    """Estimate the convergence radius of a jet along rays by the root test.

    Along a ray ``t ↦ f(x0 + t v)`` the univariate coefficients are ``c_k``
    (:func:`pinflex.jets.ray_coefficients`). The order-``j`` term equals the value
    ``|c_0|`` at ``R_j = |c_0 / c_j|^{1/j}``; the estimate is the smallest ``R_j`` over the upper
    half of the orders (``j ≥ ⌈p/2⌉``), a finite-order stand-in for Cauchy–Hadamard's
    ``1 / limsup |c_j|^{1/j}`` measured against the value itself, which is what a relative
    error cares about (see :func:`root_test`). It is not scale-free: a large constant part
    makes it optimistic. On ``λ = 3 ± √(1 + s²)`` from ``s0 = 0.5`` it over-estimates the
    distance to the branch points ``s = ±i`` by a factor 2.1 at ``p = 4``, 1.6 at ``p = 8``
    and 1.3 at ``p = 24``; :meth:`pinflex.parametric.TaylorModel.error_estimate` combines it
    with the distance to the nearest eigenvalue of the spectrum.

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)`` (e.g. ``lam_jets`` of :func:`eigen_jets`).
        direction: Ray directions ``v``: ``None`` for every coordinate axis, shape
            ``(nvars,)`` for one ray or ``(ndir, nvars)``.
        noise_rtol: Orders with ``|c_j| <= noise_rtol |c_0|`` count as zero.

    Returns:
        Radius estimates in units of ``t``: shape ``(nvars, *shape)`` for ``direction=None``,
        ``shape`` for a single direction, ``(ndir, *shape)`` otherwise; ``inf`` where no order
        of the upper half is non-zero (a polynomial of low degree along the ray).
    """
    jet = np.asarray(jet, dtype=float)
    single = direction is not None and np.ndim(direction) == 1
    dirs = np.eye(space.nvars) if direction is None else np.atleast_2d(direction)
    coeffs = np.abs(ray_coefficients(space, jet, dirs))  # (ndir, p+1, *shape)
    radius = root_test(np.moveaxis(coeffs, 1, -1), noise_rtol=noise_rtol)
    return radius[0] if single else radius


def root_test(c: np.ndarray, *, noise_rtol: float = 1e-12) -> np.ndarray:
    """Root-test radius from coefficient sizes ``|c_0| .. |c_p|`` on the last axis.

    Args:
        c: Coefficients (or their sizes) of shape ``(..., p + 1)``.
        noise_rtol: Orders with ``|c_j| <= noise_rtol |c_0|`` count as zero.

    Returns:
        ``min_{j ≥ ⌈p/2⌉} |c_0 / c_j|^{1/j}``, shape ``(...)`` (``inf`` for p = 0 or when
        those orders all vanish).
    """
    c = np.abs(np.asarray(c, dtype=float))
    p = c.shape[-1] - 1
    out = np.full(c.shape[:-1], np.inf)
    if p < 1:
        return out
    c0 = np.where(c[..., 0] > 0, c[..., 0], 1.0)
    for j in range(max(1, (p + 1) // 2), p + 1):
        ratio = c[..., j] / c0
        with np.errstate(divide="ignore"):
            out = np.minimum(out, np.where(ratio > noise_rtol, ratio ** (-1.0 / j), np.inf))
    return out


def spectrum_slopes(space: JetSpace, M_jet: np.ndarray, K_jet: np.ndarray,
                    eigvals: np.ndarray, eigvecs: np.ndarray) -> np.ndarray:
    """First derivatives of every eigenvalue at ``x0``: ``φ_jᵀ (K_a − λ_j M_a) φ_j``.

    Args:
        space: Jet space (order ≥ 1).
        M_jet: Mass-matrix jet (ncoef, n, n).
        K_jet: Stiffness-matrix jet (ncoef, n, n), or one (n, n) matrix (constant).
        eigvals: Eigenvalues at ``x0`` (m,) [rad²/s²].
        eigvecs: Their eigenvectors (n, m), ``M(x0)``-normalised.

    Returns:
        Slopes (nvars, m) [rad²/s² per variable unit]; meaningful for simple eigenvalues.
    """
    if space.order < 1:
        return np.zeros((space.nvars, np.size(eigvals)))
    first = [space.position([1 if k == a else 0 for k in range(space.nvars)])
             for a in range(space.nvars)]
    V = np.asarray(eigvecs, dtype=float)
    MV = np.einsum("aij,jm->aim", M_jet[first], V)
    out = -np.asarray(eigvals)[None, :] * np.einsum("im,aim->am", V, MV)
    if np.ndim(K_jet) == 3:
        out += np.einsum("im,aim->am", V, np.einsum("aij,jm->aim", K_jet[first], V))
    return out
