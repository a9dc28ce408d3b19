"""Parsing annotated URDF text into a :class:`RobotDescription`."""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from pinflex import beam
from pinflex.description.overlay import apply_overlay, resolve_base
from pinflex.description.types import (
    _NS,
    MOVING_JOINTS,
    SUPPORTED_JOINTS,
    FlexibleLink,
    Joint,
    JointAnnotation,
    PointMass,
    RigidInertia,
    RobotDescription,
)
from pinflex.exceptions import (
    InvalidBeamProperty,
    InvalidDescription,
    JointNotFound,
    LinkNotFound,
    UnsupportedJoint,
)


def load(path: str | Path) -> RobotDescription:
    """Read an annotated URDF file or a pinflex overlay (see :func:`apply_overlay`)."""
    path = Path(path)
    if not path.is_file():
        raise InvalidDescription(f"URDF file '{path}' does not exist")
    text = path.read_text()
    try:
        root_el = ET.fromstring(text)
    except ET.ParseError as exc:
        raise InvalidDescription(f"'{path}' is not well-formed XML: {exc}") from exc
    if root_el.tag == _NS + "overlay":
        base = resolve_base(root_el.get("base", ""), path.parent)
        return parse(apply_overlay(base.read_text(), root_el), base_dir=base.parent)
    return parse(text, base_dir=path.parent)


def parse(urdf_xml: str, base_dir: Path | None = None) -> RobotDescription:
    """Parse URDF text with pinflex annotations."""
    try:
        root_el = ET.fromstring(urdf_xml)
    except ET.ParseError as exc:
        raise InvalidDescription(f"the URDF is not well-formed XML: {exc}") from exc
    if root_el.tag != "robot":
        raise InvalidDescription(f"the URDF's root element is <{root_el.tag}>, expected <robot>")
    links = tuple(el.get("name") for el in root_el.findall("link"))
    inertias = {}
    for el in root_el.findall("link"):
        inertial = el.find("inertial")
        if inertial is not None:
            inertias[el.get("name")] = _parse_inertial(el.get("name"), inertial)
    joints: dict[str, Joint] = {}
    for el in root_el.findall("joint"):
        j = _parse_joint(el, links)
        joints[j.name] = j
    child_joints: dict[str, list[str]] = {name: [] for name in links}
    parent_joint: dict[str, str] = {}
    for j in joints.values():
        child_joints[j.parent].append(j.name)
        if j.child in parent_joint:
            raise InvalidDescription(f"link '{j.child}' has two parent joints")
        parent_joint[j.child] = j.name
    roots = [name for name in links if name not in parent_joint]
    if len(roots) != 1:
        raise InvalidDescription(f"the URDF must have exactly one root link, found {roots}")
    flexible = {}
    for el in root_el.findall(_NS + "flexible"):
        f = _parse_flexible(el, links, joints, child_joints, parent_joint)
        if f.link in flexible:
            raise InvalidDescription(f"link '{f.link}' is declared flexible twice")
        flexible[f.link] = f
    point_masses = []
    for el in root_el.findall(_NS + "point_mass"):
        point_masses.append(_parse_point_mass(el, links))
    names = [p.name for p in point_masses]
    if len(set(names)) != len(names):
        raise InvalidDescription(f"point mass names must be unique, got {names}")
    annotations: dict[str, JointAnnotation] = {}
    for el in root_el.findall(_NS + "joint"):
        a = _parse_joint_annotation(el, joints)
        if a.name in annotations:
            raise InvalidDescription(f"joint '{a.name}' has two <pinflex:joint> elements")
        annotations[a.name] = a
    absolute = False
    for el in root_el.findall(_NS + "coordinates"):
        conv = el.get("convention", "relative")
        if conv not in ("relative", "absolute"):
            raise InvalidDescription(
                f"<pinflex:coordinates convention='{conv}'>: expected 'relative' or 'absolute'"
            )
        absolute = conv == "absolute"
    return RobotDescription(
        name=root_el.get("name", "robot"),
        urdf_xml=urdf_xml,
        base_dir=base_dir,
        root=roots[0],
        links=links,
        joints=joints,
        inertias=inertias,
        flexible=flexible,
        point_masses=tuple(point_masses),
        absolute_coordinates=absolute,
        child_joints={k: tuple(v) for k, v in child_joints.items()},
        parent_joint=parent_joint,
        joint_annotations=annotations,
    )


def _vec(text: str | None, default: str, what: str) -> np.ndarray:
    try:
        out = np.array([float(t) for t in (text or default).split()])
    except ValueError as exc:
        raise InvalidDescription(f"{what}: '{text}' is not a list of numbers") from exc
    if out.shape != (3,) or not np.all(np.isfinite(out)):
        raise InvalidDescription(f"{what}: expected three finite numbers, got '{text}'")
    return out


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrix of URDF roll-pitch-yaw angles (R = Rz(y) Ry(p) Rx(r))."""
    r, p, y = rpy
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    return np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )


def _origin(el: ET.Element | None, what: str) -> tuple[np.ndarray, np.ndarray]:
    if el is None:
        return np.zeros(3), np.eye(3)
    return _vec(el.get("xyz"), "0 0 0", what + " origin xyz"), rpy_matrix(
        _vec(el.get("rpy"), "0 0 0", what + " origin rpy")
    )


def _parse_inertial(link: str, el: ET.Element) -> RigidInertia:
    xyz, rot = _origin(el.find("origin"), f"link '{link}' inertial")
    mass_el, inertia_el = el.find("mass"), el.find("inertia")
    mass = float(mass_el.get("value", "0")) if mass_el is not None else 0.0
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    vals = {k: float(inertia_el.get(k, "0")) if inertia_el is not None else 0.0 for k in keys}
    inertia = np.array(
        [
            [vals["ixx"], vals["ixy"], vals["ixz"]],
            [vals["ixy"], vals["iyy"], vals["iyz"]],
            [vals["ixz"], vals["iyz"], vals["izz"]],
        ]
    )
    return RigidInertia(mass=mass, com=xyz, inertia=rot @ inertia @ rot.T)


def _parse_joint(el: ET.Element, links: tuple[str, ...]) -> Joint:
    name = el.get("name")
    jtype = el.get("type")
    if jtype not in SUPPORTED_JOINTS:
        raise UnsupportedJoint(
            f"joint '{name}' has type '{jtype}'; pinflex handles {', '.join(SUPPORTED_JOINTS)}"
        )
    parent = el.find("parent").get("link")
    child = el.find("child").get("link")
    for link in (parent, child):
        if link not in links:
            raise LinkNotFound(link, links)
    xyz, rot = _origin(el.find("origin"), f"joint '{name}'")
    axis_el = el.find("axis")
    axis = _vec(axis_el.get("xyz") if axis_el is not None else None, "1 0 0", f"joint '{name}'")
    norm = np.linalg.norm(axis)
    if jtype != "fixed" and norm == 0.0:
        raise InvalidDescription(f"joint '{name}' has a zero axis")
    axis = axis / norm if norm > 0 else axis
    lower, upper = -np.inf, np.inf
    limit = el.find("limit")
    if limit is not None and jtype in ("revolute", "prismatic"):
        lower = float(limit.get("lower", "-inf"))
        upper = float(limit.get("upper", "inf"))
    return Joint(name, jtype, parent, child, xyz, rot, axis, lower, upper)


def _float_attr(el: ET.Element, key: str, what: str, *, required: bool = True) -> float | None:
    text = el.get(key)
    if text is None:
        if required:
            raise InvalidBeamProperty(f"{what}: attribute '{key}' is missing")
        return None
    try:
        value = float(text)
    except ValueError as exc:
        raise InvalidBeamProperty(f"{what}: {key}='{text}' is not a number") from exc
    if not np.isfinite(value) or value <= 0.0:
        raise InvalidBeamProperty(f"{what}: {key}={text} must be a positive finite number")
    return value


def _parse_section(el: ET.Element | None, what: str) -> beam.Section:
    if el is None:
        raise InvalidBeamProperty(f"{what}: <pinflex:section> is missing")
    shape = el.get("shape")
    what = what + " section"
    if shape is None:
        vals = {k: _float_attr(el, k, what) for k in ("A", "Iy", "Iz", "J")}
        return beam.Section(**vals)
    if shape == "solid_circle":
        return beam.solid_circle(_float_attr(el, "diameter", what))
    if shape == "hollow_circle":
        outer = _float_attr(el, "outer_diameter", what)
        inner_text = el.get("inner_diameter", "0")
        return beam.hollow_circle(outer, float(inner_text))
    if shape == "rectangle":
        return beam.rectangle(_float_attr(el, "width", what), _float_attr(el, "height", what))
    raise InvalidBeamProperty(
        f"{what}: unknown shape '{shape}'; use solid_circle, hollow_circle, rectangle or "
        "explicit A, Iy, Iz, J"
    )


def _parse_flexible(el, links, joints, child_joints, parent_joint) -> FlexibleLink:
    link = el.get("link")
    if link is None:
        raise InvalidDescription("<pinflex:flexible> needs a 'link' attribute")
    if link not in links:
        raise LinkNotFound(link, links)
    what = f"flexible link '{link}'"
    try:
        elements = int(el.get("elements", ""))
    except ValueError as exc:
        raise InvalidBeamProperty(
            f"{what}: 'elements' must be a positive integer, got '{el.get('elements')}'"
        ) from exc
    if elements < 1:
        raise InvalidBeamProperty(f"{what}: 'elements' must be >= 1, got {elements}")
    if el.get("tip") is not None:
        tip = _vec(el.get("tip"), "", what + " tip")
    else:
        children = child_joints[link]
        if len(children) != 1:
            raise InvalidBeamProperty(
                f"{what}: has {len(children)} child joints, so the beam end is ambiguous; "
                "give it as tip=\"x y z\" in the link frame"
            )
        tip = joints[children[0]].xyz.copy()
    length = float(np.linalg.norm(tip))
    if length <= 1e-9:
        raise InvalidBeamProperty(
            f"{what}: the beam has zero length (tip {tip.tolist()} in the link frame); give a "
            "tip point away from the link origin"
        )
    xdir = tip / length
    normal = _default_normal(xdir, joints.get(parent_joint.get(link, ""), None))
    if el.get("normal") is not None:
        normal = _vec(el.get("normal"), "", what + " normal")
    normal = normal - xdir * (normal @ xdir)
    if np.linalg.norm(normal) < 1e-9:
        raise InvalidBeamProperty(f"{what}: the normal vector is parallel to the beam axis")
    normal /= np.linalg.norm(normal)
    mat = el.find(_NS + "material")
    if mat is None:
        raise InvalidBeamProperty(f"{what}: <pinflex:material> is missing")
    section = _parse_section(el.find(_NS + "section"), what)
    E = _float_attr(mat, "E", what + " material")
    G = _float_attr(mat, "G", what + " material", required=False)
    if G is None:
        nu = float(mat.get("poisson", "0.3"))
        if not -1.0 < nu < 0.5:
            raise InvalidBeamProperty(f"{what}: poisson = {nu} must lie in (-1, 0.5)")
        G = E / (2.0 * (1.0 + nu))
    density = _float_attr(mat, "density", what + " material", required=False)
    linear = _float_attr(mat, "linear_density", what + " material", required=False)
    if (density is None) == (linear is None):
        raise InvalidBeamProperty(
            f"{what}: give exactly one of density [kg/m^3] or linear_density [kg/m]"
        )
    rho = density if density is not None else linear / section.A
    return FlexibleLink(
        link=link,
        elements=elements,
        tip=tip,
        normal=normal,
        E=E,
        G=G,
        rhoA=rho * section.A,
        rhoIp=rho * section.Ip,
        section=section,
    )


def _default_normal(xdir: np.ndarray, parent: Joint | None) -> np.ndarray:
    if parent is not None and parent.type in ("revolute", "continuous"):
        # the parent joint axis expressed in the link frame (the joint frame is the link frame)
        if abs(parent.axis @ xdir) < 1e-9:
            return parent.axis.copy()
    return np.eye(3)[int(np.argmin(np.abs(xdir)))]


def _parse_point_mass(el: ET.Element, links: tuple[str, ...]) -> PointMass:
    name = el.get("name")
    if not name:
        raise InvalidDescription("<pinflex:point_mass> needs a 'name'")
    link = el.get("link")
    if link not in links:
        raise LinkNotFound(link, links)
    what = f"point mass '{name}'"
    xyz = _vec(el.get("xyz"), "0 0 0", what + " xyz")
    try:
        mass = float(el.get("mass", "0"))
    except ValueError as exc:
        raise InvalidBeamProperty(f"{what}: mass='{el.get('mass')}' is not a number") from exc
    if not np.isfinite(mass) or mass < 0.0:
        raise InvalidBeamProperty(f"{what}: mass = {mass} must be a finite number >= 0 [kg]")
    design = el.get("design", "false").lower() in ("1", "true", "yes")
    lower = float(el.get("lower", "0"))
    upper = float(el.get("upper", "inf"))
    if design and not lower <= upper:
        raise InvalidDescription(f"{what}: lower bound {lower} is above upper bound {upper}")
    if design and lower < 0.0:
        raise InvalidDescription(f"{what}: lower bound {lower} would allow a negative mass")
    return PointMass(name, link, xyz, mass, design, lower, upper)


def _parse_joint_annotation(el: ET.Element, joints: dict[str, Joint]) -> JointAnnotation:
    name = el.get("name")
    if not name:
        raise InvalidDescription("<pinflex:joint> needs a 'name' (a moving URDF joint)")
    moving = [n for n, j in joints.items() if j.type in MOVING_JOINTS]
    if name not in moving:
        raise JointNotFound(name, moving)
    what = f"<pinflex:joint name='{name}'>"
    locked_text = el.get("locked", "false").lower()
    if locked_text not in ("1", "true", "yes", "0", "false", "no"):
        raise InvalidDescription(f"{what}: locked='{el.get('locked')}' must be true or false")
    locked = locked_text in ("1", "true", "yes")
    stiffness = _float_attr(el, "stiffness", what, required=False)
    if locked and stiffness is not None:
        raise InvalidDescription(
            f"{what}: give either stiffness=\"...\" (a spring) or locked=\"true\", not both"
        )
    return JointAnnotation(name, stiffness, locked)
