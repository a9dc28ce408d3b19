"""``pinflex export --format mjcf|urdf``: a lumped model of the arm for MuJoCo or Pinocchio.

The arguments are registered on the ``export`` subcommand by :func:`add_arguments`; the
``export`` command hands over to :func:`run` when the format is ``mjcf`` or ``urdf``.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

from pinflex.checks import check_q
from pinflex.exceptions import ConfigurationError, OutputExists

LUMPED_FORMATS = ("mjcf", "urdf")


def add_arguments(p: argparse.ArgumentParser) -> None:
    """The lumped-export options of ``pinflex export``."""
    g = p.add_argument_group("lumped model (--format mjcf | urdf, see docs/mujoco.md)")
    g.add_argument("--segments", type=int, metavar="N",
                   help="rigid segments per flexible link (default: chosen by --tol)")
    g.add_argument("--tol", type=float, default=1e-3,
                   help="with no --segments: the fewest segments whose fitted frequencies and "
                   "static compliances are within this relative error of the ERLS model "
                   "(default 1e-3)")
    g.add_argument("--max-segments", type=int, default=12,
                   help="largest segment count --tol may pick (default 12)")
    g.add_argument("--modes", type=int, metavar="K",
                   help="lowest non-rigid modes fitted per pose, with the arm's own and with "
                   "locked joints (default: one per bending plane of each flexible link)")
    g.add_argument("--axial", action=argparse.BooleanOptionalAction, default=None,
                   help="an axial spring at every hinge station (default: on for 3-D arms, "
                   "off for planar ones)")
    g.add_argument("--fit-poses", type=int, default=8,
                   help="trajectory samples the fit uses (errors are reported over all)")
    g.add_argument("--actuators", choices=("motor", "position", "none"), default="motor",
                   help="MJCF actuators on the arm's joints (default motor: joint torques)")
    g.add_argument("--kp", type=float, help="position-servo gain [N m/rad] (--actuators position)")
    g.add_argument("--kv", type=float, default=0.0,
                   help="position-servo damping [N m s/rad] (--actuators position)")
    g.add_argument("--gravity", type=float, nargs=3, default=(0.0, 0.0, -9.81),
                   metavar=("GX", "GY", "GZ"), help="MJCF gravity [m/s^2] (default 0 0 -9.81)")
    g.add_argument("--timestep", type=float,
                   help="MJCF time step [s] (default: 1/20 of the highest lumped mode's period, "
                   "at most 2 ms)")
    g.add_argument("--report", metavar="JSON", help="also write the fit report as JSON")
    g.add_argument("--force", action="store_true", help="overwrite existing output files")


def format_of(args: argparse.Namespace) -> str:
    """The export format: ``--format`` or the suffix of ``--out``."""
    if getattr(args, "format", None):
        return args.format
    suffix = Path(args.out).suffix.lower()
    return {".xml": "mjcf", ".mjcf": "mjcf", ".urdf": "urdf"}.get(suffix, "linear")


def _targets(args, fmt: str) -> list[Path]:
    out = Path(args.out)
    files = [out]
    if fmt == "urdf":
        files.append(out.with_name(out.name[:-len(out.suffix)] + ".springs.json")
                     if out.suffix else out.with_name(out.name + ".springs.json"))
    if args.report:
        files.append(Path(args.report))
    return files


def _pct(x: float) -> str:
    return f"{100 * x:.3g} %"


def run(args: argparse.Namespace, fmt: str) -> int:
    """Fit and write the lumped export."""
    from pinflex.erls import FlexibleModel
    from pinflex.lumped.damping import check_rayleigh, map_damping
    from pinflex.lumped.fidelity import segments_for_tolerance
    from pinflex.lumped.fit import fit_lumped
    from pinflex.lumped.layout import layout_of
    from pinflex.lumped.mjcf import copy_meshes, lumped_mjcf
    from pinflex.lumped.urdf import lumped_urdf
    from pinflex.lumped.visuals import arm_visuals
    from pinflex.outputs import check_file_target, write_text

    from .common import parse_values

    for path in _targets(args, fmt):
        if path.exists() and not args.force:
            raise OutputExists(f"'{path}' exists; pass --force to overwrite it or choose "
                               "another --out")
        check_file_target(path)
    if args.rayleigh is not None and args.zeta:
        raise ConfigurationError("give --zeta or --rayleigh, not both")
    if args.rayleigh is not None:
        check_rayleigh(args.rayleigh)  # refused before the fit, not after
    if args.segments is not None and args.segments < 1:
        raise ConfigurationError(f"--segments {args.segments}: give an integer >= 1")
    arm = FlexibleModel(args.urdf, planar=args.planar, values=parse_values(args.set),
                        joints=args.joints)
    if args.trajectory:
        from pinflex.erls.along import trajectory_for
        from pinflex.trajectory import Trajectory

        poses = np.atleast_2d(trajectory_for(arm, Trajectory.from_csv(args.trajectory)))
    else:
        poses = np.atleast_2d(check_q(arm, args.q if args.q is not None else np.zeros(arm.nv)))
    axial = (not arm.planar) if args.axial is None else bool(args.axial)
    layout = layout_of(arm, axial=axial)
    options = dict(poses=poses, n_modes=args.modes, max_fit_poses=args.fit_poses)
    if args.segments is None:
        choice = segments_for_tolerance(arm, args.tol, max_segments=args.max_segments,
                                        layout=layout, **options)
        fit = choice.fit
        levels = ", ".join(f"{n}: {_pct(max(w, c))}" for n, w, c in choice.levels)
        print(f"segments chosen by --tol {args.tol:g}: {choice.n_segments} per flexible link "
              f"(estimated error by segments {levels})")
    else:
        fit = fit_lumped(arm, args.segments, layout=layout, **options)
    lumped = fit.lumped
    q0 = poses[0]
    damp = map_damping(lumped, q0, zeta=args.zeta or None, rayleigh=args.rayleigh,
                       n_modes=fit.n_modes)
    visuals = arm_visuals(arm, skip_links=tuple(layout.beams))
    out = Path(args.out)
    mesh_paths = [v.mesh for v in visuals.shapes if v.kind == "mesh"]
    mesh_names = None
    meshdir = None
    if mesh_paths:
        folder = out.with_name(out.stem + "_meshes")
        copied = copy_meshes(mesh_paths, folder)
        if fmt == "mjcf":
            meshdir, mesh_names = folder.name, copied
        else:
            mesh_names = {src: f"{folder.name}/{name}" for src, name in copied.items()}
    conds = "own and locked joints" if len(fit.conditions) > 1 else "the arm's joints"
    comment = (f"pinflex lumped model of '{layout.name}': {fit.lumped.n_hinges} spring joints, "
               f"worst frequency error {_pct(fit.worst_error)} over {len(poses)} pose(s), "
               f"modes 1-{fit.n_modes}, {conds}; static compliance error "
               f"{_pct(fit.compliance_error)}; damping: {damp.description}")
    if fmt == "mjcf":
        doc = lumped_mjcf(lumped, q0, damping=damp.damping, visuals=visuals.shapes,
                          actuators=args.actuators, kp=args.kp, kv=args.kv,
                          gravity=tuple(args.gravity), timestep=args.timestep, comment=comment,
                          mesh_names=mesh_names, meshdir=meshdir)
        write_text(out, doc.text)
        notes = list(doc.notes)
        written = [str(out)]
    else:
        text, springs = lumped_urdf(lumped, q0, damping=damp.damping, visuals=visuals.shapes,
                                    mesh_names=mesh_names)
        springs_path = _targets(args, fmt)[1]
        write_text(out, text)
        write_text(springs_path, springs)
        notes = []
        written = [str(out), str(springs_path)]
    notes += list(visuals.skipped)
    report = fit.summary()
    report.update({"format": fmt, "files": written, "damping": damp.summary(),
                   "axial": axial, "notes": notes})
    if args.report:
        write_text(args.report, json.dumps(report, indent=2) + "\n")
        written.append(args.report)
    seg = {link: s.n_segments for link, s in lumped.segments.items()}
    print(f"wrote {', '.join(written)}: {lumped.nv} joints ({lumped.n_hinges} spring joints, "
          f"segments {seg}{', axial springs' if axial else ''})")
    def by_mode(errors) -> str:
        label = {"own": "own joints", "locked": "locked joints"}
        return "; ".join(f"{label[c]}: " + ", ".join(f"mode {i + 1} {_pct(e)}"
                                                     for i, e in enumerate(v))
                         for c, v in errors.items())

    print(f"fit against the ERLS model, worst over {len(poses)} pose(s): {by_mode(fit.mode_errors)}"
          f"; static compliance {_pct(fit.compliance_error)} ({fit.n_parameters} parameters "
          f"for {fit.n_quantities} quantities: {fit.determinacy})")
    print(f"equal segments with k = EI/l (not fitted): {by_mode(fit.naive_mode_errors)}; "
          f"static compliance {_pct(fit.naive_compliance_error)}")
    if fit.mode_mac:
        label = {"own": "own joints", "locked": "locked joints"}
        print("mode shapes, MAC with the ERLS modes (smallest over the fitted poses, 1 = the "
              "same shape): " + "; ".join(
                  f"{label[c]}: " + ", ".join(f"{m:.3f}" for m in v)
                  for c, v in fit.mode_mac.items()))
    if damp.kind != "none":
        print(f"damping: {damp.description}; modal ratios achieved "
              f"{np.round(damp.achieved, 5).tolist()}")
    for note in notes:
        print(f"note: {note}")
    return 0
