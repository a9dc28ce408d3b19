"""``pinflex view``: mode shapes of a flexible URDF arm, or a trajectory, in meshcat.

With ``--html FILE`` the preview is written as a static page that opens offline: every
computed mode (``--modes N``, default 6) with a selector showing each frequency, ``--mode K``
shown first; with ``--trajectory CSV`` the motion is played back with the beams coloured by
mode K's frequency. Without ``--html`` a local meshcat server is started, its URL printed, and
the scene served until Ctrl-C (or for ``--serve-seconds``). No browser is opened either way.
"""

from __future__ import annotations

import argparse
import sys
import time

import numpy as np

from pinflex.cli.common import add_robot_arguments, parse_values, robot_description


def add_parser(sub) -> None:
    """Register the ``view`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "view", help="animate a mode shape in meshcat (served locally or as static HTML)"
    )
    add_robot_arguments(p)
    p.add_argument("--mode", type=int, default=1, metavar="K",
                   help="mode to show first (or to colour a trajectory by), 1 = lowest "
                   "non-rigid mode (default: 1)")
    p.add_argument("--modes", type=int, default=6, metavar="N",
                   help="modes 1..N on the page, selectable (default: 6)")
    p.add_argument("--trajectory", default=None, metavar="CSV",
                   help="play a joint trajectory (header: t, joint names) instead")
    p.add_argument("--amplitude", type=float, default=None, metavar="A",
                   help="peak displacement drawn [m] (default: 8 %% of the robot's size)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar on stderr (shown by default when stderr is a terminal)")
    p.add_argument("--html", default=None, metavar="FILE",
                   help="write a static HTML preview instead of serving meshcat")
    p.add_argument("--serve-seconds", type=float, default=None, metavar="S",
                   help="stop serving after S seconds (default: until Ctrl-C)")
    p.add_argument("--bind", default="127.0.0.1", metavar="ADDRESS",
                   help="address the served viewer listens on (default 127.0.0.1: this machine "
                   "only); 0.0.0.0 serves every network interface, without authentication: "
                   "anyone who can reach the machine sees the scene")
    p.set_defaults(func=cmd_view)


def cmd_view(args: argparse.Namespace) -> int:
    """Run ``pinflex view``."""
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import ConfigurationError
    from pinflex.outputs import check_file_target
    from pinflex.visualization import served_visualizer, trajectory_preview
    from pinflex.visualization.modes_page import modes_preview

    if args.html:
        check_file_target(args.html, "--html")
    for name, value, top in (("--amplitude", args.amplitude, 1e3),
                             ("--serve-seconds", args.serve_seconds, 1e7)):
        if value is not None and not (np.isfinite(value) and 0.0 < value <= top):
            raise ConfigurationError(f"{name} {value} must be a positive number up to {top:g}"
                                     + (" [m]" if name == "--amplitude" else " [s]"))
    model = FlexibleModel(robot_description(args), planar=args.planar,
                          values=parse_values(args.set), joints=args.joints)
    q = np.zeros(model.nv) if args.q is None else np.array(args.q, dtype=float)
    if not 1 <= args.modes <= model.n_elastic:
        raise ConfigurationError(f"--modes {args.modes}: give 1 to {model.n_elastic} (the "
                                 "model's elastic modes)")
    if not 1 <= args.mode <= model.n_elastic:
        from pinflex.exceptions import ConfigurationError

        raise ConfigurationError(
            f"mode {args.mode} does not exist: the model has elastic modes 1..{model.n_elastic}"
        )
    vis = None if args.html else served_visualizer(bind=args.bind)
    progress = not args.no_progress and sys.stderr.isatty()
    if args.trajectory:
        from pinflex.erls.along import trajectory_for
        from pinflex.trajectory import Trajectory

        traj = Trajectory.from_csv(args.trajectory, joint_names=model.joint_names)
        from pinflex.visualization.modes_page import add_grid
        from pinflex.visualization.robot import pose_state, scene_points

        Q = trajectory_for(model, traj)
        preview = trajectory_preview(model, traj.times_s, Q, mode=args.mode, viewer=vis,
                                     progress=progress)
        add_grid(preview.viewer, np.vstack([scene_points(pose_state(model, qk, 1))
                                            for qk in Q]))
        caption = (f"{model.description.name}: {traj.n_samples} samples over "
                   f"{traj.duration_s:.3g} s, mode {args.mode} from "
                   f"{preview.info['low_hz']:.2f} to {preview.info['high_hz']:.2f} Hz")
        write = preview.write_html
    else:
        n = max(int(args.modes), int(args.mode))
        page = modes_preview(model, q, min(n, model.n_elastic), amplitude_m=args.amplitude,
                             viewer=vis, progress=progress)
        if vis is not None:
            page.select(args.mode)
        caption = page.captions[page.modes.index(args.mode)]

        def write(path):
            return page.write_html(path, initial=args.mode)
    print(caption)
    if args.html:
        print(f"wrote {write(args.html)}")
        return 0
    vis = vis or served_visualizer(bind=args.bind)
    print(f"meshcat is serving the preview at {vis.url()}"
          + ("" if args.bind == "127.0.0.1" else
             f" (listening on {args.bind}: other machines can see it)"))
    try:
        if args.serve_seconds is None:
            print("press Ctrl-C to stop")
            while True:
                time.sleep(3600.0)
        time.sleep(max(0.0, float(args.serve_seconds)))
    except KeyboardInterrupt:
        pass
    return 0
