"""Exact Taylor coefficients of M(q, y) and K(q, y) through the joint kinematics."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pinflex import jets
from pinflex.checks import check_q, check_y
from pinflex.erls import BatchAlgebra, FlexibleModel, PoseTerms, assembly, kinematics
from pinflex.exceptions import ConfigurationError, DesignVariableNotFound
from pinflex.jets import JetSpace
from pinflex.linalg import axis_rotation, skew
from pinflex.parametric.algebra import JetAlgebra
from pinflex.parametric.design import add_jets as add_design_jets
from pinflex.resources import check_order, check_taylor


def _angle_terms(model: FlexibleModel, joint_vars: dict[int, int], col: int):
    """Variables and factors of δq_pin[col] = Σ_l C[col, l] δq_user[l]."""
    return [(var, model.coord_map[col, j]) for j, var in joint_vars.items()
            if model.coord_map[col, j] != 0.0]


def _rotation_jet(space: JetSpace, axis: np.ndarray, angle0: float, terms, mm=None
                  ) -> np.ndarray:
    """Jet of the rotation about ``axis`` by ``angle0 + Σ c_k δx_k``."""
    R = jets.constant(space, axis_rotation(axis, np.array([angle0]))[0])
    k1 = skew(axis)
    k2 = k1 @ k1
    one = jets.constant(space, 1.0)
    for var, c in terms:
        s, co = jets.sin_cos_of_variable(space, var, 0.0)
        scale = float(c) ** space.multi_indices[:, var]
        s, co = s * scale, co * scale
        step = (jets.constant(space, np.eye(3)) + s[:, None, None] * k1
                + (one - co)[:, None, None] * k2)
        R = jets.matmul(space, R, step) if mm is None else mm(R, step)
    return R


def pose_jets(model: FlexibleModel, space: JetSpace, q0: np.ndarray,
              joint_vars: dict[int, int], alg=None) -> PoseTerms:
    """Jets of the ERLS pose terms (frame Jacobians, joint rotations) at ``q0``.

    Args:
        model: The flexible model.
        space: Jet space.
        q0: Expansion pose in user coordinates, (nv,).
        joint_vars: Map user joint index -> jet variable index of the expanded joints.
        alg: Jet algebra of the products (default :class:`JetAlgebra`, dense; a
            :class:`~pinflex.parametric.algebra.SparseJetAlgebra` skips zero
            coefficients: a joint's rotation depends on one variable, a frame's Jacobian on
            the joints upstream of it).
    """
    mm = (alg or JetAlgebra(space)).mm
    nv, nc = model.nv, space.ncoef
    q0p = model.coord_map @ q0
    J = {model.plan.root: np.zeros((nc, 6, nv))}
    rot, slide = {}, {}
    for j in model.plan.joints:
        if j.motion.rotates:
            terms = _angle_terms(model, joint_vars, j.user_col)
            R = j.R_o @ _rotation_jet(space, j.axis, q0p[j.user_col], terms, mm)
            t = jets.constant(space, j.xyz)
            rot[j.name] = R
        elif j.motion.moves:  # prismatic
            d = jets.constant(space, q0p[j.user_col])
            for var, c in _angle_terms(model, joint_vars, j.user_col):
                d = d + c * jets.variable(space, var, 0.0)
            R = jets.constant(space, j.R_o)
            offset = d[:, None] * (j.R_o @ j.axis)[None, :]
            slide[j.name] = offset
            t = jets.constant(space, j.xyz) + offset
        else:
            R = jets.constant(space, j.R_o)
            t = jets.constant(space, j.xyz)
        JP = J[j.parent]
        if nv == 0:
            J[j.child] = JP
            continue
        RT = np.swapaxes(R, -1, -2)
        lin = JP[:, :3] - mm(skew(t), JP[:, 3:])
        Jc = np.concatenate([mm(RT, lin), mm(RT, JP[:, 3:])], axis=1)
        if j.motion.moves:  # the joint's own rate along its rows (rotation or translation)
            Jc[0, j.motion.rows, j.user_col] += j.axis
        J[j.child] = Jc
    jac = {link: J[link] @ model.coord_map for link in model.plan.carriers}
    return PoseTerms(jac, rot, slide)


def expansion_variables(model: FlexibleModel, q0, y0, order: int,
                        joints: Sequence[str] | None, design: Sequence[str] | None):
    """Check an expansion point and name its variables (shared by both jet routes).

    Returns:
        ``(q0, y0, joint_idx, design_idx, order)``: the checked pose (nv,) and design, the
        indices of the expanded joints and design variables, and the checked order.

    Raises:
        ConfigurationError: For several poses, no variable, or an order out of range.
        DesignVariableNotFound: For an unknown design name.
    """
    q0 = check_q(model, q0).astype(float)
    if q0.ndim != 1:
        raise ConfigurationError("the expansion point must be a single pose")
    y0 = check_y(model, y0)
    joint_idx = [model.joint_index(n) for n in (model.joint_names if joints is None else joints)]
    names = model.design_names if design is None else tuple(design)
    design_idx = []
    for n in names:
        if n not in model.design_names:
            raise DesignVariableNotFound(n, model.design_names)
        design_idx.append(model.design_names.index(n))
    nvars = len(joint_idx) + len(design_idx)
    if nvars == 0:
        raise ConfigurationError("expand at least one joint or design variable")
    order = check_order(order)
    check_taylor(nvars, order, model.ndof, len(design_idx))
    return q0, y0, joint_idx, design_idx, order


def matrix_jets(model: FlexibleModel, q0, y0=None, *, order: int = 4,
                joints: Sequence[str] | None = None, design: Sequence[str] | None = None):
    """Exact Taylor coefficients of ``M(q, y)`` and ``K(q, y)`` at ``(q0, y0)``.

    Args:
        model: The flexible model.
        q0: Expansion pose (user coordinates) [rad or m], (nv,).
        y0: Expansion design values [kg] (default nominal).
        order: Truncation order p.
        joints: Names of the joints to expand (default all).
        design: Names of the design variables to expand (default all).

    Returns:
        ``(space, M_jet, K_jet, joint_idx, design_idx)``: jets of shape (ncoef, ndof, ndof);
        the variables are the listed joints then the listed design variables, in order.
    """
    q0, y0, joint_idx, design_idx, order = expansion_variables(model, q0, y0, order, joints, design)
    space = JetSpace(len(joint_idx) + len(design_idx), int(order))
    nj, nd = len(joint_idx), len(design_idx)
    # The pose terms depend on the joints only: assemble in the joints' own (smaller) jet
    # space, then embed. Design masses enter M linearly: δy_j shifts coefficients by e_j.
    if nj:
        qspace = JetSpace(nj, int(order))
        terms = pose_jets(model, qspace, q0, {j: k for k, j in enumerate(joint_idx)})
        qalg: JetAlgebra | BatchAlgebra = JetAlgebra(qspace)
        Mq, Mdq, Kq = assembly.assemble(model, terms, qalg)
        alphas = [tuple(a) for a in qspace.multi_indices.tolist()]
    else:
        terms, qalg = kinematics.pose_terms(model, q0[None]), BatchAlgebra(1)
        Mq, Mdq, Kq = assembly.assemble(model, terms, qalg)
        alphas = [()]
    zeros = (0,) * nd
    emb = np.array([space.index[a + zeros] for a in alphas])
    shape = (space.ncoef,) + Mq.shape[1:]
    M, K = np.zeros(shape), np.zeros(shape)
    M[emb] = Mq
    K[emb] = Kq
    for j in range(model.ny):
        M[emb] += y0[j] * Mdq[j]
        if j in design_idx:
            k = design_idx.index(j)
            unit = tuple(int(i == k) for i in range(nd))
            low = [i for i, a in enumerate(alphas) if sum(a) < order]
            shifted = np.array([space.index[alphas[i] + unit] for i in low], dtype=int)
            M[shifted] += Mdq[j][low]
    # section, material and spring design parameters (nonlinear in y): pinflex.parametric.design
    M, K = add_design_jets(model, space, terms, qalg, joint_idx, design_idx, y0, M, K)
    return space, M, np.array(K), joint_idx, design_idx
