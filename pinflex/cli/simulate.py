"""``pinflex simulate``: time simulation of a study's designs, or of a robot file along a motion."""

from __future__ import annotations

import argparse
import sys
import time
from typing import Any, NamedTuple

from pinflex.cli.common import add_model_arguments, parse_values
from pinflex.exceptions import ConfigurationError
from pinflex.progress import ProgressBar


def add_parser(sub) -> None:
    """Register the ``simulate`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "simulate", help="simulate a joint motion of an arm (eq. 1): a study's baseline and "
        "assigned designs, or a robot file along a trajectory CSV")
    p.add_argument("config", help="study TOML of 'pinflex assign' with a [simulation] table "
                   "(see pinflex.dynamics.study; without [[targets]] the model at its values "
                   "is simulated, no assignment), or an annotated URDF / overlay with "
                   "--trajectory")
    p.add_argument("--trajectory", metavar="CSV", default=None,
                   help="joint trajectory (header: t, joint names): required with a robot "
                   "file; with a study, replaces its [trajectory]")
    p.add_argument("--planar", action="store_true",
                   help="with a robot file: keep in-plane elastic dofs only")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--out", default=None, metavar="DIR",
                   help="folder for the run's data, always written (per design NAME: "
                   "NAME_series.json with the metrics and the frame's deflection, NAME_run.npz "
                   "with the simulation's arrays, NAME_validity.csv; run.json naming the model); "
                   "charts and playback pages only with --charts / --preview, or later with "
                   "'pinflex report DIR'")
    p.add_argument("--charts", action="store_true",
                   help="with --out: also write the charts (tip_deflection.png, validity.png)")
    p.add_argument("--preview", action="store_true",
                   help="with --out: also write the meshcat playback page of each design "
                   "(NAME_playback.html)")
    p.add_argument("--exaggeration", type=float, default=200.0,
                   help="with --preview: factor on the elastic motion in the playback pages "
                   "(0: no playback; default 200)")
    p.add_argument("--tol", type=float, default=None, metavar="TOL",
                   help="prescribed drive: halve the time step until the Richardson estimate of "
                   "its error (relative to the largest elastic coordinate) is at most TOL; "
                   "overrides the study's [simulation] tol")
    g = p.add_argument_group("simulation settings (override the study's [simulation] keys)")
    g.add_argument("--drive", choices=("prescribed", "torque"), default=None,
                   help="prescribed joint motion (default) or computed torque + PD")
    g.add_argument("--route", choices=("linear", "nonlinear"), default=None,
                   help="torque drive: 'linear' (default with kp > 0) linearises about the "
                   "rigid computed-torque motion and reports its linearisation error estimate "
                   "(warns above [simulation] linearisation_threshold, 0.01); 'nonlinear' "
                   "integrates the nonlinear equations (adaptive generalized-alpha, about "
                   "1000x slower on benchmark A)")
    g.add_argument("--after", type=float, default=None, metavar="S",
                   help="simulated time after the last trajectory sample [s] (default 0.5)")
    g.add_argument("--gravity", type=float, nargs=3, default=None, metavar=("GX", "GY", "GZ"),
                   help="gravity in world axes [m/s^2] (default none)")
    g.add_argument("--rayleigh", type=float, nargs=2, default=None, metavar=("ALPHA", "BETA"),
                   help="Rayleigh damping alpha [1/s], beta [s] (pinflex.dynamics.damping)")
    g.add_argument("--modal-damping", type=float, nargs="+", default=None, metavar="RATIO",
                   help="modal damping ratios of the lowest locked-joint modes")
    g.add_argument("--frame", default=None, metavar="LINK",
                   help="output link (default 'tool')")
    g.add_argument("--point", type=float, nargs=3, default=None, metavar=("X", "Y", "Z"),
                   help="output point on the frame's link [m]")
    g.add_argument("--sample-hz", type=float, default=None, metavar="HZ",
                   help="output rate [Hz] (default 5000)")
    g.add_argument("--terms", choices=("eq1", "full"), default=None,
                   help="prescribed drive: eq1 (paper 000 eq. 1, default) or full (adds the "
                   "centrifugal, Euler and geometric-stiffness terms of a fast motion)")
    g.add_argument("--strict", action="store_true", default=None,
                   help="refuse a motion too fast for eq. (1) (validity indicator above its "
                   "threshold) instead of warning")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar on stderr (shown by default when stderr is a terminal)")
    add_model_arguments(p, default_joints=None)
    p.set_defaults(func=cmd_simulate)


def simulation_overrides(args: argparse.Namespace) -> dict:
    """The ``[simulation]`` keys given on the command line (checked with the study's)."""
    out: dict[str, Any] = {}
    for key, name in (("drive", "drive"), ("after_s", "after"), ("frame", "frame"),
                      ("sample_hz", "sample_hz"), ("terms", "terms"), ("strict", "strict"),
                      ("route", "route")):
        if getattr(args, name, None) is not None:
            out[key] = getattr(args, name)
    for key in ("gravity", "point"):
        if getattr(args, key, None) is not None:
            out[key] = list(getattr(args, key))
    if getattr(args, "rayleigh", None) is not None and getattr(args, "modal_damping", None):
        raise ConfigurationError("give --rayleigh or --modal-damping, not both")
    if getattr(args, "rayleigh", None) is not None:
        out["damping"] = {"kind": "rayleigh", "alpha": args.rayleigh[0],
                          "beta": args.rayleigh[1]}
    elif getattr(args, "modal_damping", None):
        out["damping"] = {"kind": "modal", "ratios": list(args.modal_damping)}
    return out


class StudyRun(NamedTuple):
    """What :func:`run_study` returns."""

    reports: list
    sims: list
    settings: Any
    result: Any
    source: dict


def _is_study(path: str) -> bool:
    return str(path).lower().endswith(".toml")


class DesignProgress:
    """``progress(done, total)`` of one simulation drawn as a bar (made on the first call)."""

    def __init__(self, label: str, enabled: bool):
        self.label, self.enabled = label, enabled
        self.bar: ProgressBar | None = None

    def __call__(self, done: int, total: int) -> None:
        """Advance the bar to ``done`` of ``total``."""
        if self.bar is None:
            self.bar = ProgressBar(total, self.label, self.enabled)
        self.bar.update(done - self.bar.done)

    def close(self) -> None:
        """Draw the final state, if the bar was ever drawn."""
        if self.bar is not None:
            self.bar.close()


def run_study(path, joints: str | None = None, values: dict[str, float] | None = None,
              tol: float | None = None, *, trajectory: str | None = None,
              planar: bool = False, simulation: dict | None = None, progress: bool = False,
              ) -> StudyRun:
    """Simulate a study's designs (after its assignment), or a robot file along a trajectory.

    Everything the drive refuses (a locked joint the trajectory turns, a locked joint under
    the torque drive, an unknown output link) is checked before the assignment runs.

    Args:
        path: Study TOML (``[simulation]`` table; ``[[targets]]`` optional), or a robot file
            (annotated URDF or overlay) with ``trajectory``.
        joints: Joint conditions overriding the study's ``joints`` key (``--joints``).
        values: Parameter values overriding and adding to the study's ``values`` (``--set``).
        tol: Step-error tolerance overriding the study's ``tol`` (``--tol``).
        trajectory: Trajectory CSV (required with a robot file; replaces a study's).
        planar: With a robot file: in-plane elastic dofs only.
        simulation: ``[simulation]`` keys overriding the study's (checked with them).
        progress: Show progress bars on stderr: one over the stages (the assignment, then
            each simulation) and one inside each prescribed-drive simulation (its
            coefficient grid, integration and torques).

    Returns:
        :class:`StudyRun` ``(reports, [(simulation, dynamics)], settings, assignment result or
        None, model source)``: the baseline and assigned designs of a study with targets, else
        one design ``"design"``; the source is :func:`pinflex.dynamics.saved.model_source`.
    """
    from pathlib import Path

    from pinflex.assignment.study import AssignmentConfig, resolve, run_config
    from pinflex.dynamics.study import (
        check_drive,
        load_simulation_study,
        parse_simulation_table,
        simulate_design,
    )

    overrides = dict(simulation or {})
    if tol is not None:
        overrides["tol"] = tol
    if _is_study(path):
        cfg, settings = load_simulation_study(path, overrides)
    else:
        if trajectory is None:
            raise ConfigurationError(
                f"'{path}' is a robot file: give the motion with --trajectory CSV (or a study "
                "TOML with a [simulation] table)")
        cfg = AssignmentConfig(robot=resolve(str(path), Path.cwd()), planar=planar,
                               trajectory={}, targets=[])
        settings = parse_simulation_table(overrides)
    if trajectory is not None:
        cfg.trajectory = {"csv": str(Path(trajectory).resolve())}
    if joints is not None:
        cfg.joints = joints
    if values:
        cfg.values = {**(cfg.values or {}), **values}
    model = cfg.build_model()
    traj = cfg.build_trajectory(model)
    check_drive(model, traj, settings)
    stages = ["assignment", "baseline", "assigned"] if cfg.targets else ["design"]
    bar = ProgressBar(len(stages), "simulate: " + ", ".join(stages), progress)
    result = None
    if cfg.targets:
        model, traj, result = run_config(cfg, model=model, trajectory=traj)
        bar.update()
        designs = [("baseline", result.y_before), ("assigned", result.y)]
    else:
        designs = [("design", None)]
    reports, sims = [], []
    for name, y in designs:
        inner = DesignProgress(f"simulate {name}", progress)
        rep, sim, dyn = simulate_design(model, traj, y, settings, name, progress=inner)
        inner.close()
        reports.append(rep)
        sims.append((sim, dyn))
        bar.update()
    bar.close()
    from pinflex.dynamics.saved import model_source

    source = model_source(cfg.robot, planar=cfg.planar, joints=cfg.joints, values=cfg.values)
    return StudyRun(reports, sims, settings, result, source)


def write_charts(reports, sims, out) -> list[str]:
    """The charts of a run into folder ``out``; returns the files written.

    ``tip_deflection.png`` and, when the runs have a validity indicator, ``validity.png``.
    """
    from pathlib import Path

    from pinflex.dynamics.charts import deflection_chart, validity_chart

    out = Path(out)
    files = [str(deflection_chart(reports, out / "tip_deflection.png"))]
    named = [(rep.name, sim.validity) for rep, sim in zip(reports, sims)
             if sim.validity is not None]
    if named:
        files.append(str(validity_chart(named, out / "validity.png")))
    return files


def write_previews(reports, sims, dyns, out, exaggeration: float) -> list[str]:
    """The meshcat playback page of each design, ``NAME_playback.html`` in folder ``out``."""
    from pathlib import Path

    from pinflex.visualization.playback import simulation_playback_html

    return [str(simulation_playback_html(dyn, sim, Path(out) / f"{rep.name}_playback.html",
                                         exaggeration=exaggeration))
            for rep, sim, dyn in zip(reports, sims, dyns)]


def cmd_simulate(args: argparse.Namespace) -> int:
    """Run ``pinflex simulate``."""
    if not 0.0 <= args.exaggeration <= 1e6:
        raise ConfigurationError(f"--exaggeration {args.exaggeration:g}: give a factor from 0 "
                                 "(no playback) to 1e6")
    if (args.charts or args.preview) and not args.out:
        raise ConfigurationError("--charts and --preview write into the --out folder: give "
                                 "--out DIR")
    preview = args.preview and args.exaggeration > 0
    if args.out:
        from pinflex.outputs import check_dir_target

        check_dir_target(args.out)
    if preview:
        from pinflex.visualization.offline import require_meshcat

        require_meshcat("the playback pages of --preview")
    t0 = time.perf_counter()
    reports, sims, settings, result, source = run_study(
        args.config, args.joints, parse_values(args.set) if args.set else None, args.tol,
        trajectory=args.trajectory, planar=args.planar, simulation=simulation_overrides(args),
        progress=not args.no_progress and sys.stderr.isatty())
    total = time.perf_counter() - t0
    files: list[str] = []
    if args.out:
        from pinflex.dynamics.saved import save_run

        runs = [sim for sim, _ in sims]
        files += [str(f) for f in save_run(args.out, reports, runs, source=source,
                                           drive=settings.drive, gravity=settings.gravity)]
        if args.charts:
            files += write_charts(reports, runs, args.out)
        if preview:
            files += write_previews(reports, runs, [dyn for _, dyn in sims], args.out,
                                    args.exaggeration)
    designs = []
    for rep in reports:
        d = rep.summary()
        designs.append({
            "name": rep.name, "y": d["y"], "final_q": d["final_q"],
            "tip_peak_m": d["tip_peak_m"], "tip_rms_m": d["tip_rms_m"],
            "residual_amplitude_m": d["residual_amplitude_m"],
            "dominant_frequency_hz": d["dominant_frequency_hz"],
            "steps": d["steps"], "time_s": d["time_s"],
            "step_error_estimate": d.get("error_estimate"),
            "linearisation_error_estimate": d.get("linearisation_error"),
            "residual_joint_condition": d["joint_condition"],
            "residual_reference_hz": d["reference_hz"], "frame": d["frame"],
            "terms": d.get("terms", "eq1"), "validity": d.get("validity"),
        })
    out_json = {"drive": settings.drive, "designs": designs, "files": files,
                "total_time_s": total}
    if args.json:
        from pinflex.outputs import json_text

        print(json_text(out_json))
        return 0
    w = sys.stdout.write
    w(f"drive: {settings.drive}; output frame '{reports[0].frame}'; residual vibration with "
      f"{reports[0].joint_condition} joints\n")
    for d in designs:
        f = d["dominant_frequency_hz"]
        w(f"  {d['name']:9s} y = {d['y']}: peak {1e3 * d['tip_peak_m']:.4f} mm, RMS "
          f"{1e3 * d['tip_rms_m']:.4f} mm, residual {1e3 * d['residual_amplitude_m']:.4f} mm at "
          f"{'-' if f is None else f'{f:.3f}'} Hz (reference "
          f"{d['residual_reference_hz'][0]:.3f} Hz); {d['steps']} steps, {d['time_s']:.2f} s\n")
        v = d["validity"]
        if v is not None:
            w(f"            validity of eq. (1): |omega|^2/omega_1^2 = {v['max_speed_ratio']:.3g}"
              f", |alpha|/omega_1^2 = {v['max_accel_ratio']:.3g} (threshold "
              f"{v['threshold']:g}{'; EXCEEDED' if v['exceeded'] else ''}); terms "
              f"{d['terms']}\n")
    for f in files:
        w(f"wrote {f}\n")
    return 0
