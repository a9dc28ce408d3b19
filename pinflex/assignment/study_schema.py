"""The schema of TOML assignment studies, and the checks that list every problem at once.

Every table and key of a study is one entry of :data:`STUDY`. The checks refuse unknown keys
in any table (with the closest valid name: ``ordr`` -> ``order``), values of the wrong TOML
type (``planar = "no"`` is a string, not a boolean; ``mode = 1.7`` is not a whole number;
booleans are never numbers), non-finite numbers (TOML allows ``nan`` and ``inf``), values out
of range (``order`` above :data:`pinflex.resources.MAX_TAYLOR_ORDER`, a non-positive target
frequency, a band whose low edge is above its high edge) and, once the robot is loaded, mode
numbers the model does not have, design names it does not declare, and poses of the wrong
length. All problems of a file are gathered into one :class:`~pinflex.exceptions.StudyError`.

Extending the format is one entry: a key is ``"name": Key(kind, ...)`` in its table's
``keys``; a table is ``Key("table", keys={...})``; an array of tables ``Key("tables", ...)``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import TypeGuard

from pinflex.exceptions import StudyError
from pinflex.resources import MAX_TAYLOR_ORDER
from pinflex.validation import Problem, closest, suggestion


@dataclass(frozen=True)
class Key:
    """One key of a study table.

    Attributes:
        kind: 'str', 'bool', 'int', 'float', 'floats' (array of numbers), 'ints', 'mapping'
            (table of name = number), 'table', 'tables' (array of tables), 'points' (array of
            [x, y, z]), 'float_or_floats', 'orientation' ("keep", "free" or [r, p, y]),
            'foreign_table' (a table whose keys another module checks), 'strs' (array of
            strings).
        required: Whether the key must be present.
        gt, ge, le: Bounds of numbers (of every entry for arrays and mappings).
        choices: Allowed strings.
        keys: Keys of a 'table' or of each entry of 'tables'.
        min_items: Fewest entries of an array.
        rules: Checks ``rule(table, report)`` of a table's values.
        doc: One line of documentation.
    """

    kind: str
    required: bool = False
    gt: float | None = None
    ge: float | None = None
    le: float | None = None
    choices: tuple[str, ...] = ()
    keys: Mapping[str, Key] = field(default_factory=dict)
    min_items: int = 0
    rules: tuple[Callable[[dict, Callable[[str, str], None]], None], ...] = ()
    doc: str = ""


def _one_trajectory(table: dict, report) -> None:
    given = [k for k in ("builtin", "csv", "path") if k in table]
    if len(given) != 1:
        report("", "give exactly one of builtin = \"...\", csv = \"...\" or a "
               "[trajectory.path] table" + (f" (got {', '.join(given)})" if given else ""))


def _band_order(table: dict, report) -> None:
    lo, hi = table.get("low_hz"), table.get("high_hz")
    if _number(lo) and _number(hi) and not lo < hi:
        report("low_hz", f"low_hz = {lo:g} must be below high_hz = {hi:g}")


_MODE = Key("int", required=True, ge=1, doc="non-rigid mode number, 1 = lowest")

#: The study format: top-level keys and tables.
STUDY: dict[str, Key] = {
    "robot": Key("str", required=True,
                 doc="annotated URDF or overlay, relative to the study or builtin:NAME"),
    "planar": Key("bool", doc="keep in-plane elastic dofs only (default false)"),
    "joints": Key("str", choices=("free", "locked", "annotated"),
                  doc="joint conditions: annotated (the file's <pinflex:joint>, the default), "
                  "or the overrides free and locked"),
    "values": Key("mapping", doc="parameters and point masses set before the study"),
    "simulation": Key("foreign_table", doc="time simulation settings (checked by "
                      "pinflex simulate)"),
    "trajectory": Key("table", rules=(_one_trajectory,), doc="the motion", keys={
        "builtin": Key("str", choices=("benchmark_a",), doc="a shipped trajectory"),
        "csv": Key("str", doc="CSV file: t, then one column per joint"),
        "path": Key("table", doc="a workspace path solved by inverse kinematics", keys={
            "frame": Key("str", required=True, doc="frame that follows the path"),
            "waypoints": Key("points", required=True, min_items=1, doc="points [m]"),
            "relative": Key("bool", doc="waypoints are offsets from the start"),
            "start_q": Key("floats", doc="joint values at the start"),
            "samples": Key("int", ge=2, le=100_000, doc="number of samples"),
            "duration_s": Key("float", gt=0.0, doc="duration [s]"),
            "profile": Key("str", choices=("minimum_jerk", "uniform"), doc="timing law"),
            "orientation": Key("orientation", doc="'keep', 'free' or roll-pitch-yaw [rad]"),
            "on_limits": Key("str", choices=("raise", "warn"), doc="joint-limit policy"),
        }),
    }),
    "expansion": Key("table", doc="the Taylor model", keys={
        "q0": Key("floats", doc="expansion pose (default: the middle sample)"),
        "y0": Key("mapping", ge=0.0, doc="expansion design {name = value} (each in its "
                  "variable's unit)"),
        "order": Key("int", ge=0, le=MAX_TAYLOR_ORDER, doc="Taylor order"),
        "quantity": Key("str", choices=("freq_hz", "eigval"), doc="expanded quantity"),
        "design": Key("strs", doc="design variables to choose (default: all)"),
    }),
    "targets": Key("tables", min_items=1, doc="wanted frequencies (pinflex assign)", keys={
        "mode": _MODE,
        "freq_hz": Key("float_or_floats", required=True, gt=0.0,
                       doc="target [Hz], constant or one per sample"),
        "weight": Key("float", ge=0.0, doc="weight in the cost (default 1)"),
    }),
    "constraints": Key("table", doc="QP constraints", keys={
        "mass_budget_kg": Key("float", doc="largest total added mass [kg] (below the "
                              "lower bounds it is infeasible, reported by the QP)"),
        "floors": Key("tables", doc="lowest allowed frequencies", keys={
            "mode": _MODE, "freq_hz": Key("float", required=True, gt=0.0, doc="floor [Hz]"),
        }),
        "bands": Key("tables", rules=(_band_order,), doc="forbidden frequency bands", keys={
            "mode": _MODE,
            "low_hz": Key("float", required=True, gt=0.0, doc="band start [Hz]"),
            "high_hz": Key("float", required=True, gt=0.0, doc="band end [Hz]"),
        }),
    }),
    "options": Key("table", doc="reporting and refinement", keys={
        "baseline": Key("mapping", ge=0.0, doc="the 'before' design {name = value}"),
        "refine": Key("bool", doc="re-expand at the answer and solve again"),
        "report_modes": Key("ints", ge=1, doc="further modes to report"),
        "confirm_tol": Key("float", gt=0.0, le=1.0, doc="largest relative difference "
                           "between the answer's predicted and exact frequencies (default "
                           "0.005)"),
        "target_tol": Key("float", gt=0.0, doc="largest exact target error for the "
                          "status 'met' (default 0.05)"),
        "max_refinements": Key("int", ge=0, le=100, doc="most re-expansions (default 8)"),
    }),
    "sizing": Key("table", doc="least design mass under the floors (pinflex size)", keys={
        "step_fraction": Key("float", gt=0.0, le=1.0, doc="trust region as a fraction of "
                             "the estimated radius (default 0.5)"),
        "max_expansions": Key("int", ge=1, le=1000, doc="most re-expansions (default 30)"),
        "tol_hz": Key("float", gt=0.0, doc="floor tolerance on the exact model [Hz] "
                      "(default 1e-6)"),
    }),
}


def _number(x) -> TypeGuard[float]:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _type_name(value) -> str:
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


class _StudyChecker:
    def __init__(self) -> None:
        self.problems: list[Problem] = []

    def add(self, where: str, message: str) -> None:
        self.problems.append(Problem(where, message, StudyError))

    def table(self, data, spec: Mapping[str, Key], where: str, rules=()) -> None:
        if not isinstance(data, dict):
            self.add(where, f"expected a table, got {_type_name(data)}")
            return
        for key in data:
            if key not in spec:
                self.add(_join(where, key), f"unknown key in {where or 'the study'}; "
                         + suggestion(key, spec))
        for key, k in spec.items():
            if key not in data:
                if k.required:
                    self.add(_join(where, key), "is missing")
                continue
            self.value(data[key], k, _join(where, key))
        for rule in rules:
            rule(data, lambda key, msg: self.add(_join(where, key) if key else where, msg))

    def value(self, value, k: Key, where: str) -> None:
        kind = k.kind
        if kind == "table":
            self.table(value, k.keys, where, k.rules)
        elif kind == "tables":
            if not isinstance(value, list) or not all(isinstance(v, dict) for v in value):
                self.add(where, f"expected an array of tables ([[{where}]]), got "
                         f"{_type_name(value)}")
                return
            if len(value) < k.min_items:
                self.add(where, f"needs at least {k.min_items} entry")
            for i, entry in enumerate(value):
                self.table(entry, k.keys, f"{where}[{i}]", k.rules)
        elif kind == "foreign_table":
            if not isinstance(value, dict):
                self.add(where, f"expected a table, got {_type_name(value)}")
        elif kind == "bool":
            if not isinstance(value, bool):
                hint = " (a TOML boolean is written without quotes)" if isinstance(
                    value, str) else ""
                self.add(where, f"expected true or false, got {_type_name(value)}{hint}")
        elif kind == "strs":
            if not isinstance(value, list) or not all(isinstance(v, str) for v in value):
                self.add(where, f"expected an array of strings, got {_type_name(value)}")
            elif not value:
                self.add(where, "must not be empty")
        elif kind == "str":
            if not isinstance(value, str):
                self.add(where, f"expected a string, got {_type_name(value)}")
            elif k.choices and value not in k.choices:
                self.add(where, f"{value!r} is not one of "
                         + ", ".join(repr(c) for c in k.choices) + "; "
                         + suggestion(value, k.choices))
        elif kind in ("int", "float"):
            self.number(value, k, where)
        elif kind in ("floats", "ints", "float_or_floats"):
            if kind == "float_or_floats" and not isinstance(value, list):
                self.number(value, k, where)
                return
            if not isinstance(value, list):
                self.add(where, f"expected an array of numbers, got {_type_name(value)}")
                return
            if len(value) < max(k.min_items, 1 if kind == "float_or_floats" else 0):
                self.add(where, "must not be empty")
            for i, v in enumerate(value):
                self.number(v, Key("int" if kind == "ints" else "float", gt=k.gt, ge=k.ge,
                                   le=k.le), f"{where}[{i}]")
        elif kind == "mapping":
            if not isinstance(value, dict):
                self.add(where, f"expected a table {{ name = value }}, got {_type_name(value)}")
                return
            for name, v in value.items():
                self.number(v, Key("float", ge=k.ge, le=k.le), _join(where, name))
        elif kind == "points":
            if not isinstance(value, list) or len(value) < k.min_items:
                self.add(where, "expected an array of [x, y, z] points")
                return
            for i, p in enumerate(value):
                if not isinstance(p, list) or len(p) != 3:
                    self.add(f"{where}[{i}]", "expected [x, y, z]")
                    continue
                for j, v in enumerate(p):
                    self.number(v, Key("float"), f"{where}[{i}][{j}]")
        elif kind == "orientation":
            if isinstance(value, str):
                if value not in ("keep", "free"):
                    self.add(where, f"{value!r} is not 'keep', 'free' or [roll, pitch, yaw]; "
                             + suggestion(value, ("keep", "free")))
            elif isinstance(value, list) and len(value) == 3:
                for j, v in enumerate(value):
                    self.number(v, Key("float"), f"{where}[{j}]")
            else:
                self.add(where, "expected 'keep', 'free' or [roll, pitch, yaw]")
        else:  # pragma: no cover - a schema typo
            raise AssertionError(kind)

    def number(self, value, k: Key, where: str) -> None:
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.add(where, f"expected a number, got {_type_name(value)}")
            return
        if k.kind == "int" and not isinstance(value, int):
            self.add(where, f"expected a whole number, got {value!r}")
            return
        if not math.isfinite(value):
            self.add(where, f"must be finite, got {value!r}")
            return
        if k.gt is not None and not value > k.gt:
            self.add(where, f"{value!r} must be above {k.gt:g}")
        elif k.ge is not None and not value >= k.ge:
            self.add(where, f"{value!r} must be >= {k.ge:g}")
        elif k.le is not None and not value <= k.le:
            extra = (" (the maximum Taylor order; cover a long motion with several expansion "
                     "points instead)") if k.le == MAX_TAYLOR_ORDER else ""
            self.add(where, f"{value!r} must be at most {k.le:g}{extra}")


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else str(key)


def check_study(data: dict) -> list[Problem]:
    """Problems of a study's TOML data against :data:`STUDY` (an empty list when valid)."""
    checker = _StudyChecker()
    checker.table(data, STUDY, "")
    return checker.problems


def check_override(key: str, value) -> list[Problem]:
    """Problems of one dotted-key value (``expansion.order``, ``targets.0.freq_hz``)."""
    spec: Mapping[str, Key] = STUDY
    k: Key | None = None
    parts = key.split(".")
    i = 0
    while i < len(parts):
        part = parts[i]
        if k is not None and k.kind == "tables" and part.isdigit():
            spec = k.keys
            i += 1
            continue
        if k is not None and k.kind == "mapping":
            k = Key("float", ge=k.ge, le=k.le)
            break
        if part not in spec:
            return [Problem(key, f"unknown key '{part}'; " + suggestion(part, spec), StudyError)]
        k = spec[part]
        spec = k.keys
        i += 1
    if k is None:
        return [Problem(key, "names no study key", StudyError)]
    checker = _StudyChecker()
    checker.value(value, k, key)
    return checker.problems


def check_against_model(data: dict, model, where_robot: str = "robot") -> list[Problem]:
    """Problems that need the loaded robot: mode numbers, design names, pose lengths."""
    problems: list[Problem] = []

    def add(where, message):
        problems.append(Problem(where, message, StudyError))

    nx, nv = getattr(model, "n_elastic", model.nx), model.nv
    names = list(model.design_names)
    modes_seen: dict[int, str] = {}

    def mode(value, where):
        if isinstance(value, int) and not isinstance(value, bool) and value > nx:
            add(where, f"mode {value} does not exist: the model has elastic modes 1..{nx}")

    for i, t in enumerate(_list(data.get("targets"))):
        if isinstance(t, dict):
            m = t.get("mode")
            mode(m, f"targets[{i}].mode")
            if isinstance(m, int) and m in modes_seen:
                add(f"targets[{i}].mode", f"mode {m} already has a target "
                    f"({modes_seen[m]})")
            elif isinstance(m, int):
                modes_seen[m] = f"targets[{i}]"
    cons = data.get("constraints", {})
    for kind in ("floors", "bands"):
        for i, entry in enumerate(_list(cons.get(kind)) if isinstance(cons, dict) else []):
            if isinstance(entry, dict):
                mode(entry.get("mode"), f"constraints.{kind}[{i}].mode")
    opts = data.get("options", {})
    if isinstance(opts, dict):
        for i, m in enumerate(_list(opts.get("report_modes"))):
            mode(m, f"options.report_modes[{i}]")
        for key in ("baseline",):
            _design_names(opts.get(key), names, f"options.{key}", model, add)
    exp = data.get("expansion", {})
    if isinstance(exp, dict):
        _design_names(exp.get("y0"), names, "expansion.y0", model, add)
        chosen = exp.get("design")
        if isinstance(chosen, list):
            _design_names({n: None for n in chosen if isinstance(n, str)}, names,
                          "expansion.design", model, add)
        q0 = exp.get("q0")
        if isinstance(q0, list) and len(q0) != nv:
            add("expansion.q0", f"has {len(q0)} values; the robot has {nv} moving joints "
                f"({', '.join(model.joint_names)})")
    traj = data.get("trajectory", {})
    path = traj.get("path") if isinstance(traj, dict) else None
    if isinstance(path, dict) and isinstance(path.get("start_q"), list):
        if len(path["start_q"]) != nv:
            add("trajectory.path.start_q", f"has {len(path['start_q'])} values; the robot has "
                f"{nv} moving joints")
    return problems


def _list(value) -> list:
    return value if isinstance(value, list) else []


def _design_names(table, names, where, model, add) -> None:
    if not isinstance(table, dict):
        return
    for name, value in table.items():
        if name not in names:
            hit = closest(name, names)
            add(f"{where}.{name}", "is not a design variable of the robot; "
                + (f"did you mean '{hit}'?" if hit else f"design variables: "
                   f"{', '.join(names) or '(none)'}"))
            continue
        d = model.design[names.index(name)]
        if _number(value) and not d.lower <= value <= d.upper:
            unit = f" {d.unit}" if getattr(d, "unit", "") else ""
            add(f"{where}.{name}", f"= {value:g}{unit} is outside the bounds "
                f"[{d.lower:g}, {d.upper:g}]{unit} of '{name}'")
