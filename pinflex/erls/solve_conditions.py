"""Conditioned modal solve of models with joint springs, locked joints or section design.

:mod:`pinflex.erls.solve` keeps the low modes of a fine mesh exact for free joints: in its
solver coordinates ``w`` the stiffness is the identity and the eigenvalues are ``λ = 1/μ`` of a
symmetric mass. This module extends that form to the other joint conditions and to design
parameters of the beams, instead of the nodal-coordinate pencil whose low modes lose digits
like ``ε λ_max/λ_1 ∝ N⁴`` (N elements per link: a spring 33 % off at 512 elements).

* **Relative joint values.** Every moving joint gets the coordinate of its physical relative
  motion ``r_j = (C q)_j − aᵀθ_parent(w)`` (:mod:`pinflex.erls.joints`): the congruence
  ``q = C⁻¹ (r + G w)`` (``G`` the rows ``aᵀθ_parent`` in solver coordinates) is unit
  triangular and exact. In ``[w; r]`` the stiffness is diagonal: ``I`` on ``w``, ``k_j`` on a
  spring's ``r_j``, 0 on a free joint's. A locked joint is ``r_j = 0``: its column is dropped.
* **Section and material design.** The solver coordinates are scaled by the element blocks at
  the nominal design; at a design ``y`` a link's stiffness is ``I_N ⊗ K̂(y)`` (block diagonal,
  :mod:`pinflex.parametric.solver_design`) and its mass gains ``Σ_c Δf_c M̂_c(q)``. With
  ``K̂ = L Lᵀ`` (one small Cholesky per link) the coordinates ``w' = Lᵀ w`` restore ``K = I``.
* **Inverse form.** The free joints are condensed out of the mass, the springs' ``r`` scaled by
  ``1/√k``: ``λ = 1/μ`` of one symmetric matrix per pose, as for free joints (unresolved high
  modes go to the nodal pencil, as there).
* **Soft springs.** A spring whose mode lies far below the elastic spectrum (estimated
  ``λ_s/λ_1 < SOFT_SPLIT``) would put a huge ``μ_s`` beside the elastic ones and cost them
  ``λ_1/λ_s`` in relative accuracy. Its coordinate is split off instead: with ``A, C, D`` the
  blocks of the mass over the other elastic coordinates ``u`` and the soft ones ``s``, the
  elastic modes solve ``μ u = (A − C (D − μ K_s)⁻¹ Cᵀ) u`` exactly; the linear part in ``μ``
  is the well-conditioned pencil ``(A − C D⁻¹ Cᵀ) u = μ (I + F) u``, ``F = C D⁻¹ K_s D⁻¹ Cᵀ``
  (rank of the soft springs, ``‖F‖ ~ λ_s/λ_1``), and the rest, ``O((λ_s/λ)²)``, is added by one
  first-order correction (error ``O((λ_s/λ)³)``). The soft modes solve the small
  ``K_s s = λ (D + Cᵀ (μ − A)⁻¹ C) s`` by fixed-point iteration, the resolvent as its Neumann
  series in ``λ A``. Both parts keep full relative accuracy whatever the spring's softness.

A spring softer than :data:`pinflex.erls.joints.SOFT_SPRING_RATIO` times the softest beam's
own stiffness is made a free joint when the model is built (a ``SoftSpringWarning``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex import beam
from pinflex.erls import design as erls_design
from pinflex.erls import eigensolve, solve
from pinflex.exceptions import EigenSolverError

#: Estimated ratio λ_spring/λ_1 below which a spring's coordinate is split off the inverse
#: form (see the module docstring): the inverse form would lose ``ε/ratio`` on the elastic
#: modes, the split's remainder is ``ratio³``; at 1e-4 both are below 1e-11.
SOFT_SPLIT = 1e-4

_K_NAMES = ("EA", "GJ", "EIy", "EIz")


def covered(model) -> bool:
    """Whether this module solves the model: springs, locks or beam design, and a beam."""
    return model.nx > 0 and not solve.supported(model)


# ------------------------------------------------------------------------ design blocks


def _unit_tip(spec, name: str, nd: np.ndarray) -> np.ndarray:
    """Clamped-tip block of the element stiffness per unit of rigidity ``name``."""
    le = spec.length_m / spec.elements
    args = [0.0, 0.0, 0.0, 0.0]
    args[_K_NAMES.index(name)] = 1.0
    return beam.element_stiffness(le, *args)[6:, 6:][np.ix_(nd, nd)]


def link_blocks(model, data=None) -> dict:
    """Per design channel of a beam, its constant solver-coordinate block (per workspace).

    Returns ``{channel index: block}``: for a stiffness channel the per-element ``K̂_c``
    (r × r), for a mass channel the six blocks ``(H_oo, H_oe, H_ov, H_ee, H_ev, H_vv)``.
    """
    return model.workspace(data).cached("solver_design_blocks",
                                        lambda: _build_link_blocks(model, data))


def _build_link_blocks(model, data) -> dict:
    plan = solve.solve_plan(model, data)
    out: dict = {}
    for n, ch in enumerate(model.plan.design.channels):
        if ch.name == "stiffness":
            continue
        core = plan.cores[ch.owner]
        bp = model.plan.beams[ch.owner]
        spec = bp.spec
        rows = np.asarray(bp.rows)
        N = spec.elements
        r = rows.size // (N + 1)
        nd = rows[:r]
        if ch.kind == "K":
            le = spec.length_m / N
            sec = spec.section
            ke = beam.element_stiffness(le, spec.E * sec.A, spec.G * sec.J, spec.E * sec.Iy,
                                        spec.E * sec.Iz)
            Dt = np.linalg.cholesky(ke[6:, 6:][np.ix_(nd, nd)]).T  # as solve_plan
            zinv = np.linalg.inv(Dt)
            blk = zinv.T @ _unit_tip(spec, ch.name, nd) @ zinv
            out[n] = 0.5 * (blk + blk.T)
            continue
        A = np.concatenate([core.C, core.R, bp.jac], axis=1)[rows]
        H = A.T @ (ch.unit @ A)
        H = 0.5 * (H + H.T)
        o = core.stop - core.start
        out[n] = (H[:o, :o], H[:o, o : o + 6], H[:o, o + 6 :], H[o : o + 6, o : o + 6],
                  H[o : o + 6, o + 6 :], H[o + 6 :, o + 6 :])
    return out


def parent_rows(model, plan, alg, twists, sources, joints) -> np.ndarray:
    """``aᵀθ_parent`` of each joint over ``w``: (lead, len(joints), nx) in the algebra ``alg``.

    ``θ_parent`` is the elastic rotation (translation for a prismatic joint) of the joint's
    attachment on its parent, ``a`` the joint axis; zero on the ground or a rigid parent.
    """
    nx = plan.nx
    index = {id(j): i for i, j in enumerate(model.plan.joints)}
    out = np.zeros((alg.size, len(joints), nx))
    for row, joint in enumerate(joints):
        tw = twists[joint.parent]
        e_full = None
        if tw is not None:
            e = solve.explicit_twist(tw, sources, alg)
            e_full = np.zeros((alg.size, 6, nx))
            e_full[:, :, : e.shape[-1]] = e
        tau = solve.attach_twist(plan.joint_attach[index[id(joint)]], e_full, alg, nx)
        if tau is None:
            continue
        a = joint.R_o @ joint.axis  # the joint axis in parent link axes
        part = tau[:, joint.motion.rows]  # rotation (revolute) or translation (prismatic)
        out[:, row] = np.einsum("i,lix->lx", a, part)
    return out


# ------------------------------------------------------------------------------- pencil


@dataclass
class Pencil:
    """The pencil of ``b`` poses over ``[w'; r]`` and the maps back to ``[w; q]``.

    ``M`` (b, nx + nv, nx + nv): the mass over the scaled elastic coordinates ``w'`` (stiffness
    ``I``) and the relative values ``r`` of every joint in user order: a spring's has the
    stiffness ``k`` ((b, ns), springs at user columns ``springs``), a free joint's none
    (``free``), a locked joint's is 0 (its row and column are not used). ``H`` (b, nv, nx)
    gives ``q = Ci r + H w``; ``scale[link]`` the per-element ``L⁻ᵀ`` (b, r, r) with
    ``w = L⁻ᵀ w'``.
    """

    M: np.ndarray
    k: np.ndarray
    springs: np.ndarray  # user columns of the springs (order of k)
    free: np.ndarray  # user columns of the free joints
    H: np.ndarray
    Ci: np.ndarray
    scale: dict


def _design_terms(model, plan, terms, y, b, alg, twists, sources, M, data):
    """Add the mass channels to ``M`` (in place); per-link ``K̂`` (b, r, r) and spring k (b, ns).

    Returns:
        ``(M, khat, k_design)``: ``khat[link]`` the element block at ``y`` (solver scaling of
        the nominal design), ``k_design[joint] `` the stiffness of a spring whose stiffness is a
        design parameter (b,).
    """
    khat: dict = {}
    k_design: dict = {}
    channels = model.plan.design.channels
    if not channels:
        return M, khat, k_design
    names = [d.name for d in model.design]
    nominal = model.y0

    def at(vec):
        return lambda name: vec[..., names.index(name)]

    erls_design.check_sections(model, at(y))
    f = [np.broadcast_to(np.asarray(v, dtype=float), (b,))
         for v in erls_design.channel_values(model, at(y))]
    f0 = erls_design.channel_values(model, at(nominal))
    blocks = link_blocks(model, data)
    nx, nv = plan.nx, plan.nv
    ep_cache: dict = {}
    for n, (ch, fc, fc0) in enumerate(zip(channels, f, f0)):
        if ch.name == "stiffness":
            k_design[ch.owner] = np.array(fc)
            continue
        delta = fc - float(fc0)
        core = plan.cores[ch.owner]
        if ch.kind == "K":
            if ch.owner not in khat:
                r = blocks[n].shape[0]
                khat[ch.owner] = np.broadcast_to(np.eye(r), (b, r, r)).copy()
            khat[ch.owner] += delta[:, None, None] * blocks[n]
            continue
        if not np.any(delta):
            continue
        if ch.owner not in ep_cache:
            tw = twists[ch.owner]
            ep_cache[ch.owner] = (None if tw is None else
                                  solve.explicit_twist(tw, sources, alg, core.start))
        solve.link_mass(core, blocks[n], terms.jac[ch.owner], ep_cache[ch.owner], alg, nx, nv,
                        nx + nv, out=M, factor=delta)
    return M, khat, k_design


def pencil(model, terms, y: np.ndarray, b: int, data=None) -> Pencil:
    """The solver-coordinate pencil of ``b`` poses (see :class:`Pencil`).

    Args:
        model: The flexible model (springs, locks or beam design; see :func:`covered`).
        terms: Pose terms of the ``b`` poses.
        y: Checked design values (ny,) or (b, ny).
        b: Number of poses.
        data: Workspace.
    """
    plan = solve.solve_plan(model, data)
    nx, nv = plan.nx, plan.nv
    alg = solve.lead_algebra(None, b)
    M = solve.mass(model, terms, y, b, data=data)
    twists, sources = solve.factored_twists(model, plan, terms, alg)
    M, khat, k_design = _design_terms(model, plan, terms, y, b, alg, twists, sources, M, data)
    # relative joint values: r = C q − G w (G = aᵀθ_parent), q = Ci (r + G w)
    by_col = {j.user_col: j for j in model.plan.joints if j.user_col >= 0}
    ordered = [by_col[i] for i in range(nv)]
    Ci = np.linalg.inv(model.coord_map)
    H = Ci @ parent_rows(model, plan, alg, twists, sources, ordered)  # q = Ci r + H w
    _relative_values(M, H, Ci, nx)
    for j, a in model.plan.conditions.armatures:  # reflected rotor inertia: a on r_j itself
        M[:, nx + j.user_col, nx + j.user_col] += a
    # scaled elastic coordinates of the links whose stiffness depends on the design
    scale = {}
    for link, K in khat.items():
        core = plan.cores[link]
        try:
            L = np.linalg.cholesky(K)
        except np.linalg.LinAlgError as exc:  # pragma: no cover - sections checked above
            raise EigenSolverError(f"the element stiffness of link '{link}' is not positive at "
                                   "this design") from exc
        S = np.swapaxes(np.linalg.inv(L), 1, 2)  # w' = Lᵀ w: M' = Sᵀ M S, S = blockdiag(L⁻ᵀ)
        r = S.shape[-1]
        sl = slice(core.start, core.stop)
        nel = (core.stop - core.start) // r
        rows = M[:, sl, :].reshape(b, nel, r, -1)
        M[:, sl, :] = np.einsum("bji,bnjk->bnik", S, rows).reshape(b, nel * r, -1)
        cols = M[:, :, sl].reshape(b, -1, nel, r)
        M[:, :, sl] = np.einsum("bmnj,bji->bmni", cols, S).reshape(b, -1, nel * r)
        scale[link] = S
    M += np.swapaxes(M, 1, 2)  # (NumPy buffers the overlapping transpose)
    M *= 0.5
    conds = model.plan.conditions.conditions
    springs = np.array([i for i, c in enumerate(conds) if c.kind == "spring"], dtype=int)
    free = np.array([i for i, c in enumerate(conds) if c.kind == "free"], dtype=int)
    k = np.empty((b, springs.size))
    stiff = {j.name: kk for j, kk in model.plan.conditions.spring_joints}
    for s, i in enumerate(springs):
        name = by_col[i].name
        k[:, s] = k_design.get(name, stiff[name])
    return Pencil(M, k, springs, free, H, Ci, scale)


# ---------------------------------------------------------------------------- eigensolve


def _relative_values(M: np.ndarray, H: np.ndarray, Ci: np.ndarray, nx: int, rows: int = 1024):
    """``M ← Tᵀ M T`` in place, ``T = [[I, 0], [H, Ci]]`` (``q = Ci r + H w``), by row blocks."""
    X = M[:, :, nx:].copy()
    for r0 in range(0, M.shape[1], rows):
        M[:, r0 : r0 + rows, :nx] += X[:, r0 : r0 + rows] @ H
    M[:, :, nx:] = X @ Ci
    Y = M[:, nx:, :].copy()
    HT = np.swapaxes(H, 1, 2)
    for r0 in range(0, nx, rows):
        M[:, r0 : min(r0 + rows, nx), :] += HT[:, r0 : r0 + rows] @ Y
    M[:, nx:, :] = Ci.T @ Y


def _condense(P: Pencil, nx: int):
    """``(B_e, Lf, Yf)``: the mass over ``[w'; r_springs]`` with the free joints condensed out."""
    M = P.M
    e = np.concatenate([np.arange(nx), nx + P.springs])
    Be = M[:, e[:, None], e] if P.springs.size else M[:, :nx, :nx].copy()
    if not P.free.size:
        return Be, None, None
    f = nx + P.free
    try:
        Lf = np.linalg.cholesky(M[:, f[:, None], f])
    except np.linalg.LinAlgError as exc:
        raise EigenSolverError(
            "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
            "add inertia to the links it drives"
        ) from exc
    Yf = np.linalg.solve(Lf, M[:, f[:, None], e])
    Be -= np.swapaxes(Yf, 1, 2) @ Yf
    return Be, Lf, Yf


def _soft_sets(Be: np.ndarray, k: np.ndarray, nx: int) -> list[np.ndarray]:
    """Per pose, the springs (indices into ``r_s``) to split off (see :data:`SOFT_SPLIT`).

    With ``μ_j = D_jj/k_j`` the inverse-form diagonal of spring ``j`` and ``t`` the trace of the
    ``w`` block (``≥ μ_1`` of the elastic coordinates), the split-off set is the largest one
    whose every spring has ``SOFT_SPLIT · μ_j`` above ``t`` plus the ``μ`` of the springs kept
    in the inverse form: starting from all springs, the stiffest offender is kept back until
    none is left.
    """
    out = []
    ns = k.shape[1]
    for i in range(Be.shape[0]):
        if not ns:
            out.append(np.zeros(0, dtype=int))
            continue
        mu = np.diagonal(Be[i])[nx:] / k[i]
        t = float(np.trace(Be[i, :nx, :nx]))
        soft = np.ones(ns, dtype=bool)
        while soft.any():
            bad = soft & (SOFT_SPLIT * mu <= t + float(mu[~soft].sum()))
            if not bad.any():
                break
            soft[np.flatnonzero(bad)[np.argmin(mu[bad])]] = False
        out.append(np.flatnonzero(soft))
    return out


def _eig_desc(B: np.ndarray, k: int, vectors: bool):
    """The ``k`` largest eigenvalues (descending) of a symmetric B, and their vectors."""
    n = B.shape[0]
    if eigensolve.use_lanczos(n, k):
        mu, V = eigensolve._lanczos(B, k, vectors)
        if vectors:
            return mu[::-1], V[:, ::-1]
        return mu, None
    if vectors:
        mu, V = np.linalg.eigh(B)
        return mu[::-1][:k], V[:, ::-1][:, :k]
    return np.linalg.eigvalsh(B)[::-1][:k], None


def _check(mu: np.ndarray, k: int):
    """Number of leading ``mu`` (of ``k``) above the rounding level."""
    if not np.all(np.isfinite(mu)):
        raise EigenSolverError("the eigensolver returned non-finite values: the mass or the "
                               "stiffness of the model is not finite")
    ok = mu[:k] > eigensolve.noise_level(mu)
    return k if ok.all() else int(np.argmin(ok))


def _solve_pose(Be: np.ndarray, k_s: np.ndarray, soft: np.ndarray, nx: int, n_modes: int,
                vectors: bool, pencil_fn):
    """Eigenvalues (ascending, ``n_modes``) and shapes over ``[w'; r_s]`` of one pose."""
    ns = k_s.size
    ne = nx + ns
    if not soft.size:
        sc = 1.0 / np.sqrt(k_s)
        d = np.concatenate([np.ones(nx), sc])
        B = Be  # scaled in place (Be is not used again)
        B[nx:, :] *= sc[:, None]
        B[:, nx:] *= sc[None, :]
        mu, V = _eig_desc(B, n_modes, vectors)
        r = _check(mu, n_modes)
        lam = 1.0 / mu
        Z = None if V is None else d[:, None] * (V[:, :r] / np.sqrt(mu[:r]))
        if r < n_modes:
            lam_d, Z_d = _from_nodal(pencil_fn, r, n_modes, vectors)
            lam[r:] = lam_d
            return lam, Z, Z_d
        return lam, Z, None
    hard = np.setdiff1d(np.arange(ns), soft)
    u_idx = np.concatenate([np.arange(nx), nx + hard])
    s_idx = nx + soft
    d = np.concatenate([np.ones(nx), 1.0 / np.sqrt(k_s[hard])])
    A = d[:, None] * Be[np.ix_(u_idx, u_idx)] * d[None, :]
    C = d[:, None] * Be[np.ix_(u_idx, s_idx)]
    D = Be[np.ix_(s_idx, s_idx)]
    Ks = k_s[soft]
    try:
        Ld = np.linalg.cholesky(D)
    except np.linalg.LinAlgError as exc:
        raise EigenSolverError("the ERLS mass matrix Mqq is singular: a joint moves no mass; "
                               "add inertia to the links it drives") from exc
    Z = np.linalg.solve(Ld, C.T)  # (s, nu)
    Af = A - Z.T @ Z
    W = np.linalg.solve(Ld.T, Z)  # D⁻¹ Cᵀ
    G = np.sqrt(Ks)[:, None] * W
    # P = (I + GᵀG)^(-1/2) = I + V (diag((1 + σ²)^(-1/2)) − 1) Vᵀ
    _, sig, Vt = np.linalg.svd(G, full_matrices=False)
    corr = 1.0 / np.sqrt(1.0 + sig**2) - 1.0

    def P(X):
        return X + Vt.T @ (corr[:, None] * (Vt @ X))

    Bt = P(P(Af).T).T
    Bt = 0.5 * (Bt + Bt.T)
    n_el = min(n_modes, u_idx.size)
    n_soft = min(soft.size, n_modes)
    mu, V = _eig_desc(Bt, n_el, True)
    r = _check(mu, n_el)
    # elastic modes: u from the linear pencil, then the first-order rest of the resolvent
    U = P(V[:, :r])  # uᵀ (I + F) u = 1
    Dinv = np.linalg.inv(D)
    mu_el = mu[:r].copy()
    Cu = C.T @ U  # (s, r)
    for i in range(r):
        x = mu_el[i]
        Xm = Dinv @ np.diag(Ks) @ Dinv @ np.diag(Ks) @ np.linalg.inv(D - x * np.diag(Ks))
        mu_el[i] = x - x * x * float(Cu[:, i] @ (0.5 * (Xm + Xm.T)) @ Cu[:, i])
    lam_el = 1.0 / mu_el
    # soft modes: K_s s = λ (D + Cᵀ (μ − A)⁻¹ C) s, fixed point in λ
    series = _resolvent_series(A, C)
    lam_s, S_s = _soft_modes(D, Ks, series)
    lam_s, S_s = lam_s[:n_soft], S_s[:, :n_soft]
    found = np.concatenate([lam_s, lam_el])
    order = np.argsort(found)
    m = min(n_modes, found.size)
    lam = np.empty(n_modes)
    lam[:m] = found[order][:m]
    Zs = None
    if vectors:
        cols = []
        for j in range(lam_s.size):  # u = (μ − A)⁻¹ C s = Σ λ^(m+1) Aᵐ C s
            s_vec = S_s[:, j]
            u = sum(lam_s[j] ** (m + 1) * (Q @ s_vec) for m, Q in enumerate(series[1]))
            cols.append(_assemble(u, s_vec, u_idx, s_idx, d, ne))
        for i in range(r):
            s_vec = -np.linalg.solve(D - mu_el[i] * np.diag(Ks), Cu[:, i])
            cols.append(_assemble(U[:, i], s_vec, u_idx, s_idx, d, ne))
        Zs = np.stack(cols, axis=1)
        Zs = Zs / np.sqrt(np.einsum("im,ij,jm->m", Zs, Be, Zs))[None, :]
        Zs = Zs[:, order][:, :m]
    if m < n_modes:  # high modes the conditioned form does not resolve
        lam_d, Z_d = _from_nodal(pencil_fn, m, n_modes, vectors)
        lam[m:] = lam_d
        return lam, Zs, Z_d
    return lam, Zs, None


def _assemble(u, s_vec, u_idx, s_idx, d, ne):
    z = np.zeros(ne)
    z[u_idx] = d * u
    z[s_idx] = s_vec
    return z


def _resolvent_series(A: np.ndarray, C: np.ndarray, terms: int = 8):
    """``(Cᵀ Aᵐ C, Aᵐ C)`` for m < ``terms``: the Neumann series of ``Cᵀ (μ − A)⁻¹ C``.

    Used with ``λ = 1/μ`` of a split-off spring, where ``λ ‖A‖ ≤ λ tr A < SOFT_SPLIT``: eight
    terms leave less than ``SOFT_SPLIT⁸`` of the sum.
    """
    out_q, out_a = [], []
    X = C
    for _ in range(terms):
        out_q.append(C.T @ X)
        out_a.append(X)
        X = A @ X
    return out_q, out_a


def _soft_modes(D: np.ndarray, Ks: np.ndarray, series):
    """Eigenvalues (ascending) and ``s`` vectors of the soft springs' small problem."""
    import scipy.linalg

    qs = series[0]
    ns = Ks.size
    Kd = np.diag(Ks)
    lam0 = scipy.linalg.eigh(Kd, D, eigvals_only=True)
    lam = np.empty(ns)
    S = np.empty((ns, ns))
    for j in range(ns):
        lj = lam0[j]
        for _ in range(60):
            Deff = D + sum(lj ** (m + 1) * Q for m, Q in enumerate(qs))
            w, V = scipy.linalg.eigh(Kd, 0.5 * (Deff + Deff.T))
            new = w[j]
            done = abs(new - lj) <= 4.0 * np.finfo(float).eps * abs(new)
            lj = new
            if done:
                break
        lam[j] = lj
        S[:, j] = V[:, j]
    return lam, S


def _from_nodal(pencil_fn, lo: int, k: int, vectors: bool):
    """Modes ``lo..k-1`` from the nodal pencil (high modes of extreme spectra)."""
    if pencil_fn is None:
        raise eigensolve._unresolved(lo + 1,
                                     "its eigenvalue is below the rounding level of the mass")
    lam, phi = eigensolve._direct(pencil_fn, lo, k, vectors)
    return lam, phi


def eigvals(model, P: Pencil, n_modes: int | None, pencil_fn=None) -> np.ndarray:
    """Non-rigid eigenvalues (b, k) ascending of the pencil ``P`` of ``b`` poses."""
    nx = model.nx
    ns = P.springs.size
    k = nx + ns if n_modes is None else min(int(n_modes), nx + ns)
    Be, _, _ = _condense(P, nx)
    soft = _soft_sets(Be, P.k, nx)
    out = np.empty((Be.shape[0], k))
    plain = [i for i, s in enumerate(soft) if not s.size]
    if plain and not eigensolve.use_lanczos(nx + ns, k):  # batched: one eigvalsh for these poses
        B = Be if len(plain) == Be.shape[0] else Be[plain]  # scaled in place
        sc = 1.0 / np.sqrt(P.k[plain])
        B[:, nx:, :] *= sc[:, :, None]
        B[:, :, nx:] *= sc[:, None, :]
        mu = np.linalg.eigvalsh(B)[:, ::-1]
        if not np.all(np.isfinite(mu)):
            _check(mu.ravel(), 0)
        lam = 1.0 / mu[:, :k]
        good = mu[:, :k] > eigensolve.noise_level(mu)[:, None]
        for row, i in enumerate(plain):
            if not good[row].all():
                r = int(np.argmin(good[row]))
                lam[row, r:] = _from_nodal(None if pencil_fn is None else
                                           (lambda i=i: pencil_fn(i)), r, k, False)[0]
        out[plain] = lam
        done = set(plain)
    else:
        done = set()
    for i in range(Be.shape[0]):
        if i in done:
            continue
        out[i] = _solve_pose(Be[i], P.k[i], soft[i], nx, k, False,
                             None if pencil_fn is None else (lambda i=i: pencil_fn(i)))[0]
    return out


def eigvecs(model, P: Pencil, n_modes: int | None, pencil_fn=None, data=None):
    """One pose: ``(lam, shapes_w, shapes_x)`` as :func:`pinflex.erls.eigensolve.eigvecs`.

    ``shapes_w`` over ``[w; q_all]`` (nx + nv, r) for the modes the conditioned form resolves,
    ``shapes_x`` over the modal coordinates ``[x; q_kept]`` from the nodal pencil for the rest.
    """
    nx = model.nx
    ns = P.springs.size
    k = nx + ns if n_modes is None else min(int(n_modes), nx + ns)
    Be, Lf, Yf = _condense(P, nx)
    soft = _soft_sets(Be, P.k, nx)[0]
    lam, Z, Zx = _solve_pose(Be[0], P.k[0], soft, nx, k, True, pencil_fn)
    # back to [w; q_all]: scaled w, spring and free relative values, locked r = 0
    nv = P.H.shape[1]
    ne = nx + ns
    r_all = np.zeros((nv, Z.shape[1]))
    r_all[P.springs] = Z[nx:ne]
    if Lf is not None:
        r_all[P.free] = -np.linalg.solve(np.swapaxes(Lf[0], 0, 1), Yf[0] @ Z)
    w = Z[:nx].copy()
    plan_cores = solve.solve_plan(model, data).cores
    for link, S in P.scale.items():
        core = plan_cores[link]
        r = S.shape[-1]
        sl = slice(core.start, core.stop)
        w[sl] = np.einsum("ij,njm->nim", S[0], w[sl].reshape(-1, r, w.shape[1])).reshape(
            -1, w.shape[1])
    q = P.Ci @ r_all + P.H[0] @ w
    shapes_w = np.concatenate([w, q], axis=0)
    return lam, shapes_w, Zx
