"""``pinflex export``: M, K, damping and a state-space model for control design."""

from __future__ import annotations

import argparse

import numpy as np

from pinflex.cli.common import (
    add_robot_arguments,
    add_speed_arguments,
    joint_value,
    parse_values,
    robot_description,
    speed_terms,
)


def add_parser(sub) -> None:
    """Register the ``export`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser(
        "export", help="M, K, damping and state-space (A, B, C, D) to .npz or .mat; or a "
        "lumped model of the arm to MJCF (MuJoCo) or URDF",
        description="Linear model at a pose (--q) or at every sample of a trajectory "
        "(--trajectory). Coordinates p = [x; q]: elastic nodal coordinates then joints; "
        "state [p; dp/dt]; inputs: joint torques; outputs: p. See docs/exports.md. "
        "With --format mjcf or urdf: a lumped model (rigid segments and spring joints) fitted "
        "to the arm's modes at the pose or along the trajectory; see docs/mujoco.md.",
    )
    add_robot_arguments(p)
    p.add_argument("--trajectory", metavar="CSV", help="export at every sample of a trajectory")
    p.add_argument("--zeta", type=float, default=0.0,
                   help="modal damping ratio of every elastic mode (default 0)")
    p.add_argument("--rayleigh", type=float, nargs=2, metavar=("ALPHA", "BETA"),
                   help="Rayleigh damping of the deformation [1/s, s]: every locked-joint mode "
                   "decays at alpha/2 + beta omega^2/2, the rigid motion is not damped")
    p.add_argument("--torque-input", choices=("motor", "generalized"), default="motor",
                   help="linear model: motor (default): the actuator acts on both bodies of the "
                   "joint (B = G^T, with the reaction on a flexible parent); generalized: the "
                   "torque on the joint coordinate only")
    p.add_argument("--qd", type=joint_value, nargs="+", metavar="V",
                   help="linear model about a MOVING state: joint velocities at --q [rad/s or "
                   "m/s] (every joint held by its motor: needs --joints locked)")
    p.add_argument("--qdd", type=joint_value, nargs="+", metavar="V",
                   help="joint accelerations at --q [rad/s^2 or m/s^2] (with --qd or alone)")
    add_speed_arguments(
        p, terms_help="linearise about the moving state (--qd/--qdd, or with --trajectory "
        "each sample's, velocities and accelerations by second-order finite differences of "
        "the samples) with eq. (1)'s gyroscopic terms only (eq1, the default with --qd/--qdd) "
        "or with the centrifugal, Euler and geometric-stiffness terms (full); see "
        "docs/exports.md",
        rates_when="with --trajectory and --terms:",
        motion_note=": the exported model is then the prescribed simulation's at each sample")
    p.add_argument("--out", required=True,
                   help="output file: .npz or .mat (linear model), .xml (MJCF), .urdf")
    p.add_argument("--format", choices=("linear", "mjcf", "urdf"),
                   help="what to write (default: from the suffix of --out)")
    from pinflex.cli import export_lumped

    export_lumped.add_arguments(p)
    p.set_defaults(func=cmd_export)


def cmd_export(args: argparse.Namespace) -> int:
    """Run ``pinflex export``."""
    from pinflex.cli import export_lumped

    from pinflex.exceptions import ConfigurationError

    fmt = export_lumped.format_of(args)
    terms = speed_terms(args)
    moving = terms is not None or args.qd is not None or args.qdd is not None
    if fmt in export_lumped.LUMPED_FORMATS:
        if moving or args.rates != "samples":
            raise ConfigurationError("--qd, --qdd, --terms, --at-speed and --rates give the "
                                     "linear model (.npz or .mat) about a moving state, not a "
                                     "lumped model")
        return export_lumped.run(args, fmt)
    from pinflex.erls import FlexibleModel
    from pinflex.native.export import linear_model, save_linear_model

    if args.rates != "samples" and not (moving and args.trajectory):
        raise ConfigurationError("--rates gives the joint rates of the samples' moving states: "
                                 "give it with --trajectory and --terms")
    model = FlexibleModel(robot_description(args), planar=args.planar,
                          values=parse_values(args.set), joints=args.joints)
    times = qd = qdd = None
    rates_checked = False
    if args.trajectory:
        from pinflex.erls.along import trajectory_for
        from pinflex.trajectory import Trajectory

        if args.qd is not None or args.qdd is not None:
            raise ConfigurationError("--qd/--qdd give the state at --q; with --trajectory the "
                                     "rates come from the samples (give --terms)")
        traj = Trajectory.from_csv(args.trajectory, joint_names=model.joint_names)
        q = trajectory_for(model, traj)
        times = traj.times_s
        if moving and args.rates == "motion":
            from pinflex.dynamics.motion import JointMotion
            from pinflex.trajectory.samples import in_model_order

            q, qd, qdd = JointMotion(in_model_order(model, traj)).sample(times)
        elif moving:
            from pinflex.erls.validity import sample_rates

            if times.size < 3:
                raise ConfigurationError("--terms with --trajectory differentiates the samples: "
                                         f"give at least 3 samples, not {times.size}")
            qd, qdd = sample_rates(times, q)
            rates_checked = True
    else:
        q = np.array(args.q if args.q is not None else np.zeros(model.nv), dtype=float)
        qd, qdd = args.qd, args.qdd
    if moving:
        from pinflex.dynamics.export import linear_model_at_state

        data = linear_model_at_state(model, q, qd, qdd, terms=terms or "eq1",
                                     zeta=args.zeta,
                                     rayleigh=args.rayleigh, torque_input=args.torque_input)
    else:
        data = linear_model(model, q, zeta=args.zeta, rayleigh=args.rayleigh,
                            torque_input=args.torque_input)
    if times is not None:
        data["times_s"] = np.asarray(times)
    if rates_checked:  # finite-difference rates: are they good enough for the speed terms?
        from pinflex.erls.validity import check_sample_rates, validity

        w1 = 2.0 * np.pi * np.where(data["freq_hz"][:, 0] > 0.0, data["freq_hz"][:, 0], np.nan)
        indicator = validity(model, times, q, qd, qdd, w1, warn=False, basis="at speed")
        check_sample_rates(times, q, indicator)
    path = save_linear_model(data, args.out)
    shape = "x".join(str(s) for s in data["A"].shape)
    state = ""
    if "drive" in data:
        state = (f"; about the moving state (terms={terms or 'eq1'}, every joint held: "
                 "velocity terms in 'velocity', the motion's load in 'drive')")
    print(f"wrote {path}: A {shape}, {model.ndof} coordinates ({model.nx} elastic + "
          f"{model.ndof - model.nx} joints), {model.nv} inputs ({args.torque_input} joint "
          "torques); "
          f"joints {model.joint_switch}{state}")
    return 0
