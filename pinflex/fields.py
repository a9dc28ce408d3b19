"""The one schema engine of pinflex's input files: declarative fields and their checks.

Every value pinflex reads from a file is declared once as a :class:`Field`: its kind, unit,
hard bounds, physical and plausible ranges, whether it is required, and one line of
documentation. Three tables are written with it:

* the pinflex URDF annotations (:data:`pinflex.description.schema.SCHEMA`: elements whose
  ``attrs`` are fields, values read from attribute text),
* TOML studies (:data:`pinflex.assignment.study_schema.STUDY`),
* the ``[simulation]`` table of a study (:data:`pinflex.assignment.study_schema.SIMULATION`).

The engine reads a value in two ways, which end in the same checks:

* :func:`parse_text` turns XML attribute text into a typed value through the one number
  grammar (:func:`pinflex.validation.parse_number`);
* :func:`check_value` checks a typed value (TOML, a Python argument): its type (a boolean is
  never a number, ``1.7`` is not a whole number, NaN and inf are not finite), the keys of
  tables (unknown keys with the closest valid name, missing required keys), the length of
  arrays, and the table's cross-key rules.

Both call :func:`check_range`, which reports a value outside the hard bounds as an error,
outside the physical range as ``"physical"`` (refused by default, a warning on request) and
outside the plausible range as a warning. Problems go to a ``report(where, message, level)``
callback; each reader turns them into its own named error (:class:`~pinflex.exceptions.
SchemaError`, :class:`~pinflex.exceptions.StudyError`, ...) listing every problem at once.

:func:`field_rows` lists a table for documentation (name, kind, unit, range, required, doc).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field

from pinflex.validation import parse_int, parse_number, suggestion

#: ``report(where, message, level)``; level is ``"error"``, ``"physical"`` or ``"warning"``.
Report = Callable[[str, str, str], None]


@dataclass(frozen=True)
class Field:
    """One value of an input file.

    Attributes:
        kind: Scalars: ``'float'``, ``'int'``, ``'bool'``, ``'str'`` (a non-empty string),
            ``'choice'`` (one of ``choices``), ``'name'`` (letters, digits, '_', '.', '-'),
            ``'ident'`` (letters, digits, '_'), ``'text'`` (XML only: non-empty text).
            Compound: ``'vec3'`` (three floats), ``'array'`` (of ``item``), ``'mapping'``
            (a table ``{name = item}``), ``'table'`` (of ``keys``), ``'tables'`` (an array
            of tables of ``keys``), ``'either'`` (one of ``options``, picked by the value's
            type: a list, a table or a scalar).
        required: Whether it must be present.
        gt, ge, le, lt: Hard bounds of a number (of every number of a compound value).
        physical: ``(low, high)`` outside which the value is not physical (refused by
            default; only a warning where the reader allows it).
        plausible: ``(low, high)`` outside which a warning is issued.
        why: Reason shown with a physical or plausible finding.
        unit: Unit of the value, shown in messages and docs.
        choices: Allowed strings of a ``'choice'``.
        reference: XML only: whether ``{parameter}`` may stand for the number.
        keys: Fields of a ``'table'`` or of each table of ``'tables'``.
        item: Field of each entry of an ``'array'`` or ``'mapping'``.
        options: Alternatives of an ``'either'``.
        min_items, max_items: Bounds on the number of entries of a compound value.
        rules: Cross-key checks ``rule(table, report)`` with ``report(key, message)``, run on
            a table after its keys.
        doc: One line of documentation.
    """

    kind: str = "float"
    required: bool = False
    gt: float | None = None
    ge: float | None = None
    le: float | None = None
    lt: float | None = None
    physical: tuple[float, float] | None = None
    plausible: tuple[float, float] | None = None
    why: str = ""
    unit: str = ""
    choices: tuple[str, ...] = ()
    reference: bool = True
    keys: Mapping[str, Field] = field(default_factory=dict)
    item: Field | None = None
    options: tuple[Field, ...] = ()
    min_items: int = 0
    max_items: int | None = None
    rules: tuple[Callable, ...] = ()
    doc: str = ""

    @property
    def numeric(self) -> bool:
        """Whether the value is a number or a vector of numbers."""
        return self.kind in ("float", "int", "vec3")

    def bounds_text(self) -> str:
        """The hard bounds as text, e.g. ``"(0, 1e+20]"`` (empty when unbounded)."""
        lo = (f"({self.gt:g}" if self.gt is not None else
              f"[{self.ge:g}" if self.ge is not None else "")
        hi = (f"{self.lt:g})" if self.lt is not None else
              f"{self.le:g}]" if self.le is not None else "")
        if not lo and not hi:
            return ""
        return f"{lo or '(-inf'}, {hi or 'inf)'}"


#: Longest array read from an input file (entries); bigger inputs belong in a data file.
MAX_ITEMS = 100_000

_IDENT_CHARS = set("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_")
_NAME_CHARS = _IDENT_CHARS | set(".-")


def _is_ident(text: str, chars: set[str]) -> bool:
    return bool(text) and (text[0].isascii() and (text[0].isalpha() or text[0] == "_")) and \
        all(c in chars for c in text)


# --------------------------------------------------------------------- text (XML)
def parse_text(f: Field, text: str):
    """The typed value of attribute text for field ``f``; ``ValueError`` saying why not.

    Numbers follow the one grammar (:func:`pinflex.validation.parse_number`), vectors are
    three numbers separated by ASCII spaces, booleans ``true``/``false``/``1``/``0``.
    """
    kind = f.kind
    if kind == "float":
        return parse_number(text)
    if kind == "int":
        return parse_int(text)
    if kind == "vec3":
        parts = split_vector(text)
        if len(parts) != 3:
            raise ValueError(f"expected three numbers, got {len(parts)}")
        return tuple(parse_number(p) for p in parts)
    if kind == "bool":
        t = text.strip(" \t\r\n").lower()
        if t in ("true", "1"):
            return True
        if t in ("false", "0"):
            return False
        raise ValueError("expected true or false")
    if kind == "choice":
        if text not in f.choices:
            raise ValueError("expected " + " or ".join(f"'{c}'" for c in f.choices)
                             + "; " + suggestion(text, f.choices))
        return text
    if kind == "ident":
        if not _is_ident(text, _IDENT_CHARS):
            raise ValueError("expected a name of ASCII letters, digits and '_' starting with a "
                             "letter")
        return text
    if kind == "name":
        if not _is_ident(text, _NAME_CHARS):
            raise ValueError("expected a name of ASCII letters, digits, '_', '.', '-' "
                             "starting with a letter")
        return text
    if not text.strip():
        raise ValueError("must not be empty")
    return text


def split_vector(text: str) -> list[str]:
    """The words of a vector attribute, separated by ASCII whitespace only."""
    return [w for w in re.split(r"[ \t\r\n]+", text) if w]


# --------------------------------------------------------------------- ranges
def _fmt(value) -> str:
    return f"{value:g}" if isinstance(value, float) else repr(value)


def check_range(f: Field, value: float, label: str, where: str, report: Report, *,
                subject: str = "") -> bool:
    """Check one number against the bounds and ranges of ``f``; False if a hard bound fails.

    Args:
        f: The field.
        value: The number (already known to be finite).
        label: How the value is named in messages, e.g. ``"E=70"`` or ``"1e+12"``.
        where: Location passed to ``report``.
        report: The problem callback.
        subject: What the physical range is about, e.g. ``" for a robot link"``.
    """
    unit = f" [{f.unit}]" if f.unit else ""
    bad = None
    if f.gt is not None and not value > f.gt:
        bad = "a positive number" if f.gt == 0 else f"above {f.gt:g}"
    elif f.ge is not None and not value >= f.ge:
        bad = "a number >= 0" if f.ge == 0 else f">= {f.ge:g}"
    elif f.lt is not None and not value < f.lt:
        bad = f"below {f.lt:g}"
    elif f.le is not None and not value <= f.le:
        bad = f"at most {f.le:g}"
    if bad is not None:
        report(where, f"{label} must be {bad}{unit}{_why_bound(f)}", "error")
        return False
    why = f"; {f.why}" if f.why else ""
    if f.physical is not None and not f.physical[0] <= value <= f.physical[1]:
        report(where, f"{label}{unit} is outside [{f.physical[0]:g}, {f.physical[1]:g}], not "
               f"physical{subject}{why}", "physical")
    elif f.plausible is not None and not f.plausible[0] <= value <= f.plausible[1]:
        report(where, f"{label}{unit} is unusual{subject} (outside [{f.plausible[0]:g}, "
               f"{f.plausible[1]:g}]){why}", "warning")
    return True


def _why_bound(f: Field) -> str:
    return f" ({f.why})" if f.why and f.physical is None and f.plausible is None else ""


# --------------------------------------------------------------------- typed values
def type_name(value) -> str:
    """How a value is named in messages: ``the string 'x'``, ``the boolean true``, ..."""
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, int | float):
        return f"the number {value!r}"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, dict):
        return "a table"
    return type(value).__name__


def _join(where: str, key) -> str:
    return f"{where}.{key}" if where else str(key)


def check_value(value, f: Field, where: str, report: Report, *, subject: str = "") -> None:
    """Check a typed value (TOML data, a Python argument) against ``f``; problems reported."""
    kind = f.kind
    if kind == "table":
        check_table(value, f.keys, where, report, f.rules, subject=subject)
    elif kind == "tables":
        if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
            report(where, f"expected an array of tables ([[{where}]]), got {type_name(value)}",
                   "error")
            return
        if _count(value, f, where, report):
            for i, entry in enumerate(value):
                check_table(entry, f.keys, f"{where}[{i}]", report, f.rules, subject=subject)
    elif kind == "either":
        check_value(value, pick_option(f, value), where, report, subject=subject)
    elif kind == "bool":
        if not isinstance(value, bool):
            hint = " (a TOML boolean is written without quotes)" if isinstance(value, str) \
                else ""
            report(where, f"expected true or false, got {type_name(value)}{hint}", "error")
    elif kind in ("str", "choice", "name", "ident", "text"):
        if not isinstance(value, str):
            report(where, f"expected a string, got {type_name(value)}", "error")
        elif kind == "choice" and value not in f.choices:
            report(where, f"{value!r} is not one of " + ", ".join(repr(c) for c in f.choices)
                   + "; " + suggestion(value, f.choices), "error")
        elif not value.strip():
            report(where, "must not be empty", "error")
        elif kind in ("name", "ident"):
            try:
                parse_text(f, value)
            except ValueError as exc:
                report(where, str(exc), "error")
    elif kind in ("float", "int"):
        check_number(value, f, where, report, subject=subject)
    elif kind == "vec3":
        if not isinstance(value, list | tuple) or len(value) != 3:
            report(where, f"expected [x, y, z], got {type_name(value)}"
                   + (f" of {len(value)}" if isinstance(value, list) else ""), "error")
            return
        for j, v in enumerate(value):
            check_number(v, Field("float", gt=f.gt, ge=f.ge, le=f.le, lt=f.lt, unit=f.unit),
                         f"{where}[{j}]", report, subject=subject)
    elif kind == "array":
        if not isinstance(value, list):
            report(where, f"expected an array, got {type_name(value)}", "error")
            return
        if _count(value, f, where, report):
            item = f.item or Field("float")
            for i, v in enumerate(value):
                check_value(v, item, f"{where}[{i}]", report, subject=subject)
    elif kind == "mapping":
        if not isinstance(value, dict):
            report(where, f"expected a table {{ name = value }}, got {type_name(value)}",
                   "error")
            return
        item = f.item or Field("float")
        for name, v in value.items():
            check_value(v, item, _join(where, name), report, subject=subject)
    else:  # pragma: no cover - a schema typo
        raise AssertionError(kind)


def pick_option(f: Field, value) -> Field:
    """The alternative of an ``'either'`` field matching the value's type."""
    def shape(g: Field) -> str:
        if g.kind in ("array", "vec3", "tables"):
            return "list"
        if g.kind in ("table", "mapping"):
            return "dict"
        return "scalar"

    want = "list" if isinstance(value, list) else "dict" if isinstance(value, dict) else "scalar"
    for g in f.options:
        if shape(g) == want:
            return g
    return f.options[0]


def _count(value: list, f: Field, where: str, report: Report) -> bool:
    n = len(value)
    if n < f.min_items:
        report(where, "must not be empty" if f.min_items == 1 else
               f"needs at least {f.min_items} entries, got {n}", "error")
        return False
    most = f.max_items if f.max_items is not None else MAX_ITEMS
    if n > most:
        report(where, f"has {n} entries, more than the {most} allowed", "error")
        return False
    return True


def check_number(value, f: Field, where: str, report: Report, *, subject: str = "") -> None:
    """A typed number: not a boolean or string, whole for ``'int'``, finite, within range."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        report(where, f"expected a number, got {type_name(value)}", "error")
        return
    if f.kind == "int" and not isinstance(value, int):
        report(where, f"expected a whole number, got {value!r}", "error")
        return
    if not math.isfinite(value):
        report(where, f"must be finite, got {value!r}", "error")
        return
    check_range(f, value, repr(value), where, report, subject=subject)


def check_table(data, keys: Mapping[str, Field], where: str, report: Report, rules=(), *,
                subject: str = "") -> None:
    """Check a table: unknown keys (closest valid name), missing keys, each value, rules."""
    if not isinstance(data, dict):
        report(where, f"expected a table, got {type_name(data)}", "error")
        return
    for key in data:
        if key not in keys:
            report(_join(where, key), f"unknown key in {where or 'the study'}; "
                   + suggestion(str(key), keys), "error")
    for key, f in keys.items():
        if key not in data:
            if f.required:
                report(_join(where, key), "is missing", "error")
            continue
        check_value(data[key], f, _join(where, key), report, subject=subject)
    for rule in rules:
        rule(data, lambda key, msg, _w=where: report(_join(_w, key) if key else _w, msg,
                                                      "error"))


# --------------------------------------------------------------------- documentation
def field_rows(keys: Mapping[str, Field], prefix: str = "") -> Iterator[dict]:
    """One row per field of a table and its sub-tables, for reference documentation.

    Yields:
        ``{"name", "kind", "unit", "bounds", "physical", "plausible", "required", "doc"}``
        with dotted names for sub-tables (``trajectory.path.samples``).
    """
    for name, f in keys.items():
        full = f"{prefix}{name}"
        yield {
            "name": full,
            "kind": f.kind if f.kind != "choice" else " | ".join(f.choices),
            "unit": f.unit,
            "bounds": f.bounds_text(),
            "physical": "" if f.physical is None else f"[{f.physical[0]:g}, {f.physical[1]:g}]",
            "plausible": "" if f.plausible is None else
            f"[{f.plausible[0]:g}, {f.plausible[1]:g}]",
            "required": f.required,
            "doc": f.doc,
        }
        if f.kind in ("table", "tables"):
            yield from field_rows(f.keys, full + ("[]." if f.kind == "tables" else "."))
