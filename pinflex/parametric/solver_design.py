"""Section, material and joint-spring design terms in the solver coordinates.

The solver coordinates of :mod:`pinflex.erls.solve` scale every element of a flexible link by
the Cholesky factor ``Dt`` of its clamped-tip stiffness at the nominal design: ``w = Dt z``.
``Dt`` stays frozen at the nominal design, so a design that changes the section or the
material changes only constant per-link blocks:

* **Stiffness.** The tip block is linear in the rigidities, ``k_tip(y) = Σ_c f_c(y) k_c``
  (``c = EA, GJ, EIy, EIz``), so in ``w`` the stiffness of a link is ``I_N ⊗ K̂(y)`` with
  ``K̂(y) = I + Σ_c (f_c(y) − f_c(nom)) Dt⁻ᵀ k_c Dt⁻¹``: still block diagonal, and it does
  not depend on the pose. Its jet has coefficients only on the pure-design multi-indices.
* **Mass.** The beam mass is linear in ``ρA`` and ``ρI_p``; the constant blocks ``H`` of
  :class:`pinflex.erls.solve._LinkCore` are then ``Σ_c f_c H_c`` with ``H_c = Aᵀ M_c A``
  (``A`` the link's constant kinematic map), and the link's part of the mass assembly is
  linear in them: ``M(q, y) = M(q, nom) + Σ_c (f_c(y) − f_c(nom)) M̂_c(q)`` where ``M̂_c``
  is the link's part assembled with ``H_c``.
* **Joint springs.** ``K += k gᵀ g`` with ``g = [−aᵀθ_parent(w), C_j]`` the physical relative
  motion (:mod:`pinflex.erls.joints`), ``θ_parent`` the elastic rotation at the joint's
  attachment in solver coordinates; a stiffness that is a design parameter is one more
  channel with the unit matrix ``gᵀ g``.

Degrees in the design variables (exact jets whatever the degree: the channel functions run in
jet arithmetic, :mod:`pinflex.parametric.design`): point masses 1 (``M``); joint stiffness 1
(``K``); ``E`` 1 in ``EA, EI``; ``G`` 1 in ``GJ``; density 1 in ``ρA, ρI_p``; linear density 1
in ``ρA``; explicit ``A, I, J`` 1; circle diameters: ``A, ρA`` degree 2, ``I, J, ρI_p`` degree 4
(hollow circle: jointly in outer diameter and wall); rectangle ``A`` 2 (bilinear), ``I`` 4;
products of a material and a section variable add their degrees (``E·I``: 5). Not polynomial:
the rectangle's torsion constant (a rational function of the side ratio) and, with a linear
density, ``ρI_p = μ (I_y + I_z) / A``. The pose enters only the mass terms, so the stiffness jet
is zero on every coefficient that involves a joint.
"""

from __future__ import annotations

import numpy as np

from pinflex.erls import design as erls_design
from pinflex.erls import eigensolve, solve
from pinflex.erls.solve_conditions import link_blocks, parent_rows
from pinflex.exceptions import ConfigurationError
from pinflex.jets import JetSpace
from pinflex.parametric.algebra import SparseJetAlgebra
from pinflex.parametric.design import _separable_pairs, channel_jets

__all__ = ["add_terms", "covered", "expansion_eigenpairs", "link_blocks", "spring_rows"]


def covered(model) -> bool:
    """Whether the solver-coordinate route takes this model's expansion.

    Every design variable (point masses, sections, materials, joint stiffness) and every joint
    condition (free, spring, locked) is covered; a model without elastic coordinates is not.
    """
    return model.nx > 0


def spring_rows(model, terms, alg, twists, sources, joint) -> np.ndarray:
    """``g`` (lead, 1, nd): the joint's physical relative motion over ``[w; q]``."""
    plan = solve.solve_plan(model)
    nx, nd = plan.nx, plan.nx + plan.nv
    g = np.zeros((alg.size, 1, nd))
    g[:, 0, :nx] = -parent_rows(model, plan, alg, twists, sources, [joint])[:, 0]
    g[alg.const_at, 0, nx:] += model.coord_map[joint.user_col]
    return g


def _spring_unit(model, terms, alg, twists, sources, joint) -> np.ndarray:
    g = spring_rows(model, terms, alg, twists, sources, joint)
    return alg.mm(np.swapaxes(g, -1, -2), g)


def add_terms(model, space: JetSpace, terms, alg, nj: int, design_idx, y0, M: np.ndarray,
              K0: np.ndarray):
    """Add the section, material and spring terms to the solver-coordinate jets.

    Args:
        model: The flexible model.
        space: The (reduced) jet space: ``nj`` expanded joints, then the design variables.
        terms: Pose terms in the joints' jet space (or at ``q0`` when ``nj`` is 0).
        alg: Their algebra (a sparse jet algebra, or None for one pose).
        nj: Number of expanded joints in ``space``.
        design_idx: Expanded design variables (indices into ``model.design``).
        y0: Expansion design (ny,).
        M: Mass jet (space.ncoef, nd, nd) without these terms (modified in place).
        K0: The plain stiffness ``blockdiag(I, 0)`` (nd, nd).

    Returns:
        ``(M, K)``: ``K`` is ``K0`` itself when nothing adds stiffness, else its jet.
    """
    plan = solve.solve_plan(model)
    nx, nv = plan.nx, plan.nv
    nd = nx + nv
    channels = model.plan.design.channels
    locks = bool(model.plan.conditions.locked_joints)
    armatures = model.plan.conditions.armatures
    if not channels and not model.plan.conditions.spring_joints and not locks and not armatures:
        return M, K0
    salg = solve.lead_algebra(alg, 1)
    twists, sources = solve.factored_twists(model, plan, terms, salg)
    nq = salg.size  # coefficients of the joints' space (1 without joints)
    nd_vars = len(design_idx)
    if nj:
        qspace = JetSpace(nj, space.order)
        alphas = [tuple(a) for a in qspace.multi_indices.tolist()]
    else:
        alphas = [()]
    zeros = (0,) * nd_vars
    emb = np.array([space.index[a + zeros] for a in alphas])
    K = np.zeros((space.ncoef, nd, nd))
    K[0] = K0
    stiff = bool(model.plan.conditions.spring_joints)  # whether K differs from K0
    # springs at their nominal stiffness: K += k gᵀ g (pose jets at zero design degree); a
    # design stiffness adds (k(y) − k(nom)) gᵀ g below, as a channel
    units = {j.name: _spring_unit(model, terms, salg, twists, sources, j)
             for j, _ in model.plan.conditions.spring_joints}
    for j, k in model.plan.conditions.spring_joints:
        K[emb] += k * units[j.name]
    # reflected rotor inertias: M += a gᵀg on the same relative motion (pose jets)
    for j, a in armatures:
        unit = units[j.name] if j.name in units else _spring_unit(model, terms, salg, twists,
                                                                  sources, j)
        M[emb] += a * unit
    if channels:
        names = [d.name for d in model.design]
        y0 = np.asarray(y0, dtype=float)
        f, f0 = channel_jets(model, space.order, y0, design_idx)
        if nd_vars:
            ia, ib, tg = _separable_pairs(space.order, nj, nd_vars)
        else:
            ia, ib, tg = np.arange(nq), np.zeros(nq, dtype=int), emb
        # the constant coefficient from the float formulas: exactly zero at the nominal design
        # (the jet arithmetic may round the same value differently)
        at_y0 = erls_design.channel_values(model, lambda n: float(y0[names.index(n)]))
        for fc, v, v0 in zip(f, at_y0, f0):
            fc[0] = float(v) - float(v0)
        blocks = link_blocks(model)
        ep_cache: dict = {}
        for n, (ch, fc) in enumerate(zip(channels, f)):
            nz = fc[ib] != 0.0  # a channel depends on few design variables: few pairs
            if not np.any(nz):
                continue
            pa, pb, pt = ia[nz], ib[nz], tg[nz]
            if ch.name == "stiffness":
                K[pt] += units[ch.owner][pa] * fc[pb][:, None, None]
                stiff = True
                continue
            core = plan.cores[ch.owner]
            if ch.kind == "K":
                n_el = (core.stop - core.start) // blocks[n].shape[0]
                blk = np.kron(np.eye(n_el), blocks[n])
                pure = pa == 0  # the stiffness does not depend on the pose
                sl = slice(core.start, core.stop)
                K[pt[pure], sl, sl] += fc[pb[pure]][:, None, None] * blk
                stiff = True
                continue
            if ch.owner not in ep_cache:
                tw = twists[ch.owner]
                ep_cache[ch.owner] = (None if tw is None else
                                      solve.explicit_twist(tw, sources, salg, core.start))
            unit = solve.link_mass(core, blocks[n], terms.jac[ch.owner], ep_cache[ch.owner],
                                   salg, nx, nv, nd)
            M[pt] += unit[pa] * fc[pb][:, None, None]
    if locks:
        return _eliminate_locks(model, space, terms, salg, twists, sources, emb, M,
                                K if stiff else None)
    return M, (K if stiff else K0)


def _eliminate_locks(model, space: JetSpace, terms, salg, twists, sources, emb, M, K):
    """``Tᵀ M T`` and ``Tᵀ K T`` over the modal coordinates ``[w; q_kept]`` (locked joints).

    ``T`` maps ``[w; q_kept]`` to ``[w; q_all]`` (:func:`pinflex.erls.joints.transform`): the
    identity on ``w`` and the kept joints, and on a locked joint's row ``q_L = C_LL⁻¹ (G_w w −
    C_LK q_kept)`` with ``G_w`` the parent attachment's rotation about the joint axis in solver
    coordinates (a pose jet). Only those few rows differ from a selection, so each side of the
    congruence is a column scatter plus one thin jet product. ``K = None`` is the constant
    ``blockdiag(I, 0)``, which ``T`` keeps (its ``w`` rows are ``[I, 0]``).
    """
    nx = model.nx
    nd = nx + model.nv
    ndof = model.ndof
    T0 = model.plan.conditions.lock_T0
    rows = np.asarray(model.plan.conditions.lock_rows, dtype=int)
    others = np.setdiff1d(np.arange(nd), rows)
    cols = np.argmax(T0[others], axis=1)  # each kept coordinate's modal column
    G = np.stack([-spring_rows(model, terms, salg, twists, sources, j)[:, 0, :nx]
                  for j in model.plan.conditions.locked_joints], axis=1)  # (lead, nL, nx)
    TL = np.zeros((space.ncoef, rows.size, ndof))
    TL[0] = T0[rows]
    TL[emb, :, :nx] += np.einsum("lm,cmx->clx", model.plan.conditions.lock_inv, G)
    alg = SparseJetAlgebra(space)

    def right(X):  # X @ T for a jet X (ncoef, r, nd)
        out = np.zeros(X.shape[:2] + (ndof,))
        out[:, :, cols] = X[:, :, others]
        return out + alg.mm(np.ascontiguousarray(X[:, :, rows]), TL)

    def congruent(X):
        XT = right(X)
        return right(np.swapaxes(XT, 1, 2)).swapaxes(1, 2).copy()

    Mm = congruent(M)
    Mm = 0.5 * (Mm + np.swapaxes(Mm, 1, 2))
    if K is None:
        K0 = np.zeros((ndof, ndof))
        K0[:nx, :nx] = np.eye(nx)
        return Mm, K0
    Km = congruent(K)
    return Mm, 0.5 * (Km + np.swapaxes(Km, 1, 2))


def expansion_eigenpairs(model, K0: np.ndarray, M0: np.ndarray, modes=()):
    """All eigenpairs of the solver-coordinate pencil ``(K0, M0)`` at the expansion point.

    ``K0`` is positive definite on the elastic coordinates (``w`` and the spring joints' ``q``)
    and zero on the free joints. A Cholesky factor of the mass would lose the low modes' digits
    (in ``w`` the mass spans the whole spectrum), so the pencil is solved in the inverse form of
    :func:`pinflex.parametric.conditioned.expansion_eigenpairs`: with ``K_ee = L Lᵀ`` the
    elastic coordinates ``u = Lᵀ [w; q_s]`` make the stiffness the identity, the free joints are
    condensed out of the mass, and the symmetric ``B = M_uu − M_uf M_ff⁻¹ M_fu`` gives
    ``μ = 1/λ``. A constant change of coordinates of one pencil: eigenvalues unchanged.

    Modes the inverse form does not resolve (a spring far softer than the beams) are taken
    from a direct solve of the same pencil (:func:`_high_modes_direct`); those of them in
    ``modes`` (indices into the returned ``w``) are polished by inverse iteration, so their
    residual is at the rounding level the eigenpair jets require.

    Returns:
        ``(w, V)``: eigenvalues ascending (free joints' zeros first) and mass-normalised
        shapes over ``[w; q]`` (columns in the order of ``w``).
    """
    nd = K0.shape[0]
    nx = model.nx
    Z = None
    Winv = model.plan.conditions.modal_Winv
    if Winv is not None:
        # absolute user angles: split free and sprung joints in relative values r = W q_kept
        # (:func:`pinflex.erls.joints.setup`), where a free joint carries no stiffness
        Z = np.eye(nd)
        Z[nx:, nx:] = Winv
        K0, M0 = Z.T @ K0 @ Z, Z.T @ M0 @ Z
    e = np.asarray(model.plan.conditions.elastic_cols, dtype=int)
    fr = np.asarray(model.plan.conditions.rigid_cols, dtype=int)
    L = np.linalg.cholesky(K0[np.ix_(e, e)])
    Linv = np.linalg.inv(L)  # u = Lᵀ z: z = L⁻ᵀ u
    Mue = Linv @ M0[np.ix_(e, e)] @ Linv.T
    Muf = Linv @ M0[np.ix_(e, fr)]
    Mff = M0[np.ix_(fr, fr)]
    if fr.size:
        Lf = np.linalg.cholesky(Mff)
        Y = np.linalg.solve(Lf, Muf.T)
        B = Mue - Y.T @ Y
    else:
        B = Mue
    mu, U = np.linalg.eigh(0.5 * (B + B.T))
    mu, U = mu[::-1], U[:, ::-1]
    bad = ~(mu > eigensolve.noise_level(mu))
    phi_u = U / np.sqrt(np.where(bad, 1.0, mu))
    V = np.zeros((nd, nd))
    nf = fr.size
    V[e, nf:] = Linv.T @ phi_u
    if nf:
        V[fr, nf:] = -np.linalg.solve(Mff, Muf.T @ phi_u)
        V[fr, :nf] = np.linalg.inv(Lf.T)
    lam = np.concatenate([np.zeros(nf), 1.0 / np.where(bad, 1.0, mu)])
    if np.any(bad):
        lam, V = _high_modes_direct(K0, M0, lam, V, mu, nf, modes)
    if Z is not None:
        V = Z @ V
    return lam, V


def _high_modes_direct(K0, M0, lam, V, mu, nf, polish=()):
    """Modes the inverse form leaves unresolved (or resolves worse), from a direct solve.

    Mode ``j`` of the inverse form carries a relative rounding error ``~ ε λ_j/λ_1``, of the
    direct (Cholesky of the mass) solve of the same pencil ``~ ε λ_max/λ_j``: a spring far
    softer than the beams puts a huge ``μ`` first and leaves the highest modes of the inverse
    form below its rounding level (they were refused, and the expansion fell back to the nodal
    pencil, which lost the spring mode: 0.86 % at 1e-4 N m/rad). From the first mode where the
    direct solve is the better one, the modes are taken from it: same pencil and coordinates,
    same mass normalisation. Its pairs have residuals ``~ ε λ_max``; those in ``polish`` get
    two steps of inverse iteration with the Rayleigh quotient.
    """
    import scipy.linalg

    lam_d, V_d = scipy.linalg.eigh(0.5 * (K0 + K0.T), 0.5 * (M0 + M0.T), check_finite=False)
    lam_d, V_d = lam_d[nf:], V_d[:, nf:]  # the free joints' zeros first
    ne = lam_d.size
    tiny = np.finfo(float).tiny
    inv_err = np.where(mu > eigensolve.noise_level(mu), lam[nf:] / max(lam[nf], tiny), np.inf)
    with np.errstate(divide="ignore", over="ignore"):
        dir_err = np.abs(lam_d[-1]) / np.abs(lam_d)
    better = np.flatnonzero(dir_err < inv_err)
    j0 = int(better[0]) if better.size else ne
    if np.any(~(lam_d[j0:] > 64.0 * np.finfo(float).eps * abs(lam_d[-1]))):
        raise ConfigurationError(
            f"modes {nf + j0 + 1}.. at the expansion point are resolved neither in solver "
            "coordinates nor by a direct solve; use fewer elements"
        )
    lam = lam.copy()
    V = V.copy()
    lam[nf + j0 :] = lam_d[j0:]
    V[:, nf + j0 :] = V_d[:, j0:]
    for j in polish:
        if j < nf + j0:
            continue
        x = V[:, j]
        for _ in range(2):  # inverse iteration, shift at the current eigenvalue
            lu = scipy.linalg.lu_factor(K0 - lam[j] * M0, check_finite=False)  # near-singular
            y = scipy.linalg.lu_solve(lu, M0 @ x, check_finite=False)
            x = y / np.sqrt(y @ M0 @ y)
            lam[j] = float(x @ K0 @ x)
        V[:, j] = x
    return lam, V
