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
    rtol = 1e-4                 # torque drive: step control (relative to the peak)
    atol = 1e-14                # [m, rad]: its floor
    rho_inf = 0.9               # torque drive: generalized-alpha high-frequency radius
                                # (prescribed: 1, the trapezoidal rule, unless given)
    # step_s = 2e-4             # torque drive (default: adaptive, rtol/atol): fixed steps
                                # of step_s and step_s / 2, Richardson-extrapolated
    kp = 0.0                    # torque drive: PD gains on the motor angles [N m/rad]
    kd = 0.0                    #               [N m s/rad]
    # route = "linear"          # torque drive (default with kp > 0): linearised about the
                                # rigid computed-torque motion, with its error estimate
                                # (pinflex.dynamics.torque_linear); "nonlinear": the
                                # nonlinear equations (rtol, atol, step_s belong to it)
    # linearisation_threshold = 0.01  # route "linear": warn above this estimate
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

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

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
    atol: float = 1e-14
    rho_inf: float | None = None
    tol: float | None = None
    step_s: float | None = None
    kp: float = 0.0
    kd: float = 0.0
    route: str | None = None
    linearisation_threshold: float | None = None
    terms: str = "eq1"
    strict: bool = False
    validity_threshold: float = 0.1


def parse_simulation_table(table) -> SimulationSettings:
    """Validate a ``[simulation]`` table; every problem is listed in one error.

    The table is checked by the schema engine (:mod:`pinflex.fields`) against
    :data:`pinflex.assignment.study_schema.SIMULATION`, as the rest of the study is.

    Raises:
        InvalidSimulationTable: Unknown keys, wrong types, values out of range.
    """
    from pinflex.assignment.study_schema import SIMULATION, STUDY
    from pinflex.fields import check_table

    if table is None:
        return SimulationSettings()
    problems: list[str] = []

    def report(where, message, level):
        problems.append(f"{where}: {message}" if where else message)

    check_table(table, SIMULATION, "", report, STUDY["simulation"].rules)
    if problems:
        raise InvalidSimulationTable(problems)
    out: dict[str, Any] = {k: float(v) if isinstance(v, int | float) and not isinstance(v, bool)
                           else v for k, v in table.items()
                           if k not in ("damping", "gravity", "point")}
    for k in ("gravity", "point"):
        if k in table:
            out[k] = tuple(float(c) for c in table[k])
    d = table.get("damping", "none")
    if isinstance(d, dict):
        out["damping"] = Damping(str(d["kind"]), float(d.get("alpha", 0.0)),
                                 float(d.get("beta", 0.0)),
                                 tuple(float(r) for r in d.get("ratios", ())))
    else:
        out["damping"] = Damping()
    return SimulationSettings(**out)


def check_simulation_size(settings: SimulationSettings, duration_s: float, ndof: int,
                          nv: int) -> None:
    """Bound a simulation's output before it starts: samples and memory, with the estimate.

    Raises:
        ResourceLimitExceeded: The output series would not fit in the memory limit
            (:func:`pinflex.resources.check_memory`).
    """
    from pinflex.resources import check_series

    samples = (float(duration_s) + settings.after_s) * settings.sample_hz + 1
    # per sample: time, elastic coordinates, their rates, joint values and rates, the
    # output point (position, velocity)
    check_series(samples, 1 + 2 * ndof + 2 * nv + 6,
                 f"a simulation of {duration_s + settings.after_s:g} s at {settings.sample_hz:g} "
                 f"Hz ({samples:.3g} output samples of {ndof} coordinates)",
                 "lower sample_hz or after_s in [simulation]")


def load_simulation_study(path: str | Path, overrides: dict | None = None):
    """``(assignment config, simulation settings)`` of a study file.

    Args:
        path: Study TOML.
        overrides: ``[simulation]`` keys replacing the file's (command-line options), checked
            with them.
    """
    from pinflex.assignment.study import load_config
    from pinflex.description.source import read_text
    from pinflex.validation import load_toml

    text = read_text(path, "study file", ConfigurationError)
    data = load_toml(text, str(path), ConfigurationError)
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


def simulate_design(model, trajectory, y, settings: SimulationSettings, name: str,
                    progress=None):
    """Simulate one design of a study; returns ``(report, simulation, dynamics)``.

    ``progress``, when given, is called as ``progress(done, total)`` by the prescribed drive
    (:func:`~pinflex.dynamics.prescribed.simulate_prescribed`); the torque drive reports
    nothing before it ends.
    """
    from pinflex.dynamics.prescribed import simulate_prescribed
    from pinflex.dynamics.response import vibration_report
    from pinflex.dynamics.terms import ErlsDynamics
    from pinflex.dynamics.torque import simulate_torque

    model.description.require_link(settings.frame)
    check_simulation_size(settings, trajectory.duration_s, model.ndof, model.nv)
    dyn = ErlsDynamics(model, y=y, gravity=list(settings.gravity))
    if settings.drive == "prescribed":
        sim = simulate_prescribed(dyn, trajectory, after_s=settings.after_s,
                                  damping=settings.damping, sample_hz=settings.sample_hz,
                                  rho_inf=settings.rho_inf, tol=settings.tol,
                                  terms=settings.terms, strict=settings.strict,
                                  validity_threshold=settings.validity_threshold,
                                  progress=progress)
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
                              validity_threshold=settings.validity_threshold,
                              route=settings.route,
                              linearisation_threshold=settings.linearisation_threshold)
    rep = vibration_report(dyn, sim, name=name, frame=settings.frame, xyz=settings.point)
    return rep, sim, dyn
