"""Model no more than the scene needs: the element count that meets a frequency tolerance.

:func:`elements_for_tolerance` refines every flexible link together (element counts times
1, 2, 4, ...), and estimates the discretization error of each level by Richardson
extrapolation with the *observed* order: from three consecutive levels ``f0, f1, f2``,
``p = log2(|f1 − f0| / |f2 − f1|)`` (clipped to [1, 8]; a Hermite beam converges as h⁴ in
bending, its linear axial and torsion fields as h²), and the error of ``f2`` is estimated as
``|f2 − f1| / (2^p − 1)``. The cheapest level whose estimate meets the tolerance on every
requested mode is returned with its estimate. The estimate assumes the levels are in the
asymptotic range (consecutive orders agree); where they do not, the order is clipped and the
estimate is cautious (a low p gives a large estimate). A difference cannot vanish by a change
of sign between levels: the meshes are nested and the mass consistent, so (Rayleigh–Ritz) each
sorted frequency decreases with every refinement (modes 1–6 of benchmark A, also stretched,
and the UR5 at ×1, 2, 4, 8), and ``f2 − f1`` is small only where the level has converged.

The fine meshes this needs are solved in relative coordinates (:mod:`pinflex.erls.solve`), so
rounding does not pollute the differences.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pinflex.description import RobotDescription, load
from pinflex.exceptions import ConfigurationError


@dataclass(frozen=True)
class FidelityChoice:
    """The element counts picked for a tolerance.

    Attributes:
        factor: Refinement factor over the description's element counts.
        elements: Elements per flexible link at that factor.
        freq_hz: Frequencies [Hz] of the requested modes at that level, (k,).
        estimate: Estimated relative discretization error per mode at that level, (k,).
        order: Observed convergence order per mode, (k,).
        levels: ``(factor, freq_hz, estimate)`` of every level computed.
    """

    factor: int
    elements: dict
    freq_hz: np.ndarray
    estimate: np.ndarray
    order: np.ndarray
    levels: tuple


def refined(description: RobotDescription, factor: int) -> RobotDescription:
    """The description with every flexible link's element count multiplied by ``factor``."""
    flexible = {name: dataclasses.replace(spec, elements=spec.elements * int(factor))
                for name, spec in description.flexible.items()}
    return dataclasses.replace(description, flexible=flexible)


def elements_for_tolerance(description, q, tol: float, *, n_modes: int = 3, y=None,
                           planar: bool = False, max_factor: int = 64,
                           **model_kwargs) -> FidelityChoice:
    """Cheapest uniform refinement whose estimated frequency error is at most ``tol``.

    Args:
        description: A description or the path of an annotated URDF.
        q: The pose (user coordinates).
        tol: Relative tolerance on the frequencies of the lowest ``n_modes`` modes.
        n_modes: Number of lowest non-rigid modes judged.
        y: Design values (default nominal).
        planar: Planar model.
        max_factor: Largest refinement factor tried (a power of two).
        **model_kwargs: Passed to :class:`~pinflex.erls.FlexibleModel` (``values``,
            ``joints``, ...).

    Raises:
        ConfigurationError: ``tol`` is not positive, or no level up to ``max_factor`` meets it.
    """
    from pinflex.erls import FlexibleModel

    if not np.isfinite(tol) or tol <= 0.0:
        raise ConfigurationError(f"tol = {tol!r}: give a positive relative tolerance")
    if not isinstance(description, RobotDescription):
        description = load(description)
    factors, freqs, levels = [], [], []
    factor = 1
    while factor <= max_factor:
        model = FlexibleModel(refined(description, factor), planar=planar, **model_kwargs)
        freqs.append(model.frequencies(q, y, n_modes=n_modes))
        factors.append(factor)
        if len(freqs) >= 3:
            f0, f1, f2 = freqs[-3:]
            d1, d2 = np.abs(f1 - f0), np.abs(f2 - f1)
            with np.errstate(divide="ignore", invalid="ignore"):
                p = np.log2(np.where(d2 > 0, d1 / d2, 2.0**8))
            p = np.clip(np.nan_to_num(p, nan=8.0), 1.0, 8.0)
            est = d2 / (2.0**p - 1.0) / np.abs(f2)
            levels.append((factor, f2, est))
            if np.all(est <= tol):
                elements = {n: s.elements * factor for n, s in description.flexible.items()}
                return FidelityChoice(factor, elements, f2, est, p, tuple(levels))
        factor *= 2
    raise ConfigurationError(
        f"no refinement up to {max_factor}x the description's elements meets tol = {tol:g} "
        f"(estimate at the finest level: {np.max(levels[-1][2]) if levels else np.nan:.2e})"
    )
