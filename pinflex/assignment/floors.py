"""Floors, bands and the mass budget of an assignment held on the exact model.

The QP imposes floors and bands on the partially linear polynomial, which can be off by tens
of Hz away from its expansion design (benchmark A, mode 2 at y = 0: 453.3 Hz predicted,
487.5 Hz exact). Three corrections make them hold on the exact model:

* :func:`floors_on_exact`: when the polynomial declares the floors infeasible, the exact model
  checks ``y0``, the design before and the box corners (:func:`~pinflex.assignment.verify.
  exact_floor_candidates`); if none meets them the refusal stands and says so, else the floor
  rows are shifted by the exact-minus-predicted offsets at the best of them and the QP solved
  again;
* :func:`corrected_floors`: floor rows shifted so that the polynomial equals the exact
  (tracked) frequencies at a given design, where the driver re-expands or corrects;
* :func:`violation`: how far an answer's exact frequencies and design mass are from the
  floors, bands and budget, relative to each limit.
"""

from __future__ import annotations

import warnings

import numpy as np

from pinflex.assignment.verify import exact_floor_candidates, floor_margins, verify_tracked
from pinflex.exceptions import AssignmentInfeasible, AssignmentWarning

__all__ = ["FLOOR_RTOL", "corrected_floors", "floors_on_exact", "violation"]

#: Relative tolerance of floors, bands and the mass budget on the exact model: a floor
#: ``f_min`` holds when every tracked exact frequency is at least ``f_min (1 − FLOOR_RTOL)``.
FLOOR_RTOL = 1e-6


def floors_on_exact(model, Q, build, problem, taylor, y_before, exc, floors, quantity):
    """Re-solve a QP whose polynomial floors were infeasible with exact-corrected floors.

    Args:
        model: The flexible model.
        Q: Trajectory samples (ns, nv).
        build: ``build(floors, taylor) -> (problem, taylor)`` rebuilding the QP with other
            floor rows on the same Taylor model.
        problem: The refused QP.
        taylor: Its Taylor model.
        y_before: The design before.
        exc: The refusal.
        floors: The user's floors ``[(mode, f_min_hz)]``.
        quantity: The QP's quantity.

    Returns:
        ``(problem, taylor, solution)`` of the corrected QP.

    Raises:
        AssignmentInfeasible: No checked design meets the floors on the exact model either.
    """
    from pinflex.assignment.solve import solve_assignment_qp

    reference = (taylor.q0, taylor.y0)
    best = None
    for y in exact_floor_candidates(model, problem, taylor, y_before):
        m = floor_margins(model, Q, y, floors, reference)
        if best is None or m > best[1]:
            best = (y, m)
    if best is None or best[1] < 0:
        detail = ("no design meets the box and linear constraints" if best is None else
                  f"the best of the checked designs (y0, the design before and the box "
                  f"corners), y = {np.round(best[0], 6).tolist()}, misses a floor by "
                  f"{-best[1]:.4g} Hz")
        raise AssignmentInfeasible(
            f"{exc} [refused by the partially linear Taylor model and confirmed on the exact "
            f"model: {detail}]", problem, None, refused_by="exact") from None
    y_star = best[0]
    solution = None
    tol = FLOOR_RTOL * max(float(np.max(np.abs(np.asarray(f, dtype=float)))) for _, f in floors)
    for _ in range(4):
        problem, taylor = build(corrected_floors(model, Q, taylor, y_star, floors, quantity,
                                                 reference), taylor)
        solution = solve_assignment_qp(problem)
        y = taylor.y0.copy()
        y[list(taylor.design_idx)] += solution.dy
        if floor_margins(model, Q, y, floors, reference) >= -tol:
            break
        y_star = y
    warnings.warn(
        "the partially linear Taylor model declared the frequency floors infeasible, but the "
        f"exact model meets them at y = {np.round(best[0], 6).tolist()} (margin "
        f"{best[1]:.4g} Hz); the floors were corrected by the exact-minus-predicted offsets "
        "and the QP solved again (floors_model = 'taylor+exact')",
        AssignmentWarning,
        stacklevel=3,
    )
    return problem, taylor, solution


def corrected_floors(model, Q, taylor, y_star, floors, quantity, reference, exact_hz=None):
    """Floors shifted so that the polynomial equals the exact tracked model at ``y_star``.

    Args:
        model: The flexible model.
        Q: Trajectory samples (ns, nv).
        taylor: The Taylor model whose rows are shifted.
        y_star: The design where the polynomial is made exact.
        floors: ``[(mode, f_min_hz)]``.
        quantity: ``'freq_hz'`` or ``'eigval'`` (the QP's quantity).
        reference: ``(q0, y0)`` the modes are tracked from.
        exact_hz: ``{mode: (ns,) tracked exact frequencies at y_star}`` when known.

    Returns:
        ``[(mode, (ns,) shifted floors [Hz])]``.
    """
    if exact_hz is None:
        modes = tuple(sorted({int(m) for m, _ in floors}))
        tr = verify_tracked(model, Q, y_star, np.ones((1, Q.shape[0])), [modes[0]], modes,
                            reference).tracking
        exact_hz = {m: tr.freq_hz[:, k] for k, m in enumerate(modes)}
    l0, L = taylor.linear_parts(Q, quantity=quantity)
    didx = list(taylor.design_idx)
    dy = y_star[didx] - taylor.y0[didx]
    out = []
    for m, fmin in floors:
        k = taylor.modes.index(int(m))
        pred = l0[:, k] + L[:, k, :] @ dy
        exact_f = np.asarray(exact_hz[int(m)], dtype=float)
        fmin = np.broadcast_to(np.asarray(fmin, dtype=float), exact_f.shape)
        if quantity == "eigval":
            lam = (2 * np.pi * fmin) ** 2 - ((2 * np.pi * exact_f) ** 2 - pred)
            out.append((int(m), np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)))
        else:
            out.append((int(m), fmin - (exact_f - pred)))
    return out


def violation(freq_by_mode, floors, bands, mass=None, budget=None) -> float:
    """Largest relative violation of floors, bands and the budget (0 when all hold).

    Args:
        freq_by_mode: ``{mode: (ns,) exact tracked frequencies [Hz]}``.
        floors: ``[(mode, f_min_hz)]`` (constant or per sample).
        bands: ``[(mode, a_hz, b_hz)]``.
        mass: The design mass counted by the budget [kg].
        budget: The mass budget [kg], or None.

    Returns:
        ``max`` over floors of ``(f_min − f) / f_min``, over bands of the depth inside the
        band over its upper edge, and ``(mass − budget) / budget``; at least 0.
    """
    worst = 0.0
    for m, fmin in floors:
        f = freq_by_mode[int(m)]
        fm = np.broadcast_to(np.asarray(fmin, dtype=float), f.shape)
        worst = max(worst, float(np.max((fm - f) / np.abs(fm))))
    for m, a, b in bands:
        f = freq_by_mode[int(m)]
        inside = np.minimum(f - a, b - f)  # > 0 inside the band
        worst = max(worst, float(np.max(inside)) / abs(b))
    if budget is not None and mass is not None:
        worst = max(worst, (mass - float(budget)) / max(abs(float(budget)), 1e-12))
    return max(worst, 0.0)
