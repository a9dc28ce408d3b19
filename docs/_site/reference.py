"""Reference pages generated from the code: the annotation schema, the study files, the CLI.

Each page is rendered from the table the readers themselves check against, so that a key or an
attribute added to the code appears here at the next build, with its type, bounds and one line
of documentation. ``python docs/_site/reference.py DIR`` writes the pages into ``DIR`` (to read
them without building the site).
"""

from __future__ import annotations

import dataclasses
import inspect
import math
import sys
from pathlib import Path

_GENERATED = (
    "<!-- generated at build time from {source}: edit the code, not this page -->\n\n"
)


def _num(x: float) -> str:
    if x == math.inf:
        return "∞"
    if x == -math.inf:
        return "−∞"
    return f"{x:g}"


def _cell(text: str) -> str:
    return str(text).replace("|", "\\|").replace("\n", " ")


# --------------------------------------------------------------------- annotation schema
def _attr_bounds(a) -> str:
    parts = []
    if a.gt is not None:
        parts.append(f"> {_num(a.gt)}")
    if a.ge is not None:
        parts.append(f"≥ {_num(a.ge)}")
    if a.lt is not None:
        parts.append(f"< {_num(a.lt)}")
    if a.le is not None:
        parts.append(f"≤ {_num(a.le)}")
    if a.kind == "choice" and a.choices:
        parts.append(" / ".join(f"`{c}`" for c in a.choices))
    return ", ".join(parts)


def _attr_ranges(a) -> str:
    parts = []
    if a.physical is not None:
        parts.append(f"refused outside [{_num(a.physical[0])}, {_num(a.physical[1])}]")
    if a.plausible is not None:
        parts.append(f"warned outside [{_num(a.plausible[0])}, {_num(a.plausible[1])}]")
    return "; ".join(parts)


def annotations_page() -> str:
    """The elements and attributes of the namespace ``urn:pinflex:urdf:1``."""
    from pinflex.description import schema
    from pinflex.description.types import NAMESPACE

    lines = [
        _GENERATED.format(source="pinflex.description.schema.SCHEMA"),
        "# Annotation schema",
        "",
        f"Every element of the namespace `{NAMESPACE}` that pinflex reads, with every "
        "attribute, in the order the checks know them. A URDF parser that is not pinflex "
        "(Pinocchio's included) ignores these elements. Anything else in the namespace is "
        "refused with the file, line and the closest valid name. Values are checked in three "
        "tiers: *bounds* are always enforced; values outside the *refused* range are "
        "non-physical for a robot link (refused by default, warned with "
        "`plausibility=\"warn\"`); values outside the *warned* range raise a "
        "`PlausibilityWarning`. Numeric attributes marked *{param}* may be written as "
        "`{name}`, a reference to a `<pinflex:parameter>`.",
        "",
        "How the elements fit together is shown in [Declaring flexible links](../overlays.md).",
        "",
    ]
    for name, el in schema.SCHEMA.items():
        lines.append(f"## `<pinflex:{name}>`")
        lines.append("")
        if el.doc:
            lines.append(el.doc[0].upper() + el.doc[1:] + ".")
            lines.append("")
        parents = ", ".join(
            "the document root" if p == "<document>" else
            ("a URDF `<robot>`" if p == "robot" else f"`<pinflex:{p}>`") for p in el.parents)
        lo, hi = el.count
        count = (f"exactly {lo}" if lo == hi else
                 f"{lo} to {hi}" if hi is not None else f"at least {lo}" if lo else "any number")
        lines.append(f"Appears in {parents}; {count} per parent.")
        if el.declares:
            lines.append(f" Its `{el.declares}` declares a name that numeric attributes may "
                         f"reference as `{{{el.declares}}}`.")
        lines.append("")
        lines.append("| attribute | meaning | type | values |")
        lines.append("|---|---|---|---|")
        for aname, a in el.attrs.items():
            kind = a.kind + (f" [{a.unit}]" if a.unit else "")
            values = "; ".join(v for v in (
                "required" if a.required else "",
                _attr_bounds(a),
                _attr_ranges(a),
                "may be {param}" if a.reference and a.kind in ("float", "int", "vec3") else "",
            ) if v)
            lines.append("| " + " | ".join(_cell(c) for c in (
                f"`{aname}`", a.doc, kind, values)) + " |")
        lines.append("")
    lines += [
        "## Limits",
        "",
        f"- At most {schema.MAX_ELEMENTS_PER_LINK} elements per flexible link.",
        f"- Coordinates of points and vectors within ±{_num(schema.MAX_COORDINATE)} m.",
        "",
    ]
    return "\n".join(lines)


# --------------------------------------------------------------------- study files
_KINDS = {
    "str": "string", "bool": "boolean", "int": "integer", "float": "number",
    "floats": "array of numbers", "ints": "array of integers",
    "mapping": "table of name = number", "table": "table", "tables": "array of tables",
    "points": "array of [x, y, z]", "float_or_floats": "number or array of numbers",
    "orientation": "\"keep\", \"free\" or [roll, pitch, yaw]",
    "foreign_table": "table",
}


def _key_bounds(k) -> str:
    parts = []
    if k.gt is not None:
        parts.append(f"> {_num(k.gt)}")
    if k.ge is not None:
        parts.append(f"≥ {_num(k.ge)}")
    if k.le is not None:
        parts.append(f"≤ {_num(k.le)}")
    if k.choices:
        parts.append(" / ".join(f"`\"{c}\"`" for c in k.choices))
    if k.min_items:
        parts.append(f"at least {k.min_items} entries")
    return ", ".join(parts)


def _study_table(title: str, keys, lines: list[str], anchor_note: str = "") -> None:
    lines.append(f"## `{title}`")
    lines.append("")
    if anchor_note:
        lines.append(anchor_note)
        lines.append("")
    lines.append("| key | meaning | type | values |")
    lines.append("|---|---|---|---|")
    nested = []
    for name, k in keys.items():
        values = "; ".join(v for v in ("required" if k.required else "", _key_bounds(k)) if v)
        lines.append("| " + " | ".join(_cell(c) for c in (
            f"`{name}`", k.doc, _KINDS.get(k.kind, k.kind), values)) + " |")
        if k.kind in ("table", "tables") and k.keys:
            nested.append((name, k))
    lines.append("")
    prefix = "" if title == "top level" else title.strip("[]") + "."
    for name, k in nested:
        t = f"[[{prefix}{name}]]" if k.kind == "tables" else f"[{prefix}{name}]"
        _study_table(t, k.keys, lines, k.doc[0].upper() + k.doc[1:] + "." if k.doc else "")


def _simulation_section(lines: list[str]) -> None:
    from pinflex.dynamics import study as sim

    settings = {f.name: f for f in dataclasses.fields(sim.SimulationSettings)}
    defaults = sim.SimulationSettings()
    lines += [
        "## `[simulation]`",
        "",
        "Read by `pinflex simulate` (the assignment ignores it). Every key is optional.",
        "",
        "| key | default | allowed |",
        "|---|---|---|",
    ]
    bounds = getattr(sim, "_NUMBERS", {})
    for name in settings:
        value = getattr(defaults, name)
        if dataclasses.is_dataclass(value):
            value = "none"
        allowed = ""
        if name in bounds:
            lo, hi, inclusive = bounds[name]
            allowed = f"{'[' if inclusive else '('}{_num(lo)}, {_num(hi)}]"
        elif name == "drive":
            allowed = "`\"prescribed\"` / `\"torque\"`"
        elif name == "damping":
            allowed = ("`\"none\"`, `{ kind = \"rayleigh\", alpha, beta }` or "
                       "`{ kind = \"modal\", ratios = [...] }`")
        elif name in ("gravity", "point"):
            allowed = "[x, y, z]"
        elif name == "frame":
            allowed = "a link name"
        lines.append(f"| `{name}` | `{value}` | {_cell(allowed)} |")
    lines += ["", "The keys, as the reader documents them:", "", "```toml"]
    doc = inspect.getdoc(sim) or ""
    block = doc.split("::", 1)[1] if "::" in doc else ""
    body = [ln[4:] for ln in block.splitlines() if ln.startswith("    ") or not ln.strip()]
    while body and not body[-1].strip():
        body.pop()
    while body and not body[0].strip():
        body.pop(0)
    lines += body
    lines += ["```", ""]


def study_page() -> str:
    """The TOML study format of ``pinflex assign`` and ``pinflex simulate``."""
    from pinflex.assignment import study_schema

    lines = [
        _GENERATED.format(source="pinflex.assignment.study_schema.STUDY and "
                          "pinflex.dynamics.study"),
        "# Study and simulation files",
        "",
        "A study is one TOML file read by `pinflex assign`, `pinflex simulate`, `pinflex "
        "batch assign` and `pinflex size`. Unknown keys, wrong TOML types, NaN or inf, and "
        "values out of range are refused, every problem of a file in one error, with the "
        "closest valid key name. [Study files](../howto/study-files.md) shows complete "
        "examples.",
        "",
    ]
    _study_table("top level", study_schema.STUDY, lines)
    _simulation_section(lines)
    return "\n".join(lines)


# --------------------------------------------------------------------- command line
def cli_page() -> str:
    """``pinflex --help`` and each subcommand's ``--help``."""
    import argparse
    import os

    from pinflex.cli import SUBCOMMANDS, build_parser

    os.environ.setdefault("COLUMNS", "100")
    parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    lines = [
        _GENERATED.format(source="the argument parsers of pinflex.cli"),
        "# Command line",
        "",
        "`pinflex SUBCOMMAND --help` prints the same text. Exit status: 0 on success; 3 when "
        "`assign` or `size` ran but the exact model does not meet the targets, floors or "
        "constraints; 2 for a user error (one line on stderr saying what to fix); 1 for an "
        "internal error (one line; `--debug` shows the traceback); 130 when interrupted; 141 "
        "when the reader of standard output went away (`pinflex modes ... | head`).",
        "",
        "Long commands draw a progress bar on stderr when it is a terminal (`modes "
        "--trajectory`, `path`, `assign`, `size`, `simulate`, `view`, `batch`, `prbdm`); "
        "`--no-progress` hides it.",
        "",
        "```text",
        parser.format_help().rstrip(),
        "```",
        "",
    ]
    for name in SUBCOMMANDS:
        p = sub.choices[name]
        lines += [f"## `pinflex {name}`", "", "```text", p.format_help().rstrip(), "```", ""]
    return "\n".join(lines)


def pages() -> dict[str, str]:
    """Generated pages by their path in the site."""
    return {
        "reference/annotations.md": annotations_page(),
        "reference/study.md": study_page(),
        "reference/cli.md": cli_page(),
    }


if __name__ == "__main__":
    out = Path(sys.argv[1] if len(sys.argv) > 1 else ".")
    for uri, text in pages().items():
        path = out / uri
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
        print(path)
