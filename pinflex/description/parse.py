"""Parsing annotated URDF text into a :class:`RobotDescription`."""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np

from pinflex import beam
from pinflex.description.checks import check_annotations, check_physical
from pinflex.description.overlay import apply_overlay, resolve_base
from pinflex.description.params import Resolver, parse_parameters
from pinflex.description.schema import MAX_ELEMENTS_PER_LINK, Checked, attribute_unit
from pinflex.description.source import input_path, parse_xml, read_text
from pinflex.description.types import (
    _NS,
    MOVING_JOINTS,
    SUPPORTED_JOINTS,
    FlexibleLink,
    Joint,
    JointAnnotation,
    PointMass,
    RigidBody,
    RigidInertia,
    RobotDescription,
)
from pinflex.description.urdf_checks import check_urdf
from pinflex.exceptions import (
    InvalidBeamProperty,
    InvalidDescription,
    JointNotFound,
    LinkNotFound,
    UnreadableFile,
    UnsupportedJoint,
)
from pinflex.sections import SHAPES, PropertyInputs, beam_properties
from pinflex.fields import split_vector
from pinflex.validation import parse_number, raise_problems


def load(path: str | Path, values: dict[str, float] | None = None, *,
         plausibility: str = "refuse", allow_paths: bool = False) -> RobotDescription:
    """Read an annotated URDF file or a pinflex overlay (see :func:`apply_overlay`).

    Every annotation is checked against :mod:`pinflex.description.schema` first (file, line,
    element and attribute of every problem, in one error).

    Args:
        path: The file.
        values: Overrides of ``<pinflex:parameter>`` values (checked against their bounds).
        plausibility: 'refuse' values that are non-physical for a robot link (default), or
            only 'warn' about them (impossible values are refused either way).
        allow_paths: Read an overlay's base URDF and the meshes of the visual geometry
            from anywhere; by default they must lie in the file's folder (or the base URDF's,
            for its meshes) or in example-robot-data (:class:`UnsafePath` otherwise).
    """
    from pinflex.validation import require_bool

    allow_paths = require_bool(allow_paths, "allow_paths")
    path = input_path(path, "URDF file", UnreadableFile)
    values = check_values(values)
    text = read_text(path, "URDF file")
    doc = parse_xml(text, str(path))
    if doc.root.tag == _NS + "overlay":
        checked, problems = check_annotations(doc, plausibility=plausibility, raise_now=False,
                                              values=values)
        raise_problems(str(path), problems, " in the overlay")
        base = resolve_base(doc.root.get("base", ""), path.parent, allow_paths=allow_paths)
        flexible = frozenset(el.get("link", "") for el in doc.root.findall(_NS + "flexible"))
        base_text, base_problems = _checked_base(base, flexible, plausibility)
        raise_problems(str(base), list(base_problems))
        merged = apply_overlay(base_text, doc.root)
        return _build(ET.fromstring(merged), merged, base.parent, values, str(path), checked,
                      plausibility, allow_paths)
    return parse(text, base_dir=path.parent, values=values, source=str(path),
                 plausibility=plausibility, allow_paths=allow_paths)


def check_values(values) -> dict[str, float] | None:
    """Parameter and point-mass overrides as ``{name: float}``; anything else refused by name."""
    if values is None:
        return None
    from pinflex.exceptions import ConfigurationError
    from pinflex.validation import require_number

    if not isinstance(values, dict):
        raise ConfigurationError(f"values must be a dict {{name: number}}, got {values!r}")
    out = {}
    for name, value in values.items():
        if not isinstance(name, str):
            raise ConfigurationError(f"values: the name {name!r} is not a string")
        out[name] = require_number(value, f"values['{name}']")
    return out


def _checked_base(base: Path, flexible: frozenset, plausibility: str):
    """Text and problems of an overlay's base URDF (cached while the file is unchanged)."""
    stat = base.stat()
    return _checked_base_cached(str(base), stat.st_mtime_ns, stat.st_size, flexible,
                                plausibility)


@functools.lru_cache(maxsize=16)
def _checked_base_cached(base: str, _mtime: int, _size: int, flexible: frozenset,
                         plausibility: str):
    base_text = read_text(base, "the overlay's base URDF")
    base_doc = parse_xml(base_text, base)
    _, problems = check_annotations(base_doc, plausibility=plausibility, raise_now=False)
    problems += check_urdf(base_doc, set(flexible), upstream=True, raise_now=False)
    return base_text, tuple(problems)


def parse(urdf_xml: str, base_dir: Path | None = None,
          values: dict[str, float] | None = None, *, source: str = "<string>",
          plausibility: str = "refuse", allow_paths: bool = False) -> RobotDescription:
    """Parse URDF text with pinflex annotations, checked as :func:`load` does.

    Args:
        urdf_xml: The URDF text.
        base_dir: Folder of the file, for relative mesh paths.
        values: Overrides of ``<pinflex:parameter>`` values by name (checked against the
            parameters' bounds; names that are not parameters are ignored here, they may be
            point masses set by :class:`pinflex.FlexibleModel`).
        source: Name of the text in messages.
        plausibility: 'refuse' (default) or 'warn' about non-physical values.
        allow_paths: Let the visual geometry read meshes outside ``base_dir`` and the
            package roots (see :func:`load`).
    """
    values = check_values(values)
    doc = parse_xml(urdf_xml, source)
    checked, problems = check_annotations(doc, plausibility=plausibility, raise_now=False,
                                          values=values)
    if doc.root.tag == "robot":
        flexible = {el.get("link", "") for el in doc.root.findall(_NS + "flexible")}
        problems += check_urdf(doc, flexible, raise_now=False)
    raise_problems(source, problems)
    return _build(doc.root, urdf_xml, base_dir, values, source, checked, plausibility,
                  allow_paths)


def _reparse(urdf_xml: str, base_dir: Path | None, source: str, plausibility: str,
             allow_paths: bool, values: dict) -> RobotDescription:
    """The description of the same text with other parameter values (its ``reparse``)."""
    return parse(urdf_xml, base_dir=base_dir, values=values, source=source,
                 plausibility=plausibility, allow_paths=allow_paths)


def _build(root_el: ET.Element, urdf_xml: str, base_dir: Path | None,
           values: dict[str, float] | None, source: str, checked: Checked,
           plausibility: str, allow_paths: bool = False) -> RobotDescription:
    if root_el.tag != "robot":
        raise InvalidDescription(f"the URDF's root element is <{root_el.tag}>, expected <robot>")
    params = parse_parameters(root_el, _NS, values)
    R = Resolver(params, attribute_unit)
    links = tuple(_name(el, "<link>") for el in root_el.findall("link"))
    inertias = {}
    for el in root_el.findall("link"):
        inertial = el.find("inertial")
        if inertial is not None:
            inertias[_name(el, "<link>")] = _parse_inertial(_name(el, "<link>"), inertial)
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
        f = _parse_flexible(el, links, joints, child_joints, parent_joint, R)
        if f.link in flexible:
            raise InvalidDescription(f"link '{f.link}' is declared flexible twice")
        flexible[f.link] = f
    bodies, notes = _kept_inertias(root_el, flexible, inertias)
    for el in root_el.findall(_NS + "body"):
        bodies.append(_parse_body(el, links, R))
    body_names = [b.name for b in bodies]
    if len(set(body_names)) != len(body_names):
        raise InvalidDescription(f"body names must be unique, got {body_names}")
    point_masses = []
    for el in root_el.findall(_NS + "point_mass"):
        point_masses.append(_parse_point_mass(el, links, R))
    names = [p.name for p in point_masses]
    if len(set(names)) != len(names):
        raise InvalidDescription(f"point mass names must be unique, got {names}")
    annotations: dict[str, JointAnnotation] = {}
    for el in root_el.findall(_NS + "joint"):
        a = _parse_joint_annotation(el, joints, R)
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
    desc = RobotDescription(
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
        parameters=R.finish(),
        values={k: float(v) for k, v in (values or {}).items() if k in params},
        bodies=tuple(bodies),
        inertia_notes=tuple(notes),
        allow_paths=bool(allow_paths),
        reparse=functools.partial(_reparse, urdf_xml, base_dir, source, plausibility,
                                  bool(allow_paths)),
    )
    check_physical(desc, checked, source, plausibility=plausibility)
    return desc


def _vec(text: str | None, default: str, what: str) -> np.ndarray:
    try:
        out = np.array([parse_number(t) for t in split_vector(text or default)])
    except ValueError as exc:
        raise InvalidDescription(f"{what}: {exc}") from exc
    if out.shape != (3,) or not np.all(np.isfinite(out)):
        raise InvalidDescription(f"{what}: expected three finite numbers, got '{text}'")
    return out


def rpy_matrix(rpy: np.ndarray) -> np.ndarray:
    """Rotation matrix of URDF roll-pitch-yaw angles (R = Rz(y) Ry(p) Rx(r)).

    Args:
        rpy: ``(roll, pitch, yaw)`` (3,) [rad] about the fixed x, y, z axes.

    Returns:
        Rotation matrix (3, 3).
    """
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


def _kept_inertias(root_el: ET.Element, flexible: dict, inertias: dict):
    """Bodies for the URDF inertia each beam link keeps, and one note per link.

    The beam's own inertia is taken at the file's nominal design (parameter values as
    written, before ``values=`` / ``--set``), so the kept part is the same for every design.
    """
    from pinflex.description.link_inertia import kept_link_inertia

    nominal = {n: p.value for n, p in parse_parameters(root_el, _NS, None).items()}
    bodies, notes = [], []
    for link, f in flexible.items():
        urdf = inertias.get(link)
        if urdf is None or urdf.mass <= 0.0:
            continue
        props = beam_properties(f.inputs, nominal.__getitem__) if f.inputs is not None else {
            "rhoA": f.rhoA, "rhoIp": f.rhoIp}
        body, note = kept_link_inertia(link, f.inertia, urdf, f.tip, f.rotation,
                                       float(props["rhoA"]), float(props["rhoIp"]))
        notes.append(note)
        if body is not None:
            mass, com, inertia = body
            bodies.append(RigidBody(f"{link}.urdf", link, com, mass, inertia,
                                    "urdf" if f.inertia == "keep" else "urdf excess"))
    return bodies, notes


def _parse_body(el: ET.Element, links: tuple[str, ...], R: Resolver) -> RigidBody:
    name = el.get("name") or ""
    if not name:
        raise InvalidDescription("<pinflex:body> needs a 'name'")
    link = el.get("link") or ""
    if link not in links:
        raise LinkNotFound(link, links)
    what = f"body '{name}'"
    xyz = _vec(R.text(el, "xyz", what), "0 0 0", what + " xyz")
    mass = R.number(el, "mass", what)
    g = {k: R.number(el, k, what, required=False, positive=False) or 0.0
         for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    inertia = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                        [g["ixz"], g["iyz"], g["izz"]]])
    from pinflex.description.link_inertia import second_moments

    if np.linalg.eigvalsh(second_moments(inertia)).min() < -1e-9 * max(
            float(np.abs(inertia).max()), 1e-300):
        raise InvalidBeamProperty(f"{what}: the rotational inertia is not a rigid body's "
                                  "(principal moments must be >= 0, each at most the sum of "
                                  "the other two)")
    return RigidBody(name, link, xyz, float(mass or 0.0), inertia, "body")


def _parse_inertial(link: str, el: ET.Element) -> RigidInertia:
    xyz, rot = _origin(el.find("origin"), f"link '{link}' inertial")
    mass_el, inertia_el = el.find("mass"), el.find("inertia")
    mass = _urdf_number(mass_el, "value", "0", f"link '{link}' mass")
    keys = ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")
    vals = {k: _urdf_number(inertia_el, k, "0", f"link '{link}' inertia") for k in keys}
    inertia = np.array(
        [
            [vals["ixx"], vals["ixy"], vals["ixz"]],
            [vals["ixy"], vals["iyy"], vals["iyz"]],
            [vals["ixz"], vals["iyz"], vals["izz"]],
        ]
    )
    return RigidInertia(mass=mass, com=xyz, inertia=rot @ inertia @ rot.T)


def _urdf_number(el: ET.Element | None, key: str, default: str | None, what: str,
                 absent: float = 0.0) -> float:
    """A number attribute of a plain URDF element, read by pinflex's number grammar."""
    text = None if el is None else el.get(key, default)
    if text is None:
        return absent
    try:
        return parse_number(text)
    except ValueError as exc:
        raise InvalidDescription(f"{what} {key}: {exc}") from exc


def _name(el: ET.Element | None, what: str, key: str = "name") -> str:
    """A required string attribute of a URDF element."""
    value = None if el is None else el.get(key)
    if not value:
        raise InvalidDescription(f"{what} needs a '{key}' attribute")
    return value


def _parse_joint(el: ET.Element, links: tuple[str, ...]) -> Joint:
    name = _name(el, "<joint>")
    jtype = el.get("type")
    if jtype not in SUPPORTED_JOINTS:
        raise UnsupportedJoint(
            f"joint '{name}' has type '{jtype}'; pinflex handles {', '.join(SUPPORTED_JOINTS)}"
        )
    parent = _name(el.find("parent"), f"joint '{name}' <parent>", "link")
    child = _name(el.find("child"), f"joint '{name}' <child>", "link")
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
        lower = _urdf_number(limit, "lower", None, f"joint '{name}' limit", -np.inf)
        upper = _urdf_number(limit, "upper", None, f"joint '{name}' limit", np.inf)
    return Joint(name, str(jtype), parent, child, xyz, rot, axis, lower, upper)


def _float_attr(el: ET.Element, key: str, what: str, *, required: bool = True,
                R: Resolver | None = None, design_ok: bool = False) -> float | None:
    return (R or Resolver({}, attribute_unit)).number(el, key, what, required=required, design_ok=design_ok)


def _entry(el: ET.Element, key: str, what: str, R: Resolver, *, required: bool = True):
    """A property input: the number, or the name of the design parameter it references."""
    value = R.number(el, key, what, required=required, design_ok=True)
    if value is None:
        return None
    ref = R.ref(el, key)
    return ref if ref is not None else value


def _parse_section(el: ET.Element | None, what: str, R: Resolver):
    """``(shape, section inputs)`` of a ``<pinflex:section>``."""
    if el is None:
        raise InvalidBeamProperty(f"{what}: <pinflex:section> is missing")
    shape = el.get("shape")
    what = what + " section"
    if shape not in SHAPES:
        raise InvalidBeamProperty(
            f"{what}: unknown shape '{shape}'; use solid_circle, hollow_circle, rectangle or "
            "explicit A, Iy, Iz, J"
        )
    allowed = SHAPES[shape]
    extra = sorted(set(el.keys()) - set(allowed) - {"shape"})
    if extra:
        raise InvalidBeamProperty(
            f"{what}: attribute(s) {extra} do not belong to shape '{shape or 'explicit'}', "
            f"which takes {', '.join(allowed)}"
        )
    if shape == "hollow_circle":
        if el.get("inner_diameter") is not None and el.get("wall") is not None:
            raise InvalidBeamProperty(f"{what}: give inner_diameter or wall, not both")
        out = {"outer_diameter": _entry(el, "outer_diameter", what, R)}
        if el.get("wall") is not None:
            out["wall"] = _entry(el, "wall", what, R)
        elif el.get("inner_diameter") is not None:
            value = R.number(el, "inner_diameter", what, positive=False, design_ok=True)
            if value is not None and value < 0.0:
                raise InvalidBeamProperty(f"{what}: inner_diameter = {value} must be >= 0 [m]")
            ref = R.ref(el, "inner_diameter")
            out["inner_diameter"] = ref if ref is not None else value
        return shape, out
    return shape, {k: _entry(el, k, what, R) for k in allowed}


def _parse_flexible(el, links, joints, child_joints, parent_joint, R: Resolver) -> FlexibleLink:
    link = el.get("link")
    if link is None:
        raise InvalidDescription("<pinflex:flexible> needs a 'link' attribute")
    if link not in links:
        raise LinkNotFound(link, links)
    what = f"flexible link '{link}'"
    count = R.number(el, "elements", what)  # checked by the schema: a whole number in range
    elements = int(count) if count is not None else 0
    if count != elements or not 1 <= elements <= MAX_ELEMENTS_PER_LINK:
        raise InvalidBeamProperty(
            f"{what}: 'elements' must be a whole number in 1..{MAX_ELEMENTS_PER_LINK}, got "
            f"'{el.get('elements')}'"
        )
    if el.get("tip") is not None:
        tip = _vec(R.text(el, "tip", what), "", what + " tip")
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
        normal = _vec(R.text(el, "normal", what), "", what + " normal")
    normal = normal - xdir * (normal @ xdir)
    if np.linalg.norm(normal) < 1e-9:
        raise InvalidBeamProperty(f"{what}: the normal vector is parallel to the beam axis")
    normal /= np.linalg.norm(normal)
    mat = el.find(_NS + "material")
    if mat is None:
        raise InvalidBeamProperty(f"{what}: <pinflex:material> is missing")
    shape, section_inputs = _parse_section(el.find(_NS + "section"), what, R)
    mwhat = what + " material"
    material = {"E": _entry(mat, "E", mwhat, R)}
    if mat.get("G") is not None:
        material["G"] = _entry(mat, "G", mwhat, R)
    else:
        nu = R.number(mat, "poisson", mwhat, required=False, positive=False)
        nu = 0.3 if nu is None else nu
        if not -1.0 < nu < 0.5:
            raise InvalidBeamProperty(f"{what}: poisson = {nu} must lie in (-1, 0.5)")
        material["poisson"] = nu
    density = _entry(mat, "density", mwhat, R, required=False)
    linear = _entry(mat, "linear_density", mwhat, R, required=False)
    if (density is None) == (linear is None):
        raise InvalidBeamProperty(
            f"{what}: give exactly one of density [kg/m^3] or linear_density [kg/m]"
        )
    if density is not None:
        material["density"] = density
    else:
        material["linear_density"] = linear
    inputs = PropertyInputs(shape, section_inputs, material)
    values = {n: p.value for n, p in R.params.items()}
    props = beam_properties(inputs, values.__getitem__)
    if shape == "hollow_circle":

        def num(entry):
            return values[entry] if isinstance(entry, str) else entry

        od = num(section_inputs["outer_diameter"])
        if "wall" in section_inputs:
            w = num(section_inputs["wall"])
            if not 2.0 * w <= od:
                raise InvalidBeamProperty(
                    f"{what} section: wall = {w} must be at most half the outer diameter {od} [m]"
                )
        else:
            inner = num(section_inputs.get("inner_diameter", 0.0))
            if not inner < od:
                raise InvalidBeamProperty(
                    f"{what} section: inner_diameter = {inner} must satisfy 0 <= inner < outer "
                    f"= {od} [m]"
                )
    section = beam.Section(A=props["A"], Iy=props["Iy"], Iz=props["Iz"], J=props["J"])
    G = props["GJ"] / props["J"]
    return FlexibleLink(
        inertia=el.get("inertia", "keep-excess"),
        link=link,
        elements=elements,
        tip=tip,
        normal=normal,
        E=props["EA"] / props["A"],
        G=G,
        rhoA=props["rhoA"],
        rhoIp=props["rhoIp"],
        section=section,
        inputs=inputs,
    )


def _default_normal(xdir: np.ndarray, parent: Joint | None) -> np.ndarray:
    if parent is not None and parent.type in ("revolute", "continuous"):
        # the parent joint axis expressed in the link frame (the joint frame is the link frame)
        if abs(parent.axis @ xdir) < 1e-9:
            return parent.axis.copy()
    return np.eye(3)[int(np.argmin(np.abs(xdir)))]


def _parse_point_mass(el: ET.Element, links: tuple[str, ...], R: Resolver) -> PointMass:
    name = el.get("name")
    if not name:
        raise InvalidDescription("<pinflex:point_mass> needs a 'name'")
    link = el.get("link") or ""
    if link not in links:
        raise LinkNotFound(link, links)
    what = f"point mass '{name}'"
    xyz = _vec(R.text(el, "xyz", what), "0 0 0", what + " xyz")
    mass = R.number(el, "mass", what, required=False, positive=False, design_ok=True)
    mass = 0.0 if mass is None else mass
    mass_ref = R.ref(el, "mass")
    if not np.isfinite(mass) or mass < 0.0:
        raise InvalidBeamProperty(f"{what}: mass = {mass} must be a finite number >= 0 [kg]")
    design = el.get("design", "false").strip().lower() in ("1", "true")
    if design and mass_ref is not None:
        raise InvalidDescription(
            f"{what}: its mass references the design parameter '{mass_ref}'; the parameter is "
            "the design variable, so drop design=\"true\" from the point mass"
        )
    lower = R.number(el, "lower", what, required=False, positive=False)
    upper = R.number(el, "upper", what, required=False, positive=False)
    lower = 0.0 if lower is None else lower
    upper = np.inf if upper is None else upper
    if design and not lower <= upper:
        raise InvalidDescription(f"{what}: lower bound {lower} is above upper bound {upper}")
    if design and lower < 0.0:
        raise InvalidDescription(f"{what}: lower bound {lower} would allow a negative mass")
    return PointMass(name, link, xyz, mass, design, lower, upper, mass_ref)


def _parse_joint_annotation(el: ET.Element, joints: dict[str, Joint],
                            R: Resolver) -> JointAnnotation:
    name = el.get("name")
    if not name:
        raise InvalidDescription("<pinflex:joint> needs a 'name' (a moving URDF joint)")
    moving = [n for n, j in joints.items() if j.type in MOVING_JOINTS]
    if name not in moving:
        raise JointNotFound(name, moving)
    what = f"<pinflex:joint name='{name}'>"
    locked_text = el.get("locked", "false").strip().lower()
    if locked_text not in ("1", "true", "0", "false"):
        raise InvalidDescription(f"{what}: locked='{el.get('locked')}' must be true or false")
    locked = locked_text in ("1", "true")
    prismatic = joints[name].type == "prismatic"
    unit = "N/m" if prismatic else "N m/rad"
    stiffness = R.number(el, "stiffness", what, required=False, design_ok=True, unit=unit)
    stiffness_ref = R.ref(el, "stiffness")
    if locked and stiffness is not None:
        raise InvalidDescription(
            f"{what}: give either stiffness=\"...\" (a spring) or locked=\"true\", not both"
        )
    damping = R.number(el, "damping", what, required=False, positive=False,
                       unit="N s/m" if prismatic else "N m s/rad")
    armature = R.number(el, "armature", what, required=False, positive=False,
                        unit="kg" if prismatic else "kg m^2")
    for key, value in (("damping", damping), ("armature", armature)):
        if value is not None and not (np.isfinite(value) and value >= 0.0):
            raise InvalidBeamProperty(f"{what}: {key} = {value} must be a finite number >= 0")
    return JointAnnotation(name, stiffness, locked, stiffness_ref, damping or 0.0,
                           armature or 0.0)
