"""One pose per call: the row layout ``M = Sᵀ W S`` of the conditioned solve.

The batched assembly of :func:`pinflex.erls.solve.mass` pays per call for its block
bookkeeping; for one pose the mass is one product of a sparse-in-structure row matrix ``S``
(the pose's kinematic rows) with a constant weight ``W`` built once per workspace.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pinflex.erls.solve import SolvePlan, solve_plan
from pinflex.erls.terms import joint_step
from pinflex.linalg import translate_twist


def _one_pose_joints(model, plan: SolvePlan, data=None) -> tuple:
    """Per joint, the constants :func:`root_twists_one` uses (cached per workspace, read-only).

    ``(const, needed, step)``: the attachment's constant part placed on all ``nx`` columns
    (6, nx) or None, whether the one-pose solve reads the child's twist (or a descendant's),
    and the joint's step (:func:`~pinflex.erls.terms.joint_step`) when it is constant (a
    joint that does not move), else None.
    """
    return model.workspace(data).cached("one_pose_joints",
                                        lambda: _build_one_pose_joints(model, plan))


def _build_one_pose_joints(model, plan: SolvePlan) -> tuple:
    # the links whose root twist the one-pose solve reads (beams, rigid inertias, point
    # masses) and their ancestors; joints to other links (a tool frame) are skipped
    needed = set(plan.cores) | set(model.plan.inertias) | {
        pm.link for pm in model.plan.point_masses} | {b.link for b in model.plan.bodies}
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
        step = None if j.motion.moves else joint_step(j)
        if step is not None:
            step.setflags(write=False)
        out.append((const, j.child in needed, step))
    return tuple(out)


def root_twists_one(model, plan: SolvePlan, terms, data=None) -> dict:
    """:func:`~pinflex.erls.solve.root_twists` of one pose (b = 1), without the algebra.

    The same rule (:func:`~pinflex.erls.terms.joint_step`), only for the links the one-pose
    solve reads (beams, rigid inertias, point masses) and their ancestors: other links (a
    tool frame behind the last mass) get no entry.
    """
    nx = plan.nx
    rot, slide = terms.rot, terms.slide
    twist: dict = {model.plan.root: None}
    for j, att, (const, needed, step) in zip(model.plan.joints, plan.joint_attach,
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
        if step is None:  # the joint moves: its step at this pose, (1, 6, 6)
            step = joint_step(j, rot.get(j.name), slide.get(j.name))
        twist[j.child] = (step @ tau).reshape(1, 6, nx)
    return twist


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
    for body, att in zip(model.plan.bodies, plan.body_attach):  # folded into its beam block
        r0, size = blocks_of[body.link]
        core = plan.cores[body.link]
        o = core.stop - core.start
        T = np.zeros((6, size))
        if att.const is not None:
            T[:, att.start - core.start : att.stop - core.start] = att.const
        T[:, o : o + 6] = att.lin
        T[:, o + 6 : o + 12] = translate_twist(body.xyz)
        W0[r0 : r0 + size, r0 : r0 + size] += T.T @ body.inertia @ T
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


