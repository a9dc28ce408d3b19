"""Packaging: every package is listed, the shipped descriptions are package data."""

import tomllib
from pathlib import Path

import pytest

from pinflex.description.builtin import builtin_dir, builtin_names, builtin_path
from pinflex.exceptions import ConfigurationError

ROOT = Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())


def test_every_package_is_listed_in_pyproject():
    """The explicit package list equals the packages in the source tree, plus pinflex.urdf."""
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "pinflex").rglob(
        "__init__.py") if "__pycache__" not in p.parts}
    listed = set(PYPROJECT["tool"]["setuptools"]["packages"])
    assert listed == found | {"pinflex.urdf"}
    assert PYPROJECT["tool"]["setuptools"]["package-dir"] == {"pinflex.urdf": "urdf"}


def test_package_data_covers_every_shipped_description():
    """Each file of urdf/ matches a package-data glob of pinflex.urdf; no stale entries."""
    globs = PYPROJECT["tool"]["setuptools"]["package-data"]["pinflex.urdf"]
    files = sorted(p.name for p in (ROOT / "urdf").iterdir() if p.is_file())
    assert files and all(any(Path(f).match(g) for g in globs) for f in files)
    assert builtin_names() == files
    assert PYPROJECT["tool"]["setuptools"]["package-data"]["pinflex"] == ["py.typed"]


def test_builtin_path_finds_files_and_names_the_available_ones():
    """builtin_path returns the checkout's file; an unknown name lists what exists."""
    assert builtin_path("two_link.urdf") == (ROOT / "urdf" / "two_link.urdf").resolve()
    assert builtin_dir() == (ROOT / "urdf").resolve()
    with pytest.raises(ConfigurationError, match="available: .*two_link.urdf"):
        builtin_path("nope.urdf")
