"""Model no more than the scene needs: the fewest segments per link that meet a tolerance.

:func:`segments_for_tolerance` fits lumped arms with N = N₀, N₀ + 1, ... segments on every
flexible link (N₀ the fewest whose hinges carry the asked modes) and returns the first whose
*estimated error* meets the tolerance. The estimate is the fit's own worst relative error
against the ERLS model: the largest of its worst frequency error (every given pose, modes
1..k, own and locked joints) and its worst static compliance error. Those are errors on the
fitted quantities against the arm's ERLS model (the reference the lumped arm stands for),
not a bound on modes above k.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex.exceptions import ConfigurationError, LinkTooShort, TooFewSegments, TooManyModes
from pinflex.lumped.fit import LumpedFit, check_segments, default_modes, fit_lumped
from pinflex.lumped.layout import ArmLayout, layout_of


@dataclass(frozen=True)
class SegmentChoice:
    """The segment count picked for a tolerance.

    Attributes:
        n_segments: Segments per flexible link.
        estimate: Its estimated error [-].
        fit: The chosen fit.
        levels: ``(N, worst frequency error, compliance error)`` of every fit tried.
    """

    n_segments: int
    estimate: float
    fit: LumpedFit
    levels: tuple[tuple[int, float, float], ...]


def fit_error(fit: LumpedFit) -> float:
    """The error a tolerance is judged by: worst frequency or compliance error [-]."""
    return max(fit.worst_error, fit.compliance_error)


def segments_for_tolerance(arm, tol: float, *, poses=None, n_modes: int | None = None,
                           max_segments: int = 12, axial: bool = False,
                           layout: ArmLayout | None = None, **fit_options) -> SegmentChoice:
    """Fewest segments per link whose fitted lumped arm is within ``tol`` of the ERLS model.

    Args:
        arm: The :class:`~pinflex.erls.FlexibleModel`.
        tol: Relative tolerance on frequencies and compliances [-].
        poses: Arm poses (n, nv) (default: the zero pose).
        n_modes: Modes judged (default: one per bending plane of each flexible link).
        max_segments: Largest count tried.
        axial: Axial springs at every station.
        layout: The arm's layout if already read.
        **fit_options: Passed to :func:`~pinflex.lumped.fit.fit_lumped`.

    Raises:
        ConfigurationError: ``tol`` not positive.
        TooFewSegments: No count up to ``max_segments`` (or up to what the shortest link
            holds) meets ``tol``; the message gives the best reached.
    """
    if not isinstance(tol, int | float) or not np.isfinite(tol) or tol <= 0.0:
        raise ConfigurationError(f"tol = {tol!r}: give a positive relative tolerance")
    layout = layout_of(arm, axial=axial) if layout is None else layout
    k = default_modes(layout) if n_modes is None else int(n_modes)
    per_link = len(layout.axes) if not layout.planar else 1
    # fewest segments whose hinges carry k modes under locked joints (the smaller count)
    n0 = max(2, 1 + int(np.ceil(k / max(1, per_link * len(layout.beams)))))
    levels = []
    erls = None
    for n in range(n0, max_segments + 1):
        try:
            check_segments(layout, {link: n for link in layout.beams})
        except LinkTooShort:
            break
        try:
            fit = fit_lumped(arm, n, poses=poses, n_modes=k, layout=layout, erls=erls,
                             warn_above=None, **fit_options)
        except TooManyModes:
            continue
        erls = fit.erls_hz
        levels.append((n, fit.worst_error, fit.compliance_error))
        if fit_error(fit) <= tol:
            return SegmentChoice(n, fit_error(fit), fit, tuple(levels))
    best = min(levels, key=lambda row: max(row[1], row[2])) if levels else None
    reached = (f"; the best was {max(best[1], best[2]):.3g} with {best[0]} segments"
               if best else "")
    hint = "" if layout.axial or layout.planar else " or axial springs (--axial)"
    raise TooFewSegments(
        f"no lumped arm with up to {levels[-1][0] if levels else n0} segments per link meets "
        f"tol = {tol:g}{reached}: raise the tolerance, allow more segments (--max-segments)"
        f"{hint}")
