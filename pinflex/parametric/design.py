"""Exact jets of the design-parameter terms of ``M`` and ``K`` (sections, materials, springs).

``M(q, y) = M_nom(q) + Σ_c (f_c(y) − f_c(y_nom)) M_c(q)`` (:mod:`pinflex.erls.design`): the
channel functions ``f_c`` (section formulas) are run in jet arithmetic in the design variables
(:class:`pinflex.jets.scalar.Scalar`), the unit matrices ``M_c(q)`` in jet arithmetic in the
joints, and the two are multiplied as separable jets: the coefficient of ``δq^α δy^β`` is
``M_c[α] · f_c[β]`` for ``|α| + |β| ≤ p``, one product per coefficient of the full space.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from pinflex.erls import design as erls_design
from pinflex.jets import JetSpace
from pinflex.jets.scalar import Scalar, coefficients


@lru_cache(maxsize=32)
def _separable_pairs(order: int, nj: int, nd: int):
    """Index arrays ``(ia, ib, target)`` of the product of a joint jet and a design jet."""
    space = JetSpace(nj + nd, order)
    qspace = JetSpace(nj, order) if nj else None
    dspace = JetSpace(nd, order)
    q_alphas = [tuple(a) for a in qspace.multi_indices.tolist()] if qspace is not None else [()]
    d_betas = [tuple(b) for b in dspace.multi_indices.tolist()]
    ia, ib, tg = [], [], []
    for i, a in enumerate(q_alphas):
        for k, b in enumerate(d_betas):
            if sum(a) + sum(b) <= order:
                ia.append(i)
                ib.append(k)
                tg.append(space.index[a + b])
    return np.array(ia), np.array(ib), np.array(tg)


def channel_jets(model, order: int, y0, design_idx):
    """Each design channel's value as a jet in the expanded design variables, after the checks.

    The sections of ``y0`` are checked (:func:`pinflex.erls.design.check_sections`) first.

    Args:
        model: The flexible model.
        order: Jet order.
        y0: Expansion design, (ny,).
        design_idx: Expanded design variables (indices into ``model.design``).

    Returns:
        ``(f, f0)``: per channel, its coefficients (writable copies) in the design variables'
        own jet space (one constant when none is expanded), and its value at the nominal
        design ``model.y0``.
    """
    y0 = np.asarray(y0, dtype=float)
    names = [d.name for d in model.design]
    nominal = model.y0
    f0 = erls_design.channel_values(model, lambda n: nominal[names.index(n)])
    erls_design.check_sections(model, lambda n: y0[names.index(n)])
    if not len(design_idx):
        return [np.array([float(v)]) for v in
                erls_design.channel_values(model, lambda n: float(y0[names.index(n)]))], f0
    dspace = JetSpace(len(design_idx), order)
    var_of = {names[j]: k for k, j in enumerate(design_idx)}

    def get(name):
        j = names.index(name)
        if name in var_of:
            return Scalar.variable(dspace, var_of[name], y0[j])
        return float(y0[j])

    return [coefficients(dspace, v).copy() for v in erls_design.channel_values(model, get)], f0


def add_jets(model, space: JetSpace, terms, alg, joint_idx, design_idx, y0, M, K):
    """Add the design-parameter channels to the jets ``M``, ``K`` of the full space.

    Args:
        model: The flexible model.
        space: Full jet space (expanded joints, then expanded design variables).
        terms: Pose terms in the joints' jet space (or at ``q0`` when no joint is expanded).
        alg: The algebra of ``terms``.
        joint_idx: Expanded joints (user indices).
        design_idx: Expanded design variables (indices into ``model.design``).
        y0: Expansion design, (ny,).
        M: Jet of M, (ncoef, ndof, ndof), modified copy returned.
        K: Jet of K, likewise.
    """
    if not model.plan.design.channels:
        return M, K
    nj, nd = len(joint_idx), len(design_idx)
    f, f0 = channel_jets(model, space.order, y0, design_idx)
    if nd:
        ia, ib, tg = _separable_pairs(space.order, nj, nd)
    else:
        ia = np.arange(space.ncoef)
        ib = np.zeros(space.ncoef, dtype=int)
        tg = np.arange(space.ncoef)
    for fc, fc0 in zip(f, f0):
        fc[0] -= fc0
    which = [bool(np.any(fc)) for fc in f]
    if not any(which):
        return M, K
    comps = erls_design.components(model, terms, alg, which)
    M, K = np.array(M, copy=True), np.array(K, copy=True)
    for ch, fc, C in zip(model.plan.design.channels, f, comps):
        if C is None:
            continue
        contrib = C[ia] * fc[ib][:, None, None]
        if ch.kind == "M":
            M[tg] += contrib
        else:
            K[tg] += contrib
    return M, K
