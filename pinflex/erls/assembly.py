"""Assembly of the nodal-coordinate pencil ``M(q, y)``, ``K(q, y)`` on any algebra.

The elastic root twist of every link follows the unique-ERLS rule of each joint
(:func:`pinflex.erls.terms.joint_step`); beams, rigid inertias, point masses and rigid bodies add their
kinetic energy, beams their strain energy, and the joint conditions
(:mod:`pinflex.erls.joints`) map the result to the modal coordinates.
"""

from __future__ import annotations

import numpy as np

from pinflex.erls import joints as joint_conditions
from pinflex.erls.terms import (
    Algebra,
    PoseTerms,
    carrier_rows,
    propagate_root_twists,
    twist_at,
    zeros_like,
)


def assemble(model, terms: PoseTerms, alg: Algebra):
    """``(M0, Mdesign, K)`` of :meth:`pinflex.erls.FlexibleModel.assemble`."""
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


def root_twists(model, terms: PoseTerms, alg: Algebra) -> dict[str, np.ndarray | None]:
    """``{link: (b, 6, nx) or None}`` of :meth:`pinflex.erls.FlexibleModel.root_twists`."""
    return propagate_root_twists(model.plan, terms, alg,
                                 lambda k, j, e: twist_at(alg, j.attach, e))
