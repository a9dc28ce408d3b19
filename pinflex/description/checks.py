"""Checks of a description document against :data:`~pinflex.description.schema.SCHEMA`.

:func:`check_annotations` walks every pinflex element and attribute of a document (an
annotated URDF or an overlay) and collects every problem with its line;
:func:`check_physical` compares the parsed beams with their links (section size against
length, implied density). The plain URDF around the annotations is checked by
:mod:`pinflex.description.urdf_checks`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

from pinflex.description.params import Parameter, read_parameters, reference
from pinflex.description.schema import (
    _NS,
    MAX_COORDINATE,
    SCHEMA,
    URDF_TOP_LEVEL,
    Attr,
    Checked,
    _Context,
)
from pinflex.description.source import XmlDocument, element_label, local_name
from pinflex.description.types import NAMESPACE
from pinflex.exceptions import (
    ImplausibleValue,
    InvalidAttribute,
    InvalidDescription,
    PlausibilityWarning,
    UnknownAttribute,
    UnknownElement,
)
from pinflex.fields import check_range, parse_text, split_vector
from pinflex.validation import Problem, closest, parse_number, raise_problems, suggestion


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
        label = name if name is not None else element_label(el)
        self.problems.append(Problem(self.where(el, attr, label), message, error,
                                     PlausibilityWarning if warning else None))

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
            ns, local = local_name(child.tag)
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
            ns, local = local_name(child.tag)
            mine = ns == NAMESPACE
            if not top and mine and not inside_pinflex:
                self.add(child, None, f"<pinflex:{local}> must be a direct child of <robot>",
                         UnknownElement)
            if not mine:
                for key in child.attrib:
                    kns, klocal = local_name(key)
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
            kns, klocal = local_name(key)
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
