r"""Exact derivatives of a lumped arm's mass matrix with respect to its hinge stations.

In world axes at a pose, with every joint's spatial axis :math:`S_k = (o_k \times a_k, a_k)`
(prismatic: :math:`(a_k, 0)`) and the bodies' spatial inertias :math:`I_b`,
:math:`M_{kl} = S_k^T I^c_{kl} S_l`, :math:`I^c_{kl}` the composite inertia of the deeper of
the two joints' subtrees (zero when neither joint supports the other).

At rest every hinge angle is zero, so each flexible link is straight. Moving the station
:math:`s_h` of a link by :math:`\delta` along its world axis :math:`e` then changes exactly two
things, everything else staying where it is in the world:

* the hinges at that station move: :math:`\partial S_k / \partial s_h = (e \times a_k, 0)`;
* the slice of beam at :math:`s_h` passes from segment h to segment h−1: the segment bodies
  change by :math:`\pm\iota`, the beam's spatial inertia per length at :math:`s_h` (a point
  mass :math:`\rho A` and, in 3-D, the section's rotary inertia about the beam axes).

Hence :math:`\partial M/\partial s_h = \partial S^T I^c S + S^T I^c \partial S
+ J_{h-1}^T \iota J_{h-1} - J_h^T \iota J_h`, with :math:`J_j` the Jacobian of segment j's
body. ``tests/test_lumped_fit.py`` checks M against Pinocchio's CRBA and the derivative
against central differences of rebuilt models.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pinflex.lumped.model import LumpedArm


@dataclass(frozen=True)
class PoseGeometry:
    """World quantities of a lumped arm at one pose (hinges at rest).

    Attributes:
        S: Spatial joint axes in world axes at the world origin (6, nv), (linear, angular).
        composite: Composite inertia of the deeper joint of every related pair
            (nv, nv, 6, 6); zero for unrelated pairs.
        support: ``support[j]`` boolean mask (nv,) of the joints supporting joint id j.
        oMi: World placement of every joint (njoints).
    """

    S: np.ndarray
    composite: np.ndarray
    support: np.ndarray
    oMi: list


def pose_geometry(lumped: LumpedArm, q) -> PoseGeometry:
    """World axes, composite inertias and supports of the lumped arm at arm pose ``q``."""
    model = lumped.model
    data = lumped._pin_data()
    qc = lumped.configuration(q)
    pin.computeJointJacobians(model, data, qc)
    S = np.array(data.J)
    nj, nv = model.njoints, model.nv
    body = np.zeros((nj, 6, 6))
    for j in range(1, nj):
        body[j] = data.oMi[j].act(model.inertias[j]).matrix()
    comp = body.copy()
    for j in range(nj - 1, 0, -1):
        comp[model.parents[j]] += comp[j]
    support = np.zeros((nj, nv), dtype=bool)
    vidx = np.array([model.joints[j].idx_v if j else -1 for j in range(nj)])
    pair = np.zeros((nv, nv, 6, 6))
    for j in range(1, nj):
        anc = [a for a in model.supports[j] if a > 0]
        support[j, vidx[anc]] = True
        vj = vidx[j]
        for a in anc:
            va = vidx[a]
            pair[va, vj] = comp[j]
            pair[vj, va] = comp[j]
    return PoseGeometry(S, pair, support, [pin.SE3(m) for m in data.oMi])


def mass_from_geometry(geo: PoseGeometry, armature: np.ndarray) -> np.ndarray:
    """``M`` (nv, nv) from the world form (equals CRBA plus armature)."""
    M = np.einsum("ak,klab,bl->kl", geo.S, geo.composite, geo.S)
    M[np.diag_indices_from(M)] += armature
    return 0.5 * (M + M.T)


def _slice_inertia(beam, point: np.ndarray, axes: np.ndarray, planar: bool) -> np.ndarray:
    """Spatial inertia per length of the beam at a world point; ``axes`` the beam axes."""
    if planar:  # no rotation but about the normal, where segments carry no rotary term
        return pin.Inertia(beam.rhoA, point, np.zeros((3, 3))).matrix()
    rot = (beam.rhoIp * np.outer(axes[:, 0], axes[:, 0])
           + beam.rhoI[0] * np.outer(axes[:, 1], axes[:, 1])
           + beam.rhoI[1] * np.outer(axes[:, 2], axes[:, 2]))
    return pin.Inertia(beam.rhoA, point, rot).matrix()


def station_derivatives(lumped: LumpedArm, geo: PoseGeometry) -> dict[tuple[str, int], np.ndarray]:
    """``∂M/∂s_h`` (nv, nv) [kg m] of every hinge station ``(link, h)`` at the pose of ``geo``."""
    out = {}
    model = lumped.model
    S, comp = geo.S, geo.composite
    for (link, h), ids in lumped.hinge_ids.items():
        beam = lumped.layout.beams[link]
        first = lumped.segment_ids[(link, 0)]
        seg = lumped.segments[link]
        jid0, frame0 = lumped.frames[link]
        oMlink = geo.oMi[jid0] * frame0
        axes = oMlink.rotation @ beam.rotation
        e = axes[:, 0]
        point = oMlink.translation + seg.stations_m[h - 1] * e
        dS = np.zeros_like(S)
        for jid in ids:
            v = model.joints[jid].idx_v
            dS[:3, v] = np.cross(e, S[3:, v])
        dM = np.einsum("ak,klab,bl->kl", dS, comp, S)
        dM = dM + dM.T
        iota = _slice_inertia(beam, point, axes, lumped.layout.planar)
        before = lumped.segment_ids[(link, h - 1)] if h > 1 else first
        after = lumped.segment_ids[(link, h)]
        Jb = S * geo.support[before][None, :]
        Ja = S * geo.support[after][None, :]
        dM += Jb.T @ iota @ Jb - Ja.T @ iota @ Ja
        out[(link, h)] = 0.5 * (dM + dM.T)
    return out
