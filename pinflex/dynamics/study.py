"""Simulation studies: the study file of ``pinflex assign`` plus a ``[simulation]`` table.

Example (all keys optional; the defaults shown)::

    [simulation]
    drive = "prescribed"        # or "torque": rigid computed torque + PD on the motor angles
    after_s = 0.5               # simulated time after the last trajectory sample [s]
    damping = "none"            # or { kind = "rayleigh", alpha = 0.0, beta = 1e-5 }
                                # or { kind = "modal", ratios = [0.01, 0.02] }
    gravity = [0.0, 0.0, 0.0]   # world axes [m/s^2]
    frame = "tool"              # output link; point = [x, y, z] on it [m]
    point = [0.0, 0.0, 0.0]
    sample_hz = 5000.0          # output rate [Hz]
    # tol = 0.01                # prescribed drive (default: absent): the time step halves
                                # until the Richardson estimate of the step error (relative
                                # to the largest elastic coordinate) meets it
    rtol = 1e-4                 # torque drive: step control
    atol = 1e-9                 # [m, rad]
    rho_inf = 0.9               # torque drive: generalized-alpha high-frequency radius
                                # (prescribed: 1, the trapezoidal rule, unless given)
    # step_s = 2e-4             # torque drive (default: adaptive, rtol/atol): fixed steps
                                # of step_s and step_s / 2, Richardson-extrapolated
    kp = 0.0                    # torque drive: PD gains on the motor angles [N m/rad]
    kd = 0.0                    #               [N m s/rad]
    terms = "eq1"               # prescribed drive: or "full" (centrifugal, Euler and
                                # geometric-stiffness terms; pinflex.dynamics.speed)
    strict = false              # refuse a motion too fast for eq. (1) (validity indicator
                                # above validity_threshold) instead of warning
    validity_threshold = 0.1    # pinflex.erls.validity

With ``[[targets]]``, the study simulates the baseline design (``[options] baseline``, default
the lower bounds) and the design the assignment finds; without them, the model at its values
(``values``), with no assignment.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

from pinflex.dynamics.damping import Damping
from pinflex.exceptions import ConfigurationError


class InvalidSimulationTable(ConfigurationError):
    """The ``[simulation]`` table of a study has unknown keys, wrong types or values."""

    def __init__(self, problems: list[str]):
        self.problems = list(problems)
        super().__init__("[simulation]: " + "; ".join(self.problems))


@dataclass(frozen=True)
class SimulationSettings:
    """The parsed ``[simulation]`` table (see the module doc for the keys and defaults)."""

    drive: str = "prescribed"
    after_s: float = 0.5
    damping: Damping = field(default_factory=Damping)
    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    frame: str = "tool"
    point: tuple[float, float, float] = (0.0, 0.0, 0.0)
    sample_hz: float = 5000.0
    rtol: float = 1e-4
    atol: float = 1e-9
    rho_inf: float | None = None
    tol: float | None = None
    step_s: float | None = None
    kp: float = 0.0
    kd: float = 0.0
    terms: str = "eq1"
    strict: bool = False
    validity_threshold: float = 0.1


_NUMBERS = {  # key: (lower, upper, lower inclusive)
    "after_s": (0.0, math.inf, False),
    "sample_hz": (0.0, math.inf, False),
    "rtol": (0.0, 1.0, False),
    "atol": (0.0, math.inf, False),
    "rho_inf": (0.0, 1.0, True),
    "tol": (0.0, 1.0, False),
    "step_s": (0.0, math.inf, True),
    "kp": (0.0, math.inf, True),
    "kd": (0.0, math.inf, True),
    "validity_threshold": (0.0, math.inf, False),
}


def _is_number(v) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


def parse_simulation_table(table) -> SimulationSettings:
    """Validate a ``[simulation]`` table; every problem is listed in one error.

    Raises:
        InvalidSimulationTable: Unknown keys, wrong types, values out of range.
    """
    if table is None:
        return SimulationSettings()
    if not isinstance(table, dict):
        raise InvalidSimulationTable([f"must be a table, got {type(table).__name__}"])
    problems: list[str] = []
    known = {"drive", "damping", "gravity", "frame", "point", "terms", "strict", *_NUMBERS}
    for k in sorted(set(table) - known):
        problems.append(f"unknown key '{k}' (known: {', '.join(sorted(known))})")
    out: dict = {}
    drive = table.get("drive", "prescribed")
    if drive not in ("prescribed", "torque"):
        problems.append(f"drive = {drive!r} must be 'prescribed' or 'torque'")
    else:
        out["drive"] = drive
    for k, (lo, hi, inclusive) in _NUMBERS.items():
        if k not in table:
            continue
        v = table[k]
        if not _is_number(v):
            problems.append(f"{k} = {v!r} must be a finite number")
        elif not ((lo <= v if inclusive else lo < v) and v <= hi):
            problems.append(f"{k} = {v!r} must lie in {'[' if inclusive else '('}{lo:g}, {hi:g}]")
        else:
            out[k] = float(v)
    if "terms" in table:
        if table["terms"] not in ("eq1", "full"):
            problems.append(f"terms = {table['terms']!r} must be 'eq1' or 'full'")
        else:
            out["terms"] = table["terms"]
    if "strict" in table:
        if not isinstance(table["strict"], bool):
            problems.append(f"strict = {table['strict']!r} must be true or false")
        else:
            out["strict"] = table["strict"]
    for k in ("gravity", "point"):
        if k in table:
            v = table[k]
            if not (isinstance(v, list) and len(v) == 3 and all(_is_number(c) for c in v)):
                problems.append(f"{k} = {v!r} must be a list of 3 finite numbers")
            else:
                out[k] = tuple(float(c) for c in v)
    if "frame" in table:
        if not isinstance(table["frame"], str) or not table["frame"]:
            problems.append(f"frame = {table['frame']!r} must be a link name")
        else:
            out["frame"] = table["frame"]
    if "damping" in table:
        d = table["damping"]
        if d == "none":
            out["damping"] = Damping()
        elif isinstance(d, dict):
            dk = set(d) - {"kind", "alpha", "beta", "ratios"}
            if dk:
                problems.append(f"damping: unknown keys {sorted(dk)} (known: kind, alpha, beta, "
                                "ratios)")
            kind = d.get("kind")
            if kind not in ("rayleigh", "modal"):
                problems.append(f"damping.kind = {kind!r} must be 'rayleigh' or 'modal'")
            bad = [f"damping.{k} = {d[k]!r} must be a finite number >= 0"
                   for k in ("alpha", "beta") if k in d and not (_is_number(d[k]) and d[k] >= 0)]
            problems += bad
            ratios = d.get("ratios", [])
            if not (isinstance(ratios, list) and all(_is_number(r) and 0 <= r < 1
                                                     for r in ratios)):
                problems.append(f"damping.ratios = {ratios!r} must be a list of numbers in [0, 1)")
                ratios = []
            if kind == "modal" and not ratios:
                problems.append("damping.kind = 'modal' needs ratios = [...]")
            if kind == "rayleigh" and "ratios" in d:
                problems.append("damping.ratios belongs to kind = 'modal'")
            if kind == "modal" and ({"alpha", "beta"} & set(d)):
                problems.append("damping.alpha and beta belong to kind = 'rayleigh'")
            if not problems:
                out["damping"] = Damping(str(kind), float(d.get("alpha", 0.0)),
                                         float(d.get("beta", 0.0)), tuple(map(float, ratios)))
        else:
            problems.append(f"damping = {d!r} must be 'none' or a table with kind = ...")
    if out.get("drive") == "torque" and out.get("terms") == "full":
        problems.append("terms = 'full' is for drive = 'prescribed' (the torque drive "
                        "integrates eq. (1))")
    if out.get("drive") == "torque" and isinstance(out.get("damping"), Damping) and \
            out["damping"].kind == "modal":
        problems.append("drive = 'torque' takes Rayleigh damping or none")
    if problems:
        raise InvalidSimulationTable(problems)
    return SimulationSettings(**out)


def load_simulation_study(path: str | Path, overrides: dict | None = None):
    """``(assignment config, simulation settings)`` of a study file.

    Args:
        path: Study TOML.
        overrides: ``[simulation]`` keys replacing the file's (command-line options), checked
            with them.
    """
    from pinflex.assignment.study import load_config

    path = Path(path)
    if not path.is_file():
        raise ConfigurationError(f"study file '{path}' does not exist")
    try:
        data = tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigurationError(f"'{path}' is not valid TOML: {exc}") from exc
    table = data.get("simulation")
    if overrides:
        table = {**(table if isinstance(table, dict) else {}), **overrides}
    settings = parse_simulation_table(table)
    return load_config(path), settings


def check_drive(model, trajectory, settings: SimulationSettings) -> None:
    """What the drive refuses, checked before any work (the assignment of a study).

    Raises:
        ConfigurationError: The prescribed drive turns a locked joint, the torque drive meets
            a locked joint, or the output frame is not a link of the robot.
    """
    from pinflex.dynamics.prescribed import check_locked_motion

    model.description.require_link(settings.frame)
    if settings.drive == "prescribed":
        check_locked_motion(model, trajectory)
        return
    locked = [c.name for c in model.joint_conditions if c.kind == "locked"]
    if locked:
        raise ConfigurationError(
            f"drive = 'torque' integrates every joint coordinate; joints {locked} are locked in "
            "this model: model a brake as a stiff spring (joints={name: stiffness}), or hold "
            "the joints with the prescribed drive (drive = 'prescribed', the trajectory "
            "constant in them)")


def simulate_design(model, trajectory, y, settings: SimulationSettings, name: str):
    """Simulate one design of a study; returns ``(report, simulation, dynamics)``."""
    from pinflex.dynamics.prescribed import simulate_prescribed
    from pinflex.dynamics.response import vibration_report
    from pinflex.dynamics.terms import ErlsDynamics
    from pinflex.dynamics.torque import simulate_torque

    model.description.require_link(settings.frame)
    dyn = ErlsDynamics(model, y=y, gravity=list(settings.gravity))
    if settings.drive == "prescribed":
        sim = simulate_prescribed(dyn, trajectory, after_s=settings.after_s,
                                  damping=settings.damping, sample_hz=settings.sample_hz,
                                  rho_inf=settings.rho_inf, tol=settings.tol,
                                  terms=settings.terms, strict=settings.strict,
                                  validity_threshold=settings.validity_threshold)
    else:
        from pinflex.dynamics.motion import JointMotion

        motion = JointMotion(trajectory)
        sim = simulate_torque(dyn, q0=motion.q_start, trajectory=motion,
                              duration_s=motion.t1 - motion.t0 + settings.after_s,
                              kp=settings.kp, kd=settings.kd, damping=settings.damping,
                              sample_hz=settings.sample_hz, rtol=settings.rtol,
                              atol=settings.atol,
                              rho_inf=0.9 if settings.rho_inf is None else settings.rho_inf,
                              step_s=settings.step_s or None, strict=settings.strict,
                              validity_threshold=settings.validity_threshold)
    rep = vibration_report(dyn, sim, name=name, frame=settings.frame, xyz=settings.point)
    return rep, sim, dyn
