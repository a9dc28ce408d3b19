"""Atomic output files: every HTML, PNG, JSON and CSV that pinflex writes goes through here.

A file is written to a temporary file in the same folder and moved over the target with
``os.replace`` only once it is complete, so an interrupted or failed write never leaves a
truncated file where a good one was (the rename is atomic on POSIX and Windows within one
file system). Failures that the user can fix (the target is a folder, the folder is a file,
no permission, disk full) raise :class:`~pinflex.exceptions.OutputError` naming the path.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

from pinflex.exceptions import OutputError


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def output_dir(path: str | Path, what: str = "output folder") -> Path:
    """Create the folder ``path`` (and parents) if needed and check that it is a folder."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{what} '{path}' exists and is a file, not a folder; "
                          "choose another --out")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create {what} '{path}': {_reason(exc)}") from exc
    if not os.access(path, os.W_OK | os.X_OK):
        raise OutputError(f"{what} '{path}' is not writable")
    return path


def check_file_target(path: str | Path, what: str = "output file") -> Path:
    """Check, before any work, that a file can later be written at ``path``.

    Raises:
        OutputError: ``path`` is a folder, or its folder is a file or cannot be created.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{what} '{path}' is a folder; give a file name")
    parent = path.parent
    while not parent.exists() and parent != parent.parent:
        parent = parent.parent
    if parent.exists() and not parent.is_dir():
        raise OutputError(f"{what} '{path}': '{parent}' is a file, not a folder")
    if parent.exists() and not os.access(parent, os.W_OK | os.X_OK):
        raise OutputError(f"{what} '{path}': folder '{parent}' is not writable")
    return path


def check_dir_target(path: str | Path, what: str = "output folder") -> Path:
    """Check, before any work, that ``path`` is or can become a writable folder."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{what} '{path}' exists and is a file, not a folder; "
                          "choose another name")
    if not path.exists():
        check_file_target(path, what)
    elif not os.access(path, os.W_OK | os.X_OK):
        raise OutputError(f"{what} '{path}' is not writable")
    return path


@contextlib.contextmanager
def atomic_path(path: str | Path, what: str = "output file") -> Iterator[Path]:
    """A temporary path to write; it replaces ``path`` when the block ends without error.

    The temporary file sits in the target's folder (created if needed) and is removed if the
    block raises. The new file gets the old file's permissions, or the default ones (umask).

    Raises:
        OutputError: ``path`` is a folder, its folder cannot be created or written.
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{what} '{path}' is a folder; give a file name")
    folder = output_dir(path.parent if str(path.parent) else Path("."), "folder")
    try:
        fd, tmp_name = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.", suffix=".tmp")
    except OSError as exc:
        raise OutputError(f"cannot write {what} '{path}': {_reason(exc)}") from exc
    os.close(fd)
    tmp = Path(tmp_name)
    try:
        yield tmp
        try:
            mode = path.stat().st_mode & 0o777
        except OSError:
            umask = os.umask(0)
            os.umask(umask)
            mode = 0o666 & ~umask
        os.chmod(tmp, mode)
        os.replace(tmp, path)
    except OSError as exc:
        raise OutputError(f"cannot write {what} '{path}': {_reason(exc)}") from exc
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def write_text(path: str | Path, text: str, what: str = "output file") -> Path:
    """Write UTF-8 text atomically; returns the path."""
    with atomic_path(path, what) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_bytes(path: str | Path, data: bytes, what: str = "output file") -> Path:
    """Write bytes atomically; returns the path."""
    with atomic_path(path, what) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def save_figure(fig, path: str | Path, **kwargs) -> Path:
    """``fig.savefig`` atomically (the format follows the target's suffix); returns the path."""
    path = Path(path)
    fmt = path.suffix[1:].lower() or "png"
    with atomic_path(path, "figure") as tmp:
        fig.savefig(tmp, format=fmt, **kwargs)
    return path


def json_text(obj, what: str = "the result", **kwargs) -> str:
    """``json.dumps(obj)`` that never writes ``NaN`` or ``Infinity`` (which are not JSON).

    Raises:
        OutputError: ``obj`` holds a non-finite number; the message names where (a result
            that is not finite is a defect or a bad input, never something to print).
    """
    import json

    try:
        return json.dumps(obj, allow_nan=False, **kwargs)
    except ValueError:
        where = _non_finite(obj, "")
        raise OutputError(f"{what} holds a non-finite number at {where or 'top level'}; "
                          "refusing to write invalid JSON (check the inputs' magnitudes)"
                          ) from None


def _non_finite(obj, path: str) -> str | None:
    import math

    if isinstance(obj, float):
        return path if not math.isfinite(obj) else None
    if isinstance(obj, dict):
        for k, v in obj.items():
            hit = _non_finite(v, f"{path}.{k}" if path else str(k))
            if hit is not None:
                return hit
    elif isinstance(obj, list | tuple):
        for i, v in enumerate(obj):
            hit = _non_finite(v, f"{path}[{i}]")
            if hit is not None:
                return hit
    return None
