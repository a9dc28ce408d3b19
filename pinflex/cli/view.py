"""``pinflex view``: a mode shape of a flexible URDF arm in meshcat.

With ``--html FILE`` the preview is written as a static page that opens offline; without it a
local meshcat server is started, its URL printed, and the scene served until Ctrl-C (or for
``--serve-seconds``). No browser is opened either way.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from pinflex.cli.common import add_robot_arguments, parse_values


def add_parser(sub) -> None:
    """Register the ``view`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "view", help="animate a mode shape in meshcat (served locally or as static HTML)"
    )
    add_robot_arguments(p)
    p.add_argument("--mode", type=int, default=1, metavar="K",
                   help="mode to animate, 1 = lowest non-rigid mode (default: 1)")
    p.add_argument("--amplitude", type=float, default=None, metavar="A",
                   help="peak displacement drawn [m] (default: 8 %% of the robot's size)")
    p.add_argument("--html", default=None, metavar="FILE",
                   help="write a static HTML preview instead of serving meshcat")
    p.add_argument("--serve-seconds", type=float, default=None, metavar="S",
                   help="stop serving after S seconds (default: until Ctrl-C)")
    p.set_defaults(func=cmd_view)


def cmd_view(args: argparse.Namespace) -> int:
    """Run ``pinflex view``."""
    from pinflex.erls import FlexibleModel
    from pinflex.visualization import mode_preview, served_visualizer

    model = FlexibleModel(args.urdf, planar=args.planar, values=parse_values(args.set),
                          joints=args.joints)
    q = np.zeros(model.nv) if args.q is None else np.array(args.q, dtype=float)
    if args.html:
        preview = mode_preview(model, q, args.mode, amplitude_m=args.amplitude)
        path = preview.write_html(args.html)
        print(preview.caption)
        print(f"wrote {path}")
        return 0
    vis = served_visualizer()
    preview = mode_preview(model, q, args.mode, amplitude_m=args.amplitude, viewer=vis)
    print(preview.caption)
    print(f"meshcat is serving the preview at {vis.url()}")
    try:
        if args.serve_seconds is None:
            print("press Ctrl-C to stop")
            while True:
                time.sleep(3600.0)
        time.sleep(max(0.0, float(args.serve_seconds)))
    except KeyboardInterrupt:
        pass
    return 0
