"""Rigid-body inertias the modal model uses, and a Pinocchio model carrying them.

A :class:`~pinflex.FlexibleModel` keeps the Pinocchio model it parsed (``arm.model``) with the
URDF inertias of every link. The modal model replaces the inertial of each flexible link by its
beam's mass (UR5 upper arm from example-robot-data: 8.39 kg in the URDF, 1.53 kg for the aluminium
tube of ``urdf/ur5_flexible.xml``), and adds point masses. The functions here give the
inertias the modal model actually uses.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pinflex.checks import check_y
from pinflex.native.urdf import inertia_from_spatial


def beam_spatial_inertia(plan) -> np.ndarray:
    """6x6 spatial inertia (linear, angular) at the link origin of a beam's rigid motion.

    ``Jᵀ M J`` with ``M`` the beam's consistent mass matrix and ``J`` the map from a link twist
    to the beam's nodal dofs: the kinetic energy of the beam moving rigidly with its link.
    """
    return plan.jac.T @ plan.mass @ plan.jac


def effective_inertias(arm) -> dict[str, pin.Inertia]:
    """``{flexible link: pin.Inertia}`` of the beams at the link origin in link axes."""
    return {link: inertia_from_spatial(beam_spatial_inertia(p))
            for link, p in arm.plan.beams.items()}


def effective_model(arm, y=None, *, point_masses: bool = True) -> pin.Model:
    """Copy of ``arm.model`` with beam inertias on flexible links, its bodies (the URDF
    inertia beam links keep, ``<pinflex:body>``) and point masses.

    Args:
        arm: The flexible model.
        y: Design values [kg] for design point masses (default: nominal).
        point_masses: Add the point masses (at their values) to the links carrying them.

    Returns:
        A ``pinocchio.Model`` whose joint-space mass matrix ``pin.crba`` equals the rigid block
        ``M[nx:, nx:]`` of the modal model at the same pose (relative coordinates).
    """
    model = arm.model.copy()
    desc = arm.description

    def add(link: str, inertia: pin.Inertia, sign: float = 1.0) -> None:
        f = model.frames[model.getFrameId(link, pin.FrameType.BODY)]
        moved = np.array(f.placement.act(inertia).matrix())
        j = f.parentJoint
        total = np.array(model.inertias[j].matrix()) + sign * moved
        model.inertias[j] = inertia_from_spatial(total)

    for link, inertia in effective_inertias(arm).items():
        urdf = desc.inertias.get(link)
        if urdf is not None and urdf.mass > 0.0:
            add(link, pin.Inertia(urdf.mass, urdf.com, urdf.inertia), -1.0)
        add(link, inertia)
    for body in desc.bodies:  # kept URDF inertias and <pinflex:body> elements
        add(body.link, pin.Inertia(body.mass, np.asarray(body.com), np.asarray(body.inertia)))
    if point_masses:
        values = dict(arm.point_mass_values)
        yv = check_y(arm, y)
        for d, v in zip(arm.design, np.atleast_1d(yv)):
            values[d.name] = float(v)
        for p in desc.point_masses:
            if values[p.name] > 0.0:
                add(p.link, pin.Inertia(values[p.name], np.asarray(p.xyz), np.zeros((3, 3))))
    return model
