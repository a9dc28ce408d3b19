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
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path

from pinflex.exceptions import OutputError


def _reason(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def _target(path, what: str) -> Path:
    """``path`` as a Path whose kind can be asked (``is_dir`` raises for names too long)."""
    if not isinstance(path, str | os.PathLike):
        raise OutputError(f"{what} must be a path, got {type(path).__name__}")
    path = Path(path)
    try:
        path.exists()
    except (OSError, ValueError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else str(exc)
        raise OutputError(f"{what} '{str(path)[:80]}...' cannot be used: {reason}") from None
    return path


def output_dir(path: str | Path, what: str = "output folder") -> Path:
    """Create the folder ``path`` (and parents) if needed and check that it is a folder."""
    path = _target(path, what)
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
    path = _target(path, what)
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
    path = _target(path, what)
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
    path = _target(path, what)
    if not str(path) or str(path) == ".":
        raise OutputError(f"{what}: the file name is empty")
    if path.is_dir():
        raise OutputError(f"{what} '{path}' is a folder; give a file name")
    try:
        st = path.lstat()
    except OSError:
        st = None
    if st is not None and not (stat.S_ISREG(st.st_mode) or stat.S_ISLNK(st.st_mode)):
        # a device, pipe or socket: replacing it would destroy it (e.g. /dev/full as root)
        raise OutputError(f"{what} '{path}' is a device, pipe or socket, not a file; "
                          "give the name of a regular file")
    folder = output_dir(path.parent if str(path.parent) else Path("."), "folder")
    clean_stale(folder, path.name)
    try:
        fd, tmp_name = tempfile.mkstemp(dir=folder, prefix=f".{path.name}.{os.getpid()}-",
                                        suffix=".tmp")
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


#: A temporary file of a writer whose process id cannot be checked is stale after this [s].
STALE_AFTER_S = 3600.0


def clean_stale(folder: Path, name: str) -> list[Path]:
    """Remove the temporary files that killed writes of ``name`` left in ``folder``.

    A write goes to ``.NAME.PID-XXXX.tmp`` first; when its process was killed the file
    stays. It is removed on the next write of the same target when that process no longer
    exists (or, for a file without a readable process id, when it is older than
    :data:`STALE_AFTER_S`). Files of running writers are left alone.

    Returns:
        The files removed.
    """
    import time

    removed: list[Path] = []
    prefix = f".{name}."
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return removed
    now = time.time()
    for entry in entries:
        if not (entry.name.startswith(prefix) and entry.name.endswith(".tmp")):
            continue
        middle = entry.name[len(prefix):-len(".tmp")]
        pid_text = middle.split("-", 1)[0]
        try:
            stale = not _alive(int(pid_text)) if pid_text.isdigit() and "-" in middle else (
                now - entry.stat(follow_symlinks=False).st_mtime > STALE_AFTER_S)
        except OSError:
            continue
        if stale and entry.is_file(follow_symlinks=False):
            with contextlib.suppress(OSError):
                os.unlink(entry.path)
                removed.append(Path(entry.path))
    return removed


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except (PermissionError, OverflowError, ValueError):
        return True
    return True


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
