"""Assembly of the nodal-coordinate pencil ``M(q, y)``, ``K(q, y)`` on any algebra.

The elastic root twist of every link follows the unique-ERLS rule of each joint
(:func:`pinflex.erls.terms.joint_step`); beams, rigid inertias, point masses and rigid bodies add their
kinetic energy, beams their strain energy, and the joint conditions
(:mod:`pinflex.erls.joints`) map the result to the modal coordinates.
"""

from __future__ import annotations

import numpy as np

from pinflex.erls import design as design_channels
from pinflex.erls import joints as joint_conditions
from pinflex.erls.kinematics import root_twists
from pinflex.erls.terms import (
    Algebra,
    BatchAlgebra,
    PoseTerms,
    carrier_rows,
    twist_at,
    zeros_like,
)

__all__ = ["add_design_masses", "assemble", "matrices_from_terms", "root_twists"]


def add_design_masses(M0: np.ndarray, Md: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``M = M0 + Σ_j y_j Md_j`` for one design (ny,) or one per pose (n, ny)."""
    if Md.shape[0] == 0:
        return M0
    if y.ndim == 1:
        return M0 + np.tensordot(y, Md, axes=(0, 0))
    return M0 + np.einsum("nj,jnab->nab", y, Md)


def assemble(model, terms: PoseTerms, alg: Algebra):
    """Assemble M without design masses, M per unit design mass, and K.

    Works on any algebra ``alg`` (poses or Taylor coefficients on the leading axis).

    Args:
        model: The flexible model.
        terms: Pose terms of ``b`` poses (:func:`pinflex.erls.kinematics.pose_terms`) or
            their jets.
        alg: The algebra of the leading axis (:class:`BatchAlgebra` for poses, a jet
            algebra for Taylor coefficients).

    Returns:
        ``M0`` (b, nd, nd), ``Mdesign`` (ny, b, nd, nd), ``K`` (b, nd, nd) after the joint
        conditions are applied, so ``nd = ndof`` (the modal coordinates ``[x; q_kept]``).
        Units: mass entries [kg, kg m, kg m²], stiffness [N/m, N, N m] per coordinate
        pair; ``Mdesign`` is per kg of each design mass.
    """
    nx = model.nx
    nd = nx + model.nv  # [x; q_all]; joint conditions map to the modal coordinates
    twist = root_twists(model, terms, alg)
    M = None
    K = None
    for link, bp in model.plan.beams.items():
        e = twist[link]
        sel, root, jac, mass, stiffness = bp.kept
        bx = alg.const(sel) if e is None else alg.const(sel) + root @ e
        w = np.concatenate([bx, jac @ terms.jac[link]], axis=-1)
        m = alg.mm(np.swapaxes(w, -1, -2), mass @ w)
        k = alg.mm(np.swapaxes(bx, -1, -2), stiffness @ bx)
        M = m if M is None else M + m
        K = k if K is None else K + k
    for link, inertia in model.plan.inertias.items():
        e = twist[link]
        jl = terms.jac[link]
        g = np.concatenate([zeros_like(jl, nx) if e is None else e, jl], axis=-1)
        m = alg.mm(np.swapaxes(g, -1, -2), inertia @ g)
        M = m if M is None else M + m
    design_index = model.plan.design.mass_index
    carriers = model.plan.carriers
    shape_b = terms.jac[carriers[0]].shape[:1] if carriers else (1,)
    Mdesign = np.zeros((model.ny,) + shape_b + (nd, nd))
    for pm in model.plan.point_masses:
        name, link = pm.name, pm.link
        g = carrier_rows(twist_at(alg, pm.attach, twist[link]), terms.jac[link], pm.xyz, 3, nx)
        m = alg.mm(np.swapaxes(g, -1, -2), g)
        if name in design_index:
            Mdesign[design_index[name]] += m
        else:
            value = model.point_mass_values[name]
            M = value * m if M is None else M + value * m
    for body in model.plan.bodies:  # rigid bodies on beams: all six twist rows
        tau = twist_at(alg, body.attach, twist[body.link])
        g = carrier_rows(tau, terms.jac[body.link], body.xyz, 6, nx)
        m = alg.mm(np.swapaxes(g, -1, -2), body.inertia @ g)
        M = m if M is None else M + m
    if M is None:
        M = np.zeros(shape_b + (nd, nd))
    Kfull = np.zeros(M.shape)
    if K is not None:
        Kfull[..., :nx, :nx] = K
    return joint_conditions.apply(model, terms, alg, twist, M, Mdesign, Kfull)


def matrices_from_terms(model, terms: PoseTerms, y: np.ndarray, n_poses: int):
    """Batched ``(M, K)`` from the pose terms of ``n_poses`` poses and checked designs.

    Args:
        model: The flexible model.
        terms: Pose terms of the poses (:func:`pinflex.erls.kinematics.pose_terms`), leading
            axis ``n_poses``.
        y: Design values checked by :func:`pinflex.checks.check_y`, (ny,) or
            (n_poses, ny) [kg].
        n_poses: Number of poses on the leading axis.

    Returns:
        ``(M, K)``, each (n_poses, ndof, ndof), with the design masses and design
        stiffness channels added.
    """
    M0, Md, K = assemble(model, terms, BatchAlgebra(n_poses))
    M = add_design_masses(M0, Md, y)
    return design_channels.add_to(model, terms, y, M, K, n_poses)
