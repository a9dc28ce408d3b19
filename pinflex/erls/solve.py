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

Cost: one symmetric eigensolve of ``Bred`` per pose (batched over poses with NumPy), with no
Cholesky of the mass, no ``sygst`` and no explicit inverse: less work than a generalized
eigensolver of the same size.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pinflex import beam
from pinflex.erls.terms import offset_block
from pinflex.exceptions import EigenSolverError
from pinflex.linalg import rotate_twist, translate_twist

_EPS = np.finfo(float).eps
_LINALG: tuple | None = None  # (scipy.linalg.blas, scipy.linalg.lapack), imported on first use


def _linalg() -> tuple:
    """SciPy's BLAS and LAPACK wrappers (imported once, on the first one-pose solve)."""
    global _LINALG
    from scipy.linalg import blas, lapack

    _LINALG = (blas, lapack)
    return _LINALG


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
    return SolvePlan(cores, joint_attach, pm_attach, nx, model.nv)


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


class _Batch:
    """Leading axis of poses: constants apply to every pose, products are plain."""

    const_at = slice(None)

    def __init__(self, size: int):
        self.size = size

    @staticmethod
    def mm(a, b):
        return a @ b


def lead_algebra(alg, b: int):
    """``alg`` as used here: the batch algebra of ``b`` poses, or a jet algebra.

    A jet algebra (``pinflex.parametric.matrices.JetAlgebra``) has the Taylor coefficients on
    the leading axis: constants enter the constant coefficient only, and the product of two
    pose-dependent factors is the truncated Cauchy product (``alg.mm``); a constant times a
    jet is a plain product.
    """
    if alg is None or not hasattr(alg, "space"):
        return _Batch(b)
    alg.size = alg.space.ncoef
    alg.const_at = 0
    return alg


def attach_twist(att: _Attach, root, alg, nx: int):
    """Elastic twist (lead, 6, nx) at an attachment, or None when it is identically zero."""
    if att.const is None and root is None:
        return None
    out = np.zeros((alg.size, 6, nx)) if root is None else att.lin @ root
    if att.const is not None:
        out[alg.const_at, :, att.start : att.stop] += att.const
    return out


def _one_pose_joints(model, plan: SolvePlan, data=None) -> tuple:
    """Per joint, the constants :func:`root_twists_one` uses (cached per workspace, read-only).

    ``(const, P, needed)``: the attachment's constant part placed on all ``nx`` columns
    (6, nx) or None, the joint's projection as its two diagonal 3 × 3 blocks (2, 3, 3), times
    ``R_oᵀ`` for joints whose rotation is constant, and whether the one-pose solve reads the
    child's twist (or a descendant's).
    """
    return model.workspace(data).cached("one_pose_joints",
                                        lambda: _build_one_pose_joints(model, plan))


def _build_one_pose_joints(model, plan: SolvePlan) -> tuple:
    # the links whose root twist the one-pose solve reads (beams, rigid inertias, point
    # masses) and their ancestors; joints to other links (a tool frame) are skipped
    needed = set(plan.cores) | set(model.plan.inertias) | {
        pm.link for pm in model.plan.point_masses}
    for j in reversed(model.plan.joints):  # children after their parents: walk back up
        if j.child in needed:
            needed.add(j.parent)
    out = []
    for j, att in zip(model.plan.joints, plan.joint_attach):
        const = None
        if att.const is not None:
            const = np.zeros((6, plan.nx))
            const[:, att.start : att.stop] = att.const
            const.setflags(write=False)
        P = np.stack([j.proj[:3, :3], j.proj[3:, 3:]])
        if j.kind != "revolute":
            P = P @ j.R_o.T
        P.setflags(write=False)
        out.append((const, P, j.child in needed))
    return tuple(out)


def root_twists_one(model, plan: SolvePlan, terms, data=None) -> dict:
    """:func:`root_twists` of one pose (b = 1), without the algebra indirection.

    Only for the links the one-pose solve reads (beams, rigid inertias, point masses) and
    their ancestors: other links (a tool frame behind the last mass) get no entry.
    """
    nx = plan.nx
    twist: dict = {model.plan.root: None}
    for j, att, (const, P, needed) in zip(model.plan.joints, plan.joint_attach,
                                          _one_pose_joints(model, plan, data)):
        if not needed:
            continue
        e = twist[j.parent]
        if e is None:
            if const is None:
                twist[j.child] = None
                continue
            tau = const
        else:
            tau = att.lin @ e[0]
            if const is not None:
                tau[:, att.start : att.stop] += att.const
        if j.kind == "prismatic":
            tau = tau + offset_block(terms.slide[j.name])[0] @ tau
        elif j.kind == "revolute":
            P = P @ terms.rot[j.name][0].T  # projection after the joint's rotation
        # the two 3-row halves (translation, rotation) each turned and projected
        twist[j.child] = (P @ tau.reshape(2, 3, nx)).reshape(1, 6, nx)
    return twist


def root_twists(model, plan: SolvePlan, terms, b: int, alg=None) -> dict:
    """Elastic twist of every link root (link axes) in solver coordinates, (b, 6, nx)."""
    alg = lead_algebra(alg, b)
    twist = {model.plan.root: None}
    for j, att in zip(model.plan.joints, plan.joint_attach):
        tau = attach_twist(att, twist[j.parent], alg, plan.nx)
        if tau is None:
            twist[j.child] = None
            continue
        if j.kind == "prismatic":
            tau = tau + alg.mm(offset_block(terms.slide[j.name]), tau)
            rotated = rotate_twist(j.R_o.T) @ tau
        elif j.kind == "revolute":
            rotated = alg.mm(rotate_twist(np.swapaxes(terms.rot[j.name], -1, -2)), tau)
        else:
            rotated = rotate_twist(j.R_o.T) @ tau
        twist[j.child] = j.proj @ rotated
    return twist


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
        if j.kind == "prismatic":
            step = _lift(alg, np.eye(6)) + offset_block(terms.slide[j.name])
            step = j.proj @ rotate_twist(j.R_o.T) @ step
        elif j.kind == "revolute":
            step = j.proj @ rotate_twist(np.swapaxes(terms.rot[j.name], -1, -2))
        else:
            step = _lift(alg, j.proj @ rotate_twist(j.R_o.T))
        twists[j.child] = (step if T_in is None else mm(step, T_in), src)
    return twists, sources


def explicit_twist(tw, sources, alg, stop: int | None = None):
    """``T @ tau`` of a factored twist on its first ``stop`` columns (None: all it has)."""
    T, k = tw
    tau, width = sources[k]
    if stop is not None and stop < width:
        tau = tau[:, :, :stop]
    return alg.mm(T, tau)


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
    mm, c0, lead = alg.mm, alg.const_at, alg.size
    nx, nv = plan.nx, plan.nv
    nd = nx + nv
    twists, sources = factored_twists(model, plan, terms, alg)
    M = np.zeros((lead, nd, nd))
    Md = np.zeros((model.ny, lead, nd, nd)) if split else None
    for link, c in plan.cores.items():
        a, z = c.start, c.stop
        J = terms.jac[link]
        M[c0, a:z, a:z] += c.H_oo
        if nv:
            X = c.H_ov @ J
            M[:, a:z, nx:] += X
            M[:, nx:, a:z] += np.swapaxes(X, -1, -2)
            M[:, nx:, nx:] += mm(np.swapaxes(J, -1, -2), c.H_vv @ J)
        if twists[link] is not None:
            ep = explicit_twist(twists[link], sources, alg, a)  # upstream columns only
            a = ep.shape[-1]
            X = c.H_oe @ ep
            M[:, c.start : z, :a] += X
            M[:, :a, c.start : z] += np.swapaxes(X, -1, -2)
            epT = np.swapaxes(ep, -1, -2)
            M[:, :a, :a] += mm(epT, c.H_ee @ ep)
            if nv:
                X = mm(epT, c.H_ev @ J)
                M[:, :a, nx:] += X
                M[:, nx:, :a] += np.swapaxes(X, -1, -2)
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
        gJ = (translate_twist(xyz) @ terms.jac[link])[:, :3]
        W = value * eye3 if np.ndim(value) == 0 else value
        if link in plan.cores:  # on a beam: its own coordinates and the root twist, explicit
            e = None if twists[link] is None else explicit_twist(twists[link], sources, alg)
            e_full = None
            if e is not None:
                e_full = np.zeros((lead, 6, nx))
                e_full[:, :, : e.shape[-1]] = e
            tau = attach_twist(att, e_full, alg, nx)
            g = np.zeros((lead, 3, nd))
            if tau is not None:
                g[:, :, :nx] = tau[:, :3]
            g[:, :, nx:] = gJ
            target += mm(np.swapaxes(g, -1, -2), W @ g)
        else:
            add_rigid(slot, link, translate_twist(xyz)[:3], gJ, W)
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


#: Largest row count of the one-pose layout (:func:`mass_one`); larger models use :func:`mass`.
ONE_POSE_MAX_ROWS = 400


class OnePoseLayout:
    """Row layout of the one-pose mass ``M = Sᵀ W S`` (built once per model, read-only).

    Each mass carrier owns rows of ``S`` (its kinematic variables as rows over ``[w; q]``):
    a beam its own coordinates (identity on its columns), its root twist (6) and its frame
    twist (6, the Jacobian on the joint columns), weighted by the beam's constant
    ``Aᵀ M_link A``; a rigid inertia its frame twist (6), weighted by the spatial inertia. A
    point mass on a link that owns rows moves with them: its velocity is ``T`` times those
    rows (``T = [const, lin, to_point]`` on a beam's rows, ``to_point`` on an inertia's), so
    it adds ``m TᵀT`` to their weight block instead of rows of its own (``folded``:
    ``(design column, first row, TᵀT)`` of the design masses, added per call); a point mass
    on a link without rows keeps its velocity (3) as rows, weighted by its mass. ``S0`` holds
    the constant entries, ``W0`` the constant weights (design masses are set per call).

    Planar models: the out-of-plane components of every root and frame twist are zero at
    every pose (:func:`_planar_zero_rows`); those rows stay in ``S0`` (the per-pose fill
    writes whole twists) and ``keep`` lists the others, the rows ``W0``, ``A``, ``A_el`` and
    ``F`` are laid out on and :func:`mass_one` returns.

    For the mode shapes: ``A2 = [A; A_el]``, ``A`` mapping the rows of ``S`` to the node
    twists of every beam (beam axes; ``[C, R, J_frame]`` of each beam, its nodes stacked in
    plan order) and ``A_el`` its elastic part (without the frame-twist columns);
    ``X = A_el[x rows]`` gives the nodal coordinates ``x``; ``node_links`` names the beam of
    each 3-row block of ``A2``'s rows and ``node_slices`` the blocks of each beam in ``A``.
    ``F`` holds the same rows in the order one product serves them: ``X`` first, then per
    beam its rows of ``A`` and of ``A_el`` together (``field_rows[link] = (start, stop)``, the
    ``A`` half first), so that one product ``F Z`` gives the nodal coordinates and every
    beam's fields, and one rotation per beam turns both halves.
    """

    __slots__ = ("S0", "W0", "beams", "inertias", "masses", "design_diag", "design_cols",
                 "A2", "X", "node_links", "node_slices", "F", "field_rows", "folded", "keep")

    def __init__(self, S0, W0, beams, inertias, masses, design_diag, design_cols, A2, X,
                 node_links, node_slices, F, field_rows, folded=(), keep=None):
        self.folded, self.keep = folded, keep
        self.S0, self.W0 = S0, W0
        self.beams, self.inertias, self.masses = beams, inertias, masses
        self.design_diag, self.design_cols = design_diag, design_cols
        self.A2, self.X = A2, X
        self.node_links, self.node_slices = node_links, node_slices
        self.F, self.field_rows = F, field_rows


def one_pose_layout(model, data=None) -> OnePoseLayout | None:
    """The :class:`OnePoseLayout` of a model (built once per workspace), or None when too large.

    Above :data:`ONE_POSE_MAX_ROWS` rows a dense ``W`` would cost more than the structured
    assembly of :func:`mass`.
    """
    return model.workspace(data).cached("one_pose_layout",
                                        lambda: _build_one_pose_layout(model, data))


def _build_one_pose_layout(model, data) -> OnePoseLayout | None:
    plan = solve_plan(model, data)
    nx, nv = plan.nx, plan.nv
    nd = nx + nv
    carriers = set(plan.cores) | set(model.plan.inertias)  # links that own rows
    own_rows = [pm.link not in carriers for pm in model.plan.point_masses]
    n_rows = (sum(c.stop - c.start + 12 for c in plan.cores.values())
              + 6 * len(model.plan.inertias) + 3 * sum(own_rows))
    if n_rows > ONE_POSE_MAX_ROWS:
        return None
    S0 = np.zeros((n_rows, nd))
    W0 = np.zeros((n_rows, n_rows))
    n_node_rows = sum(c.C.shape[0] for c in plan.cores.values())
    A = np.zeros((n_node_rows, n_rows))
    A_el = np.zeros((n_node_rows, n_rows))
    x_index = np.zeros(nx, dtype=int)
    node_links: list[int] = []
    node_slices: dict[str, tuple[int, int]] = {}
    beams, inertias, masses = [], [], []
    blocks_of: dict[str, tuple[int, int]] = {}  # link -> (first row, rows) of its block
    r = 0
    t = 0
    for link, c in plan.cores.items():
        o = c.stop - c.start
        blocks_of[link] = (r, o + 12)
        S0[r : r + o, c.start : c.stop] = np.eye(o)
        W0[r : r + o + 12, r : r + o + 12] = np.block([
            [c.H_oo, c.H_oe, c.H_ov],
            [c.H_oe.T, c.H_ee, c.H_ev],
            [c.H_ov.T, c.H_ev.T, c.H_vv],
        ])
        beams.append((link, r + o, r + o + 6))  # root-twist rows, frame-twist rows
        n_t = c.C.shape[0]
        A_el[t : t + n_t, r : r + o] = c.C
        A_el[t : t + n_t, r + o : r + o + 6] = c.R
        A[t : t + n_t, r : r + o + 6] = A_el[t : t + n_t, r : r + o + 6]
        A[t : t + n_t, r + o + 6 : r + o + 12] = model.plan.beams[link].jac
        x_index[c.start : c.stop] = t + c.x_rows
        node_links += [len(node_slices)] * (n_t // 3)
        node_slices[link] = (t // 3, (t + n_t) // 3)
        r += o + 12
        t += n_t
    for link, inertia in model.plan.inertias.items():
        W0[r : r + 6, r : r + 6] = inertia
        inertias.append((link, r))
        blocks_of.setdefault(link, (r, 6))
        r += 6
    design_index = model.plan.design.mass_index
    diag, cols, folded = [], [], []
    for pm, att, own in zip(model.plan.point_masses, plan.pm_attach, own_rows):
        if not own:  # velocity = T (rows of its link's block): weight m TᵀT on that block
            r0, size = blocks_of[pm.link]
            to_point = translate_twist(pm.xyz)[:3]
            if pm.link in plan.cores:
                core = plan.cores[pm.link]
                o = core.stop - core.start
                T = np.zeros((3, size))
                if att.const is not None:
                    T[:, att.start - core.start : att.stop - core.start] = att.const[:3]
                T[:, o : o + 6] = att.lin[:3]
                T[:, o + 6 : o + 12] = to_point
            else:  # a rigid inertia's rows: [elastic root twist | frame twist] = its twist
                T = to_point
            B = T.T @ T
            B.setflags(write=False)
            if pm.name in design_index:
                folded.append((design_index[pm.name], r0, r0 + size, B))
            else:
                W0[r0 : r0 + size, r0 : r0 + size] += model.point_mass_values[pm.name] * B
            continue
        if att.const is not None:
            S0[r : r + 3, att.start : att.stop] = att.const[:3]
        idx = np.arange(r, r + 3)
        if pm.name in design_index:
            diag.append(idx * (n_rows + 1))
            cols.append(np.full(3, design_index[pm.name]))
        else:
            W0[idx, idx] = model.point_mass_values[pm.name]
        masses.append((pm.link, r, att.lin[:3], translate_twist(pm.xyz)[:3]))
        r += 3
    # planar models: rows of S that are zero at every pose leave the products (kept in S0,
    # which the per-pose fill addresses; mass_one gathers the others)
    diag_idx = np.concatenate(diag) if diag else np.zeros(0, int)
    keep = None
    drop = _planar_zero_rows(model, beams, inertias)
    if drop.size:
        keep = np.setdiff1d(np.arange(n_rows), drop)
        pos = np.full(n_rows, -1)
        pos[keep] = np.arange(keep.size)
        W0 = np.ascontiguousarray(W0[np.ix_(keep, keep)])
        A, A_el = A[:, keep], A_el[:, keep]
        if diag_idx.size:  # own-row design masses: in-plane and out-of-plane rows alike
            rows_d = diag_idx // (n_rows + 1)
            if np.any(pos[rows_d] < 0):  # pragma: no cover - velocity rows are never dropped
                raise AssertionError("a design mass row was dropped")
            diag_idx = pos[rows_d] * (keep.size + 1)
        compact = []
        for d, r0, r1, B in folded:
            local = np.flatnonzero(pos[r0:r1] >= 0)
            Bk = np.ascontiguousarray(B[np.ix_(local, local)])
            Bk.setflags(write=False)
            compact.append((d, int(pos[r0 + local[0]]), int(pos[r0 + local[0]]) + local.size,
                            Bk))
        folded = compact
        keep.setflags(write=False)
    X = A_el[x_index]
    A2 = np.concatenate([A, A_el])
    links = np.array(node_links + node_links, dtype=int)
    blocks, field_rows = [X], {}
    f = nx
    for link, (n0, n1) in node_slices.items():
        blocks += [A[3 * n0 : 3 * n1], A_el[3 * n0 : 3 * n1]]
        field_rows[link] = (f, f + 6 * (n1 - n0))
        f += 6 * (n1 - n0)
    F = np.ascontiguousarray(np.concatenate(blocks))
    for a in (S0, W0, A2, X, links, F):
        a.setflags(write=False)
    return OnePoseLayout(S0, W0, tuple(beams), tuple(inertias), tuple(masses), diag_idx,
                         np.concatenate(cols) if cols else np.zeros(0, int),
                         A2, X, links, node_slices, F, field_rows, tuple(folded), keep)


def _planar_zero_rows(model, beams, inertias) -> np.ndarray:
    """Rows of the one-pose ``S`` that a planar model keeps at zero at every pose.

    In a planar model (every revolute axis along the plane normal ``n``, beams' normals
    along it, prismatic axes in the plane; checked when the model was built) each link turns
    about ``n`` only, so ``n`` has the same coordinates in the link's axes at every pose, and
    the in-plane beams deform in the plane. Where those coordinates are ``±e_i`` (``i`` one
    axis of the link), every twist in link axes (``[v; ω]``: the elastic root twist, the
    frame twist and its Jacobian) has ``v_i = 0`` and ``ω_j = 0`` for the other two axes
    ``j``: those rows of the link's root- and frame-twist blocks are zero at every pose.
    Links whose axes are not aligned with ``n`` keep all rows. Returns the row indices.
    """
    normal = model.plane_normal
    if normal is None:
        return np.zeros(0, int)
    data = model.model.createData()
    pin.framesForwardKinematics(model.model, data, pin.neutral(model.model))
    ids = model.plan.frame_ids
    rows: list[int] = []
    starts = [(link, (re, rj)) for link, re, rj in beams] + [(link, (r,)) for link, r in inertias]
    for link, firsts in starts:
        local = data.oMf[ids[link]].rotation.T @ normal
        i = int(np.argmax(np.abs(local)))
        if abs(abs(local[i]) - 1.0) > 1e-12:
            continue
        zero = [i] + [3 + j for j in range(3) if j != i]
        rows += [r0 + z for r0 in firsts for z in zero]
    return np.array(sorted(rows), dtype=int)


def mass_one(model, layout: OnePoseLayout, terms, twist: dict, y: np.ndarray):
    """Mass matrix (nd, nd) of one pose in solver coordinates, as :func:`mass` (b = 1).

    Returns:
        ``(M, S)``: the mass and the pose's rows ``S`` (n_rows, nd) of :class:`OnePoseLayout`.

    Args:
        model: The flexible model.
        layout: Its :func:`one_pose_layout`.
        terms: Pose terms of the pose (leading axis 1).
        twist: Its solver-coordinate root twists (:func:`root_twists`, b = 1).
        y: Checked design values (ny,).
    """
    nx = model.nx
    S = layout.S0.copy()
    jac = terms.jac
    for link, re, rj in layout.beams:
        e = twist[link]
        if e is not None:
            S[re : re + 6, :nx] = e[0]
        S[rj : rj + 6, nx:] = jac[link][0]
    for link, r in layout.inertias:
        e = twist[link]
        if e is not None:
            S[r : r + 6, :nx] = e[0]
        S[r : r + 6, nx:] = jac[link][0]
    for link, r, lin, to_point in layout.masses:
        e = twist[link]
        if e is not None:
            S[r : r + 3, :nx] += lin @ e[0]
        S[r : r + 3, nx:] = to_point @ jac[link][0]
    W = layout.W0
    if layout.design_diag.size:
        W = W.copy()
        W.flat[layout.design_diag] = y[layout.design_cols]
    for d, r0, r1, B in layout.folded:  # design masses moving with their link's rows
        value = float(y[d])
        if value:  # (a zero mass adds nothing)
            if W is layout.W0:
                W = W.copy()
            W[r0:r1, r0:r1] += value * B
    if layout.keep is not None:
        S = S[layout.keep]  # (rows zero at every pose left out)
    M = S.T @ (W @ S)
    M += M.T  # (NumPy buffers the overlapping transpose)
    M *= 0.5
    return M, S


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


def eigvecs(model, M: np.ndarray, n_modes: int | None = None, pencil=None):
    """Eigenvalues λ (k,) and mass-normalised shapes of one pose.

    Returns:
        ``(lam, shapes_w, shapes_x)``: the modes the inverse form resolves as solver-coordinate
        shapes ``[w; q]`` (nd, r), and the rest (recovered from the nodal pencil, see
        :func:`eigvals`) directly over ``[x; q]`` (nd, k - r). The q part is the condensed
        rigid-coordinate response.
    """
    blas, lapack = _LINALG or _linalg()
    nx = model.nx
    k = nx if n_modes is None else min(int(n_modes), nx)
    nd = M.shape[-1]
    # condense as condense() does, through LAPACK/BLAS directly (one pose: the wrappers'
    # checks cost more than these small factorizations); Bred's lower triangle only
    Lq = Y = None
    Bred = M[:nx, :nx]
    if model.nv:
        Lq, info = lapack.dpotrf(M[nx:, nx:], lower=1, clean=1)
        if info != 0:
            raise EigenSolverError(
                "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
                "add inertia to the links it drives"
            )
        Y, info = lapack.dtrtrs(Lq, M[nx:, :nx], lower=1)
        Bred = blas.dsyrk(-1.0, Y, beta=1.0, c=Bred, trans=1, lower=1)  # Mww - Y^T Y
    if k == 0:
        return np.zeros(0), np.zeros((nd, 0)), np.zeros((nd, 0))
    if use_lanczos(nx, k):
        mu, V = _lanczos(np.tril(Bred) + np.tril(Bred, -1).T, k, True)
    elif k == nx:
        mu, V, info = lapack.dsyevd(Bred, compute_v=1, lower=1)
        if info != 0:
            raise EigenSolverError("the symmetric eigensolver did not converge: the mass of the "
                                   "model is not finite")
    else:
        import scipy.linalg

        mu, V = scipy.linalg.eigh(Bred, lower=True, subset_by_index=[nx - k, nx - 1],
                                  driver="evr", check_finite=False)
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
