"""The ``pinflex`` command line."""

from __future__ import annotations

import argparse
import json
import sys
from collections.abc import Sequence

import numpy as np

from pinflex.exceptions import ConfigurationError, PinflexError


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


def _cmd_modes(args: argparse.Namespace) -> int:
    from pinflex.erls import FlexibleModel

    model = FlexibleModel(args.urdf, planar=args.planar, values=parse_values(args.set))
    q = np.array(args.q if args.q is not None else np.zeros(model.nv), dtype=float)
    result = model.modes(q, n_modes=args.modes)
    freqs = result.freq_hz
    if args.json:
        out = {
            "robot": model.description.name,
            "planar": model.planar,
            "coordinates": model.coordinates,
            "joint_names": list(model.joint_names),
            "q": q.tolist(),
            "design": {d.name: float(v) for d, v in zip(model.design, result.y)},
            "ndof": model.ndof,
            "elastic_dof": model.nx,
            "rigid_modes": result.rigid_modes,
            "frequencies_hz": freqs.tolist(),
        }
        print(json.dumps(out))
        return 0
    print(f"{model.description.name}: {model.ndof} dof ({model.nx} elastic + {model.nv} rigid), "
          f"{'planar' if model.planar else 'spatial'}, {model.coordinates} joint coordinates")
    print("q = " + ", ".join(f"{n}={v:.6g}" for n, v in zip(model.joint_names, q)))
    if model.ny:
        values = ", ".join(f"{d.name}={v:.6g} kg" for d, v in zip(model.design, result.y))
        print(f"design: {values}")
    print(f"rigid modes: {result.rigid_modes}")
    print(f"{'mode':>4}  {'frequency [Hz]':>16}")
    for i, f in enumerate(freqs, start=1):
        print(f"{i:>4}  {f:>16.6f}")
    return 0


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``pinflex`` command."""
    from pinflex import __version__

    parser = argparse.ArgumentParser(
        prog="pinflex",
        description="Flexible-link robots on Pinocchio: modal analysis, Taylor modal models, "
        "eigenfrequency assignment, pseudo-rigid-body models.",
    )
    parser.add_argument("--version", action="version", version=f"pinflex {__version__}")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("modes", help="eigenfrequencies of a flexible URDF arm at a pose")
    p.add_argument("urdf", help="annotated URDF (or pinflex overlay) file")
    p.add_argument("--q", type=float, nargs="+", metavar="V",
                   help="joint values, one per moving joint, in the file's convention "
                   "(default: zeros)")
    p.add_argument("--set", action="append", metavar="NAME=VALUE",
                   help="set a point mass [kg] (repeatable)")
    p.add_argument("--modes", type=int, default=None, help="number of modes to report")
    p.add_argument("--planar", action="store_true", help="keep in-plane elastic dofs only")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(func=_cmd_modes)

    _optional_commands(sub)
    return parser


def _optional_commands(sub) -> None:
    import importlib
    import importlib.util

    from pinflex import assign_cli, view_cli
    from pinflex.batch import cli as batch_cli

    assign_cli.add_parser(sub)
    view_cli.add_parser(sub)
    batch_cli.add_parser(sub)
    # the PRBDM command registers itself when its module is present
    if importlib.util.find_spec("pinflex.prbdm.cli") is not None:
        importlib.import_module("pinflex.prbdm.cli").add_parser(sub)


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pinflex`` command."""
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        func = getattr(args, "func", None) or args.run
        return int(func(args) or 0)
    except PinflexError as exc:
        print(f"pinflex: error: {exc}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
