"""Pinocchio kinematics of a flexible model: frame Jacobians, joint rotations and offsets.

:func:`pose_terms` serves many poses (rotations by Rodrigues' formula, batched);
:func:`pose_terms_one` one pose in one Pinocchio pass (rotations read from it). Both write the
Pinocchio ``Data`` of the workspace they are given (``data``, by default the calling thread's
workspace of the model), never the model. :func:`pose_terms_and_placements` adds the world
placement of every beam's nodes from the same pass.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pinocchio as pin

from pinflex.erls.terms import Algebra, PoseTerms, propagate_root_twists, twist_at
from pinflex.erls.workspace import FlexibleData


class NodePlacement(NamedTuple):
    """World placement of a beam's nodes at one pose.

    Attributes:
        positions_m: Node positions (N+1, 3) in the world frame [m].
        rotation: Rotation (3, 3) of the beam axes in the world frame.
    """

    positions_m: np.ndarray
    rotation: np.ndarray


def pose_terms(arm, Q: np.ndarray, data: FlexibleData | None = None) -> PoseTerms:
    """Pinocchio Jacobians and joint rotations at poses Q (n, nv).

    Args:
        arm: The flexible model.
        Q: Checked joint coordinates (n, nv) in the user convention [rad or m]; not
            validated (use :func:`pinflex.checks.check_q` first).
        data: Workspace (default: this thread's).

    Returns:
        :class:`PoseTerms`: ``jac`` ``{carrier link: (n, 6, nv)}`` LOCAL frame Jacobians
        over the user coordinates, ``rot`` ``{revolute joint: (n, 3, 3)}`` child-in-parent
        rotations, ``slide`` ``{prismatic joint: (n, 3)}`` child origin offsets [m].
    """
    data = arm.workspace(data)
    model, pdata = arm.model, data.pin
    n = Q.shape[0]
    jac = {link: np.zeros((n, 6, arm.nv)) for link in arm.plan.carriers}
    fids = [(link, arm.plan.frame_ids[link]) for link in arm.plan.carriers]
    for i in range(n if arm.nv else 0):
        qp = arm.pin_configuration(Q[i])
        pin.computeJointJacobians(model, pdata, qp)
        for link, fid in fids:
            jac[link][i] = pin.getFrameJacobian(model, pdata, fid, pin.LOCAL).reshape(6, -1)
    names, cols, A0, A1, A2, plain = arm._rodrigues
    if not plain:
        for link in jac:
            jac[link] = jac[link] @ arm.coord_map
    qrel = Q @ arm.coord_map.T
    rot, slide = {}, {}
    if names:  # R_o R(axis, angle) = R_o + sin R_o K + (1 - cos) R_o K^2, all joints at once
        angle = qrel[:, cols][..., None, None]
        R = A0 + np.sin(angle) * A1 + (1.0 - np.cos(angle)) * A2
        for i, name in enumerate(names):
            rot[name] = R[:, i]
    for j in arm.plan.joints:
        s = j.motion.slide(j, qrel)
        if s is not None:
            slide[j.name] = s
    return PoseTerms(jac, rot, slide)


def pose_terms_one(arm, q: np.ndarray, data: FlexibleData | None = None) -> PoseTerms:
    """:func:`pose_terms` of one checked pose (nv,), leading axis 1, without the batch loop.

    Leaves the workspace's Pinocchio data at this pose (joint placements and Jacobians).

    Args:
        arm: The flexible model.
        q: Joint coordinates (nv,) in the user convention [rad or m], already checked.
        data: Workspace (default: this thread's).

    Returns:
        :class:`PoseTerms`: ``jac`` ``{link: (1, 6, nv)}``, ``rot`` ``{joint: (1, 3, 3)}``,
        ``slide`` ``{prismatic joint: (1, 3)}`` [m].
    """
    data = arm.workspace(data)
    if not arm.nv:
        return pose_terms(arm, q[None], data)
    model, pdata = arm.model, data.pin
    cmap = arm.coord_map
    qrel = np.dot(cmap, q)
    pin.computeJointJacobians(model, pdata, arm._configuration_of(qrel))
    names, cols, A0, A1, A2, plain = arm._rodrigues
    jac = {}
    ids, local, dot = arm.plan.frame_ids, pin.LOCAL, np.dot
    for link in arm.plan.carriers:
        J = pin.getFrameJacobian(model, pdata, ids[link], local)
        jac[link] = (J if plain else dot(J.reshape(6, -1), cmap)).reshape(1, 6, -1)
    rot, slide = {}, {}
    # a revolute joint's rotation R_o Rot(axis, θ): Pinocchio's parent-to-joint placement
    # of this pass (pose_terms: the same by Rodrigues' formula, batched)
    liMi = pdata.liMi
    for name, jid in arm._revolute_ids:
        rot[name] = liMi[jid].rotation[None]
    for j in arm.plan.joints:
        s = j.motion.slide(j, qrel)
        if s is not None:
            slide[j.name] = s[None]
    return PoseTerms(jac, rot, slide)


def placements(arm, pdata) -> dict[str, NodePlacement]:
    """Node placements from Pinocchio ``pdata`` whose frame placements are up to date."""
    out = {}
    oMf, ids = pdata.oMf, arm.plan.frame_ids
    for link, nodes_h, axes in arm._placement_constants:
        H = oMf[ids[link]].homogeneous[:3]  # [R | p]
        out[link] = NodePlacement(nodes_h @ H.T, H[:, :3] @ axes)
    return out


def pose_terms_and_placements(
    arm, q: np.ndarray, data: FlexibleData | None = None
) -> tuple[PoseTerms, dict[str, NodePlacement]]:
    """:func:`pose_terms` and the model's ``node_placements`` of one checked pose (nv,).

    One kinematics pass serves both (the frame placements follow from the joint placements
    the Jacobians were computed with).

    Args:
        arm: The flexible model.
        q: Joint coordinates (nv,) in the user convention [rad or m], already checked by
            :func:`pinflex.checks.check_q` (not validated again).
        data: Workspace (default: this thread's).

    Returns:
        ``(terms, placements)``: :class:`PoseTerms` with leading axis 1 and
        ``{link: NodePlacement}`` as ``node_placements``.
    """
    ws = arm.workspace(data)
    if not arm.nv:
        return pose_terms(arm, q[None], ws), arm.node_placements(q, data=ws)
    terms = pose_terms_one(arm, q, ws)
    pin.updateFramePlacements(arm.model, ws.pin)
    return terms, placements(arm, ws.pin)


def root_twists(model, terms: PoseTerms, alg: Algebra) -> dict[str, np.ndarray | None]:
    """Elastic twist of every link root in link axes.

    Args:
        model: The flexible model.
        terms: Pose terms of ``b`` poses (:func:`pinflex.erls.kinematics.pose_terms`) or
            their jets.
        alg: The algebra of the leading axis (:class:`BatchAlgebra` for poses).

    Returns:
        ``{link: (b, 6, nx) array}``, or None for a link whose root does not move
        elastically; linear in the elastic coordinates ``x``.
    """
    return propagate_root_twists(model.plan, terms, alg,
                                 lambda k, j, e: twist_at(alg, j.attach, e))
