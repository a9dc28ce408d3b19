"""Pinocchio kinematics of a flexible model: frame Jacobians, joint rotations and offsets.

:func:`pose_terms` serves many poses (rotations by Rodrigues' formula, batched);
:func:`pose_terms_one` one pose in one Pinocchio pass (rotations read from it). Both write the
Pinocchio ``Data`` of the workspace they are given, never the model.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pinflex.erls.terms import PoseTerms
from pinflex.erls.workspace import FlexibleData


def pose_terms(arm, Q: np.ndarray, data: FlexibleData) -> PoseTerms:
    """:meth:`pinflex.erls.FlexibleModel.pose_terms` of checked poses Q (n, nv)."""
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


def pose_terms_one(arm, q: np.ndarray, data: FlexibleData) -> PoseTerms:
    """:meth:`pinflex.erls.FlexibleModel.pose_terms_one` of one checked pose (nv,)."""
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
