"""Arguments and parsing shared by several subcommands."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from pinflex.exceptions import ConfigurationError


def parse_values(items: Sequence[str] | None) -> dict[str, float]:
    """``NAME=VALUE`` strings (``--set``) to a ``{name: float}`` dictionary."""
    out = {}
    for item in items or ():
        name, sep, value = item.partition("=")
        if not sep:
            raise ConfigurationError(f"--set expects NAME=VALUE, got '{item}'")
        try:
            out[name.strip()] = float(value)
        except ValueError as exc:
            raise ConfigurationError(f"--set {item}: '{value}' is not a number") from exc
    return out


def add_robot_arguments(p: argparse.ArgumentParser) -> None:
    """The robot file, pose, point masses and planar switch of ``modes`` and ``view``."""
    p.add_argument("urdf", help="annotated URDF (or pinflex overlay) file")
    p.add_argument("--q", type=float, nargs="+", metavar="V",
                   help="joint values, one per moving joint, in the file's convention "
                   "(default: zeros)")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="set a point mass [kg] (repeatable)")
    p.add_argument("--planar", action="store_true", help="keep in-plane elastic dofs only")
