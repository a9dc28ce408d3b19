"""``pinflex path``: a joint trajectory from 3-D waypoints of a frame (Pinocchio IK)."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from pinflex.cli.common import (
    add_allow_paths,
    add_model_arguments,
    joint_value,
    parse_values,
    robot_description,
)
from pinflex.progress import ProgressBar


def add_parser(sub) -> None:
    """Register the ``path`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "path", help="joint trajectory of a frame moving through 3-D waypoints (IK)",
        description="Straight lines through waypoints of one frame, minimum-jerk timing, "
        "Pinocchio inverse kinematics warm-started along the path, joint limits checked. "
        "Writes a CSV (t, joint names) for `pinflex modes FILE --trajectory`.",
    )
    p.add_argument("urdf", help="annotated URDF (or pinflex overlay) file")
    add_allow_paths(p)
    p.add_argument("--frame", required=True, help="frame (link) that follows the path")
    p.add_argument("--through", type=float, nargs=3, action="append", required=True,
                   metavar=("X", "Y", "Z"), help="a waypoint [m] (repeat, in order)")
    p.add_argument("--relative", action="store_true",
                   help="waypoints are offsets from the frame at --q, which starts the path")
    p.add_argument("--q", type=joint_value, nargs="+", metavar="V",
                   help="start pose (IK initial guess), one value per joint (default zeros)")
    p.add_argument("--samples", type=int, default=50, help="number of samples (default 50)")
    p.add_argument("--duration", type=float, default=1.0, help="duration [s] (default 1)")
    p.add_argument("--profile", choices=("minimum_jerk", "uniform"), default="minimum_jerk")
    p.add_argument("--orientation", default="free",
                   help="'free' (position only, default), 'keep' (hold the start orientation)"
                   " or 'R,P,Y' roll-pitch-yaw [rad]")
    p.add_argument("--warn-limits", action="store_true",
                   help="warn instead of failing when a sample leaves the joint limits")
    add_model_arguments(p)
    p.add_argument("--out", required=True, help="CSV file to write")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar on stderr (shown by default when stderr is a terminal)")
    p.set_defaults(func=cmd_path)


def cmd_path(args: argparse.Namespace) -> int:
    """Run ``pinflex path``."""
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import ConfigurationError
    from pinflex.trajectory.cartesian import path_from_spec

    model = FlexibleModel(robot_description(args), values=parse_values(args.set),
                          joints=args.joints)
    orientation: object = args.orientation
    if orientation not in ("free", "keep"):
        try:
            orientation = [float(v) for v in str(orientation).split(",")]
        except ValueError as exc:
            raise ConfigurationError(
                f"--orientation {args.orientation!r}: use free, keep or R,P,Y"
            ) from exc
    spec = {
        "frame": args.frame,
        "waypoints": args.through,
        "relative": args.relative,
        "start_q": args.q,
        "samples": args.samples,
        "duration_s": args.duration,
        "profile": args.profile,
        "orientation": orientation,
        "on_limits": "warn" if args.warn_limits else "raise",
    }
    bar = ProgressBar(args.samples, "path: samples",
                      enabled=not args.no_progress and sys.stderr.isatty())
    traj = path_from_spec(model, spec, progress=bar)
    bar.close()
    traj.to_csv(args.out)
    speed = np.abs(np.diff(traj.q, axis=0) / np.diff(traj.times_s)[:, None]).max(axis=0)
    print(f"{traj.n_samples} samples over {traj.duration_s:.4g} s written to {args.out}")
    print("peak joint speed [rad/s or m/s]: " + ", ".join(
        f"{n}={v:.3g}" for n, v in zip(traj.joint_names, speed)))
    return 0
