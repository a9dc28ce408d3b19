"""Arguments and parsing shared by several subcommands."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from pinflex.exceptions import ConfigurationError
from pinflex.validation import parse_number


def parse_values(items: Sequence[str] | None) -> dict[str, float]:
    """``NAME=VALUE`` strings (``--set``) to a ``{name: float}`` dictionary."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep:
            raise ConfigurationError(f"--set expects NAME=VALUE, got '{item}'")
        if name.strip() in out:
            raise ConfigurationError(f"--set {name.strip()} is given twice; give each name once")
        try:
            out[name.strip()] = parse_number(value)
        except ValueError as exc:
            raise ConfigurationError(f"--set {item}: {exc}") from exc
    return out


JOINT_CHOICES = ("free", "locked", "annotated")


def bounded_value(text: str, limit: float, unit_hint: str) -> float:
    """An argument value: a number of pinflex's grammar, at most ``limit`` in size.

    Raises:
        argparse.ArgumentTypeError: Not a number, or beyond ``limit`` (the message ends with
            ``unit_hint``).
    """
    import argparse

    try:
        value = parse_number(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None
    if abs(value) > limit:
        raise argparse.ArgumentTypeError(f"{text!r} is beyond {limit:g}: {unit_hint}")
    return value


def joint_value(text: str) -> float:
    """A ``--q`` value: a number of the grammar, at most 1e6 in size [rad or m]."""
    from pinflex.trajectory.samples import MAX_JOINT_VALUE

    return bounded_value(text, MAX_JOINT_VALUE, "joint values are in radians or metres")


def add_model_arguments(p: argparse.ArgumentParser, *, default_joints: str | None = "annotated",
                        with_set: bool = True) -> None:
    """``--joints`` (and ``--set``) of every command that builds a flexible model.

    ``default_joints=None`` leaves the choice to the command's input (a study file).
    """
    p.add_argument("--joints", choices=JOINT_CHOICES, default=default_joints,
                   help="joint conditions: annotated (the file's <pinflex:joint> springs and "
                   "locks, other joints free; a file without them has every joint free), or "
                   "an override: free (no joint stiffness, paper 000) or locked (every joint "
                   "held rigidly)" + (f" (default: {default_joints})" if default_joints else
                                      " (default: the study's, else annotated)"))
    if with_set:
        p.add_argument("--set", action="append", metavar="NAME=VALUE",
                       help="set a parameter or point mass (repeatable)")


def joints_text(model) -> str:
    """One line naming the model's joint conditions, e.g. ``joints: q1 free, q2 k=1e+03``."""
    labels = model.joint_labels()
    return "joints: " + ", ".join(f"{n} {v}" for n, v in labels.items())


def inertia_text(model) -> str:
    """One line: what each beam link kept of its URDF inertia (empty when none has one)."""
    notes = model.description.inertia_notes
    return ("link inertia: " + "; ".join(notes)) if notes else ""


def add_allow_paths(p: argparse.ArgumentParser) -> None:
    """``--allow-paths``: read files a description names from outside its folder."""
    p.add_argument("--allow-paths", action="store_true",
                   help="read an overlay's base URDF and mesh files from anywhere (default: "
                   "only from the description's folder and the package roots)")


def robot_description(args: argparse.Namespace):
    """The description of ``args.urdf``, with ``--allow-paths`` if the command has it."""
    from pinflex.description import load

    return load(args.urdf, allow_paths=bool(getattr(args, "allow_paths", False)))


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """The robot file, pose, parameters, joints and planar switch of ``modes`` and ``view``."""
    p.add_argument("urdf", help="annotated URDF (or pinflex overlay) file")
    add_allow_paths(p)
    p.add_argument("--q", type=joint_value, nargs="+", metavar="V",
                   help="joint values, one per moving joint, in the file's convention "
                   "(default: zeros)")
    add_model_arguments(p)
    p.add_argument("--planar", action="store_true", help="keep in-plane elastic dofs only")


def add_speed_arguments(p: argparse.ArgumentParser, *, terms_help: str, rates_when: str,
                        motion_note: str = "") -> None:
    """Add ``--terms``, ``--at-speed`` and ``--rates``, shared by modes and export.

    The moving-state options of ``pinflex modes`` and ``pinflex export``; read back by
    :func:`speed_terms`.
    """
    p.add_argument("--terms", choices=("eq1", "full"), help=terms_help)
    p.add_argument("--at-speed", action="store_true", help="the same as --terms full")
    p.add_argument("--rates", choices=("samples", "motion"), default="samples",
                   help=f"{rates_when} joint velocities and accelerations by second-order "
                   "finite differences of the samples (samples, default) or from the "
                   "rest-to-rest quintic spline through them that pinflex simulate drives "
                   f"(motion{motion_note})")


def speed_terms(args: argparse.Namespace) -> str | None:
    """The terms of ``--terms`` / ``--at-speed`` (None: the frozen-pose model)."""
    from pinflex.exceptions import ConfigurationError

    if args.at_speed and args.terms not in (None, "full"):
        raise ConfigurationError(f"--at-speed is --terms full; it does not go with --terms "
                                 f"{args.terms}")
    return "full" if args.at_speed else args.terms
