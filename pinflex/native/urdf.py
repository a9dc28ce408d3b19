"""URDF text of a Pinocchio model kept in memory.

A ``pin.Model`` has no URDF attached to it. :func:`urdf_from_model` writes one that Pinocchio
parses back into the same kinematic tree with the same inertias, so that the rest of pinflex
(which reads a description, see :mod:`pinflex.description`) can work on models that were built
in Python or loaded by another tool.

Links are the model's BODY frames; joints its moving joints plus its FIXED_JOINT frames.
Pinocchio merges the inertia of links attached through fixed joints into the moving joint that
carries them and keeps each such link's own inertia on its fixed-joint frame; the writer splits
them again, so each link gets back its own inertial. A joint without a BODY frame (a model
built by hand with ``addJoint``/``appendBodyToJoint``) gets a link named after the joint,
``<joint>_body``.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from pinflex.exceptions import ConfigurationError, UnsupportedJoint

_AXES = {"X": "1 0 0", "Y": "0 1 0", "Z": "0 0 1"}


def _num(v: float) -> str:
    return repr(float(v))


def _origin(parent: ET.Element, placement: pin.SE3) -> None:
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    ET.SubElement(
        parent,
        "origin",
        {
            "xyz": " ".join(_num(v) for v in placement.translation),
            "rpy": " ".join(_num(v) for v in rpy),
        },
    )


def _joint_kind(jm) -> tuple[str, np.ndarray]:
    """URDF type and axis of a one-dof Pinocchio joint."""
    short = jm.shortname()
    kinds = {
        "JointModelR": "revolute",
        "JointModelRUB": "continuous",
        "JointModelP": "prismatic",
    }
    for prefix, kind in kinds.items():
        if short[:-1] == prefix and short[-1] in _AXES:
            return kind, np.array([float(t) for t in _AXES[short[-1]].split()])
    unaligned = {
        "JointModelRevoluteUnaligned": "revolute",
        "JointModelRevoluteUnboundedUnaligned": "continuous",
        "JointModelPrismaticUnaligned": "prismatic",
    }
    if short in unaligned:
        return unaligned[short], np.array(jm.extract().axis, dtype=float)
    raise UnsupportedJoint(
        f"Pinocchio joint type {short} is not supported; pinflex handles revolute, continuous "
        "and prismatic joints (one degree of freedom each) on a fixed base"
    )


def _inertial(link: ET.Element, inertia: pin.Inertia) -> None:
    if inertia.mass <= 0.0:
        return
    el = ET.SubElement(link, "inertial")
    ET.SubElement(
        el, "origin", {"xyz": " ".join(_num(v) for v in inertia.lever), "rpy": "0 0 0"}
    )
    ET.SubElement(el, "mass", {"value": _num(inertia.mass)})
    I3 = inertia.inertia
    ET.SubElement(
        el,
        "inertia",
        {
            "ixx": _num(I3[0, 0]), "ixy": _num(I3[0, 1]), "ixz": _num(I3[0, 2]),
            "iyy": _num(I3[1, 1]), "iyz": _num(I3[1, 2]), "izz": _num(I3[2, 2]),
        },
    )


def _spatial(inertia: pin.Inertia) -> np.ndarray:
    return np.array(inertia.matrix())


def inertia_from_spatial(S: np.ndarray) -> pin.Inertia:
    """pin.Inertia of a 6x6 spatial inertia (linear, angular) at the frame origin."""
    m = float(S[0, 0])
    if m <= 1e-14 * max(1.0, float(np.abs(S).max())):
        return pin.Inertia.Zero()
    mc = S[3:, :3]  # m [c]x
    c = np.array([mc[2, 1], mc[0, 2], mc[1, 0]]) / m
    cx = pin.skew(c)
    return pin.Inertia(m, c, S[3:, 3:] + m * cx @ cx)


def link_names(model: pin.Model) -> tuple[str, dict[int, str]]:
    """Root link name and the link carried by each moving joint (by joint index)."""
    frames = model.frames
    root = "universe"
    for f in frames:
        if f.type == pin.FrameType.BODY and f.parentJoint == 0 and f.parentFrame == 0:
            root = f.name
            break
    child: dict[int, str] = {}
    for j in range(1, model.njoints):
        name = model.names[j]
        for fid, f in enumerate(frames):
            if f.type == pin.FrameType.JOINT and f.name == name and f.parentJoint == j:
                for g in frames:
                    if g.type == pin.FrameType.BODY and g.parentFrame == fid:
                        child[j] = g.name
                        break
                break
        if j not in child:
            for g in frames:
                if (
                    g.type == pin.FrameType.BODY
                    and g.parentJoint == j
                    and g.placement.isIdentity()
                ):
                    child[j] = g.name
                    break
        child.setdefault(j, f"{name}_body")
    return root, child


def urdf_from_model(model: pin.Model, name: str | None = None) -> str:
    """URDF text that Pinocchio parses into the same kinematic tree and inertias.

    Args:
        model: A fixed-base Pinocchio model with one-dof joints (revolute, continuous,
            prismatic, aligned or not).
        name: Robot name (default: ``model.name`` or ``"robot"``).

    Returns:
        The URDF text (no visual or collision geometry).

    Raises:
        UnsupportedJoint: A joint with more than one degree of freedom (free flyer, spherical,
            planar, ...) or a type without a URDF equivalent.
    """
    if not isinstance(model, pin.Model):
        raise ConfigurationError(
            f"expected a pinocchio.Model or RobotWrapper, got {type(model).__name__}"
        )
    tree = _Tree(model)
    robot = ET.Element("robot", {"name": name or model.name or "robot"})
    own, fixed = _own_inertias(model, tree)
    for link in tree.placement:
        el = ET.SubElement(robot, "link", {"name": link})
        if link in own:
            _inertial(el, inertia_from_spatial(own[link]))
    for j in range(1, model.njoints):
        _joint_element(robot, model, tree, j)
    for f, parent, kid in fixed:
        _fixed_joint(robot, f.name, parent, kid, tree.placement[parent].actInv(f.placement))
    # BODY frames added by hand without a fixed-joint frame: fixed to their joint's link
    reached = set(tree.body_of_joint.values()) | {kid for _, _, kid in fixed}
    for link in tree.placement:
        if link not in reached:
            _fixed_joint(robot, f"{link}_fixed", tree.body_of_joint[tree.joint_of[link]], link,
                         tree.placement[link])
    return ET.tostring(robot, encoding="unicode")


class _Tree:
    """Links of a Pinocchio model: the link of each joint, and every link's placement."""

    def __init__(self, model: pin.Model):
        self.root, self.child = link_names(model)
        self.body_of_joint = {0: self.root, **self.child}
        # the link of every BODY frame, its placement in its joint's frame and that joint
        self.placement: dict[str, pin.SE3] = {self.root: pin.SE3.Identity()}
        self.joint_of: dict[str, int] = {self.root: 0}
        for j, link in self.child.items():
            self.placement[link] = pin.SE3.Identity()
            self.joint_of[link] = j
        for f in model.frames:
            if f.type == pin.FrameType.BODY and f.name not in self.placement:
                self.placement[f.name] = f.placement
                self.joint_of[f.name] = f.parentJoint


def _own_inertias(model: pin.Model, tree: _Tree) -> tuple[dict[str, np.ndarray], list]:
    """Each link's own spatial inertia, and the fixed joints (frame, parent, child).

    A link behind a fixed joint keeps its inertia (on the fixed-joint frame); the moving
    joint's merged inertia gives it back.
    """
    frames = model.frames
    own: dict[str, np.ndarray] = {}
    merged = {j: _spatial(model.inertias[j]) for j in range(model.njoints)}
    fixed = []
    for fid, f in enumerate(frames):
        if f.type != pin.FrameType.FIXED_JOINT or fid == 0:
            continue
        parent = frames[f.parentFrame]
        kids = [g.name for g in frames if g.type == pin.FrameType.BODY and g.parentFrame == fid]
        if parent.type != pin.FrameType.BODY or len(kids) != 1:
            continue
        fixed.append((f, parent.name, kids[0]))
        own[kids[0]] = _spatial(f.inertia)
        merged[f.parentJoint] = merged[f.parentJoint] - _spatial(f.placement.act(f.inertia))
    for j, link in tree.body_of_joint.items():
        own[link] = merged[j]
    return own, fixed


def _joint_element(robot: ET.Element, model: pin.Model, tree: _Tree, j: int) -> None:
    """The ``<joint>`` of moving joint ``j``: origin, links, axis and limits."""
    frames = model.frames
    jm = model.joints[j]
    kind, axis = _joint_kind(jm)
    jframe = [f for f in frames if f.type == pin.FrameType.JOINT and f.name == model.names[j]]
    parent_link = tree.body_of_joint[model.parents[j]]
    if jframe and frames[jframe[0].parentFrame].type == pin.FrameType.BODY:
        parent_link = frames[jframe[0].parentFrame].name
    origin = tree.placement[parent_link].actInv(model.jointPlacements[j])
    el = ET.SubElement(robot, "joint", {"name": model.names[j], "type": kind})
    _origin(el, origin)
    ET.SubElement(el, "parent", {"link": parent_link})
    ET.SubElement(el, "child", {"link": tree.child[j]})
    ET.SubElement(el, "axis", {"xyz": " ".join(_num(v) for v in axis)})
    lim = {
        "effort": _num(model.effortLimit[jm.idx_v]),
        "velocity": _num(model.velocityLimit[jm.idx_v]),
    }
    if kind != "continuous":
        for key, value in (("lower", model.lowerPositionLimit[jm.idx_q]),
                           ("upper", model.upperPositionLimit[jm.idx_q])):
            if np.isfinite(value) and abs(value) < 1e300:
                lim[key] = _num(value)
    ET.SubElement(el, "limit", lim)


def _fixed_joint(robot: ET.Element, name: str, parent: str, child: str, origin: pin.SE3) -> None:
    el = ET.SubElement(robot, "joint", {"name": name, "type": "fixed"})
    _origin(el, origin)
    ET.SubElement(el, "parent", {"link": parent})
    ET.SubElement(el, "child", {"link": child})
