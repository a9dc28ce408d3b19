"""Memory and time bounds checked before a computation starts.

pinflex works on dense matrices: a model of ``n`` dof needs about ``6 n^2`` doubles per pose
for its modal analysis (M, K, the reduced pair, the Cholesky factor and the eigensolver's
workspace) and ``O(n^3)`` flops; a Taylor expansion in ``v`` variables to order ``p`` holds
``C(v + p, p)`` coefficient matrices of M and K (one more set per design variable) and costs
about ``C(2 v + p, p)`` coefficient products per matrix entry. These estimates are made before
any work; a request above the memory limit raises :class:`ResourceLimitExceeded` saying how
much it would need and what to change, a long one warns a :class:`CostWarning`.

The memory limit is half of the memory available when pinflex starts the computation (from
``/proc/meminfo``; 4 GiB where that is unknown); the environment variable
``PINFLEX_MAX_MEMORY_GB`` sets it explicitly. Requests of at most :data:`ALWAYS_ALLOWED_BYTES`
are accepted without reading ``/proc/meminfo`` (a file read on every small call would cost
more than the modal analysis it guards); the variable, when set, is still read and checked.
Taylor orders above :data:`MAX_TAYLOR_ORDER`
are refused outright: the cost grows combinatorially, and an order beyond 12 buys nothing
that several expansion points (:func:`pinflex.parametric.expand_along`) do not give cheaper.
"""

from __future__ import annotations

import math
import os
import warnings

from pinflex.exceptions import ConfigurationError, CostWarning, ResourceLimitExceeded

#: Highest Taylor order accepted by :func:`pinflex.expand` and TOML studies.
MAX_TAYLOR_ORDER = 12

#: Above this estimated time [s] a computation warns before it starts.
WARN_SECONDS = 60.0

#: Requests up to this size [bytes] are never refused for the available memory (16 MiB: a
#: single-pose dense modal analysis of about 600 dof); ``PINFLEX_MAX_MEMORY_GB`` still applies.
ALWAYS_ALLOWED_BYTES = 16 * 2**20

_BYTES = 8
_DENSE_COPIES = 6
_FLOPS_PER_S = 2e9  # a conservative dense LAPACK rate on one core
_JET_S_PER_PRODUCT = 1e-7  # per coefficient product and matrix entry (benchmark A, p = 12)


def _env_limit_bytes() -> int | None:
    """``PINFLEX_MAX_MEMORY_GB`` in bytes, None when unset; checked."""
    env = os.environ.get("PINFLEX_MAX_MEMORY_GB")
    if not env:
        return None
    try:
        value = float(env)
    except ValueError:
        raise ConfigurationError(
            f"PINFLEX_MAX_MEMORY_GB={env!r} is not a number of gigabytes"
        ) from None
    if not value > 0.0 or not math.isfinite(value):
        raise ConfigurationError(f"PINFLEX_MAX_MEMORY_GB={env!r} must be positive")
    return int(value * 2**30)


def memory_limit_bytes() -> int:
    """The memory a single computation may use [bytes] (see the module docstring)."""
    env = _env_limit_bytes()
    if env is not None:
        return env
    try:
        with open("/proc/meminfo") as stream:
            for line in stream:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024 // 2
    except (OSError, ValueError, IndexError):
        pass
    return 4 * 2**30


def format_gb(nbytes: float) -> str:
    return f"{nbytes / 2**30:.3g} GiB"


def check_memory(nbytes: float, what: str, fix: str) -> None:
    """Raise :class:`ResourceLimitExceeded` if ``nbytes`` exceeds :func:`memory_limit_bytes`.

    Without ``PINFLEX_MAX_MEMORY_GB``, requests of at most :data:`ALWAYS_ALLOWED_BYTES` pass
    without reading the available memory.
    """
    env = _env_limit_bytes()
    if env is None and nbytes <= ALWAYS_ALLOWED_BYTES:
        return
    limit = env if env is not None else memory_limit_bytes()
    if nbytes > limit:
        raise ResourceLimitExceeded(
            f"{what} would need about {format_gb(nbytes)} of memory, more than the {format_gb(limit)} "
            f"allowed (half the available memory, or PINFLEX_MAX_MEMORY_GB); {fix}"
        )


def warn_time(seconds: float, what: str) -> None:
    """Warn a :class:`CostWarning` when the estimate exceeds :data:`WARN_SECONDS`."""
    if seconds > WARN_SECONDS:
        warnings.warn(f"{what} is estimated to take about {seconds:.0f} s", CostWarning,
                      stacklevel=3)


def modal_estimate(ndof: int, n_poses: int = 1) -> tuple[float, float]:
    """``(bytes, seconds)`` of a dense modal analysis of ``ndof`` dof at ``n_poses`` poses."""
    nbytes = float(n_poses) * _DENSE_COPIES * ndof * ndof * _BYTES
    seconds = float(n_poses) * 12.0 * ndof**3 / _FLOPS_PER_S
    return nbytes, seconds


def check_modal(ndof: int, n_poses: int = 1, what: str = "the modal analysis") -> None:
    """Bound a dense modal analysis before it starts (memory refused, time warned)."""
    nbytes, seconds = modal_estimate(ndof, n_poses)
    fix = ("use fewer elements per link" if n_poses == 1 else
           "use fewer elements per link or pass the poses in smaller batches")
    check_memory(nbytes, f"{what} of {ndof} dof" + (f" at {n_poses} poses" if n_poses > 1
                                                    else ""), fix)
    warn_time(seconds, f"{what} of {ndof} dof" + (f" at {n_poses} poses" if n_poses > 1
                                                 else ""))


def check_model_size(elements, nv: int, planar: bool, what: str) -> None:
    """Bound a model's assembly and modal analysis before any matrix is built.

    Args:
        elements: Element count of each flexible link.
        nv: Rigid joint count.
        planar: Whether the model keeps 3 dof per node (else 6).
        what: The model, for the message.

    The model has at most ``nv + sum k e`` dof (``k`` = 3 or 6 per node); its modal analysis
    is bounded by :func:`modal_estimate`. Each beam is first assembled densely on its
    ``6 (e + 1)`` node dof (three such matrices at once), which bounds the longest link.
    """
    k = 3 if planar else 6
    ndof = int(nv) + sum(k * int(e) for e in elements)
    line = max((6 * (int(e) + 1) for e in elements), default=0)
    nbytes = max(modal_estimate(ndof)[0], 3.0 * line * line * _BYTES)
    check_memory(nbytes, f"{what} ({ndof} dof, {max(elements, default=0)} elements on its "
                 "longest link)", "use fewer elements per link")


def taylor_estimate(nvars: int, order: int, ndof: int, ndesign: int = 0) -> tuple[float, float]:
    """``(bytes, seconds)`` of exact Taylor coefficients of M and K (see the module)."""
    ncoef = math.comb(nvars + order, order)
    nbytes = float(ncoef) * (4 + ndesign) * ndof * ndof * _BYTES
    seconds = float(math.comb(2 * nvars + order, order)) * ndof * ndof * _JET_S_PER_PRODUCT
    return nbytes, seconds


def check_order(order, what: str = "order") -> int:
    """A Taylor order as an int in ``[0, MAX_TAYLOR_ORDER]``."""
    if isinstance(order, bool) or not isinstance(order, int):
        try:
            import numpy as np

            if isinstance(order, np.integer):
                order = int(order)
            else:
                raise TypeError
        except TypeError:
            raise ConfigurationError(f"{what} must be a whole number, got {order!r}") from None
    if not 0 <= order <= MAX_TAYLOR_ORDER:
        raise ConfigurationError(
            f"{what} = {order} must be between 0 and {MAX_TAYLOR_ORDER} (pinflex's maximum: "
            "the cost grows combinatorially with the order; cover a long motion with several "
            "expansion points instead, pinflex.parametric.expand_along)"
        )
    return order


def check_taylor(nvars: int, order: int, ndof: int, ndesign: int = 0) -> None:
    """Bound a Taylor expansion before it starts (memory refused, time warned)."""
    nbytes, seconds = taylor_estimate(nvars, order, ndof, ndesign)
    what = f"a Taylor expansion of order {order} in {nvars} variables on {ndof} dof"
    check_memory(nbytes, what, "lower the order, expand fewer joints or design variables, "
                 "or use fewer elements")
    warn_time(seconds, what)


#: Most poses a single modal sweep may take (a walk between poses, a trajectory); each is a
#: dense modal analysis, so this many take minutes even on small models.
MAX_POSES = 100_000


def check_poses(n_poses: float, ndof: int, what: str, fix: str,
                maximum: int = MAX_POSES) -> int:
    """Bound a sweep of modal analyses before it starts: count, memory and time.

    Raises:
        ResourceLimitExceeded: More than ``maximum`` poses, or more memory than allowed; the
            message gives the count and the time or memory estimate.
    """
    nbytes, seconds = modal_estimate(ndof, 1)
    seconds = max(seconds, 5e-4)  # per pose with tracking, measured on small models
    if not n_poses <= maximum:
        raise ResourceLimitExceeded(
            f"{what} needs {n_poses:.4g} modal analyses of {ndof} dof (about "
            f"{n_poses * seconds:.3g} s), more than the {maximum} allowed; {fix}")
    n = int(n_poses)
    check_memory(float(n) * 2 * ndof * min(ndof, 64) * _BYTES,
                 f"{what} ({n} poses of {ndof} dof)", fix)
    warn_time(n * seconds, f"{what} ({n} modal analyses of {ndof} dof)")
    return n


def check_series(n_samples: float, width: int, what: str, fix: str) -> int:
    """Bound a time series of ``n_samples`` rows of ``width`` numbers before it is made.

    Raises:
        ResourceLimitExceeded: Its memory estimate exceeds the limit (:func:`check_memory`),
            with the sample count in the message.
    """
    if not n_samples <= 2**53:
        raise ResourceLimitExceeded(f"{what} would have {n_samples:.3g} samples; {fix}")
    check_memory(float(n_samples) * max(int(width), 1) * _BYTES,
                 f"{what} ({n_samples:.3g} samples of {width} numbers)", fix)
    return int(n_samples)
