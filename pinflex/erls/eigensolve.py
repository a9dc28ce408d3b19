"""Inverse-form eigensolve of the conditioned mass (see :mod:`pinflex.erls.solve`).

The non-rigid eigenvalues are ``λ = 1/μ`` with ``μ`` the eigenvalues of the symmetric
condensed mass ``Bred`` in solver coordinates; modes the inverse form does not resolve are
recovered from the nodal pencil or refused (:class:`~pinflex.exceptions.EigenSolverError`).
"""

from __future__ import annotations

import math

import numpy as np

from pinflex.erls.solve import solve_plan
from pinflex.exceptions import EigenSolverError

_EPS = np.finfo(float).eps
_LINALG: tuple | None = None  # (scipy.linalg.blas, scipy.linalg.lapack), imported on first use


def _linalg() -> tuple:
    """SciPy's BLAS and LAPACK wrappers (imported once, on the first one-pose solve)."""
    global _LINALG
    from scipy.linalg import blas, lapack

    _LINALG = (blas, lapack)
    return _LINALG



def condense(model, M: np.ndarray):
    """Elastic mass with the rigid joint coordinates condensed out, and the solve pieces.

    Returns:
        ``(Bred, Lq, Y)`` with ``Bred = Mww − Yᵀ Y``, ``Y = Lq⁻¹ Mqw`` and ``Lq`` the
        Cholesky factor of ``Mqq`` (None without joints).
    """
    nx = model.nx
    Mww = M[..., :nx, :nx]
    if not model.nv:
        return Mww, None, None
    try:
        Lq = np.linalg.cholesky(M[..., nx:, nx:])
    except np.linalg.LinAlgError as exc:
        raise EigenSolverError(
            "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
            "add inertia to the links it drives"
        ) from exc
    Y = np.linalg.solve(Lq, M[..., nx:, :nx])
    return Mww - np.swapaxes(Y, -1, -2) @ Y, Lq, Y


def noise_level(mu: np.ndarray) -> np.ndarray:
    """Absolute rounding level ``c ε μ_max`` of the computed μ (per pose), (...,).

    A backward-stable symmetric eigensolver perturbs ``Bred`` by about ``ε ‖Bred‖``; an
    eigenvalue ``μ`` below ``64 ε μ_max`` has no reliable digit left.
    """
    return 64.0 * _EPS * np.max(np.abs(mu), axis=-1)


def rounding_bound(lam: np.ndarray) -> np.ndarray:
    """Estimated relative rounding error of each eigenvalue ``λ_k`` (same shape as ``lam``).

    ``≈ c n ε λ_k / λ_1`` (see the module docstring), ``n`` the number of elastic coordinates.
    """
    lam = np.asarray(lam, dtype=float)
    n = lam.shape[-1]
    return 8.0 * max(n, 1) * _EPS * lam / lam[..., :1]


def _finite(values: np.ndarray) -> None:
    if not np.all(np.isfinite(values)):
        raise EigenSolverError("the eigensolver returned non-finite values: the mass or the "
                               "stiffness of the model is not finite")


def _unresolved(first: int, detail: str) -> EigenSolverError:
    return EigenSolverError(
        f"elastic mode {first} is not resolved: {detail}; the model is near-singular (a link "
        "that is too soft, too heavy or too long for its section, or a mass that is not "
        "positive): check the units of E, the section and the lengths"
    )


def resolved(mu: np.ndarray) -> int:
    """Number of leading (descending) μ above the rounding level, the least over poses."""
    if mu.shape[-1] == 0:
        return 0
    ok = mu > noise_level(mu)[..., None]
    ok = np.all(ok.reshape(-1, mu.shape[-1]), axis=0)
    return int(np.argmin(ok)) if not np.all(ok) else mu.shape[-1]


def _direct(pencil, lo: int, k: int, vectors: bool):
    """Modes ``lo..k-1`` from the nodal-coordinate pencil (accurate for the high modes).

    ``pencil()`` returns ``(Mred, Kxx, M)`` (one pose, nodal coordinates). The direct
    generalized solve resolves eigenvalues above ``64 ε λ_max``; a mode resolved by neither
    form is refused.
    """
    import scipy.linalg

    Mred, Kxx, _ = pencil()
    nx = Kxx.shape[-1]
    out = scipy.linalg.eigh(Kxx, Mred, subset_by_index=[lo, nx - 1], eigvals_only=not vectors,
                            check_finite=False)
    lam = out if not vectors else out[0]
    _finite(lam)
    if lam[0] <= 64.0 * _EPS * lam[-1]:
        raise _unresolved(lo + 1, "neither the relative-coordinate (inverse) nor the nodal "
                          f"(direct) form resolves it: λ spans {lam[-1]:.3e} down to below "
                          "both rounding levels")
    if not vectors:
        return lam[: k - lo], None
    return lam[: k - lo], out[1][:, : k - lo]


LANCZOS_MIN_DOF = 400


def use_lanczos(n: int, k: int) -> bool:
    """Whether the ``k`` largest μ of an ``n × n`` Bred go to Lanczos instead of a dense solve.

    Lanczos (ARPACK, through :func:`scipy.sparse.linalg.eigsh`) needs a few dozen products
    with ``Bred`` (O(n²) each) where a dense solve needs O(n³); the largest μ = 1/λ are the
    best separated part of the spectrum (μ_k ∝ k⁻⁴ for bending), so it converges fast.
    """
    return n >= LANCZOS_MIN_DOF and 4 * k <= n


def _lanczos(B: np.ndarray, k: int, vectors: bool):
    """The ``k`` largest eigenvalues of a symmetric B, descending (and vectors, ascending)."""
    from scipy.sparse.linalg import ArpackNoConvergence, eigsh

    n = B.shape[0]
    v0 = np.full(n, 1.0 / np.sqrt(n))
    try:
        out = eigsh(B, k=k, which="LA", v0=v0, ncv=min(n, max(2 * k + 1, 20)), tol=0.0,
                    return_eigenvectors=vectors)
    except ArpackNoConvergence as exc:
        raise EigenSolverError(f"the Lanczos iteration did not converge on {k} modes of "
                               f"{n}: ask for fewer modes or all of them (dense solve)") from exc
    if vectors:
        order = np.argsort(out[0])
        return out[0][order], out[1][:, order]
    return np.sort(out)[::-1], None


def eigvals(model, M: np.ndarray, n_modes: int | None = None, pencil=None) -> np.ndarray:
    """Non-rigid eigenvalues λ (ascending) from stacked solver-coordinate masses (b, nd, nd).

    Args:
        model: The flexible model.
        M: Solver-coordinate masses from :func:`mass`.
        n_modes: Number of lowest modes wanted (default all).
        pencil: ``pencil(i)`` returns the nodal-coordinate ``(Mred, Kxx, M)`` of pose ``i``;
            used to recover requested high modes that the inverse form does not resolve
            (without it they are refused).
    """
    nx = model.nx
    k = nx if n_modes is None else min(int(n_modes), nx)
    if nx == 0:
        return np.zeros(M.shape[:-2] + (0,))
    Bred, _, _ = condense(model, M)
    if use_lanczos(nx, k):
        mu = np.stack([_lanczos(B, k, False)[0] for B in Bred.reshape(-1, nx, nx)])
        mu = mu.reshape(Bred.shape[:-2] + (k,))
    else:
        mu = np.linalg.eigvalsh(Bred)[..., ::-1]
    _finite(mu)
    lam = 1.0 / mu[..., :k]
    good = mu > noise_level(mu)[..., None]
    for idx in zip(*np.nonzero(~np.all(good[..., :k], axis=-1))):
        r = int(np.argmin(good[idx]))
        if pencil is None:
            raise _unresolved(r + 1, "its eigenvalue is below the rounding level of the mass")
        lam[idx][r:] = _direct(lambda i=idx: pencil(*i), r, k, False)[0]
    return lam


def eigvals_one(model, M: np.ndarray, n_modes: int | None = None, pencil=None) -> np.ndarray:
    """:func:`eigvals` of one pose (M: (nd, nd)), without the batch bookkeeping (NumPy only).

    ``pencil()`` returns the nodal-coordinate ``(Mred, Kxx, M)`` of the pose.
    """
    nx = model.nx
    k = nx if n_modes is None else min(int(n_modes), nx)
    if nx == 0:
        return np.zeros(0)
    if use_lanczos(nx, k):
        return eigvals(model, M[None], n_modes,
                       None if pencil is None else lambda *_: pencil())[0]
    Bred = M[:nx, :nx]
    if model.nv:
        try:
            L = np.linalg.cholesky(M[nx:, nx:])
        except np.linalg.LinAlgError as exc:
            raise EigenSolverError(
                "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
                "add inertia to the links it drives"
            ) from exc
        Y = np.linalg.solve(L, M[nx:, :nx])
        Bred = Bred - Y.T @ Y
    mu = np.linalg.eigvalsh(Bred)[::-1]
    if not np.isfinite(mu).all():
        _finite(mu)
    ok = mu[:k] > 64.0 * _EPS * max(abs(mu[0]), abs(mu[-1]))  # as noise_level(): mu sorted
    lam = 1.0 / mu[:k]
    if not ok.all():
        r = int(np.argmin(ok))
        if pencil is None:
            raise _unresolved(r + 1, "its eigenvalue is below the rounding level of the mass")
        lam[r:] = _direct(pencil, r, k, False)[0]
    return lam


def _condense_one(M: np.ndarray, nx: int, nv: int):
    """``(Bred, Lq, Y)``: the elastic block with the rigid one condensed out, one pose.

    As :func:`condense`, through LAPACK/BLAS directly (one pose: the wrappers' checks cost
    more than these small factorizations); ``Bred``'s lower triangle only. ``Lq`` (the
    Cholesky factor of ``Mqq``) and ``Y = Lq⁻¹ Mqw`` are None without rigid coordinates.
    """
    blas, lapack = _LINALG or _linalg()
    Bred = M[:nx, :nx]
    if not nv:
        return Bred, None, None
    Lq, info = lapack.dpotrf(M[nx:, nx:], lower=1, clean=1)
    if info != 0:
        raise EigenSolverError(
            "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
            "add inertia to the links it drives"
        )
    Y, info = lapack.dtrtrs(Lq, M[nx:, :nx], lower=1)
    return blas.dsyrk(-1.0, Y, beta=1.0, c=Bred, trans=1, lower=1), Lq, Y  # Mww - Y^T Y


def _top_eigh(Bred: np.ndarray, nx: int, k: int):
    """The ``k`` largest eigenpairs of ``Bred`` (lower triangle given), ascending."""
    if use_lanczos(nx, k):
        return _lanczos(np.tril(Bred) + np.tril(Bred, -1).T, k, True)
    if k == nx:
        mu, V, info = (_LINALG or _linalg())[1].dsyevd(Bred, compute_v=1, lower=1)
        if info != 0:
            raise EigenSolverError("the symmetric eigensolver did not converge: the mass of the "
                                   "model is not finite")
        return mu, V
    import scipy.linalg

    return scipy.linalg.eigh(Bred, lower=True, subset_by_index=[nx - k, nx - 1],
                             driver="evr", check_finite=False)


def eigvecs(model, M: np.ndarray, n_modes: int | None = None, pencil=None):
    """Eigenvalues λ (k,) and mass-normalised shapes of one pose.

    Returns:
        ``(lam, shapes_w, shapes_x)``: the modes the inverse form resolves as solver-coordinate
        shapes ``[w; q]`` (nd, r), and the rest (recovered from the nodal pencil, see
        :func:`eigvals`) directly over ``[x; q]`` (nd, k - r). The q part is the condensed
        rigid-coordinate response.
    """
    lapack = (_LINALG or _linalg())[1]
    nx = model.nx
    k = nx if n_modes is None else min(int(n_modes), nx)
    nd = M.shape[-1]
    Bred, Lq, Y = _condense_one(M, nx, model.nv)
    if k == 0:
        return np.zeros(0), np.zeros((nd, 0)), np.zeros((nd, 0))
    mu, V = _top_eigh(Bred, nx, k)
    mu, V = mu[::-1], V[:, ::-1]
    if not math.isfinite(mu.sum()):  # a NaN or inf makes the sum one (then checked in full)
        _finite(mu)
    top, low = float(mu[0]), float(mu[-1])
    # as resolved(): mu is sorted, so the smallest decides whether all are above the noise
    r = k if low > 64.0 * _EPS * max(abs(top), abs(low)) else int(np.argmin(
        mu > 64.0 * _EPS * max(abs(top), abs(low))))
    shapes_w = np.empty((nd, r))
    phi_w = shapes_w[:nx]
    np.divide(V[:, :r], np.sqrt(mu[:r]), out=phi_w)
    if Lq is not None:  # nv is small
        np.negative(lapack.dtrtrs(Lq, Y @ phi_w, lower=1, trans=1)[0], out=shapes_w[nx:])
    else:
        shapes_w[nx:] = 0.0
    lam = 1.0 / mu
    shapes_x = np.zeros((nd, k - r))
    if r < k:
        if pencil is None:
            raise _unresolved(r + 1, "its eigenvalue is below the rounding level of the mass")
        lam_d, phix = _direct(lambda: pencil(), r, k, True)
        lam[r:] = lam_d
        Mfull = pencil()[2]
        shapes_x[:nx] = phix
        if model.nv:
            shapes_x[nx:] = -np.linalg.solve(Mfull[nx:, nx:], Mfull[nx:, :nx] @ phix)
    return lam, shapes_w, shapes_x


def to_nodal(model, twist: dict, shapes: np.ndarray, data=None) -> np.ndarray:
    """Shapes over ``[x; q]`` (nodal coordinates) of solver-coordinate shapes ``[w; q]``."""
    plan = solve_plan(model, data)
    nx = plan.nx
    out = np.array(shapes, dtype=float)
    w = shapes[:nx]
    for link, c in plan.cores.items():
        x = c.C[c.x_rows] @ w[c.start : c.stop]
        e = twist[link]
        if e is not None:
            x = x + c.R[c.x_rows] @ (e[0] @ w)
        out[c.start : c.stop] = x
    return out

