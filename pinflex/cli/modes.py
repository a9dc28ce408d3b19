"""``pinflex modes``: eigenfrequencies of a flexible URDF arm at one pose."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from pinflex.cli.common import (
    add_robot_arguments,
    add_speed_arguments,
    bounded_value,
    inertia_text,
    joints_text,
    parse_values,
    robot_description,
    speed_terms,
)


def add_parser(sub) -> None:
    """Register the ``modes`` subcommand on an ``argparse`` subparsers object."""
    p = sub.add_parser("modes", help="eigenfrequencies of a flexible URDF arm at a pose")
    add_robot_arguments(p)
    p.add_argument("--modes", type=int, default=None, help="number of modes to report")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.add_argument("--tol", type=float, default=None, metavar="TOL",
                   help="pick the fewest elements per link whose estimated relative error "
                   "(Richardson, observed order) on the reported modes is at most TOL")
    p.add_argument("--trajectory", metavar="CSV",
                   help="joint trajectory (header: t, joint names): frequencies along the "
                   "motion, modes followed by their shapes (default 3 modes)")
    add_speed_arguments(
        p, terms_help="with --trajectory: the modes of the MOVING arm (modes at speed: every "
        "joint held by its motor on the motion, velocities and accelerations from the samples "
        "by second-order finite differences) with eq. (1)'s gyroscopic terms only (eq1) or "
        "with the centrifugal, Euler and geometric-stiffness terms (full); without it: the "
        "modes of the arm frozen at each pose",
        rates_when="with --terms:")
    p.add_argument("--strict", action="store_true",
                   help="with --trajectory: refuse a motion too fast for eq. (1) (validity "
                   "indicator above its threshold) instead of warning")
    p.add_argument("--csv", metavar="OUT", help="with --trajectory: write one row per sample")
    p.add_argument("--png", metavar="OUT", nargs="?", const="",
                   help="with --trajectory: write a chart (default name: the trajectory's "
                   "with _modes.png)")
    p.add_argument("--no-progress", action="store_true",
                   help="no progress bar on stderr (shown by default when stderr is a terminal;"
                   " with --trajectory)")
    p.add_argument("--gravity", type=gravity_value, nargs="*", metavar="G", default=None,
                   help="gravity preload: the stiffness of the arm's weight (axial forces in "
                   "the beams, loads on the joints) in the modal analysis; GX GY GZ in world "
                   "axes [m/s^2], or no value for 9.81 m/s^2 along -z of the base (default: no "
                   "preload, as paper 000). Free joints must be locked or sprung unless the "
                   "weight leaves them neutral")
    p.set_defaults(func=cmd_modes)


def gravity_value(text: str) -> float:
    """A ``--gravity`` component: a number of the grammar, at most 1e4 in size [m/s^2]."""
    from pinflex.erls.preload import MAX_GRAVITY

    return bounded_value(text, MAX_GRAVITY, "gravity is in m/s^2")


def gravity_of(args: argparse.Namespace):
    """The ``--gravity`` vector (3,) [m/s^2], or None without the flag."""
    from pinflex.erls.preload import STANDARD_GRAVITY
    from pinflex.exceptions import ConfigurationError

    if args.gravity is None:
        return None
    if not args.gravity:
        return (0.0, 0.0, -STANDARD_GRAVITY)
    if len(args.gravity) != 3:
        raise ConfigurationError(f"--gravity takes three values GX GY GZ [m/s^2] or none (9.81 "
                                 f"m/s^2 along -z), got {len(args.gravity)}")
    return tuple(args.gravity)


def cmd_modes(args: argparse.Namespace) -> int:
    """Run ``pinflex modes``."""
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import ConfigurationError

    if args.tol is not None and not 0.0 < args.tol < 1.0:
        raise ConfigurationError(f"--tol {args.tol:g}: give a relative tolerance in (0, 1)")
    model = FlexibleModel(robot_description(args), planar=args.planar,
                          values=parse_values(args.set), joints=args.joints)
    if args.modes is not None and args.modes > model.n_elastic:
        raise ConfigurationError(f"--modes {args.modes}: the model has elastic modes "
                                 f"1..{model.n_elastic}")
    gravity = gravity_of(args)
    if args.trajectory is not None:
        if gravity is not None:
            raise ConfigurationError(
                "--gravity goes with one pose (--q); along a trajectory use "
                "FlexibleModel.frequencies(Q, gravity=...) for the sorted frequencies")
        if args.tol is not None:
            raise ConfigurationError("--tol picks the elements at one pose (--q); it does not "
                                     "go with --trajectory")
        return _along(model, args)
    if args.csv or args.png is not None or speed_terms(args) or args.strict:
        raise ConfigurationError("--csv, --png, --terms, --at-speed and --strict go with "
                                 "--trajectory")
    q = np.array(args.q if args.q is not None else np.zeros(model.nv), dtype=float)
    fidelity = None
    if args.tol is not None:
        from pinflex.erls.fidelity import elements_for_tolerance, refined

        fidelity = elements_for_tolerance(
            model.description, q, args.tol, n_modes=args.modes or 3, planar=args.planar,
            values=parse_values(args.set), joints=args.joints)
        model = FlexibleModel(refined(model.description, fidelity.factor), planar=args.planar,
                              values=parse_values(args.set), joints=args.joints)
    # frequencies only: the batched numpy path, which needs no SciPy (fast start-up)
    from pinflex.erls.preload import make_preload

    preload = make_preload(model, gravity)
    freqs = model.frequencies(q, n_modes=args.modes, preload=preload)
    y = model.y0
    held = held_frequencies(model, q, n_modes=min(3, len(freqs)))
    if args.json:
        out = {
            "robot": model.description.name,
            "planar": model.planar,
            "coordinates": model.coordinates,
            "joint_names": list(model.joint_names),
            "q": q.tolist(),
            "design": {d.name: float(v) for d, v in zip(model.design, y)},
            "design_units": {d.name: d.unit for d in model.design},
            "ndof": model.ndof,
            "elastic_dof": model.nx,
            "rigid_modes": model.n_rigid,
            "joint_condition": model.joint_switch,
            "joint_condition_text": condition_text(model),
            "joints": model.joint_labels(),
            "held_frequencies_hz": {k: v.tolist() for k, v in held.items()},
            "link_inertia": list(model.description.inertia_notes),
            "frequencies_hz": freqs.tolist(),
            "preload": None if preload is None else preload.as_dict(),
        }
        if fidelity is not None:
            out["fidelity"] = {"tol": args.tol, "elements": fidelity.elements,
                               "estimated_error": fidelity.estimate.tolist(),
                               "observed_order": fidelity.order.tolist(),
                               "estimate": "Richardson from three uniform refinements"}
        from pinflex.outputs import json_text

        print(json_text(out))
        return 0
    print(f"{model.description.name}: {model.ndof} dof ({model.nx} elastic + "
          f"{model.ndof - model.nx} joint), {'planar' if model.planar else 'spatial'}, "
          f"{model.coordinates} joint coordinates")
    print(joints_text(model))
    print("joint condition: " + condition_text(model))
    if inertia_text(model):
        print(inertia_text(model))
    line = held_line(held)
    if line:
        print(line)
    print("q = " + ", ".join(f"{n}={v:.6g}" for n, v in zip(model.joint_names, q)))
    if model.ny:
        values = ", ".join(f"{d.name}={v:.6g} {d.unit}".rstrip()
                           for d, v in zip(model.design, y))
        print(f"design: {values}")
    print(f"rigid modes: {model.n_rigid}")
    if preload is not None:
        print(f"preload: {preload} (geometric stiffness of the static loads)")
    if fidelity is not None:
        els = ", ".join(f"{k}={v}" for k, v in fidelity.elements.items())
        print(f"elements for tol {args.tol:g}: {els}; estimated error of the lowest "
              f"{fidelity.estimate.size} modes <= {float(fidelity.estimate.max()):.2e} "
              "(Richardson, observed order "
              f"{', '.join(f'{p:.2f}' for p in fidelity.order)})")
    print(f"{'mode':>4}  {'frequency [Hz]':>16}")
    for i, f in enumerate(freqs, start=1):
        print(f"{i:>4}  {f:>16.6f}")
    return 0


def condition_text(model) -> str:
    """Which joint condition the model uses, in words."""
    switch = model.plan.conditions.switch
    kinds = {c.kind for c in model.joint_conditions}
    if kinds == {"free"}:
        what = ("free: no joint carries torque (paper 000's condition); the modes are those of "
                "the arm with its joints' inertia coupling the links")
    elif kinds == {"locked"}:
        what = "locked: every joint held rigidly"
    else:
        words = {"free": "free", "locked": "locked", "spring": "on springs (servos)"}
        n = {k: sum(c.kind == k for c in model.joint_conditions) for k in kinds}
        what = ", ".join(f"{v} {words[k]}" for k, v in sorted(n.items()))
    annotated = bool(model.description.joint_annotations)
    src = {"annotated": "the file's <pinflex:joint> annotations" if annotated else
           "the default: the file has no <pinflex:joint>",
           "mapping": "the joints given"}.get(switch, f"--joints {switch}")
    return f"{what} ({src})"


def held_frequencies(model, q, n_modes: int = 3) -> dict:
    """Lowest frequencies [Hz] of the same arm held at its joints, when some joint is free.

    ``{"locked": ...}`` with every joint locked and, when the file annotates springs that the
    model does not use, ``{"annotated": ...}`` on those springs. Empty when no joint is free.
    """
    from pinflex.erls import FlexibleModel

    if model.n_rigid == 0:
        return {}
    out = {}
    values = dict(model.point_mass_values)  # parameters are in the description already
    for switch in ("locked", "annotated"):
        if switch == "annotated" and (model.plan.conditions.switch == "annotated" or not any(
                a.stiffness is not None or a.locked
                for a in model.description.joint_annotations.values())):
            continue
        held = FlexibleModel(model.description, planar=model.planar, joints=switch,
                             coordinates=model.coordinates, values=values or None)
        if held.n_elastic:
            out[switch] = held.frequencies(q, n_modes=n_modes)
    return out


def held_line(held: dict) -> str:
    """One line: a held arm rings at these modes (empty when nothing is free)."""
    if not held:
        return ""
    parts = [f"{', '.join(f'{f:.4g}' for f in v)} Hz with every joint locked"
             if k == "locked" else f"{', '.join(f'{f:.4g}' for f in v)} Hz on the file's "
             "joint springs (servos)" for k, v in held.items()]
    return ("note: free joints carry no torque; an arm held by its drives rings at its "
            "locked or servo modes: " + "; ".join(parts))


def _along(model, args: argparse.Namespace) -> int:
    import sys

    from pinflex.erls.along import modes_along
    from pinflex.progress import ProgressBar
    from pinflex.trajectory import Trajectory

    traj = Trajectory.from_csv(args.trajectory, joint_names=model.joint_names)
    bar = ProgressBar(traj.n_samples, "modes along: samples",
                      enabled=not args.no_progress and sys.stderr.isatty())
    terms = speed_terms(args)
    res: Any
    if terms is None and args.rates != "samples":
        from pinflex.exceptions import ConfigurationError

        raise ConfigurationError("--rates gives the joint rates of the modes at speed: give it "
                                 "with --terms (the frozen-pose modes need no rates)")
    if terms is None:
        res = modes_along(model, traj, modes=args.modes or 3, progress=bar, strict=args.strict)
    else:
        from pinflex.dynamics import ErlsDynamics
        from pinflex.dynamics.modes import modes_at_speed_along

        res = modes_at_speed_along(ErlsDynamics(model), traj,
                                   terms=terms, n_modes=args.modes or 3, rates=args.rates,
                                   strict=args.strict, progress=bar)
    bar.close()
    if args.csv:
        res.to_csv(args.csv)
    if args.png is not None:
        if not args.png:
            from pathlib import Path

            args.png = str(Path(args.trajectory).with_name(Path(args.trajectory).stem
                                                           + "_modes.png"))
        res.plot(args.png)
    if args.json:
        print(res.to_json())
    else:
        print(res.table())
        for label, path in (("table", args.csv), ("chart", args.png)):
            if path:
                print(f"{label}: {path}")
    return 0
