"""Checks of a description document against :data:`~pinflex.description.schema.SCHEMA`.

:func:`check_annotations` walks every pinflex element and attribute of a document (an
annotated URDF or an overlay) and collects every problem with its line;
:func:`check_physical` compares the parsed beams with their links (section size against
length, implied density). The plain URDF around the annotations is checked too
(:func:`check_urdf`): joints need a name, a supported type, ``<parent>`` and ``<child>``
links that exist; numbers must be numbers; joint limits need ``lower <= upper``; a link whose
inertia the model uses (rigid and moved by a joint) needs a finite, non-negative ``<mass>``,
and a zero mass only together with a zero inertia (URDF's idiom for a massless frame link); a
zero mass with a non-zero inertia is refused, or only warned about in an upstream URDF used
through an overlay, since pinflex does not own that file. Negative and non-finite masses and
negative principal moments are refused everywhere.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from pinflex.description.schema import (
    _IDENT,
    _NAME,
    _NS,
    _REFERENCE,
    MAX_COORDINATE,
    SCHEMA,
    URDF_TOP_LEVEL,
    Attr,
    Checked,
    _Context,
)
from pinflex.description.source import XmlDocument
from pinflex.description.types import MOVING_JOINTS, NAMESPACE, SUPPORTED_JOINTS
from pinflex.exceptions import (
    ImplausibleValue,
    InvalidAttribute,
    InvalidDescription,
    PlausibilityWarning,
    UnknownAttribute,
    UnknownElement,
    UnsupportedJoint,
)
from pinflex.validation import Problem, closest, parse_int, parse_number, raise_problems, suggestion


def _local(tag: str) -> tuple[str, str]:
    if tag.startswith("{"):
        ns, _, local = tag[1:].partition("}")
        return ns, local
    return "", tag


def _near_namespace(uri: str) -> bool:
    if uri == NAMESPACE:
        return False
    return "pinflex" in uri.lower() or closest(uri, [NAMESPACE]) is not None


class _Checker:
    def __init__(self, doc: XmlDocument, plausibility: str, values=None):
        if plausibility not in ("refuse", "warn"):
            raise InvalidDescription(
                f"plausibility='{plausibility}': expected 'refuse' or 'warn'"
            )
        self.doc = doc
        self.lenient = plausibility == "warn"
        self.problems: list[Problem] = []
        self.checked = Checked()
        self.param_values = _parameter_values(doc, values)

    # -- reporting
    def where(self, el, attr: str | None = None, name: str | None = None) -> str:
        line = self.doc.line(el) if el is not None else None
        parts = [f"line {line}"] if line else []
        if name is not None:
            parts.append(name)
        if attr is not None:
            parts.append(f"attribute '{attr}'")
        return ", ".join(parts)

    def add(self, el, attr, message, error=InvalidAttribute, *, warning=False, name=None,
            physical=False):
        if physical:
            error = ImplausibleValue
            if self.lenient:
                warning = True
        self.problems.append(Problem(
            self.where(el, attr, name if name is not None else _tagname(el)), message, error,
            PlausibilityWarning if warning else None,
        ))

    # -- the walk
    def run(self) -> Checked:
        for prefix, uri, line in self.doc.prefixes:
            if prefix == "pinflex" and uri != NAMESPACE:
                self.problems.append(Problem(
                    f"line {line}", f"the prefix 'pinflex' is bound to '{uri}'; pinflex "
                    f"annotations live in xmlns:pinflex=\"{NAMESPACE}\"", UnknownElement))
        root = self.doc.root
        if root.tag == _NS + "overlay":
            self.element(root, "overlay", "<document>", "")
            self.children(root, "overlay")
        elif root.tag == "robot":
            self.children(root, "robot")
        self.stray(root, inside_pinflex=False, top=True)
        return self.checked

    def children(self, parent: ET.Element, ctx: str, owner: str = "") -> None:
        counts: dict[str, int] = {}
        allowed = sorted(k for k, e in SCHEMA.items() if ctx in e.parents)
        for child in parent:
            if not isinstance(child.tag, str):
                continue
            ns, local = _local(child.tag)
            if ns == NAMESPACE:
                spec = SCHEMA.get(local)
                if spec is None or ctx not in spec.parents:
                    if spec is not None:
                        hint = (f"<pinflex:{local}> belongs in "
                                + " or ".join(f"<{_ctxname(p)}>" for p in spec.parents))
                    else:
                        hit = closest(local, allowed)
                        hint = (f"did you mean <pinflex:{hit}>?" if hit else
                                "known here: " + ", ".join(f"<pinflex:{a}>" for a in allowed))
                    self.add(child, None, f"unknown pinflex element <pinflex:{local}> in "
                             f"<{_ctxname(ctx)}>; {hint}", UnknownElement)
                    continue
                counts[local] = counts.get(local, 0) + 1
                lo, hi = spec.count
                if hi is not None and counts[local] == hi + 1:
                    self.add(child, None, f"a second <pinflex:{local}> in <{_ctxname(ctx)}>; "
                             f"at most {hi} allowed", InvalidAttribute)
                sub_owner = owner
                if local == "flexible":
                    sub_owner = child.get("link", "")
                self.element(child, local, ctx, sub_owner)
                self.children(child, local, sub_owner)
            elif ctx not in ("robot",):
                self.add(child, None, f"<{local}> is not allowed in <{_ctxname(ctx)}>"
                         + (f"; did you mean <pinflex:{closest(local, allowed)}>?"
                            if closest(local, allowed) else
                            "; known here: " + ", ".join(f"<pinflex:{a}>" for a in allowed)),
                         UnknownElement, name=f"<{local}>")
            elif ns and _near_namespace(ns):
                self.add(child, None, f"<{local}> is in namespace '{ns}', not pinflex's "
                         f"'{NAMESPACE}': it would be ignored", UnknownElement,
                         name=f"<{local}>")
            elif not ns and local not in URDF_TOP_LEVEL:
                hit = closest(local, [k for k in SCHEMA if "robot" in SCHEMA[k].parents])
                if hit is not None:
                    self.add(child, None, f"<{local}> is not URDF and has no pinflex: prefix, "
                             f"so it would be ignored; did you mean <pinflex:{hit}>?",
                             UnknownElement, name=f"<{local}>")
        for local in allowed:
            lo = SCHEMA[local].count[0]
            if counts.get(local, 0) < lo:
                self.add(parent, None, f"<pinflex:{local}> is missing", InvalidAttribute,
                         name=f"<{_ctxname(ctx)}>" + (f" of link '{owner}'" if owner else ""))

    def stray(self, el, *, inside_pinflex: bool, top: bool) -> None:
        """Pinflex elements out of place, and pinflex attributes on URDF elements."""
        for child in el:
            if not isinstance(child.tag, str):
                continue
            ns, local = _local(child.tag)
            mine = ns == NAMESPACE
            if not top and mine and not inside_pinflex:
                self.add(child, None, f"<pinflex:{local}> must be a direct child of <robot>",
                         UnknownElement)
            if not mine:
                for key in child.attrib:
                    kns, klocal = _local(key)
                    if kns == NAMESPACE or (kns and _near_namespace(kns)):
                        self.add(child, klocal, f"<{local}> has no pinflex attribute "
                                 f"'{klocal}'; annotations are elements such as "
                                 "<pinflex:flexible>", UnknownAttribute, name=f"<{local}>")
                if not top and ns and _near_namespace(ns):
                    self.add(child, None, f"<{local}> is in namespace '{ns}', not "
                             f"'{NAMESPACE}'", UnknownElement, name=f"<{local}>")
            self.stray(child, inside_pinflex=mine or inside_pinflex, top=False)

    def element(self, el, local: str, ctx: str, owner: str) -> None:
        spec = SCHEMA[local]
        values: dict = {}
        context = _Context(local, dict(el.attrib), owner, self.checked)
        for key, text in el.attrib.items():
            kns, klocal = _local(key)
            if kns or klocal not in spec.attrs:
                self.add(el, klocal, f"unknown attribute '{klocal}' of <pinflex:{local}>; "
                         + suggestion(klocal, spec.attrs), UnknownAttribute)
                continue
            attr = spec.attrs[klocal]
            numeric = attr.reference and attr.kind in ("float", "int", "vec3")
            ref = _REFERENCE.match(text.strip()) if numeric else None
            if ref is not None:
                self.checked.references.append((local, klocal, ref.group(1)))
                value = self.param_values.get(ref.group(1))
                if value is not None and attr.kind in ("float", "int"):
                    # a referenced value passes the same checks as the literal would
                    shown = f"{{{ref.group(1)}}} = {value!r}"
                    if self.ranges(el, klocal, attr, shown, value):
                        values[klocal] = value
                continue
            if numeric and attr.kind == "vec3" and "{" in text:
                parts = text.split()
                for part in parts:
                    m = _REFERENCE.match(part)
                    if m is not None:
                        self.checked.references.append((local, klocal, m.group(1)))
                    else:
                        try:
                            parse_number(part)
                        except ValueError as exc:
                            self.add(el, klocal, f"{klocal}={text!r}: {exc}")
                if len(parts) != 3:
                    self.add(el, klocal, f"{klocal}={text!r}: expected three numbers")
                continue
            try:
                values[klocal] = self.value(attr, text)
            except ValueError as exc:
                self.add(el, klocal, f"{klocal}={text!r}: {exc}")
                continue
            if not self.ranges(el, klocal, attr, text, values[klocal]):
                del values[klocal]  # rules see only values inside their hard bounds
        for key, attr in spec.attrs.items():
            if attr.required and key not in el.attrib:
                self.add(el, key, f"attribute '{key}' is missing")
        if spec.declares and isinstance(values.get(spec.declares), str):
            self.checked.declared.add(values[spec.declares])

        def report(attr, message, *, warning=False, physical=False):
            self.add(el, attr, message, warning=warning, physical=physical)

        for rule in spec.rules:
            rule(values, report, context)

    @staticmethod
    def value(attr: Attr, text: str):
        kind = attr.kind
        if kind == "float":
            return parse_number(text)
        if kind == "int":
            return parse_int(text)
        if kind == "vec3":
            parts = text.split()
            if len(parts) != 3:
                raise ValueError(f"expected three numbers, got {len(parts)}")
            vec = np.array([parse_number(p) for p in parts])
            if np.max(np.abs(vec)) > MAX_COORDINATE:
                raise ValueError(f"coordinates beyond {MAX_COORDINATE:g} m are not a robot")
            return vec
        if kind == "bool":
            t = text.strip().lower()
            if t in ("true", "1"):
                return True
            if t in ("false", "0"):
                return False
            raise ValueError("expected true or false")
        if kind == "choice":
            if text not in attr.choices:
                raise ValueError("expected " + " or ".join(f"'{c}'" for c in attr.choices)
                                 + "; " + suggestion(text, attr.choices))
            return text
        if kind == "ident":
            if not _IDENT.match(text):
                raise ValueError("expected a name of letters, digits and '_' starting with a "
                                 "letter")
            return text
        if kind == "name":
            if not _NAME.match(text):
                raise ValueError("expected a name of letters, digits, '_', '.', '-' "
                                 "starting with a letter")
            return text
        if not text.strip():
            raise ValueError("must not be empty")
        return text

    def ranges(self, el, key: str, attr: Attr, text: str, value) -> bool:
        """Check the bounds of a number; False when a hard bound is broken."""
        if attr.kind not in ("float", "int"):
            return True
        unit = f" [{attr.unit}]" if attr.unit else ""
        bad = None
        if attr.gt is not None and not value > attr.gt:
            bad = "a positive number" if attr.gt == 0 else f"above {attr.gt:g}"
        elif attr.ge is not None and not value >= attr.ge:
            bad = "a number >= 0" if attr.ge == 0 else f">= {attr.ge:g}"
        elif attr.lt is not None and not value < attr.lt:
            bad = f"below {attr.lt:g}"
        elif attr.le is not None and not value <= attr.le:
            bad = f"at most {attr.le:g}"
        if bad is not None:
            self.add(el, key, f"{key}={text} must be {bad}{unit}")
            return False
        why = f"; {attr.why}" if attr.why else ""
        if attr.physical is not None and not attr.physical[0] <= value <= attr.physical[1]:
            self.add(el, key, f"{key}={text}{unit} is outside [{attr.physical[0]:g}, "
                     f"{attr.physical[1]:g}], not physical for a robot link{why}",
                     physical=True)
        elif attr.plausible is not None and not (
            attr.plausible[0] <= value <= attr.plausible[1]
        ):
            self.add(el, key, f"{key}={text}{unit} is unusual for a robot link (outside "
                     f"[{attr.plausible[0]:g}, {attr.plausible[1]:g}]){why}", warning=True)
        return True


def _tagname(el) -> str:
    if el is None:
        return ""
    ns, local = _local(el.tag)
    return f"<pinflex:{local}>" if ns == NAMESPACE else f"<{local}>"


def _ctxname(ctx: str) -> str:
    if ctx in ("robot", "<document>"):
        return "robot" if ctx == "robot" else "document"
    return f"pinflex:{ctx}"


def _parameter_values(doc: XmlDocument, values) -> dict[str, float]:
    """``{name: value}`` of the document's parameters (overridden by ``values``), for the
    checks of the attributes that reference them; unreadable values are left to the
    parameter's own checks."""
    out: dict[str, float] = {}
    for el in doc.root.iter(_NS + "parameter"):
        name, text = el.get("name"), el.get("value")
        if name is None or text is None:
            continue
        try:
            out[name] = parse_number(text)
        except ValueError:
            continue
    for name, value in (values or {}).items():
        if name in out:
            out[name] = float(value)
    return out


def check_annotations(doc: XmlDocument, *, plausibility: str = "refuse",
                      raise_now: bool = True, values=None) -> tuple[Checked, list[Problem]]:
    """Check every pinflex element and attribute of a document against :data:`SCHEMA`.

    Args:
        doc: The parsed document (an annotated URDF or an overlay file).
        plausibility: 'refuse' non-physical values (default) or only 'warn' about them.
        raise_now: Raise one error listing every problem (default), else return them.
        values: Parameter values overriding the file's (``values=`` / ``--set``): an
            attribute that references a parameter is checked with its value, as a literal.

    Returns:
        ``(checked, problems)``: facts for :func:`check_physical`, and the problems.

    Raises:
        UnknownElement, UnknownAttribute, InvalidAttribute, ImplausibleValue: see the module.
    """
    checker = _Checker(doc, plausibility, values)
    checked = checker.run()
    if raise_now:
        raise_problems(doc.source, checker.problems, " in the pinflex annotations")
    return checked, checker.problems


# --------------------------------------------------------------------- the URDF around
def check_urdf(doc: XmlDocument, flexible_links: set[str], *, upstream: bool = False,
               raise_now: bool = True) -> list[Problem]:
    """Check the plain URDF parts that pinflex reads (links, inertials, joints, limits).

    Args:
        doc: The URDF document.
        flexible_links: Links made beams (their URDF inertial is replaced, so not checked).
        upstream: The file is an upstream URDF used through an overlay: a zero mass with a
            non-zero inertia warns instead of being refused.
        raise_now: Raise one error listing every problem (default), else return them.
        values: Parameter values overriding the file's (``values=`` / ``--set``): an
            attribute that references a parameter is checked with its value, as a literal.

    Returns:
        The problems (empty when ``raise_now`` and nothing was wrong).

    Raises:
        InvalidDescription (or a subclass) listing every problem.
    """
    root = doc.root
    problems: list[Problem] = []

    def add(el, message, error=InvalidDescription, warning=False, attr=None):
        line = doc.line(el)
        where = ", ".join(([f"line {line}"] if line else []) + [_tagname(el)]
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
        for sub_tag, keys in (("origin", ("xyz", "rpy")), ("axis", ("xyz",))):
            sub = el.find(sub_tag)
            for key in keys:
                if sub is not None and sub.get(key) is not None:
                    _vec_problem(sub, key, add)
        limit = el.find("limit")
        if limit is not None:
            vals = {}
            for key in ("lower", "upper", "effort", "velocity"):
                text = limit.get(key)
                if text is None:
                    continue
                try:
                    vals[key] = parse_number(text)
                except ValueError as exc:
                    add(limit, f"{label} limit {key}: {exc}", attr=key)
            if jtype in ("revolute", "prismatic") and "lower" in vals and "upper" in vals:
                if vals["lower"] > vals["upper"]:
                    add(limit, f"{label}: lower limit {vals['lower']:g} is above upper limit "
                        f"{vals['upper']:g}", attr="lower")
        if "child" in ends and "parent" in ends:
            parent_of[ends["child"]] = (ends["parent"], jtype in MOVING_JOINTS)
    for name, el in links.items():
        inertial = el.find("inertial")
        if inertial is None:
            continue
        used = name not in flexible_links and _moved(name, parent_of)
        mass_el = inertial.find("mass")
        mass = None
        if mass_el is None or mass_el.get("value") is None:
            if used:
                add(inertial, f"link '{name}': <inertial> without <mass value=\"...\"/>",
                    warning=upstream)
        else:
            try:
                mass = parse_number(mass_el.get("value", ""))
            except ValueError as exc:
                add(mass_el, f"link '{name}' mass: {exc}", attr="value")
        inertia_el = inertial.find("inertia")
        moments: dict[str, float] = {}
        if inertia_el is not None:
            for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
                text = inertia_el.get(key)
                if text is None:
                    continue
                try:
                    moments[key] = parse_number(text)
                except ValueError as exc:
                    add(inertia_el, f"link '{name}' inertia {key}: {exc}", attr=key)
        origin = inertial.find("origin")
        if origin is not None:
            for key in ("xyz", "rpy"):
                if origin.get(key) is not None:
                    _vec_problem(origin, key, add)
        if mass is not None and mass < 0.0:
            add(mass_el, f"link '{name}' has mass {mass:g} kg; a mass cannot be negative",
                attr="value")
        elif any(moments.get(k, 0.0) < 0.0 for k in ("ixx", "iyy", "izz")):
            add(inertia_el, f"link '{name}' has a negative principal moment of inertia")
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


def _moved(link: str, parent_of: dict[str, tuple[str, bool]]) -> bool:
    seen = set()
    while link in parent_of and link not in seen:
        seen.add(link)
        link, moving = parent_of[link]
        if moving:
            return True
    return False


def _vec_problem(el, key: str, add) -> None:
    text = el.get(key)
    parts = text.split()
    try:
        if len(parts) != 3:
            raise ValueError(f"expected three numbers, got '{text}'")
        for p in parts:
            parse_number(p)
    except ValueError as exc:
        add(el, f"{key}: {exc}", attr=key)


# --------------------------------------------------------------------- after parsing
def check_physical(desc, checked: Checked, source: str, *,
                   plausibility: str = "refuse") -> None:
    """Checks that need the parsed description: section size against link length, density.

    Raises:
        ImplausibleValue: with ``plausibility='refuse'``; otherwise warns.
    """
    problems: list[Problem] = []
    lenient = plausibility == "warn"

    def add(where, message, physical):
        warn = PlausibilityWarning if (not physical or lenient) else None
        problems.append(Problem(where, message, ImplausibleValue, warn))

    for name, f in desc.flexible.items():
        where = f"<pinflex:flexible link='{name}'>"
        length = f.length_m
        extent = checked.extents.get(name)
        if extent is not None and extent > length:
            add(where, f"the section is {extent:g} m across but the link is {length:g} m long; "
                "dimensions are in metres and a beam must be longer than it is wide", True)
        elif extent is not None and extent > length / 3.0:
            add(where, f"the section ({extent:g} m) is wider than a third of the link "
                f"({length:g} m): Euler-Bernoulli beams overestimate the frequencies of such "
                "stubby links", False)
        if length > 100.0:
            add(where, f"the link is {length:g} m long; lengths are in metres", False)
        rho = f.rhoA / f.section.A
        if not 1.0 <= rho <= 25000.0:
            add(where, f"the material density is {rho:.4g} kg/m^3 (from the linear density "
                "and the area), not physical for a robot link", True)
        elif not 100.0 <= rho <= 23000.0:
            add(where, f"the material density is {rho:.4g} kg/m^3, unusual for a robot link",
                False)
    raise_problems(source, problems, " in the pinflex annotations")
