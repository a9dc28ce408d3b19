"""Well-conditioned modal solve of an ERLS model: relative elastic coordinates, inverse form.

Why: in the nodal coordinates ``x`` (absolute small motions of every node) the strain energy
of a smooth mode is a small difference of large nodal terms, and the stiffness condition
number grows like N⁴ with N elements per link. A generalized eigensolver working on
``(Kₓₓ, Mred)`` then loses digits on the low modes as the mesh is refined (a two-link arm with
1024 elements on one link: relative errors of 1e-5 on mode 1).

What this module does instead (same eigenvalues in exact arithmetic):

* **Relative coordinates.** On every flexible link, node ``k`` moves as the rigid transport of
  node ``k − 1`` plus its own relative motion ``z_k`` (beam axes, the node's kept dofs); node 0
  is the joint attachment on the parent (the ERLS rule). A Hermite beam element does not strain
  under a rigid motion, so element ``k``'s strain energy is ``z_kᵀ K_tip z_k`` with ``K_tip``
  the element's tip block (clamped root): the stiffness is exactly block diagonal and constant.
* **Scaled by the element blocks.** With ``K_tip = D Dᵀ`` (Cholesky) the solver coordinates
  are ``w_k = Dᵀ z_k``: the stiffness is the identity, and the mass ``B(q, y)`` is assembled
  directly in ``w`` from constant per-link blocks (the pose enters through the root twists of
  the links and the frame Jacobians only), so the assembly scatters small blocks instead of
  multiplying dense selection matrices.
* **Inverse form.** The non-rigid eigenvalues are ``λ = 1/μ`` with ``μ`` the eigenvalues of the
  symmetric ``Bred`` (the rigid joint coordinates condensed out). A backward-stable symmetric
  eigensolver gives every ``μ`` to an absolute error of about ``n ε μ_max``: the low modes (the
  large ``μ``) keep full relative accuracy at any mesh size, mode ``k`` has a relative rounding
  error of about ``n ε λ_k / λ_1``. That is below the discretization error of mode ``k`` as
  long as ``ε N⁴ ≪ 1`` (the highest modes of a mesh are the least accurate in both respects);
  :func:`rounding_bound` returns the estimate, and modes whose eigenvalue is not resolved
  (``μ`` at the noise level) are refused.

Modules: this one holds the constant per-link blocks (:func:`solve_plan`) and the mass
assembly over poses or Taylor coefficients (:func:`mass`); :mod:`pinflex.erls.one_pose` the
row layout of one pose; :mod:`pinflex.erls.eigensolve` the inverse-form eigensolve.

Cost: one symmetric eigensolve of ``Bred`` per pose (batched over poses with NumPy), with no
Cholesky of the mass, no ``sygst`` and no explicit inverse: less work than a generalized
eigensolver of the same size.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex import beam
from pinflex.erls.terms import BatchAlgebra, carrier_rows, joint_step, propagate_root_twists
from pinflex.exceptions import EigenSolverError
from pinflex.linalg import rotate_twist, translate_twist

_EPS = np.finfo(float).eps


@dataclass(frozen=True)
class _LinkCore:
    """Constant blocks of one flexible link in solver coordinates."""

    link: str
    start: int  # first solver column of the link (columns start:stop)
    stop: int
    C: np.ndarray  # (6(N+1), rN) node twists (beam axes) from the link's own w
    R: np.ndarray  # (6(N+1), 6) node twists from the root twist (link axes)
    H_oo: np.ndarray  # blocks of Aᵀ M_link A, A = [C, R, J] on the kept rows
    H_oe: np.ndarray
    H_ov: np.ndarray
    H_ee: np.ndarray
    H_ev: np.ndarray
    H_vv: np.ndarray
    x_rows: np.ndarray  # rows of C/R giving the link's nodal coordinates x (nodes 1..N)

    @property
    def blocks(self) -> tuple:
        """``(H_oo, H_oe, H_ov, H_ee, H_ev, H_vv)``, the blocks :func:`link_mass` takes."""
        return self.H_oo, self.H_oe, self.H_ov, self.H_ee, self.H_ev, self.H_vv


@dataclass(frozen=True)
class _Attach:
    """Elastic twist (link axes) at a point = const @ w[start:stop] + lin @ root twist."""

    start: int
    stop: int
    const: np.ndarray | None  # (6, stop - start)
    lin: np.ndarray | None  # (6, 6)


@dataclass(frozen=True)
class SolvePlan:
    """Everything constant of the conditioned solve of one model (built once, cached)."""

    cores: dict
    joint_attach: tuple  # per model.plan.joints entry
    pm_attach: tuple  # per model.plan.point_masses entry
    nx: int
    nv: int
    body_attach: tuple = ()  # per model.plan.bodies entry


def supported(model) -> bool:
    """Whether this solve covers the model.

    It does for free joints and point-mass design variables; other joint conditions and
    design variables that change the beams (sections, materials) go through the nodal pencil.
    """
    plain = model.plan.conditions.plain
    masses = all(d.name in model.point_mass_values for d in model.design)
    return plain and masses and model.nx > 0


def _transport(d: float) -> np.ndarray:
    """Rigid transport of a node twist by ``d`` along the beam axis (beam axes)."""
    return translate_twist(np.array([d, 0.0, 0.0]))


def solve_plan(model, data=None) -> SolvePlan:
    """The constant data of the conditioned solve (built once per workspace ``data``)."""
    return model.workspace(data).cached("solve_plan", lambda: _build_solve_plan(model))


def _build_solve_plan(model) -> SolvePlan:
    cores = {}
    nx = model.nx
    for link, p in model.plan.beams.items():
        spec = p.spec
        n = spec.elements
        le = spec.length_m / n
        rows = np.asarray(p.rows)
        r = rows.size // (n + 1)
        nd = rows[:r]
        sec = spec.section
        ke = beam.element_stiffness(le, spec.E * sec.A, spec.G * sec.J, spec.E * sec.Iy,
                                    spec.E * sec.Iz)
        kt = ke[6:, 6:][np.ix_(nd, nd)]
        try:
            Dt = np.linalg.cholesky(kt).T  # kt = Dtᵀ Dt, w = Dt z
        except np.linalg.LinAlgError as exc:  # pragma: no cover - guarded by the parser
            raise EigenSolverError(f"the element stiffness of link '{link}' is not positive"
                                   ) from exc
        zinv = np.linalg.inv(Dt)  # z = zinv @ w (r × r, well conditioned per element)
        # node k from w_j (j <= k): P((k - j) le) E zinv, P(d) = I + d O (rigid transport)
        P0 = np.eye(6)[:, nd] @ zinv
        Ofs = (_transport(1.0) - np.eye(6))[:, nd] @ zinv
        kk = np.arange(n + 1)[:, None]
        jj = np.arange(1, n + 1)[None, :]
        below = (jj <= kk).astype(float)
        C = (below[:, None, :, None] * P0[None, :, None, :]
             + (below * (kk - jj) * le)[:, None, :, None] * Ofs[None, :, None, :])
        C = C.reshape(6 * (n + 1), r * n)
        rb = rotate_twist(spec.rotation.T)
        R = np.concatenate([_transport(k * le) @ rb for k in range(n + 1)])
        A = np.concatenate([C, R, p.jac], axis=1)[rows]
        X = p.mass[np.ix_(rows, rows)] @ A  # block tridiagonal: small, dense is fine
        H = np.empty((A.shape[1], A.shape[1]))
        H[r * n :] = A[:, r * n :].T @ X
        H[: r * n] = _cumulative_transpose(X, P0[nd], Ofs[nd], le, n, r)
        H = 0.5 * (H + H.T)
        o = r * n
        start = int(p.x_cols[0])
        assert np.array_equal(p.x_cols, np.arange(start, start + o))
        cores[link] = _LinkCore(
            link, start, start + o, C, R, H[:o, :o], H[:o, o : o + 6], H[:o, o + 6 :],
            H[o : o + 6, o : o + 6], H[o : o + 6, o + 6 :], H[o + 6 :, o + 6 :], rows[r:],
        )
    joint_attach = tuple(_attach(model, cores, j.parent, j.xyz) for j in model.plan.joints)
    pm_attach = tuple(_attach(model, cores, p.link, p.xyz) for p in model.plan.point_masses)
    body_attach = tuple(_attach(model, cores, b.link, b.xyz) for b in model.plan.bodies)
    return SolvePlan(cores, joint_attach, pm_attach, nx, model.nv, body_attach)


def _cumulative_transpose(X, P0, Ofs, le, n, r):
    """``C[rows]ᵀ X`` by reverse cumulative sums (C: node k from w_j, j ≤ k), O(n · cols)."""
    Xn = X.reshape(n + 1, r, -1)[1:]  # node 0 rows do not see the link's own w
    k = np.arange(1, n + 1, dtype=float)[:, None, None]
    S0 = np.cumsum(Xn[::-1], axis=0)[::-1]
    S1 = np.cumsum((k * Xn)[::-1], axis=0)[::-1]
    out = P0.T @ S0 + le * (Ofs.T @ (S1 - k * S0))
    return out.reshape(r * n, -1)


def _attach(model, cores, link: str, point: np.ndarray) -> _Attach:
    """Elastic twist at a point given in the frame of ``link`` (link axes)."""
    core = cores.get(link)
    if core is None:
        return _Attach(0, 0, None, translate_twist(point))
    spec = model.plan.beams[link].spec
    L, n = spec.length_m, spec.elements
    xdir = spec.tip / L
    s = float(np.clip(point @ xdir, 0.0, L))
    le = L / n
    e = min(int(s / le), n - 1)
    shape = beam.shape_matrix(le, np.array([s / le - e]))[0]
    to_link = translate_twist(point - s * xdir) @ rotate_twist(spec.rotation)
    rows = slice(6 * e, 6 * e + 12)
    const = to_link @ shape @ core.C[rows]
    return _Attach(core.start, core.stop, const, to_link @ shape @ core.R[rows])


def lead_algebra(alg, b: int):
    """``alg``, or the :class:`~pinflex.erls.terms.BatchAlgebra` of ``b`` poses when None.

    A jet algebra (:mod:`pinflex.parametric.algebra`) has the Taylor coefficients on the
    leading axis: constants enter the constant coefficient only (``const_at = 0``), and the
    product of two pose-dependent factors is the truncated Cauchy product (``alg.mm``); a
    constant times a jet is a plain product.
    """
    return BatchAlgebra(b) if alg is None else alg


def attach_twist(att: _Attach, root, alg, nx: int):
    """Elastic twist (lead, 6, nx) at an attachment, or None when it is identically zero."""
    if att.const is None and root is None:
        return None
    out = np.zeros((alg.size, 6, nx)) if root is None else att.lin @ root
    if att.const is not None:
        out[alg.const_at, :, att.start : att.stop] += att.const
    return out


def root_twists(model, plan: SolvePlan, terms, b: int, alg=None) -> dict:
    """Elastic twist of every link root (link axes) in solver coordinates, (b, 6, nx)."""
    alg = lead_algebra(alg, b)
    return propagate_root_twists(
        model.plan, terms, alg,
        lambda k, j, e: attach_twist(plan.joint_attach[k], e, alg, plan.nx))


def _lift(alg, C: np.ndarray) -> np.ndarray:
    """A constant matrix on the leading axis of ``alg``."""
    if alg.const_at == 0:
        out = np.zeros((alg.size,) + C.shape)
        out[0] = C
        return out
    return np.broadcast_to(C, (alg.size,) + C.shape)


def factored_twists(model, plan: SolvePlan, terms, alg):
    """Root twists as ``(T, source)``: twist = T (lead, 6, 6) @ sources[source] (lead, 6, nx).

    A source is the elastic twist at a joint's attachment on a flexible link; every link
    behind it through rigid links shares it, so the pose-dependent products of those links are
    6 × 6 and the wide ``(6, nx)`` factor enters once per source (composite-inertia idea).

    Returns:
        ``(twists, sources)``: ``twists[link]`` is None (no elastic motion) or ``(T, k)``;
        ``sources[k] = (tau, stop)`` with ``tau`` (lead, 6, stop) on the columns it can touch.
    """
    mm = alg.mm
    twists: dict[str, tuple | None] = {model.plan.root: None}
    sources: list[tuple[np.ndarray, int]] = []
    for j, att in zip(model.plan.joints, plan.joint_attach):
        par = twists[j.parent]
        core = plan.cores.get(j.parent)
        if core is not None:
            e_par = None if par is None else explicit_twist(par, sources, alg, core.start)
            if e_par is not None:
                e_full = np.zeros((alg.size, 6, plan.nx))
                e_full[:, :, : e_par.shape[-1]] = e_par
                e_par = e_full
            tau = attach_twist(att, e_par, alg, plan.nx)
            if tau is None:
                twists[j.child] = None
                continue
            sources.append((np.ascontiguousarray(tau[:, :, : core.stop]), core.stop))
            T_in = None
            src = len(sources) - 1
        else:
            if par is None:
                twists[j.child] = None
                continue
            T_par, src = par
            T_in = att.lin @ T_par
        step = joint_step(j, terms.rot.get(j.name), terms.slide.get(j.name), alg)
        if step.ndim == 2:
            step = _lift(alg, step)
        twists[j.child] = (step if T_in is None else mm(step, T_in), src)
    return twists, sources


def explicit_twist(tw, sources, alg, stop: int | None = None):
    """``T @ tau`` of a factored twist on its first ``stop`` columns (None: all it has)."""
    T, k = tw
    tau, width = sources[k]
    if stop is not None and stop < width:
        tau = tau[:, :, :stop]
    return alg.mm(T, tau)


def link_mass(core, H, J, ep, alg, nx: int, nv: int, nd: int, out=None,
              factor=None) -> np.ndarray:
    """One beam's part of the solver-coordinate mass, from its constant blocks ``H``.

    The one assembly of a beam's kinetic energy in solver coordinates: :func:`mass` (the
    nominal blocks of :func:`solve_plan`), the design channels of the conditioned solve
    (:mod:`pinflex.erls.solve_conditions`) and their Taylor jets
    (:mod:`pinflex.parametric.solver_design`) all add it, on any algebra.

    Args:
        core: The link's constant blocks (its columns ``start:stop``).
        H: ``(H_oo, H_oe, H_ov, H_ee, H_ev, H_vv)``: the blocks of ``Aᵀ M_link A`` over the
            link's own coordinates, its root twist and its frame twist.
        J: Frame Jacobian of the link (lead, 6, nv).
        ep: Elastic root twist on the upstream columns (lead, 6, w), or None.
        alg: The algebra of the leading axis.
        nx: Elastic coordinates; nv: joint coordinates; nd = nx + nv.
        out: Add to this (lead, nd, nd) array instead of a new one.
        factor: Scale (lead,) of the blocks (a design channel's value), or None for 1.

    Returns:
        ``out`` (or a new array) with the link's part added.
    """
    H_oo, H_oe, H_ov, H_ee, H_ev, H_vv = H
    mm, c0 = alg.mm, alg.const_at
    if out is None:
        out = np.zeros((alg.size, nd, nd))
    f = None if factor is None else np.asarray(factor)[:, None, None]

    def scaled(X):
        return X if f is None else f * X

    a, z = core.start, core.stop
    out[c0, a:z, a:z] += scaled(H_oo)
    if nv:
        X = scaled(H_ov @ J)
        out[:, a:z, nx:] += X
        out[:, nx:, a:z] += np.swapaxes(X, -1, -2)
        out[:, nx:, nx:] += scaled(mm(np.swapaxes(J, -1, -2), H_vv @ J))
    if ep is not None:
        w = ep.shape[-1]
        X = scaled(H_oe @ ep)
        out[:, a:z, :w] += X
        out[:, :w, a:z] += np.swapaxes(X, -1, -2)
        epT = np.swapaxes(ep, -1, -2)
        out[:, :w, :w] += scaled(mm(epT, H_ee @ ep))
        if nv:
            X = scaled(mm(epT, H_ev @ J))
            out[:, :w, nx:] += X
            out[:, nx:, :w] += np.swapaxes(X, -1, -2)
    return out


def mass(model, terms, y: np.ndarray, b: int, *, alg=None, split=False, data=None):
    """Mass matrix (b, ndof, ndof) in solver coordinates ``[w; q]`` (stiffness: ``I`` on w).

    Args:
        model: The flexible model.
        terms: Pose terms of ``b`` poses (or their jets, with ``alg``).
        y: Checked design values (ny,) or (b, ny) (unused with ``split``).
        b: Number of poses.
        alg: A jet algebra to assemble Taylor coefficients instead of poses.
        split: Return ``(M0, Mdesign)``: the mass without design point masses and the mass
            per unit design value, (ny, lead, nd, nd).
        data: Workspace (default: this thread's).
    """
    plan = solve_plan(model, data)
    alg = lead_algebra(alg, b)
    mm, lead = alg.mm, alg.size
    nx, nv = plan.nx, plan.nv
    nd = nx + nv
    twists, sources = factored_twists(model, plan, terms, alg)
    M = np.zeros((lead, nd, nd))
    Md = np.zeros((model.ny, lead, nd, nd)) if split else None
    for link, c in plan.cores.items():
        ep = (None if twists[link] is None else  # upstream columns only
              explicit_twist(twists[link], sources, alg, c.start))
        link_mass(c, c.blocks, terms.jac[link], ep, alg, nx, nv, nd, out=M)
    # rigid carriers: composite 6 × 6 (and 6 × nv) blocks per source, one wide product each
    comp: dict = {}

    def add_rigid(slot, link, G, GJ, W):
        """Carrier motion = G @ root twist + GJ @ q̇ (rows: 6 for an inertia, 3 for a mass).

        ``slot`` is -1 for M, or the design index whose Md the carrier goes to.
        """
        target = M if slot < 0 or Md is None else Md[slot]  # slot >= 0 only when split
        if nv:
            target[:, nx:, nx:] += mm(np.swapaxes(GJ, -1, -2), W @ GJ)
        tw = twists[link]
        if tw is None:
            return
        T, k = tw
        GT = G @ T if G is not None else T
        key = (k, slot)
        C, D = comp.get(key, (0.0, 0.0))
        C = C + mm(np.swapaxes(GT, -1, -2), W @ GT)
        if nv:
            D = D + mm(np.swapaxes(GT, -1, -2), W @ GJ)
        comp[key] = (C, D)

    def on_beam(link, att, xyz, rows):
        """Motion rows ``g`` (lead, rows, nd) of a point on a beam (:func:`carrier_rows`):
        the section's elastic twist there (own coordinates and root twist, explicit)."""
        e = None if twists[link] is None else explicit_twist(twists[link], sources, alg)
        e_full = None
        if e is not None:
            e_full = np.zeros((lead, 6, nx))
            e_full[:, :, : e.shape[-1]] = e
        return carrier_rows(attach_twist(att, e_full, alg, nx), terms.jac[link], xyz, rows, nx)

    for link, inertia in model.plan.inertias.items():
        add_rigid(-1, link, None, terms.jac[link], inertia)
    design_index = model.plan.design.mass_index
    eye3 = np.eye(3)
    for pm, att in zip(model.plan.point_masses, plan.pm_attach):
        name, link, xyz = pm.name, pm.link, pm.xyz
        design = name in design_index
        value: float | np.ndarray
        if design and split:
            value, slot = 1.0, design_index[name]
        elif design:
            value = np.broadcast_to(np.asarray(y[..., design_index[name]], float), (lead,))
            if not np.any(value):
                continue
            value, slot = value[:, None, None] * eye3, -1
        else:
            value, slot = model.point_mass_values[name], -1
            if value == 0.0:
                continue
        target = M if slot < 0 or Md is None else Md[slot]  # slot >= 0 only when split
        W = value * eye3 if np.ndim(value) == 0 else value
        if link in plan.cores:  # on a beam: its own coordinates and the root twist, explicit
            g = on_beam(link, att, xyz, 3)
            target += mm(np.swapaxes(g, -1, -2), W @ g)
        else:
            gJ = (translate_twist(xyz) @ terms.jac[link])[:, :3]
            add_rigid(slot, link, translate_twist(xyz)[:3], gJ, W)
    for body, att in zip(model.plan.bodies, plan.body_attach):  # on beams: six twist rows
        g = on_beam(body.link, att, body.xyz, 6)
        M += mm(np.swapaxes(g, -1, -2), body.inertia @ g)
    for (k, slot), (C, D) in comp.items():
        target = M if slot < 0 or Md is None else Md[slot]  # slot >= 0 only when split
        tau, w = sources[k]
        tT = np.swapaxes(tau, -1, -2)
        target[:, :w, :w] += mm(tT, mm(C, tau))
        if nv:
            X = mm(tT, D)
            target[:, :w, nx:] += X
            target[:, nx:, :w] += np.swapaxes(X, -1, -2)
    return (M, Md) if split else M

