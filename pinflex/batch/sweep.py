"""Sweeps of assignment studies: ``--sweep KEY=V1,V2,...`` over a TOML study.

A sweep option names a key of the study file (:mod:`pinflex.assignment.study`) by its dotted
TOML path, with list entries by index, and the values it takes::

    --sweep targets.0.freq_hz=185,190,195         # the first [[targets]] entry
    --sweep constraints.mass_budget_kg=0.1,0.2
    --sweep expansion.order=2,4
    --sweep trajectory.csv=slow.csv,fast.csv       # paths relative to the study file
    --sweep 'expansion.q0=[1.817,5.312],[1.9,5.2]'

Values are TOML literals (numbers, booleans, ``[arrays]``, quoted strings); a value that is
not valid TOML is taken as a bare string. Commas inside brackets or quotes do not split values.
Several ``--sweep`` options form the Cartesian product (targets x trajectories x constraints),
the first option varying slowest.

Sweepable keys: ``robot``, ``planar``, ``trajectory.builtin``, ``trajectory.csv``,
``expansion.{order, quantity, q0}``, ``expansion.y0.NAME``, ``targets.I.{mode, freq_hz, weight}``,
``constraints.mass_budget_kg``, ``constraints.floors.I.{mode, freq_hz}``,
``constraints.bands.I.{mode, low_hz, high_hz}``, ``options.refine``, ``options.baseline.NAME``,
``options.report_modes``, ``joints`` (free, locked, annotated), ``values.NAME`` (a parameter
or point mass).

A case is identified by the hash of the study file's text, the text of the files it reads
(robot description, trajectory CSV) and its overrides, so editing the study or adding a value
to a sweep recomputes exactly the cases that changed.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import re
import time
import warnings
from dataclasses import replace
from pathlib import Path

import numpy as np

from pinflex.batch.tasks import _error_text, _worker_address, config_hash
from pinflex.checks import check_q, check_y
from pinflex.erls import assembly, kinematics
from pinflex.exceptions import InvalidSweep

KIND = "assign"

_KEYS = (
    r"robot", r"planar", r"trajectory\.(builtin|csv)", r"expansion\.(order|quantity|q0)",
    r"expansion\.y0\.\w+", r"targets\.\d+\.(mode|freq_hz|weight)",
    r"constraints\.mass_budget_kg", r"constraints\.floors\.\d+\.(mode|freq_hz)",
    r"constraints\.bands\.\d+\.(mode|low_hz|high_hz)", r"options\.refine",
    r"options\.baseline\.\w+", r"options\.report_modes", r"joints", r"values\.\w+",
)
SWEEPABLE = ("robot", "planar", "trajectory.builtin", "trajectory.csv", "expansion.order",
             "expansion.quantity", "expansion.q0", "expansion.y0.NAME",
             "targets.I.mode", "targets.I.freq_hz", "targets.I.weight",
             "constraints.mass_budget_kg", "constraints.floors.I.mode",
             "constraints.floors.I.freq_hz", "constraints.bands.I.mode",
             "constraints.bands.I.low_hz", "constraints.bands.I.high_hz", "options.refine",
             "options.baseline.NAME", "options.report_modes", "joints", "values.NAME")


def split_values(text: str) -> list[str]:
    """Split ``V1,V2,...`` on commas outside brackets and quotes."""
    parts: list[str] = []
    current: list[str] = []
    depth, quote = 0, ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == "," and depth == 0:
            parts.append("".join(current).strip())
            current = []
            continue
        current.append(ch)
    parts.append("".join(current).strip())
    return parts


def parse_value(text: str):
    """A TOML literal (numbers by pinflex's grammar), or the bare string if it is not one."""
    from pinflex.validation import load_toml

    try:
        return load_toml(f"v = {text}", "--sweep", InvalidSweep)["v"]
    except InvalidSweep as exc:
        if "not valid TOML" in str(exc):
            return text
        raise InvalidSweep(f"--sweep value {text!r}: {str(exc).split(': ', 2)[-1]}") from None


def parse_sweeps(options: list[str] | None) -> list[tuple[str, list]]:
    """Parse ``--sweep KEY=V1,V2`` options into ``[(key, values), ...]``.

    Raises:
        InvalidSweep: For a missing ``=``, an empty value, an unknown or repeated key.
    """
    out: list[tuple[str, list]] = []
    for option in options or ():
        key, sep, text = option.partition("=")
        key = key.strip()
        if not sep or not text.strip():
            raise InvalidSweep(f"--sweep {option!r}: expected KEY=V1,V2,... "
                               "(e.g. targets.0.freq_hz=185,190,195)")
        if not any(re.fullmatch(pattern, key) for pattern in _KEYS):
            raise InvalidSweep(f"--sweep key {key!r} is not sweepable; sweepable keys: "
                               f"{', '.join(SWEEPABLE)} (I = list index, NAME = design "
                               "variable)")
        if key in (k for k, _ in out):
            raise InvalidSweep(f"--sweep key {key!r} is given twice; list all its values in "
                               "one option")
        values = [parse_value(v) for v in split_values(text)]
        if any(v == "" for v in values):
            raise InvalidSweep(f"--sweep {option!r} has an empty value")
        out.append((key, values))
    return out


def sweep_cases(sweeps: list[tuple[str, list]]) -> list[dict]:
    """Cartesian product of the sweeps, first sweep slowest: a list of ``{key: value}``."""
    keys = [k for k, _ in sweeps]
    count = math.prod(len(v) for _, v in sweeps)
    if count > MAX_CASES:  # counted before any case is built or checked
        sizes = " x ".join(str(len(v)) for _, v in sweeps)
        raise InvalidSweep(f"--sweep gives {count} cases ({sizes}), more than the "
                           f"{MAX_CASES} one batch may hold; split the sweep into several "
                           "runs on the same --store")
    return [dict(zip(keys, combo)) for combo in itertools.product(*(v for _, v in sweeps))]


#: Most cases of one ``pinflex batch assign`` (each is a full assignment).
MAX_CASES = 10_000


def _index(items: list, index: str, key: str) -> int:
    i = int(index)
    if i >= len(items):
        raise InvalidSweep(f"--sweep key {key!r}: the study has {len(items)} entries there "
                           f"(indices 0..{len(items) - 1})")
    return i


def apply_overrides(cfg, overrides: dict):
    """A copy of an :class:`~pinflex.assignment.study.AssignmentConfig` with sweep values applied.

    Raises:
        InvalidSweep: For an index out of range or a value of the wrong type.
    """
    from pinflex.assignment.study import resolve
    from pinflex.assignment.study_schema import check_override

    cfg = copy.deepcopy(cfg)
    for key, value in overrides.items():
        problems = check_override(key, value)
        if problems:
            raise InvalidSweep(f"--sweep {key}={value!r}: "
                               + "; ".join(p.message for p in problems))
        parts = key.split(".")
        try:
            if key == "robot":
                cfg.robot = resolve(str(value), cfg.folder)
            elif key == "planar":
                cfg.planar = bool(value)
            elif parts[0] == "trajectory":
                cfg.trajectory = {parts[1]: str(value)}
            elif key == "expansion.order":
                cfg.order = int(value)
            elif key == "expansion.quantity":
                cfg.quantity = str(value)
            elif key == "expansion.q0":
                cfg.q0 = np.array(value, dtype=float)
            elif parts[:2] == ["expansion", "y0"]:
                cfg.y0 = dict(cfg.y0 or {}, **{parts[2]: float(value)})
            elif parts[0] == "targets":
                i = _index(cfg.targets, parts[1], key)
                field = parts[2]
                cast = int if field == "mode" else float
                cfg.targets[i] = replace(cfg.targets[i], **{field: cast(value)})
            elif key == "constraints.mass_budget_kg":
                cfg.mass_budget_kg = float(value)
            elif parts[:2] == ["constraints", "floors"]:
                i = _index(cfg.floors, parts[2], key)
                mode, freq = cfg.floors[i]
                cfg.floors[i] = ((int(value), freq) if parts[3] == "mode"
                                 else (mode, float(value)))
            elif parts[:2] == ["constraints", "bands"]:
                i = _index(cfg.bands, parts[2], key)
                band = list(cfg.bands[i])
                slot = ("mode", "low_hz", "high_hz").index(parts[3])
                band[slot] = int(value) if slot == 0 else float(value)
                cfg.bands[i] = tuple(band)
            elif key == "options.refine":
                cfg.refine = bool(value)
            elif parts[:2] == ["options", "baseline"]:
                cfg.baseline = dict(cfg.baseline or {}, **{parts[2]: float(value)})
            elif key == "options.report_modes":
                cfg.report_modes = [int(m) for m in np.atleast_1d(value)]
            elif key == "joints":
                cfg.joints = str(value)
            elif parts[0] == "values":
                cfg.values = dict(cfg.values or {}, **{parts[1]: float(value)})
            else:  # pragma: no cover - parse_sweeps admits only the keys above
                raise InvalidSweep(f"--sweep key {key!r} is not sweepable")
        except (TypeError, ValueError) as exc:
            raise InvalidSweep(f"--sweep {key}={value!r}: {exc}") from exc
    return cfg


def _file_digest(path: Path | None) -> str | None:
    if path is None or not Path(path).is_file():
        return None
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def case_config(config_path: Path, cfg, overrides: dict) -> dict:
    """The configuration a case's hash covers: file digests and overrides."""
    from pinflex.assignment.study import resolve

    csv = cfg.trajectory.get("csv")
    return {
        "kind": KIND,
        "study_file": Path(config_path).name,
        "study_sha256": _file_digest(config_path),
        "robot_sha256": _file_digest(cfg.robot),
        "trajectory": dict(cfg.trajectory),
        "trajectory_sha256": _file_digest(resolve(csv, cfg.folder)) if csv else None,
        "overrides": overrides,
    }


def plan_cases(config_path: str | Path, sweeps: list[tuple[str, list]]):
    """Load the study and build every case of the sweep.

    Returns:
        A list of ``(config_hash, case_config, assignment_config, overrides)``.

    Raises:
        ConfigurationError: If the study file is invalid.
        InvalidSweep: If a sweep does not apply to it.
    """
    from pinflex.assignment.study import check_config, load_config
    from pinflex.exceptions import StudyError

    base = load_config(config_path)
    out = []
    for overrides in sweep_cases(sweeps):
        cfg = apply_overrides(base, overrides)
        if overrides:
            try:
                check_config(cfg, "--sweep " + ", ".join(f"{k}={v!r}"
                                                         for k, v in overrides.items()))
            except StudyError as exc:
                raise InvalidSweep(str(exc)) from None
        config = case_config(Path(config_path), cfg, overrides)
        out.append((config_hash(config), config, cfg, overrides))
    return out


def expansion_key(cfg) -> str:
    """What a case's Taylor expansion depends on: cases with equal keys can share one.

    Robot, planar switch, trajectory, expansion point, order and quantity; not the targets,
    weights, budget, floor and band values, baseline or reported modes (the shared expansion
    carries the union of the modes the cases need).
    """
    return json.dumps({
        "robot": str(cfg.robot), "planar": bool(cfg.planar), "trajectory": cfg.trajectory,
        "q0": None if cfg.q0 is None else np.asarray(cfg.q0, dtype=float).tolist(),
        "y0": None if cfg.y0 is None else {k: float(v) for k, v in sorted(cfg.y0.items())},
        "order": int(cfg.order), "quantity": str(cfg.quantity),
    }, sort_keys=True)


def _needed_modes(cfg) -> list[int]:
    out: list[int] = []
    for m in ([t.mode for t in cfg.targets] + [f[0] for f in cfg.floors]
              + [b[0] for b in cfg.bands]):
        if int(m) not in out:
            out.append(int(m))
    return out


def _new_row(chash: str, case: int, overrides: dict) -> dict:
    return {"seed": 0, "item": 0, "config_hash": chash, "kind": KIND, "status": "failed",
            "error": None, "params": {"case": case, "overrides": overrides}, "truth": None,
            "result": None, "metrics": {}, "worker": _worker_address()}


def _fill_row(row: dict, solve) -> None:
    """Run ``solve() -> (model, trajectory, result)`` and record it in ``row``."""
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            _, _, result = solve()
        row["truth"] = {"modes": list(result.modes),
                        "freq_before_hz_range": [result.freq_before_hz.min(axis=0).tolist(),
                                                 result.freq_before_hz.max(axis=0).tolist()],
                        "freq_after_hz_range": [result.freq_after_hz.min(axis=0).tolist(),
                                                result.freq_after_hz.max(axis=0).tolist()]}
        row["result"] = {
            "found": bool(result.found), "design": result.design, "y": result.y.tolist(),
            "y_before": result.y_before.tolist(), "qp_status": result.solution.status,
            "iterations": int(result.solution.iterations), "refinements": result.refinements,
            "max_error_before": result.max_error_before,
            "max_error_after": result.max_error_after,
            "predicted_max_error_after": result.predicted_max_error_after,
            "warnings": [f"{w.category.__name__}: {w.message}" for w in caught],
        }
        row["metrics"] = {"error_before": result.max_error_before,
                          "error_after": result.max_error_after,
                          "predicted_error_after": result.predicted_max_error_after}
        if result.found:
            row["status"] = "ok"
        else:
            row["error"] = f"qp: not solved: {result.solution.status}"
        row["timings"] = dict(result.timings_s)
    except Exception as exc:  # noqa: BLE001 - recorded in the row, never re-raised
        row["error"] = _error_text("assign", exc)
        row["timings"] = {}


def run_assign_case(cfg, overrides: dict, chash: str, case: int) -> list[dict]:
    """Solve one assignment case and verify it with the exact model (runs on a worker).

    The key is (seed 0, item 0, config_hash): a case is identified by its configuration only.

    Returns:
        A one-element list with the row; failures are recorded, never raised.
    """
    from pinflex.assignment.study import run_config

    t0, c0 = time.perf_counter(), time.process_time()
    row = _new_row(chash, case, overrides)
    _fill_row(row, lambda: run_config(cfg))
    row["timings"]["task_s"] = time.perf_counter() - t0
    row["timings"]["task_cpu_s"] = time.process_time() - c0
    return [row]


class _SharedAssembly:
    """A flexible model whose ``matrices`` reuses one assembly on a fixed set of poses.

    ``M(q, y) = M0(q) + Σ_j y_j Md_j(q)``: the pose-dependent parts (Pinocchio Jacobians,
    beam and inertia assembly) are computed once for the group's trajectory; a call on those
    poses with one design only adds the design masses. Calls on other poses, with one design
    per pose, or on a model whose design also changes sections, materials or springs go to the
    model's own method. The numbers are the model's own (same assembly, same sum); exact
    frequencies and tracked eigenpairs both go through ``matrices``. Every other attribute is
    the model's (the model itself is constant and is not changed).
    """

    def __init__(self, model, Q: np.ndarray):
        self._model, self._Q = model, np.array(Q, dtype=float)
        terms = kinematics.pose_terms(model, self._Q)
        from pinflex.erls import BatchAlgebra

        self._M0, self._Md, self._K = assembly.assemble(model, terms,
                                                        BatchAlgebra(self._Q.shape[0]))

    def __getattr__(self, name: str):
        return getattr(self._model, name)

    def matrices(self, Q, y=None, *, check_bounds: bool = True, data=None):
        """The model's ``matrices``, from the shared assembly on the group's poses."""
        from pinflex.erls.assembly import add_design_masses

        model = self._model
        Qa = np.asarray(Q, dtype=float)
        if (Qa.shape == self._Q.shape and np.array_equal(Qa, self._Q)
                and not model.plan.design.channels):
            yv = check_y(model, y, bounds=check_bounds)
            if yv.ndim == 1:
                return add_design_masses(self._M0, self._Md, yv), self._K
        return model.matrices(Q, y, check_bounds=check_bounds, data=data)


def run_assign_group(items: list) -> list[dict]:
    """Solve cases that share one expansion (equal :func:`expansion_key`) on one worker.

    The model, the trajectory, the Taylor expansion (with the union of the modes the cases
    need), the pose-dependent assembly of the exact model on the trajectory and the exact
    frequencies before (per baseline) are computed once; each case then builds and solves its
    QP and verifies its design with the exact model (design masses added to the shared
    assembly, eigenproblems solved). If the shared set-up
    fails, every case runs on its own (and records its own error).

    Args:
        items: ``(assignment_config, overrides, config_hash, case_index)`` per case.

    Returns:
        One row per case; the shared set-up time is split evenly over the rows
        (``timings["shared_setup_s"]``, ``timings["shared_by"]``).
    """
    from pinflex.assignment.study import run_config
    from pinflex.parametric import expand

    t0, c0 = time.perf_counter(), time.process_time()
    cfg0 = items[0][0]
    try:
        model = cfg0.build_model()
        traj = cfg0.build_trajectory(model)
        Q = check_q(model, traj.q)
        q0 = Q[Q.shape[0] // 2] if cfg0.q0 is None else cfg0.q0
        y0 = check_y(model, cfg0.y0)
        modes: list[int] = []
        for cfg, *_ in items:
            modes += [m for m in _needed_modes(cfg) if m not in modes]
        taylor = expand(model, q0, y0, order=cfg0.order, modes=modes)
        # every case is verified on the same poses: assemble them once
        model = _SharedAssembly(model, Q)
    except Exception:  # noqa: BLE001 - each case then reports its own error
        return [row for cfg, ov, h, case in items for row in run_assign_case(cfg, ov, h, case)]
    shared_s, shared_cpu = time.perf_counter() - t0, time.process_time() - c0
    before: dict = {}
    rows = []
    for cfg, overrides, chash, case in items:
        t1, c1 = time.perf_counter(), time.process_time()
        row = _new_row(chash, case, overrides)

        def solve(cfg=cfg):
            y_before = (check_y(model, cfg.baseline) if cfg.baseline is not None
                        else np.array([d.lower for d in model.design]))
            case_modes: list[int] = []
            report = [m for m in cfg.report_modes if m <= model.n_elastic]
            for m in [t.mode for t in cfg.targets] + report:
                if int(m) not in case_modes:
                    case_modes.append(int(m))
            key = (tuple(np.asarray(y_before, dtype=float).tolist()), tuple(case_modes))
            if key not in before:
                f = model.frequencies(Q, y_before, n_modes=max(case_modes))
                before[key] = f[:, [m - 1 for m in case_modes]]
            return run_config(cfg, model=model, trajectory=traj, taylor=taylor,
                              freq_before_hz=before[key])

        _fill_row(row, solve)
        row["timings"]["shared_setup_s"] = shared_s / len(items)
        row["timings"]["shared_by"] = float(len(items))
        row["timings"]["task_s"] = time.perf_counter() - t1 + shared_s / len(items)
        row["timings"]["task_cpu_s"] = time.process_time() - c1 + shared_cpu / len(items)
        rows.append(row)
    return rows
