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
from collections.abc import Mapping
from typing import TypeGuard

from pinflex.exceptions import StudyError
from pinflex.fields import Field, check_table, check_value
from pinflex.resources import MAX_TAYLOR_ORDER
from pinflex.validation import Problem, closest, suggestion

#: A key of a study table is one field of the schema engine (:mod:`pinflex.fields`).
Key = Field


def _one_trajectory(table: dict, report) -> None:
    given = [k for k in ("builtin", "csv", "path") if k in table]
    if len(given) != 1:
        report("", "give exactly one of builtin = \"...\", csv = \"...\" or a "
               "[trajectory.path] table" + (f" (got {', '.join(given)})" if given else ""))


def _band_order(table: dict, report) -> None:
    lo, hi = table.get("low_hz"), table.get("high_hz")
    if _number(lo) and _number(hi) and not lo < hi:
        report("low_hz", f"low_hz = {lo:g} must be below high_hz = {hi:g}")


def _one_per_mode(what: str):
    def rule(entries, report) -> None:
        seen: dict[int, int] = {}
        for i, e in enumerate(entries if isinstance(entries, list) else []):
            m = e.get("mode") if isinstance(e, dict) else None
            if isinstance(m, int) and not isinstance(m, bool):
                if m in seen:
                    report(f"[{i}].mode", f"mode {m} already has a {what} "
                           f"([{seen[m]}]); give one {what} per mode")
                else:
                    seen[m] = i
    return rule


def _some_weight(entries, report) -> None:
    weights = [e.get("weight", 1.0) for e in entries if isinstance(e, dict)]
    if weights and all(_number(w) and w == 0.0 for w in weights):
        report("", "every target has weight 0, so the assignment has nothing to do; give at "
               "least one target a positive weight")


def _damping_kinds(table: dict, report) -> None:
    kind = table.get("kind")
    if kind == "modal" and not table.get("ratios"):
        report("ratios", "kind = 'modal' needs ratios = [...]")
    if kind == "rayleigh" and "ratios" in table:
        report("ratios", "belongs to kind = 'modal'")
    if kind == "modal" and ({"alpha", "beta"} & set(table)):
        report("", "alpha and beta belong to kind = 'rayleigh'")


def _simulation_rules(table: dict, report) -> None:
    damping = table.get("damping")
    if table.get("drive") == "torque" and isinstance(damping, dict) and \
            damping.get("kind") == "modal":
        report("damping", "drive = 'torque' takes Rayleigh damping or none")
    for key in ("rtol", "atol", "step_s", "kp", "kd"):
        if key in table and table.get("drive", "prescribed") == "prescribed":
            report(key, "belongs to drive = 'torque'")
    if "route" in table and table.get("drive", "prescribed") == "prescribed":
        report("route", "belongs to drive = 'torque'")
    if table.get("drive") == "torque" and _torque_route(table) == "linear":
        for key in ("rtol", "atol", "step_s"):
            if key in table:
                report(key, "belongs to route = 'nonlinear' (the torque drive's default "
                       "route with kp > 0 is 'linear')")
    if table.get("drive") == "torque" and table.get("terms") == "full":
        report("terms", "'full' is for drive = 'prescribed' (the torque drive integrates "
               "eq. (1))")


def _torque_route(table: dict) -> str:
    """The torque drive's route a ``[simulation]`` table asks for (default: by ``kp``)."""
    route = table.get("route")
    if route in ("linear", "nonlinear"):
        return route
    kp = table.get("kp", 0.0)
    return "linear" if _number(kp) and kp > 0.0 else "nonlinear"


_MODE = Field("int", required=True, ge=1, le=10_000, doc="non-rigid mode number, 1 = lowest")


def _hz(**kwargs) -> Field:
    """A frequency [Hz] (at most 1 GHz)."""
    return Field(unit="Hz", le=1e9, **kwargs)

_ACCEL = Field("float", ge=-1e3, le=1e3, unit="m/s^2")

#: Largest output rate of a simulation [Hz] and longest simulated time after the motion
#: [s]; a request is also bounded by its memory (samples x coordinates, see
#: :func:`pinflex.dynamics.study.check_simulation_size`).
MAX_SAMPLE_HZ = 1e6
MAX_AFTER_S = 1e4

#: The ``[simulation]`` table of a study (read by ``pinflex simulate``).
SIMULATION: dict[str, Field] = {
    "drive": Field("choice", choices=("prescribed", "torque"),
                   doc="'prescribed' joint motion, or 'torque': rigid computed torque + PD"),
    "after_s": Field(gt=0.0, le=MAX_AFTER_S, unit="s",
                     doc="simulated time after the last trajectory sample (default 0.5)"),
    "damping": Field("either", doc="'none' or a table with kind = 'rayleigh' or 'modal'",
                     options=(
                         Field("choice", choices=("none",)),
                         Field("table", rules=(_damping_kinds,), keys={
                             "kind": Field("choice", required=True,
                                           choices=("rayleigh", "modal"), doc="damping law"),
                             "alpha": Field(ge=0.0, le=1e6, unit="1/s",
                                            doc="Rayleigh: alpha M"),
                             "beta": Field(ge=0.0, le=1.0, unit="s", doc="Rayleigh: beta K"),
                             "ratios": Field("array", min_items=1, max_items=10_000,
                                             item=Field(ge=0.0, lt=1.0),
                                             doc="modal damping ratios, lowest mode first"),
                         }),
                     )),
    "gravity": Field("vec3", ge=-1e3, le=1e3, unit="m/s^2",
                     doc="gravity in world axes (default [0, 0, 0])"),
    "frame": Field("name", doc="output link (default 'tool')"),
    "point": Field("vec3", ge=-1e3, le=1e3, unit="m", doc="output point on the frame"),
    "sample_hz": Field(gt=0.0, le=MAX_SAMPLE_HZ, unit="Hz", doc="output rate (default 5000)"),
    "rtol": Field(gt=0.0, lt=1.0, doc="torque drive: relative tolerance (default 1e-4)"),
    "atol": Field(gt=0.0, le=1.0, unit="m, rad", doc="torque drive: absolute tolerance "
                  "(default 1e-9)"),
    "rho_inf": Field(ge=0.0, le=1.0, doc="generalized-alpha high-frequency spectral radius"),
    "tol": Field(ge=1e-10, lt=1.0, why="a relative step error below 1e-10 is under the "
                 "round-off of the time integration and is never reached",
                 doc="prescribed drive: Richardson step-error tolerance (relative)"),
    "step_s": Field(gt=0.0, le=1.0, unit="s", doc="torque drive: fixed step"),
    "kp": Field(ge=0.0, le=1e12, unit="N m/rad", doc="torque drive: PD stiffness"),
    "kd": Field(ge=0.0, le=1e12, unit="N m s/rad", doc="torque drive: PD damping"),
    "route": Field("choice", choices=("linear", "nonlinear"),
                   doc="torque drive: 'linear' (default with kp > 0: linearised about the "
                   "rigid computed-torque motion, with its error estimate) or 'nonlinear' "
                   "(the nonlinear equations, adaptive generalized-alpha)"),
    "linearisation_threshold": Field(gt=0.0, le=1.0, doc="torque drive, route 'linear': "
                                     "linearisation error estimate above which it warns "
                                     "(default 0.01)"),
    "terms": Field("choice", choices=("eq1", "full"),
                   doc="prescribed drive: 'eq1' (default) or 'full' (centrifugal, Euler and "
                   "geometric-stiffness terms, pinflex.dynamics.speed)"),
    "strict": Field("bool", doc="refuse a motion too fast for eq. (1) instead of warning"),
    "validity_threshold": Field(gt=0.0, le=1e3, doc="threshold of the validity indicator "
                                "(default 0.1, pinflex.erls.validity)"),
}

#: The study format: top-level keys and tables.
STUDY: dict[str, Field] = {
    "robot": Field("str", required=True,
                   doc="annotated URDF or overlay, relative to the study or builtin:NAME"),
    "planar": Field("bool", doc="keep in-plane elastic dofs only (default false)"),
    "joints": Field("choice", choices=("free", "locked", "annotated"),
                    doc="joint conditions: annotated (the file's <pinflex:joint>, the default), "
                    "or the overrides free and locked"),
    "values": Field("mapping", item=Field(), doc="parameters and point masses set before the "
                    "study (checked against the robot)"),
    "simulation": Field("table", keys=SIMULATION, rules=(_simulation_rules,),
                        doc="time simulation settings (used by pinflex simulate)"),
    "trajectory": Field("table", rules=(_one_trajectory,), doc="the motion", keys={
        "builtin": Field("choice", choices=("benchmark_a",), doc="a shipped trajectory"),
        "csv": Field("str", doc="CSV file: t, then one column per joint (by name)"),
        "path": Field("table", doc="a workspace path solved by inverse kinematics", keys={
            "frame": Field("str", required=True, doc="frame that follows the path"),
            "waypoints": Field("array", required=True, min_items=1, max_items=10_000,
                               item=Field("vec3", ge=-1e3, le=1e3, unit="m"),
                               doc="points [m]"),
            "relative": Field("bool", doc="waypoints are offsets from the start"),
            "start_q": Field("array", max_items=1000, item=Field(ge=-1e6, le=1e6),
                             doc="joint values at the start"),
            "samples": Field("int", ge=2, le=20_000, doc="number of samples"),
            "duration_s": Field(gt=0.0, le=1e6, unit="s", doc="duration"),
            "profile": Field("choice", choices=("minimum_jerk", "uniform"), doc="timing law"),
            "orientation": Field("either", doc="'keep', 'free' or roll-pitch-yaw [rad]",
                                 options=(Field("choice", choices=("keep", "free")),
                                          Field("vec3", ge=-1e3, le=1e3, unit="rad"))),
            "on_limits": Field("choice", choices=("raise", "warn"), doc="joint-limit policy"),
        }),
    }),
    "expansion": Field("table", doc="the Taylor model", keys={
        "q0": Field("array", max_items=1000, item=Field(ge=-1e6, le=1e6),
                    doc="expansion pose (default: the middle sample)"),
        "y0": Field("mapping", item=Field(ge=0.0), doc="expansion design {name = value} (each "
                    "in its variable's unit)"),
        "order": Field("int", ge=0, le=MAX_TAYLOR_ORDER,
                       why="the maximum Taylor order; cover a long motion with several "
                       "expansion points instead", doc="Taylor order"),
        "quantity": Field("choice", choices=("freq_hz", "eigval"), doc="expanded quantity"),
        "design": Field("array", min_items=1, max_items=1000, item=Field("str"),
                        doc="design variables to choose (default: all)"),
    }),
    "targets": Field("tables", min_items=1, max_items=1000,
                     doc="wanted frequencies (pinflex assign)", keys={
        "mode": _MODE,
        "freq_hz": Field("either", required=True, doc="target [Hz], constant or one per "
                         "sample", options=(_hz(gt=0.0),
                                            Field("array", min_items=1,
                                                  item=_hz(gt=0.0)))),
        "weight": Field(ge=0.0, le=1e12, doc="weight in the cost (default 1)"),
    }),
    "constraints": Field("table", doc="QP constraints", keys={
        "mass_budget_kg": Field(ge=-1e9, le=1e9, unit="kg",
                                doc="largest total added mass (below the lower bounds it is "
                                "infeasible, reported by the QP)"),
        "floors": Field("tables", max_items=1000, doc="lowest allowed frequencies", keys={
            "mode": _MODE, "freq_hz": _hz(required=True, gt=0.0, doc="floor"),
        }),
        "bands": Field("tables", max_items=1000, rules=(_band_order,),
                       doc="forbidden frequency bands", keys={
            "mode": _MODE,
            "low_hz": _hz(required=True, gt=0.0, doc="band start"),
            "high_hz": _hz(required=True, gt=0.0, doc="band end"),
        }),
    }),
    "options": Field("table", doc="reporting and refinement", keys={
        "baseline": Field("mapping", item=Field(ge=0.0), doc="the 'before' design "
                          "{name = value}"),
        "refine": Field("bool", doc="re-expand at the answer and solve again"),
        "report_modes": Field("array", max_items=1000, item=Field("int", ge=1, le=10_000),
                              doc="further modes to report"),
        "confirm_tol": Field(gt=0.0, le=1.0, doc="largest relative difference between the "
                             "answer's predicted and exact frequencies (default 0.005)"),
        "target_tol": Field(gt=0.0, le=1e3, doc="largest exact target error for the status "
                            "'met' (default 0.05)"),
        "max_refinements": Field("int", ge=0, le=100, doc="most re-expansions (default 8)"),
    }),
    "sizing": Field("table", doc="least design mass under the floors (pinflex size)", keys={
        "step_fraction": Field(gt=0.0, le=1.0, doc="trust region as a fraction of the "
                               "estimated radius (default 0.5)"),
        "max_expansions": Field("int", ge=1, le=1000, doc="most re-expansions (default 30)"),
        "tol_hz": _hz(gt=0.0, doc="floor tolerance on the exact model (default 1e-6)"),
    }),
}


def _number(x) -> TypeGuard[float]:
    return isinstance(x, int | float) and not isinstance(x, bool) and math.isfinite(x)


def _problems(error=StudyError):
    problems: list[Problem] = []

    def report(where, message, level):
        problems.append(Problem(where, message, error))

    return problems, report


def _list_rules(data: dict, report) -> None:
    """Rules over arrays of tables (one target / floor per mode, some positive weight)."""
    targets = data.get("targets")
    if isinstance(targets, list):
        _one_per_mode("target")(targets, lambda k, m: report(f"targets{k}", m, "error"))
        _some_weight(targets, lambda k, m: report("targets" + k, m, "error"))
    cons = data.get("constraints")
    if isinstance(cons, dict) and isinstance(cons.get("floors"), list):
        _one_per_mode("floor")(cons["floors"],
                               lambda k, m: report(f"constraints.floors{k}", m, "error"))


def _join(where: str, key: str) -> str:
    return f"{where}.{key}" if where else str(key)


def check_study(data: dict) -> list[Problem]:
    """Problems of a study's TOML data against :data:`STUDY` (an empty list when valid)."""
    problems, report = _problems()
    check_table(data, STUDY, "", report)
    _list_rules(data, report)
    return problems


def check_override(key: str, value) -> list[Problem]:
    """Problems of one dotted-key value (``expansion.order``, ``targets.0.freq_hz``)."""
    spec: Mapping[str, Field] = STUDY
    k: Field | None = None
    parts = key.split(".")
    i = 0
    while i < len(parts):
        part = parts[i]
        if k is not None and k.kind == "tables" and part.isdigit():
            spec = k.keys
            i += 1
            continue
        if k is not None and k.kind == "mapping":
            k = k.item or Field()
            break
        if part not in spec:
            return [Problem(key, f"unknown key '{part}'; " + suggestion(part, spec), StudyError)]
        k = spec[part]
        spec = k.keys
        i += 1
    if k is None:
        return [Problem(key, "names no study key", StudyError)]
    problems, report = _problems()
    check_value(value, k, key, report)
    return problems


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
