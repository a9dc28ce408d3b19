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
from typing import Any

from pinflex.description.params import Parameter, read_parameters, reference
from pinflex.description.schema import (
    _NS,
    MAX_COORDINATE,
    SCHEMA,
    URDF_NUMBERS,
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
from pinflex.fields import check_range, parse_text, split_vector
from pinflex.validation import Problem, closest, parse_number, raise_problems, suggestion


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
    def __init__(self, doc: XmlDocument, plausibility: str,
                 values: dict[str, float] | None = None):
        if plausibility not in ("refuse", "warn"):
            raise InvalidDescription(
                f"plausibility='{plausibility}': expected 'refuse' or 'warn'"
            )
        self.doc = doc
        self.lenient = plausibility == "warn"
        self.problems: list[Problem] = []
        self.checked = Checked()
        self.params: dict[str, Parameter] = read_parameters(doc.root, _NS, values)

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
        self.names(root)
        return self.checked

    def names(self, root) -> None:
        """Parameters named like point masses; design parameters that nothing uses."""
        masses = {el.get("name"): el for el in root.findall(_NS + "point_mass")}
        used = {name for _, _, name in self.checked.references}
        for el in root.findall(_NS + "parameter"):
            name = el.get("name", "")
            if name in masses and reference(masses[name].get("mass")) != name:
                self.add(el, "name", f"parameter '{name}' has the name of a point mass whose "
                         f"mass is not '{{{name}}}'; values={{...}} and --set would set the "
                         "parameter only: rename one, or give the mass as "
                         f"mass=\"{{{name}}}\"")
            elif name and name not in used and name in self.params:
                if self.params[name].design:
                    self.add(el, "name", f"design parameter '{name}' is referenced by no "
                             "attribute, so it cannot change the model (an assignment would "
                             f"have a design variable without effect); use it as '{{{name}}}' "
                             "or drop it")
                else:
                    self.add(el, "name", f"parameter '{name}' is referenced by no attribute",
                             warning=True)

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
            value = self.attribute(el, local, klocal, attr, text, context.upper)
            if value is not None:
                values[klocal] = value
        for key, attr in spec.attrs.items():
            if attr.required and key not in el.attrib:
                self.add(el, key, f"attribute '{key}' is missing")
        text = "".join([el.text or "", *(child.tail or "" for child in el)]).strip()
        if text:  # a value written as text (or CDATA) would be ignored
            self.add(el, None, f"<pinflex:{local}> holds the text {text[:40]!r}, which pinflex "
                     "ignores; annotations take their values as attributes only",
                     UnknownElement)
        if spec.declares and isinstance(values.get(spec.declares), str):
            self.checked.declared.add(values[spec.declares])

        def report(attr, message, *, warning=False, physical=False):
            self.add(el, attr, message, warning=warning, physical=physical)

        for rule in spec.rules:
            rule(values, report, context)

    def attribute(self, el, local: str, key: str, attr: Attr, text: str, upper: dict):
        """The checked value of one attribute (references resolved), or None if refused.

        A ``{name}`` reference is checked with the value of the parameter it names (its
        ``--set``/``values=`` override if any) exactly as a literal would be, and a design
        parameter's bounds too, since an assignment may move it anywhere between them.
        """
        problems: list[tuple[str, str]] = []

        def report(_where, message, level):
            problems.append((message, level))

        numeric = attr.reference and attr.numeric
        if numeric and "{" in text:
            value = self.resolved(el, local, key, attr, text, report, upper)
        else:
            try:
                value = parse_text(attr, text)
            except ValueError as exc:
                report("", f"{key}={text!r}: {exc}", "error")
                value = None
            if value is not None and not self.in_range(attr, key, text, value, report):
                value = None  # rules see only values inside their hard bounds
        for message, level in problems:
            self.add(el, key, message, physical=level == "physical",
                     warning=level == "warning")
        return value

    def in_range(self, attr: Attr, key: str, label: str, value, report) -> bool:
        if attr.kind == "vec3":
            if max(abs(v) for v in value) > MAX_COORDINATE:
                report("", f"{key}={label!r}: coordinates beyond {MAX_COORDINATE:g} m are not "
                       "a robot", "error")
                return False
            return True
        if attr.kind not in ("float", "int"):
            return True
        return check_range(attr, value, f"{key}={label}", "", report,
                           subject=" for a robot link")

    def resolved(self, el, local: str, key: str, attr: Attr, text: str, report, upper: dict):
        """A numeric attribute holding ``{name}`` references, checked with their values."""
        words = split_vector(text) if attr.kind == "vec3" else [text]
        if attr.kind == "vec3" and len(words) != 3:
            report("", f"{key}={text!r}: expected three numbers", "error")
            return None
        cases: list[list[float]] = [[]]  # the nominal value, then design-bound corners
        names = []
        for word in words:
            name = reference(word)
            if name is None:
                try:
                    number = parse_number(word)
                except ValueError as exc:
                    report("", f"{key}={text!r}: {exc}", "error")
                    return None
                for case in cases:
                    case.append(number)
                continue
            names.append(name)
            self.checked.references.append((local, key, name))
            param = self.params.get(name)
            if param is None:
                return None  # undeclared: named when the description is built
            extra = []
            if param.design and attr.kind != "vec3":
                extra = [[*cases[0], param.lower], [*cases[0], param.upper]]
            for case in cases:
                case.append(param.value)
            cases += extra
        if not names:
            return None
        labels = ["", " at its design lower bound", " at its design upper bound"]
        value = None
        for i, case in enumerate(cases):
            v: Any
            if attr.kind == "vec3":
                v = tuple(case)
                shown = " ".join(f"{c:g}" for c in case)
            else:
                v = case[0]
                shown = f"{v:g}"
            label = f'"{text.strip()}" = {shown}{labels[i] if i < len(labels) else ""}'
            if attr.kind == "int":
                if not float(case[0]).is_integer():
                    report("", f"{key}={label} is not a whole number", "error")
                    return None
                v = int(case[0])
            if not self.in_range(attr, key, label, v, report):
                return None
            if i == 0:
                value = v
            elif i == 2:
                upper[key] = v
        return value


def _tagname(el) -> str:
    if el is None:
        return ""
    ns, local = _local(el.tag)
    return f"<pinflex:{local}>" if ns == NAMESPACE else f"<{local}>"


def _ctxname(ctx: str) -> str:
    if ctx in ("robot", "<document>"):
        return "robot" if ctx == "robot" else "document"
    return f"pinflex:{ctx}"


def check_annotations(doc: XmlDocument, *, plausibility: str = "refuse",
                      raise_now: bool = True, values: dict[str, float] | None = None
                      ) -> tuple[Checked, list[Problem]]:
    """Check every pinflex element and attribute of a document against :data:`SCHEMA`.

    Args:
        doc: The parsed document (an annotated URDF or an overlay file).
        plausibility: 'refuse' non-physical values (default) or only 'warn' about them.
        raise_now: Raise one error listing every problem (default), else return them.
        values: Parameter overrides (``--set``, ``values=``): references are checked with
            the values they will have.

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
        extent_hi = checked.extents_upper.get(name)
        if extent_hi is not None and extent_hi > length and not (extent and extent > length):
            add(where, f"at the upper bound of its design parameter the section is "
                f"{extent_hi:g} m across but the link is {length:g} m long; lower the "
                "parameter's upper bound", True)
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
    for p in desc.point_masses:
        f = desc.flexible.get(p.link)
        if f is None:
            continue
        length = f.length_m
        s = float(p.xyz @ f.tip) / length  # axial station along the beam
        if s < -0.01 * length or s > 1.01 * length:
            add(f"<pinflex:point_mass name='{p.name}'>", f"the mass sits {s:.4g} m along the "
                f"beam of link '{p.link}', which is {length:g} m long: it rides on the beam's "
                f"{'root' if s < 0 else 'tip'} through a rigid lever of "
                f"{abs(s if s < 0 else s - length):.3g} m; check xyz (link frame, metres)",
                False)
    raise_problems(source, problems, " in the pinflex annotations")
