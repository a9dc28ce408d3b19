"""Assignment studies described in a TOML file.

Example (paths are relative to the file; ``builtin:`` names a file shipped with pinflex, see
:mod:`pinflex.description.builtin`)::

    robot = "builtin:two_link.urdf"
    planar = true
    joints = "annotated"           # the file's <pinflex:joint> (default), or "free", "locked"
    values = { m1 = 0.1 }          # parameters and point masses set before the study

    [trajectory]
    builtin = "benchmark_a"        # or: csv = "traj.csv" (columns t, then joints, in the
                                   # model's user coordinates), or a 3-D workspace path:
    # [trajectory.path]            # (see pinflex.trajectory.cartesian.path_from_spec)
    # frame = "ee_link"
    # waypoints = [[0, 0.3, -0.1], [-0.2, 0.3, 0]]   # [m]
    # relative = true              # offsets from the frame at start_q
    # start_q = [0, -1.2, 1.5, -1.9, -1.57, 0]
    # samples = 40
    # duration_s = 2.0
    # orientation = "keep"         # or "free" (position only), or [roll, pitch, yaw]

    [expansion]
    q0 = [1.817, 5.312]            # default: the middle sample
    y0 = { m1 = 0.125, m2 = 0.125 }
    order = 4                      # 0 to 12 (pinflex.resources.MAX_TAYLOR_ORDER)
    quantity = "freq_hz"           # or "eigval"

    design = ["m1", "m2"]          # the variables to choose (default: all)

    [[targets]]                    # pinflex assign
    mode = 1
    freq_hz = 190.0
    weight = 1.0

    [constraints]
    mass_budget_kg = 0.3
    floors = [{ mode = 2, freq_hz = 400.0 }]
    bands = [{ mode = 3, low_hz = 650.0, high_hz = 700.0 }]

    [options]
    baseline = { m1 = 0.0, m2 = 0.0 }   # the "before" design (default: lower bounds)
    refine = false
    report_modes = [2, 3, 4]
    confirm_tol = 0.005            # the exact model must confirm the prediction this close
    target_tol = 0.05              # largest exact target error for the status "met"
    max_refinements = 8

    [sizing]                       # pinflex size: least design mass under the floors
    step_fraction = 0.5
    max_expansions = 30
    tol_hz = 1e-6

``pinflex assign`` needs ``[[targets]]``; ``pinflex size`` needs ``[constraints].floors`` and
uses ``[expansion]`` (``q0``, ``y0`` as the start, ``order``, ``design``), the mass budget
and ``[sizing]``.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import numpy as np

from pinflex.assignment.driver import assign_frequencies
from pinflex.assignment.study_schema import check_against_model, check_study
from pinflex.assignment.targets import Target
from pinflex.cases.benchmark_a_path import benchmark_a_trajectory
from pinflex.checks import check_y
from pinflex.description.builtin import builtin_path
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError, StudyError
from pinflex.trajectory import Trajectory


def resolve(value: str, folder: Path) -> Path:
    """Resolve a path from a config file (``builtin:NAME`` or relative to the file)."""
    if value.startswith("builtin:"):
        return builtin_path(value[len("builtin:"):])
    path = Path(value)
    return path if path.is_absolute() else (folder / path)


def user_trajectory(model: FlexibleModel, builtin: str) -> Trajectory:
    """A built-in trajectory converted to the model's user coordinates."""
    if builtin != "benchmark_a":
        raise ConfigurationError(f"unknown built-in trajectory '{builtin}'; use 'benchmark_a'")
    tr = benchmark_a_trajectory()  # Pinocchio's (relative) joint values
    if model.nv != tr.q.shape[1]:
        raise ConfigurationError(
            f"the benchmark_a trajectory has 2 joints; the robot has {model.nv}"
        )
    q_user = np.linalg.solve(model.coord_map, tr.q.T).T
    return Trajectory(tr.times_s, q_user, model.joint_names, name="benchmark_a")


@dataclass
class AssignmentConfig:
    """A parsed assignment study (see the module docstring for the file format)."""

    robot: Path
    planar: bool
    trajectory: dict
    targets: list[Target]
    q0: np.ndarray | None = None
    y0: dict | None = None
    order: int = 4
    quantity: str = "freq_hz"
    mass_budget_kg: float | None = None
    floors: list[tuple[int, float]] = field(default_factory=list)
    bands: list[tuple[int, float, float]] = field(default_factory=list)
    baseline: dict | None = None
    refine: bool = False
    report_modes: list[int] = field(default_factory=lambda: [2, 3, 4])
    folder: Path = Path(".")
    joints: str = "annotated"
    values: dict | None = None
    taylor_tol: float | None = None
    points_tol: float | None = None
    design: list[str] | None = None
    confirm_tol: float | None = None
    target_tol: float | None = None
    max_refinements: int | None = None
    sizing: dict = field(default_factory=dict)

    def build_model(self) -> FlexibleModel:
        """The flexible model of the study."""
        return FlexibleModel(self.robot, planar=self.planar, joints=self.joints,
                             values=self.values)

    def build_trajectory(self, model: FlexibleModel) -> Trajectory:
        """The study's trajectory in the model's user coordinates."""
        if "builtin" in self.trajectory:
            return user_trajectory(model, self.trajectory["builtin"])
        if "csv" in self.trajectory:
            return Trajectory.from_csv(resolve(self.trajectory["csv"], self.folder),
                                       joint_names=model.joint_names)
        if "path" in self.trajectory:
            from pinflex.trajectory.cartesian import path_from_spec

            return path_from_spec(model, self.trajectory["path"], name="path")
        raise ConfigurationError(
            "[trajectory] needs builtin = \"...\", csv = \"...\" or a [trajectory.path] table"
        )


def load_config(path: str | Path) -> AssignmentConfig:
    """Read an assignment study from a TOML file, checked against its schema.

    Every problem of the file (unknown keys, wrong types, values out of range, modes or design
    names the robot does not have) is listed in one :class:`StudyError`; see
    :mod:`pinflex.assignment.study_schema`.
    """
    from pinflex.description.source import input_path, read_text
    from pinflex.validation import load_toml

    path = input_path(path, "study file", StudyError)
    source = str(path)
    text = read_text(path, "study file", StudyError)
    data = load_toml(text, source, StudyError)
    return config_from_data(data, path.parent, source)


def _model_facts(robot: Path, planar: bool, joints, values) -> SimpleNamespace:
    """What the study checks need of the robot (cached while its file is unchanged)."""
    try:
        stat = robot.stat()
        key = (stat.st_mtime_ns, stat.st_size)
    except OSError:
        key = (0, 0)
    values_key = tuple(sorted(values.items())) if isinstance(values, dict) else values
    return _model_facts_cached(str(robot), bool(planar), joints, values_key, key)


@functools.lru_cache(maxsize=16)
def _model_facts_cached(robot: str, planar: bool, joints, values, _key) -> SimpleNamespace:
    model = FlexibleModel(robot, planar=planar, joints=joints,
                          values=dict(values) if values is not None else None)
    return SimpleNamespace(nx=model.n_elastic, nv=model.nv, ny=model.ny, ndof=model.ndof,
                           design=model.design, design_names=model.design_names,
                           joint_names=model.joint_names)


def config_from_data(data: dict, folder: Path, source: str = "<study>") -> AssignmentConfig:
    """An :class:`AssignmentConfig` from a study's TOML data, checked as :func:`load_config`."""
    from pinflex.exceptions import PinflexError
    from pinflex.resources import check_taylor
    from pinflex.validation import Problem, raise_problems

    problems = check_study(data)
    bad_robot = any(p.where.split(".")[0] in ("robot", "planar", "joints", "values")
                    for p in problems)
    if not bad_robot:
        try:
            robot = resolve(data["robot"], folder)
            model = _model_facts(robot, data.get("planar", False), data.get("joints", "annotated"),
                                 data.get("values"))
        except PinflexError as exc:
            problems.append(Problem("robot", str(exc), StudyError))
        else:
            problems += check_against_model(data, model)
            exp = data.get("expansion", {})
            order = exp.get("order", 4) if isinstance(exp, dict) else 4
            if not any(p.where.startswith("expansion") for p in problems):
                try:
                    check_taylor(model.nv + model.ny, int(order), model.ndof, model.ny)
                except PinflexError as exc:
                    problems.append(Problem("expansion.order", str(exc), StudyError))
    traj = data.get("trajectory", {})
    if isinstance(traj, dict) and isinstance(traj.get("csv"), str):
        csv_path = resolve(traj["csv"], folder)
        if not csv_path.is_file():
            problems.append(Problem("trajectory.csv", f"file '{csv_path}' does not exist",
                                    StudyError))
    raise_problems(source, problems, " in the study")
    exp = data.get("expansion", {})
    cons = data.get("constraints", {})
    opts = data.get("options", {})
    return AssignmentConfig(
        robot=resolve(data["robot"], folder),
        planar=data.get("planar", False),
        trajectory=data.get("trajectory", {"builtin": "benchmark_a"}),
        targets=[Target(t["mode"], t["freq_hz"], float(t.get("weight", 1.0)))
                 for t in data.get("targets", [])],
        q0=np.array(exp["q0"], dtype=float) if "q0" in exp else None,
        y0=exp.get("y0"),
        order=exp.get("order", 4),
        quantity=exp.get("quantity", "freq_hz"),
        mass_budget_kg=cons.get("mass_budget_kg"),
        floors=[(f["mode"], float(f["freq_hz"])) for f in cons.get("floors", [])],
        bands=[(b["mode"], float(b["low_hz"]), float(b["high_hz"]))
               for b in cons.get("bands", [])],
        baseline=opts.get("baseline"),
        refine=opts.get("refine", False),
        report_modes=list(opts.get("report_modes", [2, 3, 4])),
        folder=folder,
        joints=data.get("joints", "annotated"),
        values=dict(data["values"]) if "values" in data else None,
        design=list(exp["design"]) if "design" in exp else None,
        confirm_tol=opts.get("confirm_tol"),
        target_tol=opts.get("target_tol"),
        max_refinements=opts.get("max_refinements"),
        sizing=dict(data.get("sizing", {})),
    )


def check_config(cfg: AssignmentConfig, what: str = "the study") -> None:
    """Check a (possibly changed) study against its robot before any work.

    The checks of :func:`load_config` that need the robot (mode numbers, design names and
    bounds, joint count of ``q0``, parameter and point-mass names in ``values``), run on an
    :class:`AssignmentConfig`, e.g. one case of a ``pinflex batch assign --sweep``.

    Raises:
        StudyError: Listing every problem.
    """
    from pinflex.exceptions import PinflexError
    from pinflex.validation import Problem, raise_problems

    try:
        facts = _model_facts(cfg.robot, cfg.planar, cfg.joints, cfg.values)
    except PinflexError as exc:
        raise StudyError(f"{what}: {exc}") from None
    data: dict = {
        "targets": [{"mode": t.mode} for t in cfg.targets],
        "constraints": {"floors": [{"mode": m} for m, _ in cfg.floors],
                        "bands": [{"mode": m} for m, _, _ in cfg.bands]},
        "options": {"report_modes": list(cfg.report_modes)},
        "expansion": {},
    }
    if cfg.baseline is not None:
        data["options"]["baseline"] = dict(cfg.baseline)
    if cfg.y0 is not None:
        data["expansion"]["y0"] = dict(cfg.y0)
    if cfg.q0 is not None:
        data["expansion"]["q0"] = list(np.atleast_1d(cfg.q0))
    problems: list[Problem] = check_against_model(data, facts)
    raise_problems(what, problems, " in the study")


def run_config(cfg: AssignmentConfig, *, model=None, trajectory=None, taylor=None,
               freq_before_hz=None, progress: bool = False):
    """Build the model and trajectory of a study and solve it.

    Args:
        cfg: The study.
        model: Reuse this model (built from the same robot and ``planar``) instead of loading.
        trajectory: Reuse this trajectory of the study.
        taylor: Reuse this Taylor model (same q0, y0, order and design; it must carry every
            mode the targets, floors and bands name), skipping the expansion.
        freq_before_hz: Reuse the exact frequencies before (see
            :func:`~pinflex.assignment.driver.assign_frequencies`).
        progress: Show the stages' progress bar on stderr.

    Returns:
        ``(model, trajectory, result)``.
    """
    if not cfg.targets:
        raise StudyError("the study has no [[targets]] to assign (for the least "
                         "design mass under [constraints].floors, run pinflex size)")
    model = cfg.build_model() if model is None else model
    traj = cfg.build_trajectory(model) if trajectory is None else trajectory
    for i, t in enumerate(cfg.targets):
        n = np.size(t.freq_hz)
        if np.ndim(t.freq_hz) > 0 and n != traj.n_samples:
            raise StudyError(f"targets[{i}].freq_hz has {n} values; give one frequency or one "
                             f"per trajectory sample ({traj.n_samples})")
    baseline = check_y(model, cfg.baseline) if cfg.baseline is not None else None
    loop: dict[str, Any] = {k: v for k, v in (("confirm_tol", cfg.confirm_tol), ("target_tol", cfg.target_tol),
                              ("max_refinements", cfg.max_refinements)) if v is not None}
    result = assign_frequencies(
        model, traj, cfg.targets,
        y_before=baseline, refine=cfg.refine, taylor=taylor, freq_before_hz=freq_before_hz,
        progress=progress,
        report_modes=[m for m in cfg.report_modes if m <= model.n_elastic],
        q0=cfg.q0, y0=check_y(model, cfg.y0) if cfg.y0 is not None else None,
        order=cfg.order, quantity=cfg.quantity, mass_budget_kg=cfg.mass_budget_kg,
        floors=cfg.floors, bands=cfg.bands, taylor_tol=cfg.taylor_tol,
        points_tol=cfg.points_tol, design=cfg.design, **loop,
    )
    return model, traj, result


def run_sizing(cfg: AssignmentConfig, *, model=None, trajectory=None, progress: bool = False):
    """Least design mass under the study's floors (:func:`~pinflex.assignment.sizing.
    size_for_floors`): ``[constraints].floors`` and ``mass_budget_kg``, ``[expansion]``
    ``q0``, ``y0`` (the start), ``order`` and ``design``, and the ``[sizing]`` table.

    Returns:
        ``(model, trajectory, sizing_result)``.

    Raises:
        StudyError: The study has no floors.
    """
    from pinflex.assignment.sizing import size_for_floors

    if not cfg.floors:
        raise StudyError("pinflex size needs [constraints].floors = "
                         "[{ mode = 1, freq_hz = ... }] (the frequencies to keep above)")
    model = cfg.build_model() if model is None else model
    traj = cfg.build_trajectory(model) if trajectory is None else trajectory
    result = size_for_floors(
        model, traj, cfg.floors, design=cfg.design,
        y_start=check_y(model, cfg.y0) if cfg.y0 is not None else None, q0=cfg.q0,
        order=cfg.order, mass_budget_kg=cfg.mass_budget_kg, progress=progress, **cfg.sizing)
    return model, traj, result
