"""What a lumped model needs from a flexible arm: its tree, beams, masses and joint conditions.

:func:`layout_of` reads a :class:`~pinflex.erls.FlexibleModel` through its public API (the
plan, the joint conditions, the point-mass values, the coordinate map) once; everything in
:mod:`pinflex.lumped` after that works on the plain :class:`ArmLayout`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np
import pinocchio as pin

#: Hinge axes of a segment joint, in the beam axes (x along the beam, z the beam normal):
#: ``bz`` bending about z (in the plane of a planar arm), ``by`` bending about y, ``tx``
#: torsion about the beam axis, ``ax`` (optional) an axial spring: a slide along the beam axis.
AXIS_VECTORS = MappingProxyType({
    "bz": np.array([0.0, 0.0, 1.0]),
    "by": np.array([0.0, 1.0, 0.0]),
    "tx": np.array([1.0, 0.0, 0.0]),
    "ax": np.array([1.0, 0.0, 0.0]),
})
PLANAR_AXES = ("bz",)
SPATIAL_AXES = ("bz", "by", "tx")
#: Axes whose joint is a slide (the others are hinges).
SLIDE_AXES = ("ax",)


@dataclass(frozen=True)
class BeamData:
    """A flexible link's straight uniform beam.

    Attributes:
        link: Link name.
        length_m: Beam length L [m].
        rotation: Beam axes in the link frame, columns (x along the beam, y, z normal) (3, 3).
        rigidity: Rigidities by hinge axis name (see :data:`AXIS_VECTORS`): ``bz`` EI_z,
            ``by`` EI_y, ``tx`` GJ [N m^2], ``ax`` EA [N].
        rhoA: Mass per length [kg/m].
        rhoIp: Torsional rotary inertia per length [kg m].
        rhoI: Rotary inertia per length of the section about the beam's y and z axes
            ``(ρI_y, ρI_z)`` [kg m].
        radius_m: Radius of a circle of the section's area, for drawing [m].
        elements: Element count of the arm's finite-element beam (for reports).
    """

    link: str
    length_m: float
    rotation: np.ndarray
    rigidity: Mapping[str, float]
    rhoA: float
    rhoIp: float
    rhoI: tuple[float, float]
    radius_m: float
    elements: int


@dataclass(frozen=True)
class ArmJoint:
    """A moving joint of the arm and its condition in the lumped model.

    Attributes:
        name: Joint name.
        kind: 'revolute' or 'prismatic' ('continuous' URDF joints are revolute here).
        continuous: Whether the URDF joint is continuous (no limits).
        condition: 'free', 'spring' or 'locked'.
        stiffness: Spring stiffness [N m/rad or N/m]; 0 when free, ``inf`` when locked.
        damping: Joint damping [N m s/rad or N s/m] (0 unless the arm declares it).
        armature: Rotor inertia on the joint [kg m^2 or kg] (0 unless the arm declares it).
        lower: Lower limit [rad or m] (-inf when absent).
        upper: Upper limit [rad or m] (+inf when absent).
    """

    name: str
    kind: str
    continuous: bool
    condition: str
    stiffness: float
    damping: float = 0.0
    armature: float = 0.0
    lower: float = -np.inf
    upper: float = np.inf


@dataclass(frozen=True)
class JointData:
    """A URDF joint as seen from its child link.

    Attributes:
        name: Joint name.
        parent: Parent link.
        child: Child link.
        kind: 'revolute', 'prismatic' or 'fixed'.
        placement: Joint frame in the parent link frame.
        axis: Unit axis in the joint frame (3,).
    """

    name: str
    parent: str
    child: str
    kind: str
    placement: pin.SE3
    axis: np.ndarray


@dataclass(frozen=True)
class ArmLayout:
    """Plain description of a flexible arm for lumping.

    Attributes:
        name: Robot name.
        planar: Whether the arm is modelled in its plane (one bending hinge per station).
        links: Links breadth-first from the root.
        joints: Joints by child link.
        beams: Flexible links' beams ``{link: BeamData}``.
        inertias: Rigid bodies ``{link: pin.Inertia}`` at the link frame (rigid links' URDF
            inertias, and any rigid body a flexible link carries besides its beam).
        point_masses: ``(name, link, xyz (3,) [m], mass [kg])`` tuples.
        bodies: ``(name, link, pin.Inertia at the link frame)`` of the rigid bodies with full
            inertia a flexible link carries (``<pinflex:body>``, kept URDF inertia): each rides
            on the segment holding its centre of mass, as the ERLS model moves it with the
            cross-section there.
        arm_joints: Moving joints in the arm's joint order (``FlexibleModel.joint_names``).
        coord_map: ``C`` (nv, nv): relative joint values ``= C q_user``.
        axial: Whether each station also has an axial spring (a slide along the beam).
    """

    name: str
    planar: bool
    links: tuple[str, ...]
    joints: Mapping[str, JointData]
    beams: Mapping[str, BeamData]
    inertias: Mapping[str, pin.Inertia]
    point_masses: tuple[tuple[str, str, np.ndarray, float], ...]
    arm_joints: tuple[ArmJoint, ...]
    coord_map: np.ndarray
    axial: bool = False
    bodies: tuple[tuple[str, str, pin.Inertia], ...] = ()

    @property
    def axes(self) -> tuple[str, ...]:
        """Joint axes per station.

        ``('bz',)`` planar, ``('bz', 'by', 'tx')`` spatial, then ``'ax'`` with axial springs.
        """
        return (PLANAR_AXES if self.planar else SPATIAL_AXES) + (("ax",) if self.axial else ())


def inertia_from_spatial(matrix: np.ndarray) -> pin.Inertia:
    """``pin.Inertia`` of a (6, 6) spatial inertia at a frame origin, (linear, angular) order."""
    mass = float(matrix[0, 0])
    if mass <= 0.0:
        return pin.Inertia.Zero()
    cx = matrix[3:, :3] / mass
    com = np.array([cx[2, 1], cx[0, 2], cx[1, 0]])
    inertia_o = matrix[3:, 3:]
    inertia_c = inertia_o + mass * (cx @ cx)
    return pin.Inertia(mass, com, 0.5 * (inertia_c + inertia_c.T))


def _joint_extras(arm, name: str) -> tuple[float, float]:
    """(damping, armature) the arm declares on a joint, 0 where it declares none."""
    damping = armature = 0.0
    for cond in arm.joint_conditions:
        if cond.name == name:
            damping = float(getattr(cond, "damping", 0.0) or 0.0)
            armature = float(getattr(cond, "armature", 0.0) or 0.0)
    note = arm.description.joint_annotations.get(name)
    if note is not None:
        damping = damping or float(getattr(note, "damping", 0.0) or 0.0)
        armature = armature or float(getattr(note, "armature", 0.0) or 0.0)
    return damping, armature


def layout_of(arm, *, axial: bool = False) -> ArmLayout:
    """Read what lumping needs from a flexible arm, through its public API.

    Args:
        arm: A :class:`~pinflex.erls.FlexibleModel`.
        axial: Give every station an axial spring as well (the ERLS beams stretch; rigid
            segments alone do not).

    Returns:
        The arm's :class:`ArmLayout` (point masses at their current values).
    """
    plan = arm.plan
    desc = arm.description
    joints = {}
    for jp in plan.joints:
        joints[jp.child] = JointData(jp.name, jp.parent, jp.child, jp.kind,
                                     pin.SE3(np.array(jp.R_o), np.array(jp.xyz)),
                                     np.array(jp.axis, dtype=float))
    beams = {}
    for link, bp in plan.beams.items():
        spec = bp.spec
        sec = spec.section
        beams[link] = BeamData(
            link=link, length_m=spec.length_m, rotation=np.array(spec.rotation),
            rigidity=MappingProxyType({"bz": spec.E * sec.Iz, "by": spec.E * sec.Iy,
                                       "tx": spec.G * sec.J, "ax": spec.E * sec.A}),
            rhoA=float(spec.rhoA), rhoIp=float(spec.rhoIp),
            rhoI=(float(spec.rhoIp * sec.Iy / (sec.Iy + sec.Iz)),
                  float(spec.rhoIp * sec.Iz / (sec.Iy + sec.Iz))),
            radius_m=float(np.sqrt(sec.A / np.pi)), elements=int(spec.elements))
    inertias = {link: inertia_from_spatial(np.asarray(m)) for link, m in plan.inertias.items()}
    values = arm.point_mass_values
    point_masses = tuple((p.name, p.link, np.array(p.xyz, dtype=float), float(values[p.name]))
                         for p in plan.point_masses)
    bodies = tuple((b.name, b.link, pin.SE3(np.eye(3), np.array(b.xyz, dtype=float)).act(
        inertia_from_spatial(np.asarray(b.inertia)))) for b in getattr(plan, "bodies", ()))
    conds = {c.name: c for c in arm.joint_conditions}
    arm_joints = []
    for name in arm.joint_names:
        jd = desc.joints[name]
        cond = conds[name]
        damping, armature = _joint_extras(arm, name)
        arm_joints.append(ArmJoint(
            name=name, kind="prismatic" if jd.type == "prismatic" else "revolute",
            continuous=jd.type == "continuous", condition=cond.kind,
            stiffness=float(cond.stiffness), damping=damping, armature=armature,
            lower=float(jd.lower), upper=float(jd.upper)))
    return ArmLayout(
        name=desc.name, planar=bool(arm.planar), links=tuple(plan.links),
        joints=MappingProxyType(joints), beams=MappingProxyType(beams),
        inertias=MappingProxyType(inertias), point_masses=point_masses,
        arm_joints=tuple(arm_joints), coord_map=np.array(arm.coord_map, dtype=float),
        axial=bool(axial), bodies=bodies)
