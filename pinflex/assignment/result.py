"""The answer of an assignment, its exact verification and its outcome in one word.

:class:`AssignmentResult` carries the design, the exact frequencies before and after, the
Taylor model's prediction at the answer (per sample, the same array the reports write), how
far that prediction is from the exact model, and :attr:`AssignmentResult.status`:

* ``"met"``: the exact model confirms the prediction within ``confirm_tol``, every floor,
  band and the mass budget hold on the exact model, the exact target error went down and,
  with ``target_tol``, it is within it;
* ``"not_confirmed"``: the re-expansions ran out (``max_refinements``) or the trust region
  collapsed before the exact model confirmed the prediction;
* ``"floors_unmet"``: a floor, band or the mass budget is violated on the exact model;
* ``"not_improved"``: the exact target error is larger than before;
* ``"target_missed"``: the exact target error is above ``target_tol``.

The command line exits with :data:`EXIT_NOT_MET` (3) unless the status is ``"met"``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pinflex.assignment.points import PiecewiseTaylor
from pinflex.assignment.problem import AssignmentQP, QPSolution
from pinflex.parametric import TaylorModel
from pinflex.summaries import dataclass_summary

__all__ = ["EXIT_NOT_MET", "STATUSES", "AssignmentResult"]

#: Exit status of ``pinflex assign`` and ``pinflex size`` when the exact model does not meet
#: the targets, floors or constraints (0: met; 1: an input or run error; 2: usage).
EXIT_NOT_MET = 3

#: The outcomes of an assignment, best first (see the module docstring).
STATUSES = ("met", "target_missed", "not_improved", "floors_unmet", "not_confirmed")


@dataclass(frozen=True)
class AssignmentResult:
    """Answer of an assignment, with its exact verification.

    Design values are in each variable's own unit (``model.design[j].unit``: kg for masses,
    m for section dimensions, Pa for moduli, ...).

    Attributes:
        found: Whether the QP was solved.
        design: Final design values by name.
        y: Final design vector, (ny,).
        y_before: Design before assignment, (ny,).
        modes: Modes reported in the frequency arrays (targets first, then floors and bands,
            then the other reported modes).
        targets_hz: Target histories (n_targets, ns) [Hz].
        freq_before_hz: Exact frequencies before, (ns, len(modes)) [Hz].
        freq_after_hz: Exact frequencies after, (ns, len(modes)) [Hz].
        max_error_before: Largest relative target error before (exact model), fraction.
        max_error_after: Largest relative target error after (exact model), fraction.
        predicted_max_error_after: The same from :attr:`predicted_hz` (the Taylor model of
            the answer at the answer's design).
        problem: The QP the answer solves.
        solution: Its ProxQP answer.
        taylor: The Taylor model that QP was built from.
        refinements: Re-expansions made (at designs the exact model accepted).
        timings_s: Compute time of each stage [s] (wall clock).
        cpu_timings_s: The same stages in CPU time of the calling thread [s] (with
            single-thread BLAS all of the work; a loaded machine does not inflate it).
        settings: The constraints the problem was built with: ``mass_budget_kg``,
            ``floors`` ``[(mode, f_min_hz)]``, ``bands`` ``[(mode, a_hz, b_hz)]``,
            ``quantity``, ``confirm_tol``, ``target_tol`` (see
            :mod:`pinflex.assignment.report`).
        freq_before_sorted_hz: Exact frequencies before of the sorted mode numbers.
        freq_after_sorted_hz: The same after.
        max_error_before_sorted: Largest target error before on the sorted mode numbers.
        max_error_after_sorted: The same after.
        improved: Whether the tracked exact error went down (never True when it went up).
        events: Crossings, veering and ambiguous steps of the target modes along the
            trajectory, before and after (:class:`pinflex.erls.tracking.ModeEvent`).
        floors_model: Which model the floors were enforced on: ``""`` (no floors),
            ``"taylor"`` (the partially linear polynomial) or ``"taylor+exact"`` (its floor
            rows shifted by exact-minus-predicted offsets).
        floor_margin_hz: Smallest exact margin of the floors after (tracked modes) [Hz];
            negative when a floor is violated on the exact model.
        joints: The joint conditions the assignment was made under (``{joint: label}``).
        predicted_hz: The Taylor model's prediction at the answer, (ns, len(modes)) [Hz];
            NaN for modes the model does not carry.
        prediction_gap: Largest ``|predicted / exact − 1|`` over the samples and the target,
            floor and band modes.
        confirmed: Whether ``prediction_gap <= confirm_tol``.
        constraints_met: Whether floors, bands and the mass budget hold on the exact model
            (True when there are none).
        status: The outcome in one word (module docstring).
        validity: The validity indicator of eq. (1) along the trajectory at the design after
            (:class:`pinflex.erls.validity.Validity`), or None.
        iterations: One entry per QP solved: ``{"y", "gap", "cost", "violation",
            "accepted", "radius"}`` (exact cost of the targets, relative constraint
            violation, trust radius as a fraction of each variable's range).
    """

    __repr__ = dataclass_summary  # fields summarised: no array dumps

    found: bool
    design: dict[str, float]
    y: np.ndarray
    y_before: np.ndarray
    modes: tuple[int, ...]
    targets_hz: np.ndarray
    freq_before_hz: np.ndarray
    freq_after_hz: np.ndarray
    max_error_before: float
    max_error_after: float
    predicted_max_error_after: float
    problem: AssignmentQP
    solution: QPSolution
    taylor: TaylorModel | PiecewiseTaylor
    refinements: int = 0
    timings_s: dict[str, float] = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    freq_before_sorted_hz: np.ndarray | None = None
    freq_after_sorted_hz: np.ndarray | None = None
    max_error_before_sorted: float = float("nan")
    max_error_after_sorted: float = float("nan")
    improved: bool = True
    events: tuple = ()
    floors_model: str = ""
    floor_margin_hz: float | None = None
    joints: dict[str, str] = field(default_factory=dict)
    cpu_timings_s: dict[str, float] = field(default_factory=dict)
    predicted_hz: np.ndarray | None = None
    prediction_gap: float = float("nan")
    confirmed: bool = True
    constraints_met: bool = True
    status: str = "met"
    validity: Any = None
    iterations: tuple = ()

    @property
    def ok(self) -> bool:
        """Whether the exact model meets everything asked (``status == "met"``)."""
        return self.status == "met"

    def status_text(self) -> str:
        """One line saying what the status means for this answer."""
        s = self.settings or {}
        if self.status == "met":
            return (f"met: the exact model confirms the prediction within "
                    f"{100 * s.get('confirm_tol', np.nan):.3g} % (gap "
                    f"{100 * self.prediction_gap:.3g} %)")
        if self.status == "not_confirmed":
            return (f"not confirmed: the prediction is {100 * self.prediction_gap:.3g} % off "
                    f"the exact model (tolerance {100 * s.get('confirm_tol', np.nan):.3g} %) "
                    f"after {self.refinements} re-expansions")
        if self.status == "floors_unmet":
            return "floors unmet: a floor, band or the mass budget is violated on the exact model"
        if self.status == "not_improved":
            return (f"not improved: the exact target error went from "
                    f"{100 * self.max_error_before:.2f} % to {100 * self.max_error_after:.2f} %")
        return (f"target missed: the exact target error {100 * self.max_error_after:.3g} % is "
                f"above target_tol {100 * s.get('target_tol', np.nan):.3g} %")


def outcome(*, confirmed: bool, constraints_met: bool, improved: bool, error_after: float,
            target_tol: float | None) -> str:
    """The status word of an answer (the first failing check in :data:`STATUSES` order)."""
    if not confirmed:
        return "not_confirmed"
    if not constraints_met:
        return "floors_unmet"
    if not improved:
        return "not_improved"
    if target_tol is not None and error_after > target_tol:
        return "target_missed"
    return "met"
