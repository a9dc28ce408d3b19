"""Exact verification of an assignment on the *tracked* modes, and floors checked exactly.

Mode identity. A target "mode i" is the mode numbered i (sorted, non-rigid) **at the
expansion point** ``(q0, y0)`` of the Taylor model: that is the branch the Taylor series and
the QP follow. The exact model is checked on the same branch: each verified design is
tracked by shape (:func:`pinflex.erls.tracking.track_modes`) from the expansion point, along the
design change at ``q0`` and then along the trajectory (in the conditioned solve's coordinates
where it covers the model, with shapes mapped between poses so that the MACs are the nodal
ones; else on the nodal pencil). Where a target mode crosses or veers
with another one, the sorted "mode i" of the exact model is a different physical mode on
part of the trajectory; both errors are kept (tracked and sorted) and a
:class:`~pinflex.exceptions.ModeCrossingWarning` says so.

Floors. The QP's floors hold on the partially linear polynomial, which can be off by tens of
Hz away from ``y0`` (benchmark A, mode 2 at y = 0: 453.3 Hz predicted, 487.5 Hz exact). When
the QP is infeasible with floors, the floors are checked on the exact model before refusing
(:func:`exact_floor_candidates`): at ``y0``, the design "before" and the corners of the design
box. If none meets them, the refusal stands and says the exact model confirmed it; if one
does, every floor row is corrected by the exact-minus-predicted offset at that design (the
polynomial is then exact there, so the corrected QP is feasible) and the QP is solved again,
re-correcting at its answer while the exact floors are violated (at most three times).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pinflex.erls.tracking import ModeTracking, track_modes

__all__ = ["Verification", "exact_floor_candidates", "floor_margins", "verify_tracked"]


@dataclass(frozen=True)
class Verification:
    """Exact frequencies of one design on the tracked and on the sorted modes.

    Attributes:
        tracking: The tracking (numbering at the expansion point); None when the
            frequencies were given by the caller.
        freq_hz: Tracked frequencies (ns, len(modes)) [Hz].
        sorted_hz: Sorted frequencies of the same mode numbers (ns, len(modes)) [Hz].
        max_error: Largest relative target error on the tracked modes.
        max_error_sorted: The same on the sorted modes.
    """

    tracking: ModeTracking | None
    freq_hz: np.ndarray
    sorted_hz: np.ndarray
    max_error: float
    max_error_sorted: float


def verify_tracked(model, Q: np.ndarray, y: np.ndarray, targets_hz: np.ndarray,
                   target_modes: Sequence[int], modes: Sequence[int], reference
                   ) -> Verification:
    """Track ``modes`` for design ``y`` from ``reference = (q0, y0)`` and measure the errors.

    Args:
        model: The flexible model.
        Q: Trajectory samples (ns, nv), user coordinates.
        y: Design [kg], (ny,).
        targets_hz: Target histories (n_targets, ns) [Hz].
        target_modes: Mode number of each target row.
        modes: Modes to report (targets first).
        reference: Expansion point ``(q0, y0)``.
    """
    tr = track_modes(model, Q, y, modes=tuple(modes), reference=reference)
    f = tr.freq_hz
    fs = tr.sorted_hz[:, [m - 1 for m in modes]]
    cols = [list(modes).index(m) for m in target_modes]
    err = float(np.max(np.abs(f[:, cols].T / targets_hz - 1.0)))
    err_sorted = float(np.max(np.abs(fs[:, cols].T / targets_hz - 1.0)))
    return Verification(tr, f, fs, err, err_sorted)


def floor_margins(model, Q: np.ndarray, y: np.ndarray, floors, reference) -> float:
    """Smallest exact margin ``f_tracked − floor`` [Hz] over floors and samples (< 0: violated)."""
    modes = tuple(sorted({int(m) for m, _ in floors}))
    tr = track_modes(model, Q, y, modes=modes, reference=reference)
    worst = np.inf
    for m, fmin in floors:
        fm = tr.freq_hz[:, modes.index(int(m))]
        worst = min(worst, float(np.min(fm - np.broadcast_to(fmin, fm.shape))))
    return worst


def exact_floor_candidates(model, problem, taylor, y_before: np.ndarray) -> list[np.ndarray]:
    """Designs to check floors at: ``y0``, the design before, the box corners (≤ 6 variables).

    Only designs that meet the box and the user's linear rows (which are exact) are kept.
    """
    didx = list(taylor.design_idx)
    y0 = taylor.y0
    cands = [y0.copy(), np.asarray(y_before, dtype=float).copy()]
    lo, hi = problem.lower, problem.upper
    if len(didx) <= 6 and np.all(np.isfinite(lo)) and np.all(np.isfinite(hi)):
        for corner in itertools.product(*zip(lo, hi)):
            y = y0.copy()
            y[didx] += np.asarray(corner)
            cands.append(y)
    rows = np.array([g == "inequality" for g in problem.constraint_groups], dtype=bool)
    keep: list[np.ndarray] = []
    for y in cands:
        dy = y[didx] - y0[didx]
        if np.any(dy < lo - 1e-12) or np.any(dy > hi + 1e-12):
            continue
        if rows.any():
            Cy = problem.C[rows] @ dy
            if np.any(Cy < problem.l[rows] - 1e-12) or np.any(Cy > problem.u[rows] + 1e-12):
                continue
        if not any(np.array_equal(y, k) for k in keep):
            keep.append(y)
    return keep
