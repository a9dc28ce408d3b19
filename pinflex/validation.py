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

#: A plain decimal number: no ``nan``, ``inf``, ``0x..`` or ``1_000``.
NUMBER = re.compile(r"^[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?$")
INTEGER = re.compile(r"^[+-]?\d+$")


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


def parse_number(text: str) -> float:
    """A finite float from a plain decimal string; ``ValueError`` with the reason otherwise."""
    t = text.strip()
    if not NUMBER.match(t):
        if t.lower().lstrip("+-") in ("nan", "inf", "infinity"):
            raise ValueError(f"'{text}' is not a finite number")
        if "{" in t or "}" in t:
            raise ValueError(f"'{text}' is neither a number nor a {{parameter}} reference")
        raise ValueError(f"'{text}' is not a number")
    value = float(t)
    if not math.isfinite(value):
        raise ValueError(f"'{text}' is too large to be a finite number")
    return value


def parse_int(text: str) -> int:
    """An integer from a string of digits; ``ValueError`` with the reason otherwise."""
    t = text.strip()
    if not INTEGER.match(t):
        if NUMBER.match(t):
            raise ValueError(f"'{text}' is not a whole number")
        raise ValueError(f"'{text}' is not an integer")
    return int(t)


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
    """``value`` as a finite float array; strings, objects and NaN/inf refused."""
    import numpy as np

    if isinstance(value, (str, bytes)):  # a tuple: no union object built per call
        raise error(f"{name} must be numbers, got the string {value!r}")
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise error(f"{name} must be numbers, got {value!r}") from exc
    if not np.isfinite(out).all():
        raise error(f"{name} must be finite numbers (no NaN or inf), got {value!r}")
    return out
