"""Shared helpers of the input checks: problems, closest-name suggestions, strict numbers.

Readers of user input (the URDF schema in :mod:`pinflex.description.schema`, the TOML studies)
collect every :class:`Problem` of a file and raise one error listing them all
(:func:`raise_problems`); public functions check their arguments with the ``require_*``
helpers. Nothing here knows about robots.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Iterable
from dataclasses import dataclass

from pinflex.exceptions import (
    ConfigurationError,
    PinflexError,
    PinflexWarning,
    SchemaError,
    StudyError,
)

#: The one number grammar of pinflex (URDF attributes, TOML floats, CSV cells, command-line
#: values, strings given to the Python API): a plain decimal number written with the ASCII
#: digits 0-9, an optional sign, point and exponent. No ``nan``, ``inf``, ``0x..``, ``1_000``,
#: Unicode or full-width digits; surrounding whitespace may only be ASCII spaces, tabs and line
#: breaks (a no-break space is refused). Python's ``float()`` accepts all of these, and a C++
#: reader such as Pinocchio's URDF parser reads some of them differently (``"٠.٨٥٥"`` is 0.855
#: to ``float()`` and 0 to Pinocchio), so every number pinflex reads from text goes through
#: :func:`parse_number` or :func:`parse_int`.
NUMBER = re.compile(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)([eE][+-]?[0-9]+)?", re.ASCII)
INTEGER = re.compile(r"[+-]?[0-9]+", re.ASCII)
#: The whitespace allowed around a number (ASCII only).
ASCII_SPACE = " \t\r\n"


def _strip(text: str) -> str:
    return text.strip(ASCII_SPACE)


def number_problem(text) -> str | None:
    """Why ``text`` is not a number of the grammar (:data:`NUMBER`), or None if it is one."""
    if not isinstance(text, str):
        return f"{text!r} is not text"
    t = _strip(text)
    if NUMBER.fullmatch(t):
        return None
    return _why_not(text, t)


def _why_not(text: str, t: str) -> str:
    import unicodedata

    for ch in t if t else text:
        if ord(ch) > 127:
            try:
                label = unicodedata.name(ch)
            except ValueError:
                label = "unnamed"
            kind = ("a digit outside ASCII" if ch.isdigit() or ch.isnumeric() else
                    "whitespace outside ASCII" if ch.isspace() else "a non-ASCII character")
            return (f"'{text}' contains {kind} (U+{ord(ch):04X} {label}); numbers are written "
                    "with the ASCII digits 0-9")
    if not t:
        return "an empty value is not a number"
    low = t.lower().lstrip("+-")
    if low in ("nan", "inf", "infinity"):
        return f"'{text}' is not a finite number"
    if "_" in t and NUMBER.fullmatch(t.replace("_", "")):
        return f"'{text}': digit separators '_' are not allowed; write {t.replace('_', '')}"
    if "{" in t or "}" in t:
        return f"'{text}' is neither a number nor a {{parameter}} reference"
    return f"'{text}' is not a number"


def parse_number(text: str) -> float:
    """A finite float from a plain decimal string (:data:`NUMBER`); ``ValueError`` otherwise.

    The message says why (a non-ASCII digit or space, a digit separator, NaN or inf, a value
    too large for a double).
    """
    problem = number_problem(text)
    if problem is not None:
        raise ValueError(problem)
    value = float(_strip(text))
    if not math.isfinite(value):
        raise ValueError(f"'{text}' is too large to be a finite number")
    return value


def parse_int(text: str) -> int:
    """An integer from a string of ASCII digits; ``ValueError`` with the reason otherwise."""
    if not isinstance(text, str):
        raise ValueError(f"{text!r} is not text")
    t = _strip(text)
    if INTEGER.fullmatch(t):
        if len(t) > 18:
            raise ValueError(f"'{text}' is too large a whole number")
        return int(t)
    if NUMBER.fullmatch(t):
        raise ValueError(f"'{text}' is not a whole number")
    problem = _why_not(text, t)
    raise ValueError(problem.replace("is not a number", "is not an integer"))


def closest(name: str, valid: Iterable[str]) -> str | None:
    """The valid name closest to ``name`` (``difflib``), or ``None`` if none is close."""
    import difflib  # only on the error path: keeps start-up light

    valid = list(valid)
    hits = difflib.get_close_matches(name, valid, n=1, cutoff=0.6)
    if not hits:  # case slips ("e" for "E") and prefixes ("low" for "lower")
        low = {v.lower(): v for v in valid}
        if name.lower() in low:
            return low[name.lower()]
        pre = [v for v in valid if len(name) >= 2 and (v.startswith(name) or name.startswith(v))]
        return pre[0] if len(pre) == 1 else None
    return hits[0]


def suggestion(name: str, valid: Iterable[str], quote: str = "'") -> str:
    """``"did you mean 'x'?"`` or the list of valid names when none is close."""
    valid = sorted(set(valid))
    hit = closest(name, valid)
    if hit is not None:
        return f"did you mean {quote}{hit}{quote}?"
    return "valid: " + (", ".join(valid) if valid else "(none)")


@dataclass(frozen=True)
class Problem:
    """One problem found in an input file.

    Attributes:
        where: Location, e.g. ``"line 12, <pinflex:section>, attribute 'A'"``.
        message: What is wrong and what to do.
        error: The :class:`PinflexError` subclass that reports it.
        warning: A :class:`PinflexWarning` subclass instead when it is only a warning.
    """

    where: str
    message: str
    error: type[PinflexError] = ConfigurationError
    warning: type[PinflexWarning] | None = None

    def __str__(self) -> str:
        return f"{self.where}: {self.message}" if self.where else self.message


def raise_problems(source: str, problems: list[Problem], what: str = "") -> None:
    """Raise one error listing every error-level problem; warn the warnings if there is none.

    The error's class is that of the first problem; the message is one line and
    ``exc.problems`` holds the list.
    """
    errors = [p for p in problems if p.warning is None]
    if not errors:
        for p in problems:
            warnings.warn(f"{source}: {p}", p.warning, stacklevel=3)
        return
    head = f"{source}: " if source else ""
    if len(errors) == 1:
        message = f"{head}{errors[0]}"
    else:
        message = f"{head}{len(errors)} problems{what}: " + "; ".join(str(p) for p in errors)
    cls = errors[0].error
    if issubclass(cls, SchemaError | StudyError):
        raise cls(message, errors)
    exc = cls(message)
    exc.problems = errors  # type: ignore[attr-defined]
    raise exc


def require_count(value, name: str, *, minimum: int = 1, maximum: int | None = None,
                  error: type[PinflexError] = ConfigurationError) -> int:
    """``value`` as an int in ``[minimum, maximum]``; booleans, floats and strings refused."""
    import numpy as np

    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise error(f"{name} must be an integer >= {minimum}, got {value!r}")
    value = int(value)
    if value < minimum or (maximum is not None and value > maximum):
        rng = f">= {minimum}" if maximum is None else f"between {minimum} and {maximum}"
        raise error(f"{name} must be {rng}, got {value}")
    return value


def require_array(value, name: str, *, error: type[PinflexError] = ConfigurationError):
    """``value`` as a finite float array.

    Refused by name: strings (also inside lists: ``[1, 'a']``), booleans and boolean arrays,
    complex numbers (their imaginary part would be dropped), masked arrays (the mask would be
    dropped), objects that are not real numbers, NaN and inf.
    """
    import numpy as np

    if type(value) is np.ndarray and value.dtype == np.float64:  # the common, fast case
        out = value
    else:
        out = float_array(value, name, error)
    if not np.isfinite(out).all():
        raise error(f"{name} must be finite numbers (no NaN or inf), got {_short(value)}")
    return out


def _short(value) -> str:
    text = repr(value)
    return text if len(text) <= 80 else text[:77] + "..."


def float_array(value, name: str, error: type[PinflexError] = ConfigurationError):
    """``value`` as a float array (not checked for finiteness); see :func:`require_array`."""
    import numpy as np

    if isinstance(value, (str, bytes)):
        raise error(f"{name} must be numbers, got the string {_short(value)}")
    if isinstance(value, bool | np.bool_):
        raise error(f"{name} must be numbers, got the boolean {value!r}")
    if isinstance(value, np.ma.MaskedArray):
        raise error(f"{name} must be a plain array, got a masked array (its mask would be "
                    "ignored); fill or drop the masked entries first")
    if isinstance(value, list | tuple) and _has_bool(value):
        raise error(f"{name} must be numbers, got a boolean in {_short(value)}")
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError) as exc:
        raise error(f"{name} must be numbers, got {_short(value)}") from exc
    kind = raw.dtype.kind
    if kind == "O":
        flat = raw.ravel()
        for v in flat:
            if isinstance(v, bool | np.bool_) or not isinstance(
                    v, int | float | np.integer | np.floating):
                what = ("the boolean" if isinstance(v, bool | np.bool_) else
                        "the string" if isinstance(v, str | bytes) else
                        "the complex number" if isinstance(v, complex | np.complexfloating)
                        else "")
                raise error(f"{name} must be real numbers, got {what + ' ' if what else ''}"
                            f"{_short(v)} in {_short(value)}")
        try:
            return np.asarray(raw.tolist(), dtype=float)
        except (TypeError, ValueError, OverflowError) as exc:
            raise error(f"{name} must be numbers of one shape, got {_short(value)}") from exc
    if kind in "US":
        raise error(f"{name} must be numbers, got strings {_short(value)}")
    if kind == "b":
        raise error(f"{name} must be numbers, got booleans {_short(value)}")
    if kind == "c":
        raise error(f"{name} must be real numbers, got complex values {_short(value)}")
    if kind not in "iuf":
        raise error(f"{name} must be numbers, got {raw.dtype} values {_short(value)}")
    try:
        return raw.astype(float, copy=False)
    except OverflowError as exc:  # pragma: no cover - ints beyond float range
        raise error(f"{name} has values too large for a double: {_short(value)}") from exc


def _has_bool(seq) -> bool:
    """Whether a (nested) list or tuple holds a boolean (NumPy would read it as 0 or 1)."""
    import numpy as np

    for v in seq:
        if isinstance(v, bool | np.bool_):
            return True
        if isinstance(v, list | tuple) and _has_bool(v):
            return True
    return False


def require_number(value, name: str, *, error: type[PinflexError] = ConfigurationError,
                   gt: float | None = None, ge: float | None = None, le: float | None = None,
                   lt: float | None = None, unit: str = "") -> float:
    """One finite real number (int or float, not a bool, string or array) within bounds."""
    import numpy as np

    if isinstance(value, bool | np.bool_) or not isinstance(
            value, int | float | np.integer | np.floating):
        raise error(f"{name} must be a number{f' [{unit}]' if unit else ''}, got "
                    f"{_short(value)}")
    out = float(value)
    if not math.isfinite(out):
        raise error(f"{name} must be a finite number, got {out!r}")
    u = f" {unit}" if unit else ""
    if gt is not None and not out > gt:
        raise error(f"{name} = {out:g}{u} must be above {gt:g}{u}")
    if ge is not None and not out >= ge:
        raise error(f"{name} = {out:g}{u} must be at least {ge:g}{u}")
    if lt is not None and not out < lt:
        raise error(f"{name} = {out:g}{u} must be below {lt:g}{u}")
    if le is not None and not out <= le:
        raise error(f"{name} = {out:g}{u} must be at most {le:g}{u}")
    return out


def require_bool(value, name: str, *, error: type[PinflexError] = ConfigurationError) -> bool:
    """``value`` as a bool: only ``True``/``False`` (and NumPy's), not ``"no"`` or 1."""
    import numpy as np

    if not isinstance(value, bool | np.bool_):
        raise error(f"{name} must be True or False, got {_short(value)}")
    return bool(value)


def load_toml(text: str, source: str, error: type[PinflexError] = ConfigurationError) -> dict:
    """TOML data of ``text``, its numbers held to pinflex's number grammar.

    TOML itself allows digit separators (``1_000``) and hexadecimal, octal and binary
    integers (``0x10``); pinflex's grammar does not (the same number must read the same in a
    URDF attribute, a CSV cell, a TOML study and on the command line), so they are refused
    with their line. NaN and inf pass here and are refused by the schema, which names the key.

    Raises:
        error: Not valid TOML, or a number outside the grammar.
    """
    import tomllib

    for line, token in _toml_number_tokens(text):
        if "_" in token:
            why = f"digit separators '_' are not allowed; write {token.replace('_', '')}"
        else:
            why = "hexadecimal, octal and binary numbers are not allowed; write it in decimal"
        raise error(f"{source}: line {line}: {token!r}: {why}")
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:  # tomllib parses nested arrays and inline tables recursively
        raise error(f"{source}: arrays or inline tables nested too deeply to be a study "
                    "file") from None


_TOML_TOKEN = re.compile(r"[+-]?[0-9][0-9A-Za-z_.:+\-]*", re.ASCII)


def _toml_number_tokens(text: str):
    """``(line, token)`` of number-like tokens outside strings and comments using ``_``,
    ``0x``, ``0o`` or ``0b``."""
    i, n, line = 0, len(text), 1
    bare: list[tuple[int, str]] = []
    start = 0
    while i < n:
        c = text[i]
        if c in "\"'":
            bare.append((line, text[start:i]))
            triple = text.startswith(c * 3, i)
            end_mark = c * 3 if triple else c
            j = i + len(end_mark)
            while j < n:
                if c == '"' and text[j] == "\\":
                    j += 2
                    continue
                if text.startswith(end_mark, j):
                    break
                if text[j] == "\n" and not triple:
                    break
                j += 1
            line += text.count("\n", i, j)
            i = start = j + len(end_mark)
            continue
        if c == "#":
            bare.append((line, text[start:i]))
            j = text.find("\n", i)
            i = start = n if j < 0 else j
            continue
        if c == "\n":
            bare.append((line, text[start:i]))
            line += 1
            start = i + 1
        i += 1
    bare.append((line, text[start:]))
    for ln, chunk in bare:
        for m in _TOML_TOKEN.finditer(chunk):
            tok = m.group()
            if m.start() > 0 and (chunk[m.start() - 1].isalnum() or chunk[m.start() - 1] in "_-"):
                continue  # the tail of a bare key such as m1_2
            body = tok.lstrip("+-")
            if "_" in tok or body[:2].lower() in ("0x", "0o", "0b"):
                yield ln, tok
