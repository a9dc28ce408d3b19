"""Assignment QPs from several Taylor expansion points along the trajectory.

One expansion of order p describes the frequencies along a long or wide motion only as far as
its radius reaches. With a tolerance on the expansion points, the trajectory is covered by
the fewest expansions (then the lowest order) whose two-term estimate (the larger of the next
two orders' relative terms, :func:`pinflex.parametric.along.two_term_estimates`) meets it at
every sample at the expansion design ``y0`` (:func:`pinflex.parametric.expand_along` with
``criterion="estimate"``: no exact solve in the choice). The cover's exact error at ``y0``
(against the modes tracked by shape from the reference point, which each polynomial follows
through crossings) is reported beside the estimate, and a
:class:`~pinflex.exceptions.TaylorRadiusWarning` says when it misses the tolerance. Each
chosen point is then expanded again with the design variables, and every sample's QP rows come
from the model of its segment (:class:`PiecewiseTaylor`). All points share ``y0``, so the QP's
variables ``δy = y − y0`` are common to all rows.

What the points do not judge: the design direction. The QP uses the polynomial linear in the
design (eq. 9), whose error away from ``y0`` comes from that linearisation and not from the
order (benchmark A at q0 over y ∈ [0, 0.25]²: 1.30 % at p = 2, 4 and 6 alike, the full
polynomial 0.41 / 0.046 / 0.005 %, :func:`pinflex.cases.benchmark_a.taylor_errors`); one
point with the order
chosen over the design-box corners (``taylor_tol``) is the other knob, and the two are not
combined.

Mode numbers are those at each expansion point; they must name the same physical modes at all
points. The choice checks it by tracking the modes by shape (at ``y0``) from the reference
point (the expansion point nearest the trajectory's middle) along the trajectory: a mode whose
tracked sorted number at another point differs is refused with a
:class:`~pinflex.exceptions.ConfigurationError` (a crossing between the points: expand at one
point with ``--tol`` instead).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pinflex.exceptions import ConfigurationError, TaylorRadiusWarning
from pinflex.parametric import TaylorModel, expand

__all__ = ["PiecewiseTaylor", "points_for_tolerance"]


@dataclass(frozen=True)
class PiecewiseTaylor:
    """Taylor models (design included) on consecutive runs of one trajectory's samples.

    Used by the assignment wherever one :class:`~pinflex.parametric.TaylorModel` is: the
    reference point ``(q0, y0)`` numbers the modes, ``linear_parts`` gives every sample's rows
    from its own segment's model.

    Attributes:
        models: The Taylor models, one per expansion point, all at ``y0``.
        segments: Sample ranges ``(start, stop)`` (stop exclusive) of each model.
        centres: The sample each model is expanded at.
        reference: Index of the model whose point numbers the modes.
        points_choice: ``{"tol", "points", "order", "estimate", "exact_error", "candidates",
            "method"}``: the tolerance, the expansion samples, the order, the largest
            two-term estimate over the samples, the exact relative error of the cover at
            ``y0`` (against the tracked modes), ``{order: number of points}`` tried, and
            how it was chosen.
    """

    models: tuple[TaylorModel, ...]
    segments: tuple[tuple[int, int], ...]
    centres: tuple[int, ...]
    reference: int
    points_choice: dict = field(default_factory=dict)

    @property
    def _ref(self) -> TaylorModel:
        return self.models[self.reference]

    @property
    def q0(self) -> np.ndarray:
        """Joint values of the reference expansion point."""
        return self._ref.q0

    @property
    def y0(self) -> np.ndarray:
        """The common expansion design."""
        return self._ref.y0

    @property
    def design_idx(self) -> tuple[int, ...]:
        """Design variables expanded (the same in every model)."""
        return self._ref.design_idx

    @property
    def modes(self) -> tuple[int, ...]:
        """Modes expanded (the same in every model)."""
        return self._ref.modes

    @property
    def order(self) -> int:
        """The common Taylor order."""
        return self._ref.order

    @property
    def order_choice(self) -> None:
        """No single-point order choice (see ``points_choice``)."""
        return None

    @property
    def n_samples(self) -> int:
        """Number of trajectory samples covered."""
        return self.segments[-1][1]

    def linear_parts(self, Q, *, quantity: str = "eigval"):
        """``(l0, L)`` of eq. (9) at the trajectory's own samples, each from its segment.

        Args:
            Q: The joint samples (ns, nv) the points were chosen on.
            quantity: ``'eigval'`` or ``'freq_hz'``.

        Raises:
            ConfigurationError: ``Q`` does not have the covered number of samples.
        """
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        if Q.shape[0] != self.n_samples:
            raise ConfigurationError(
                f"these expansion points cover {self.n_samples} samples; got {Q.shape[0]}")
        parts = [tm.linear_parts(Q[a:b], quantity=quantity)
                 for tm, (a, b) in zip(self.models, self.segments)]
        return (np.concatenate([p[0] for p in parts]), np.concatenate([p[1] for p in parts]))


def points_for_tolerance(model, Q: np.ndarray, y0: np.ndarray, *, tol: float,
                         modes: Sequence[int], design: Sequence[str] | None = None,
                         quantity: str = "freq_hz",
                         orders: Sequence[int] = tuple(range(1, 9))) -> PiecewiseTaylor:
    """The fewest expansion points (then the lowest order) whose estimate meets ``tol``.

    Args:
        model: The flexible model.
        Q: Trajectory samples (ns, nv), user coordinates.
        y0: Expansion design (checked).
        tol: Relative tolerance on ``quantity`` (> 0).
        modes: Modes the QP uses (targets, floors, bands).
        design: Design variables to expand (default all).
        quantity: 'freq_hz' or 'eigval'.
        orders: Orders to try.

    Returns:
        A :class:`PiecewiseTaylor`.

    Raises:
        ConfigurationError: ``tol`` is not positive, or the points number a mode differently
            (a crossing between them).
    """
    import warnings

    from pinflex.erls.tracking import track_modes
    from pinflex.parametric import expand_along
    from pinflex.parametric.fidelity import TWO_TERM_RULE

    if not tol > 0:
        raise ConfigurationError(f"points tolerance {tol}: give a positive relative tolerance")
    modes = tuple(int(m) for m in modes)
    with warnings.catch_warnings():  # the cover's exact error is checked below
        warnings.simplefilter("ignore", TaylorRadiusWarning)
        cover = expand_along(model, Q, y0, tol=tol, modes=modes, orders=orders,
                             quantity=quantity, criterion="estimate")
    centres = []
    for tm in cover.models:
        d = np.linalg.norm(Q - tm.q0, axis=1)
        centres.append(int(np.argmin(d)))
    mid = Q.shape[0] // 2
    ref = min(range(len(centres)), key=lambda k: abs(centres[k] - mid))
    # the modes tracked by shape from the reference point: the numbering check, and the
    # exact values each polynomial follows (through a crossing the sorted numbers change
    # branch, the polynomial does not)
    tr = track_modes(model, Q, y0, modes=modes, reference=centres[ref])
    if len(centres) > 1:
        for k, c in enumerate(centres):
            bad = [m for m, o in zip(modes, tr.order[c]) if o != m]
            if bad:
                raise ConfigurationError(
                    f"the expansion points at samples {centres[ref]} and {c} number mode(s) "
                    f"{bad} differently (the modes cross or veer between them): expand at one "
                    "point (taylor_tol / --tol picks its order)")
    models = tuple(expand(model, Q[c], y0, order=cover.order, modes=modes, design=design)
                   for c in centres)
    exact = tr.freq_hz if quantity == "freq_hz" else tr.eigvals
    max_error = float(np.max(np.abs(cover.evaluate(Q, quantity=quantity) / exact - 1)))
    choice = {"tol": float(tol), "points": centres, "order": int(cover.order),
              "estimate": float(cover.estimate) if cover.estimate is not None else None,
              "exact_error": max_error,
              "candidates": {int(k): int(v) for k, v in cover.candidates.items()},
              "method": f"{TWO_TERM_RULE} at every sample at y0; fewest points, then "
                        "lowest order"}
    if max_error > tol:
        warnings.warn(
            f"expansion points for tol {tol:g}: the exact relative error of the cover at y0 is "
            f"{max_error:.3g} (largest two-term estimate {choice['estimate']:.3g}): "
            "the estimate was optimistic there; use a smaller tolerance",
            TaylorRadiusWarning, stacklevel=2)
    return PiecewiseTaylor(models, tuple(cover.segments), tuple(centres), ref, choice)
