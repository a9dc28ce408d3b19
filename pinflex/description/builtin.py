"""Descriptions shipped with pinflex (the repository's ``urdf/`` folder, package data).

In an installed copy (``pip install .``) the files are the package data of ``pinflex.urdf``
and are found through :mod:`importlib.resources`; in a source checkout (an editable install,
or the source folder on ``PYTHONPATH``) they are read from the checkout's ``urdf/`` folder.
"""

from __future__ import annotations

import importlib.resources
from pathlib import Path

from pinflex.exceptions import ConfigurationError

_SUFFIXES = (".urdf", ".xml")


def builtin_dir() -> Path:
    """Folder holding the shipped descriptions.

    Raises:
        ConfigurationError: The installation carries no descriptions (a broken install).
    """
    checkout = Path(__file__).resolve().parents[2]
    if (checkout / "pyproject.toml").is_file() and (checkout / "urdf").is_dir():
        return checkout / "urdf"
    try:
        folder = importlib.resources.files("pinflex.urdf")
    except ModuleNotFoundError as exc:
        raise ConfigurationError(
            "this pinflex installation has no built-in descriptions (package pinflex.urdf is "
            "missing); reinstall pinflex"
        ) from exc
    # the files of an installed copy are on disk (pip unpacks wheels); a namespace package's
    # folder object lists them but is not a path itself
    shipped = [entry for entry in folder.iterdir() if entry.name.endswith(_SUFFIXES)]
    if not shipped:
        raise ConfigurationError("this pinflex installation ships no descriptions; reinstall it")
    return Path(str(shipped[0])).parent


def builtin_names() -> list[str]:
    """Names of the shipped descriptions, sorted."""
    folder = builtin_dir()
    return sorted(p.name for p in folder.iterdir() if p.suffix in _SUFFIXES)


def builtin_path(name: str) -> Path:
    """Path of a shipped description, e.g. ``builtin_path("two_link.urdf")``.

    Args:
        name: File name in the shipped ``urdf/`` folder.

    Raises:
        ConfigurationError: No such description; the message lists the available ones.
    """
    path = builtin_dir() / name
    if name not in builtin_names() or not path.is_file():
        raise ConfigurationError(
            f"no built-in description '{name}'; available: {', '.join(builtin_names())}"
        )
    return path
