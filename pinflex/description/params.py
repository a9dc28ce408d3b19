"""Named parameters of a description and ``{name}`` references in numeric attributes.

A parameter element::

    <pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.05" design="true"/>

Any numeric attribute of a pinflex element may then read ``"{d1}"`` instead of a number (in a
vector attribute such as ``xyz``, each component may be a reference). ``design="true"`` makes
the parameter a design variable of Taylor models and assignments (it needs finite ``lower``
and ``upper`` bounds); design parameters may be used in section dimensions, explicit section
properties, ``E``, ``G``, ``density``, ``linear_density``, point-mass ``mass`` values and joint
``stiffness``, where they enter ``M`` and ``K`` through the section formulas. Other parameters
are plain named numbers and may appear in any numeric attribute.
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass

from pinflex.validation import ASCII_SPACE, parse_number
from pinflex.exceptions import (
    DesignVariableOutOfBounds,
    InvalidBeamProperty,
    InvalidDescription,
    ParameterNotFound,
)

_REF = re.compile(r"\{[ \t]*([A-Za-z_][A-Za-z0-9_]*)[ \t]*\}", re.ASCII)
_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*", re.ASCII)
_TRUE = ("1", "true", "yes")
_BOOL = _TRUE + ("0", "false", "no")


@dataclass(frozen=True)
class Parameter:
    """A named number of a description.

    Attributes:
        name: Identifier (letters, digits, underscores).
        value: Current value (the file's, or a ``values=`` / ``--set`` override) [SI].
        lower: Lower bound (``-inf`` when absent).
        upper: Upper bound (``inf`` when absent).
        design: Whether it is a design variable.
        used_in: The attributes that reference it, e.g. ``("flexible link 'l1' diameter",)``.
        unit: Its unit, from the attributes that use it (``m`` for a diameter, ``Pa`` for
            E, ``kg/m^3`` for a density, ``kg`` for a mass, ``N m/rad`` or ``N/m`` for a
            joint stiffness); ``""`` when it is unused or dimensionless.
    """

    name: str
    value: float
    lower: float = -math.inf
    upper: float = math.inf
    design: bool = False
    used_in: tuple[str, ...] = ()
    unit: str = ""


def reference(text: str | None) -> str | None:
    """The parameter name of a ``{name}`` reference, else None."""
    if text is None:
        return None
    m = _REF.fullmatch(text.strip(ASCII_SPACE))
    return m.group(1) if m else None


def _number(text: str, what: str) -> float:
    """A number of the one grammar; ``-inf``/``inf`` stand for absent bounds only."""
    if text in ("-inf", "inf"):
        return float(text)
    try:
        return parse_number(text)
    except ValueError as exc:
        raise InvalidDescription(f"{what}: {exc}") from exc


def read_parameters(root_el: ET.Element, ns: str, overrides: dict[str, float] | None
                    ) -> dict[str, Parameter]:
    """The well-formed ``<pinflex:parameter>`` elements of a document, overrides applied.

    Lenient: malformed parameters are left out (the schema checks name them), and an
    override outside its parameter's bounds is not applied (the build refuses it by name).
    Used by the schema checks to check ``{name}`` references with the values they stand for.
    """
    params: dict[str, Parameter] = {}
    for el in root_el.findall(ns + "parameter"):
        name = el.get("name", "")
        if not _NAME.fullmatch(name) or name in params:
            continue
        try:
            value = _number(el.get("value", ""), "")
            lower = _number(el.get("lower", "-inf"), "")
            upper = _number(el.get("upper", "inf"), "")
        except InvalidDescription:
            continue
        design = el.get("design", "false").strip().lower() in _TRUE
        if overrides and name in overrides:
            new = overrides[name]
            if isinstance(new, int | float) and not isinstance(new, bool) and \
                    math.isfinite(new) and lower <= new <= upper:
                value = float(new)
        if not (math.isfinite(value) and lower <= upper):
            continue
        if design and not (math.isfinite(lower) and math.isfinite(upper)):
            design = False  # refused by name elsewhere; check the nominal value only
        params[name] = Parameter(name, value, lower, upper, design)
    return params


def parse_parameters(root_el: ET.Element, ns: str, overrides: dict[str, float] | None
                     ) -> dict[str, Parameter]:
    """Read every ``<pinflex:parameter>`` and apply value overrides (checked against bounds).

    Overrides naming no parameter are left to the caller (they may be point masses).
    """
    params: dict[str, Parameter] = {}
    for el in root_el.findall(ns + "parameter"):
        name = el.get("name", "")
        if not _NAME.fullmatch(name):
            raise InvalidDescription(
                f"<pinflex:parameter name='{name}'>: a parameter name is an identifier "
                "(letters, digits and underscores, not starting with a digit)"
            )
        if name in params:
            raise InvalidDescription(f"parameter '{name}' is declared twice")
        what = f"parameter '{name}'"
        for key in ("value", "lower", "upper"):
            if reference(el.get(key)) is not None:
                raise InvalidDescription(f"{what}: {key} must be a number, not a reference")
        value_text = el.get("value")
        if value_text is None:
            raise InvalidDescription(f"{what}: attribute 'value' is missing")
        value = _number(value_text, what + " value")
        lower = _number(el.get("lower", "-inf"), what + " lower")
        upper = _number(el.get("upper", "inf"), what + " upper")
        design_text = el.get("design", "false").lower()
        if design_text not in _BOOL:
            raise InvalidDescription(f"{what}: design='{el.get('design')}' must be true or false")
        design = design_text in _TRUE
        if not lower <= upper:
            raise InvalidDescription(f"{what}: lower bound {lower} is above upper bound {upper}")
        if design and not (math.isfinite(lower) and math.isfinite(upper)):
            raise InvalidDescription(
                f"{what}: a design parameter needs finite lower=\"...\" and upper=\"...\" bounds"
            )
        if overrides and name in overrides:
            value = float(overrides[name])
        if not math.isfinite(value):
            raise InvalidDescription(f"{what}: value {value} is not finite")
        if not lower <= value <= upper:
            raise DesignVariableOutOfBounds(name, value, lower, upper)
        params[name] = Parameter(name, value, lower, upper, design)
    return params


class Resolver:
    """Reads numeric attributes, resolving ``{name}`` references and recording their use."""

    def __init__(self, params: dict[str, Parameter],
                 unit_of: Callable[[ET.Element, str], str] | None = None):
        """``unit_of(element, attribute)`` gives an attribute's unit (the schema's), which a
        parameter referenced there takes."""
        self.params = params
        self.unit_of = unit_of or (lambda el, key: "")
        self.uses: dict[str, list[str]] = {name: [] for name in params}
        self.units: dict[str, dict[str, str]] = {name: {} for name in params}

    def lookup(self, name: str, what: str, *, design_ok: bool, unit: str = "") -> Parameter:
        """The parameter ``name`` used by ``what``; errors for unknown or misplaced ones."""
        if name not in self.params:
            raise ParameterNotFound(name, self.params, what)
        p = self.params[name]
        if p.design and not design_ok:
            raise InvalidDescription(
                f"{what}: '{{{name}}}' is a design parameter, which may only set section "
                "dimensions or properties, E, G, density, linear_density, point-mass values and "
                "joint stiffness; declare it without design=\"true\" to use it here"
            )
        self.uses[name].append(what)
        if unit:
            self.units[name].setdefault(unit, what)
        return p

    def number(self, el: ET.Element, key: str, what: str, *, required: bool = True,
               positive: bool = True, design_ok: bool = False,
               unit: str | None = None) -> float | None:
        """The value of attribute ``key`` (a number or a reference); None if absent.

        ``unit`` is the attribute's unit (default: ``unit_of(el, key)``); a
        referenced parameter takes it.
        """
        text = el.get(key)
        where = f"{what} {key}"
        if text is None:
            if required:
                raise InvalidBeamProperty(f"{what}: attribute '{key}' is missing")
            return None
        name = reference(text)
        if name is not None:
            value = self.lookup(name, where, design_ok=design_ok,
                                unit=self.unit_of(el, key) if unit is None else unit).value
        elif "{" in text or "}" in text:
            raise InvalidDescription(
                f"{where}='{text}': a reference is written '{{name}}' with a parameter name"
            )
        else:
            try:
                value = parse_number(text)
            except ValueError as exc:
                raise InvalidBeamProperty(f"{what}: {key}: {exc}") from exc
        if positive and (not math.isfinite(value) or value <= 0.0):
            raise InvalidBeamProperty(f"{what}: {key}={text} must be a positive finite number"
                                      + (f" (it is {value})" if name else ""))
        return value

    def ref(self, el: ET.Element, key: str) -> str | None:
        """The name of the *design* parameter attribute ``key`` references, else None."""
        name = reference(el.get(key))
        if name is not None and name in self.params and self.params[name].design:
            return name
        return None

    def text(self, el: ET.Element, key: str, what: str) -> str | None:
        """Attribute text with every ``{name}`` token replaced by its (non-design) value."""
        text = el.get(key)
        if text is None or "{" not in text:
            return text
        out = []
        for tok in text.split():
            name = reference(tok)
            if name is None and ("{" in tok or "}" in tok):
                raise InvalidDescription(
                    f"{what} {key}='{text}': a reference is written '{{name}}'"
                )
            out.append(tok if name is None else
                       repr(self.lookup(name, f"{what} {key}", design_ok=False,
                                        unit=self.unit_of(el, key)).value))
        return " ".join(out)

    def finish(self) -> dict[str, Parameter]:
        """The parameters with the attributes that use them and their unit.

        Raises:
            InvalidDescription: A parameter is used with two different units (a diameter in
                m and a modulus in Pa cannot be the same number).
        """
        out = {}
        for n, p in self.params.items():
            units = self.units[n]
            if len(units) > 1:
                uses = "; ".join(f"[{u}] in {w}" for u, w in units.items())
                raise InvalidDescription(
                    f"parameter '{n}' is used with different units: {uses}; one parameter has "
                    "one unit, declare one parameter per quantity")
            out[n] = Parameter(p.name, p.value, p.lower, p.upper, p.design,
                               tuple(self.uses[n]), next(iter(units), ""))
        return out

