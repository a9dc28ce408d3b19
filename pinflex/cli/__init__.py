"""The ``pinflex`` command line: one parser, one error handler, one exit-code convention.

Each subcommand lives in its own module of this package and registers itself with an
``add_parser(subparsers)`` function that sets ``func`` (a function of the parsed arguments
returning the exit status). A new subcommand is a new module and one line in
:data:`SUBCOMMANDS`. A run imports only the module of the subcommand it names (start-up
stays that of the work asked for); ``pinflex --help`` and unknown names load them all.

Exit status: 0 on success; 3 when ``assign`` or ``size`` ran but the exact model does not meet
the targets, floors or constraints (:data:`pinflex.assignment.result.EXIT_NOT_MET`); 2 for a
user error (a :class:`~pinflex.exceptions.PinflexError`,
reported as one line ``pinflex: error: ...`` on stderr, or an argparse usage error); 1 for an
internal error (any other exception, reported as one line; ``--debug`` shows the traceback);
130 when interrupted; 141 (as after SIGPIPE) without a word when the reader of standard output
went away, as in ``pinflex modes ... | head``.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

#: Modules of :mod:`pinflex.cli` that register a subcommand, in the order of ``--help``.
SUBCOMMANDS: list[str] = [
    "modes",
    "path",
    "export",
    "assign",
    "size",
    "demo",
    "view",
    "batch",
    "prbdm",
    "simulate",
    "report",
]


def _number(text: str) -> float:
    """A command-line number read by pinflex's number grammar (``type=float`` options)."""
    from pinflex.validation import parse_number

    try:
        return parse_number(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _whole(text: str) -> int:
    """A command-line whole number read by pinflex's grammar (``type=int`` options)."""
    from pinflex.validation import parse_int

    try:
        return parse_int(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


class _Parser(argparse.ArgumentParser):
    """An argument parser whose usage errors are one line, like every other error.

    Options declared ``type=float`` or ``type=int`` are read by pinflex's one number grammar
    (:func:`pinflex.validation.parse_number`): ``nan``, ``inf``, ``1_0``, Unicode digits and
    non-ASCII spaces, which Python's ``float()`` and ``int()`` accept, are usage errors.
    """

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.register("type", float, _number)
        self.register("type", int, _whole)

    def error(self, message: str):
        """Print ``pinflex SUBCOMMAND: error: ...`` and the way to help; exit with status 2."""
        self.exit(2, f"{self.prog}: error: {message} (see '{self.prog} --help')\n")


def chosen_subcommand(argv: Sequence[str]) -> str | None:
    """The registered subcommand ``argv`` names, or None (help, version, none or unknown).

    The top-level options take no value, so the first word not starting with ``-`` is the
    subcommand.
    """
    for word in argv:
        if word in ("-h", "--help"):
            return None
        if not word.startswith("-"):
            return word if word in SUBCOMMANDS else None
    return None


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The argument parser of the ``pinflex`` command.

    Args:
        only: Register just this subcommand (its module alone is imported); default: all
            of :data:`SUBCOMMANDS`.
    """
    from pinflex import __version__

    parser = _Parser(
        prog="pinflex",
        description="Flexible-link robots on Pinocchio: modal analysis, Taylor modal models, "
        "eigenfrequency assignment, pseudo-rigid-body models.",
    )
    parser.add_argument("--version", action="version", version=f"pinflex {__version__}")
    parser.add_argument("--debug", action="store_true",
                        help="show the full traceback of an error instead of one line")
    sub = parser.add_subparsers(dest="command", required=True)
    for name in SUBCOMMANDS if only is None else [only]:
        importlib.import_module(f"pinflex.cli.{name}").add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pinflex`` command; returns the exit status.

    Args:
        argv: Arguments without the program name (default: ``sys.argv[1:]``).
    """
    from pinflex.exceptions import PinflexError

    words = sys.argv[1:] if argv is None else list(argv)
    try:
        args = build_parser(chosen_subcommand(words)).parse_args(words)
    except SystemExit as exc:  # usage errors (one line printed), --help, --version
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 2)
    empty = [i for i, w in enumerate(words) if w == ""]
    if empty:  # an empty file name, address or value typed on the command line is never meant
        i = empty[0]
        name = words[i - 1] if i and words[i - 1].startswith("-") else "an argument"
        print(f"pinflex {args.command}: error: an empty value was given to {name}",
              file=sys.stderr)
        return 2
    import warnings

    shown = warnings.showwarning
    if not args.debug:
        warnings.showwarning = _one_line_warning
    try:
        return int(args.func(args) or 0)
    except PinflexError as exc:
        if args.debug:
            raise
        print(f"pinflex: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        if args.debug:
            raise
        print("pinflex: interrupted", file=sys.stderr)
        return 130
    except MemoryError as exc:
        if args.debug:
            raise
        # an allocation beyond this machine's memory that no estimate caught
        print(f"pinflex: error: out of memory ({exc or 'MemoryError'}): the request is too "
              "large for this machine; use fewer elements, samples, modes or poses",
              file=sys.stderr)
        return 2
    except BrokenPipeError:
        # the reader closed the pipe: not an error of ours; stop writing, also at exit
        import os

        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 141
    except Exception as exc:  # noqa: BLE001 - the one place that turns bugs into a status
        if args.debug:
            raise
        print(f"pinflex: internal error: {type(exc).__name__}: {exc} "
              "(rerun with --debug for the traceback)", file=sys.stderr)
        return 1
    finally:
        warnings.showwarning = shown


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """A warning as one line on stderr, ``pinflex: warning: Category: message``."""
    text = " ".join(str(message).split())
    print(f"pinflex: warning: {category.__name__}: {text}", file=sys.stderr)
