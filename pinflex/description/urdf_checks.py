"""Checks of the plain URDF around pinflex's annotations: the parts pinflex reads.

Joints need a name, a supported type, ``<parent>`` and ``<child>`` links that exist; numbers
must be numbers; joint limits need ``lower <= upper``; a link whose inertia the model uses
(rigid and moved by a joint) needs a finite, non-negative ``<mass>``, and a zero mass only
together with a zero inertia (URDF's idiom for a massless frame link); a zero mass with a
non-zero inertia is refused, or only warned about in an upstream URDF used through an
overlay, since pinflex does not own that file. Negative and non-finite masses and negative
principal moments are refused everywhere.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

from pinflex.description.schema import MAX_COORDINATE, URDF_NUMBERS
from pinflex.description.source import XmlDocument, element_label
from pinflex.description.types import MOVING_JOINTS, SUPPORTED_JOINTS
from pinflex.exceptions import InvalidDescription, PlausibilityWarning, UnsupportedJoint
from pinflex.fields import check_range, parse_text
from pinflex.validation import Problem, closest, raise_problems


def check_urdf(doc: XmlDocument, flexible_links: set[str], *, upstream: bool = False,
               raise_now: bool = True) -> list[Problem]:
    """Check the plain URDF parts that pinflex reads (links, inertials, joints, limits).

    Args:
        doc: The URDF document.
        flexible_links: Links made beams (their URDF inertial is replaced, so not checked).
        upstream: The file is an upstream URDF used through an overlay: a zero mass with a
            non-zero inertia warns instead of being refused.
        raise_now: Raise one error listing every problem (default), else return them.

    Returns:
        The problems (empty when ``raise_now`` and nothing was wrong).

    Raises:
        InvalidDescription (or a subclass) listing every problem.
    """
    root = doc.root
    problems: list[Problem] = []

    def add(el, message, error=InvalidDescription, warning=False, attr=None):
        line = doc.line(el)
        where = ", ".join(([f"line {line}"] if line else []) + [element_label(el)]
                          + ([f"attribute '{attr}'"] if attr else []))
        problems.append(Problem(where, message, error,
                                PlausibilityWarning if warning else None))

    if root.tag != "robot":
        raise InvalidDescription(
            f"{doc.source}: the URDF's root element is <{root.tag}>, expected <robot>"
        )
    links: dict[str, ET.Element] = {}
    for el in root.findall("link"):
        name = el.get("name")
        if not name:
            add(el, "a <link> needs a name")
        elif name in links:
            add(el, f"link '{name}' is defined twice")
        else:
            links[name] = el
    parent_of: dict[str, tuple[str, bool]] = {}
    names: set[str] = set()
    for el in root.findall("joint"):
        name = el.get("name")
        label = f"joint '{name}'"
        if not name:
            add(el, "a <joint> needs a name")
        elif name in names:
            add(el, f"joint '{name}' is defined twice")
        names.add(name or "")
        jtype = el.get("type")
        if jtype not in SUPPORTED_JOINTS:
            add(el, f"{label} has type '{jtype}'; pinflex handles "
                f"{', '.join(SUPPORTED_JOINTS)}", UnsupportedJoint, attr="type")
        ends = {}
        for end in ("parent", "child"):
            sub = el.find(end)
            link = None if sub is None else sub.get("link")
            if not link:
                add(el, f"{label} has no <{end} link=\"...\"/>")
            elif link not in links:
                near = closest(link, links)
                add(el, f"{label}: {end} link '{link}' is not a link of the robot"
                    + (f"; did you mean '{near}'?" if near else ""), InvalidDescription)
            else:
                ends[end] = link
        numbers = _urdf_numbers(el, ("joint",), label, add)
        mimic = el.find("mimic")
        if mimic is not None:
            add(mimic, f"{label} mimics joint '{mimic.get('joint')}'; pinflex treats every "
                "joint as an independent coordinate, so the coupling is ignored"
                + (" (upstream URDF: the joint moves on its own in pinflex)" if upstream else
                   ": drop <mimic> or model the coupling outside the URDF"),
                UnsupportedJoint, warning=upstream)
        vals = numbers.get(("joint", "limit"), {})
        if el.find("limit") is not None:
            limit = el.find("limit")
            if jtype in ("revolute", "prismatic") and "lower" in vals and "upper" in vals:
                if vals["lower"] > vals["upper"]:
                    add(limit, f"{label}: lower limit {vals['lower']:g} is above upper limit "
                        f"{vals['upper']:g}", attr="lower")
        if "child" in ends and "parent" in ends:
            parent_of[ends["child"]] = (ends["parent"], jtype in MOVING_JOINTS)
    roots = [name for name in links if name not in parent_of]
    if len(roots) == 1:
        children: dict[str, list[str]] = {}
        for child, (parent, _) in parent_of.items():
            children.setdefault(parent, []).append(child)
        reached, todo = {roots[0]}, [roots[0]]
        while todo:
            for child in children.get(todo.pop(), ()):
                if child not in reached:
                    reached.add(child)
                    todo.append(child)
        cut = [name for name in links if name not in reached]
        if cut:
            add(root, f"links {', '.join(cut[:5])}{' ...' if len(cut) > 5 else ''} are not "
                f"connected to the root link '{roots[0]}': their joints form a loop")
    numbers_of = {name: _urdf_numbers(el, ("link",), f"link '{name}'", add)
                  for name, el in links.items()}
    for name, el in links.items():
        inertial = el.find("inertial")
        if inertial is None:
            continue
        used = name not in flexible_links and _moved(name, parent_of)
        mass_el = inertial.find("mass")
        if (mass_el is None or mass_el.get("value") is None) and used:
            add(inertial, f"link '{name}': <inertial> without <mass value=\"...\"/>",
                warning=upstream)
        mass = numbers_of[name].get(("link", "inertial", "mass"), {}).get("value")
        inertia_el = inertial.find("inertia")
        moments = numbers_of[name].get(("link", "inertial", "inertia"), {})
        if mass is not None and mass < 0.0:
            add(mass_el, f"link '{name}' has mass {mass:g} kg; a mass cannot be negative",
                attr="value")
        elif any(moments.get(k, 0.0) < 0.0 for k in ("ixx", "iyy", "izz")):
            add(inertia_el, f"link '{name}' has a negative principal moment of inertia")
        elif used and moments:
            _check_inertia(name, inertia_el, moments, upstream, add)
        if mass is None or not used:
            continue
        if mass == 0.0 and any(moments.values()):
            if upstream:
                add(mass_el, f"link '{name}' has mass 0 with a non-zero inertia in the "
                    "upstream URDF; pinflex keeps its rotational inertia only", warning=True,
                    attr="value")
            else:
                add(mass_el, f"link '{name}' has mass 0 but a non-zero inertia and the model "
                    "moves it: give its mass (zero mass and zero inertia make a massless frame "
                    "link)", attr="value")
    if raise_now:
        raise_problems(doc.source, problems, " in the URDF")
    return problems


def _check_inertia(name: str, el, moments: dict, upstream: bool, add) -> None:
    """A rigid body's inertia is positive semi-definite and its principal moments satisfy
    the triangle inequality (``I1 <= I2 + I3``).

    A tensor that is not positive semi-definite makes the mass matrix indefinite (every
    eigenfrequency of the arm is then meaningless): refused, warned in an upstream URDF.
    One that only breaks the triangle inequality belongs to no rigid body (common in upstream
    files, harmless to the mass matrix): warned.
    """
    import numpy as np

    g = {k: moments.get(k, 0.0) for k in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz")}
    tensor = np.array([[g["ixx"], g["ixy"], g["ixz"]], [g["ixy"], g["iyy"], g["iyz"]],
                       [g["ixz"], g["iyz"], g["izz"]]])
    w = np.linalg.eigvalsh(tensor)
    scale = float(np.abs(w).max())
    principal = ", ".join(f"{v:.4g}" for v in w)
    if w[0] < -1e-9 * scale:
        add(el, f"link '{name}': its inertia is not positive semi-definite (principal moments "
            f"{principal} kg m^2): the mass matrix would be indefinite; correct ixy, ixz, iyz "
            "or the diagonal", warning=upstream)
    elif w[2] > w[0] + w[1] + 1e-6 * scale:
        add(el, f"link '{name}': its principal moments of inertia ({principal} kg m^2) break "
            "the triangle inequality I3 <= I1 + I2 that every rigid body satisfies; check the "
            "inertia", warning=True)


def _moved(link: str, parent_of: dict[str, tuple[str, bool]]) -> bool:
    seen = set()
    while link in parent_of and link not in seen:
        seen.add(link)
        link, moving = parent_of[link]
        if moving:
            return True
    return False


def _urdf_numbers(el: ET.Element, path: tuple[str, ...], label: str, add) -> dict:
    """Check every numeric attribute below ``el`` listed in :data:`URDF_NUMBERS`.

    Returns:
        ``{path: {attribute: value}}`` of the values that passed.
    """
    out: dict[tuple[str, ...], dict] = {}
    for child in el:
        if not isinstance(child.tag, str) or child.tag.startswith("{"):
            continue
        sub = (*path, child.tag)
        fields = URDF_NUMBERS.get(sub)
        if fields is not None:
            got = out.setdefault(sub, {})
            for key, f in fields.items():
                text = child.get(key)
                if text is None:
                    continue

                def report(_where, message, level, _child=child, _key=key):
                    add(_child, f"{label} {' '.join(sub[1:])} {_key}: {message}", attr=_key,
                        warning=level == "warning")

                try:
                    value = parse_text(f, text)
                except ValueError as exc:
                    report("", str(exc), "error")
                    continue
                if f.kind != "vec3" and text != text.strip(" \t\r\n"):
                    report("", f"{text!r} has spaces around the number, which Pinocchio's "
                           "URDF reader refuses (it would skip the element)", "error")
                    continue
                if f.kind == "vec3":
                    big = max(abs(v) for v in value)
                    limit = f.le if f.le is not None else MAX_COORDINATE
                    if big > limit:
                        report("", f"{text!r}: a component beyond {limit:g}"
                               f"{' ' + f.unit if f.unit else ''} is not a robot", "error")
                        continue
                elif not check_range(f, value, text, "", report):
                    continue
                got[key] = value
        if len(sub) < 4:
            for deeper, values in _urdf_numbers(child, sub, label, add).items():
                out.setdefault(deeper, {}).update(values)
    return out
