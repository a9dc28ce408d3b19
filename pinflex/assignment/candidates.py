"""The pieces of the assignment's confirmation loop (:mod:`pinflex.assignment.driver`).

A :class:`Candidate` is one QP answer checked on the exact model by an :class:`ExactCheck`
(tracked exact frequencies, the gap to the polynomial's prediction, the QP's cost with exact
frequencies, the floor/band/budget violation). Around them: the trust region
(:func:`trust_box`), the feasibility-restoration step when the floors are out of reach on
the polynomial (:func:`restoration`), floor rows shifted by exact-minus-predicted offsets
(:func:`hold_floors`), re-expansion at an accepted design (:func:`reexpand`) and the final
choice among the candidates (:func:`choose`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from pinflex.assignment.build import budget_mass, build_assignment, predicted_hz
from pinflex.assignment.floors import FLOOR_RTOL, corrected_floors, violation
from pinflex.assignment.points import PiecewiseTaylor
from pinflex.assignment.problem import AssignmentQP, QPSolution
from pinflex.assignment.solve import solve_assignment_qp
from pinflex.assignment.targets import target_matrix
from pinflex.assignment.verify import Verification, verify_tracked
from pinflex.erls import FlexibleModel
from pinflex.exceptions import AssignmentInfeasible
from pinflex.parametric import TaylorModel


@dataclass(frozen=True)
class Candidate:
    """One QP answer checked on the exact model."""

    y: np.ndarray
    taylor: TaylorModel | PiecewiseTaylor
    problem: AssignmentQP | None
    solution: QPSolution | None
    exact: Verification
    predicted: np.ndarray | None  # (ns, len(vmodes)) [Hz]
    gap: float
    cost: float
    viol: float
    floors_model: str = ""

    def better_than(self, other: Candidate) -> bool:
        """Feasibility first (relative violation), then the exact cost."""
        if self.viol > FLOOR_RTOL or other.viol > FLOOR_RTOL:
            return self.viol < other.viol * (1 - 1e-9)
        return self.cost < other.cost - 1e-12 * abs(other.cost)


class ExactCheck:
    """What every candidate is measured by: exact tracked frequencies, gap, cost, violation."""

    def __init__(self, model, Q, trajectory, targets, vmodes, reference, build_kwargs):
        self.model, self.Q, self.vmodes, self.reference = model, Q, list(vmodes), reference
        self.tgt = target_matrix(targets, Q.shape[0])
        self.tmodes = [t.mode for t in targets]
        self.weights = np.array([t.weight for t in targets], dtype=float)
        self.omega = trajectory.trapezoid_weights()
        self.quantity = build_kwargs.get("quantity", "freq_hz")
        self.floors = list(build_kwargs.get("floors", ()))
        self.bands = list(build_kwargs.get("bands", ()))
        self.budget = build_kwargs.get("mass_budget_kg")
        self.didx: list[int] = list(range(model.ny))
        self.checked = sorted({*self.tmodes, *(int(f[0]) for f in self.floors),
                               *(int(b[0]) for b in self.bands)})

    def verify(self, y) -> Verification:
        """Exact frequencies of design ``y`` along the samples, modes tracked by shape."""
        return verify_tracked(self.model, self.Q, y, self.tgt, self.tmodes, self.vmodes,
                              self.reference)

    def by_mode(self, v: Verification) -> dict[int, np.ndarray]:
        """The tracked frequencies [Hz] of each checked mode number."""
        return {m: v.freq_hz[:, k] for k, m in enumerate(self.vmodes)}

    def cost(self, v: Verification) -> float:
        """The QP's cost (10) with the exact tracked frequencies."""
        cols = [self.vmodes.index(m) for m in self.tmodes]
        f = v.freq_hz[:, cols].T
        if self.quantity == "eigval":
            f, t = (2 * np.pi * f) ** 2, (2 * np.pi * self.tgt) ** 2
        else:
            t = self.tgt
        return float(0.5 * np.sum(self.weights[:, None] * self.omega[None, :] * (f - t) ** 2))

    def evaluate(self, y, taylor, problem, solution, floors_model="",
                 exact: Verification | None = None) -> Candidate:
        """Design ``y`` checked on the exact model (``exact``: its verification, if known)."""
        v = self.verify(y) if exact is None else exact
        pred = None if taylor is None else predicted_hz(taylor, self.Q, y, self.vmodes,
                                                        self.quantity)
        gap = 0.0 if pred is None else self.gap(pred, v)
        mass = None
        if self.budget is not None:
            mass = budget_mass(self.model, y, self.didx)
        viol = violation(self.by_mode(v), self.floors, self.bands, mass, self.budget)
        return Candidate(np.asarray(y, dtype=float), taylor, problem, solution, v, pred, gap,
                         self.cost(v), viol, floors_model)

    def gap(self, pred: np.ndarray, v: Verification) -> float:
        """Largest ``|predicted / exact - 1|`` over the samples and checked modes."""
        cols = [self.vmodes.index(m) for m in self.checked]
        p, e = pred[:, cols], v.freq_hz[:, cols]
        ok = np.isfinite(p)
        return float(np.max(np.abs(p[ok] / e[ok] - 1.0))) if ok.any() else 0.0


def choose(seen: list[Candidate], confirm_tol: float) -> Candidate:
    """The best confirmed candidate (feasibility, then cost); else the best of all."""
    confirmed = [c for c in seen if c.gap <= confirm_tol]
    pool = confirmed or seen
    best = pool[0]
    for c in pool[1:]:
        if c.better_than(best):
            best = c
    return best


def trust_box(problem: AssignmentQP, rho: np.ndarray) -> AssignmentQP:
    """The QP with its box cut to ``|δy| <= rho``."""
    return dataclasses.replace(problem, lower=np.maximum(problem.lower, -rho),
                               upper=np.minimum(problem.upper, rho))


def restoration(problem: AssignmentQP) -> AssignmentQP | None:
    """The QP with its floor rows lowered by the least shortfall the polynomial can reach.

    When no step in the (trust) box meets the floors on the polynomial, the step that comes
    closest is wanted (a feasibility-restoration step): the linear program ``max t`` subject
    to ``floor rows − t >= l`` and the other rows finds the shortfall ``t* < 0``, and the
    floor rows are lowered by it. None when the other rows alone are infeasible.
    """
    from scipy.optimize import linprog

    groups = np.array(problem.constraint_groups)
    floor = groups == "floor"
    if not floor.any():
        return None
    ny = problem.ny
    scale = np.max(np.abs(problem.C[floor]), axis=1)
    scale = np.where(scale > 0, scale, 1.0)
    rows, rhs = [], []
    Cf, lf = problem.C[floor] / scale[:, None], problem.l[floor] / scale
    rows.append(np.hstack([-Cf, np.ones((Cf.shape[0], 1))]))  # t - C dy <= -l
    rhs.append(-lf)
    other = ~floor
    Co, lo, uo = problem.C[other], problem.l[other], problem.u[other]
    for sign, bound in ((1.0, uo), (-1.0, lo)):
        ok = np.isfinite(bound)
        if ok.any():
            rows.append(np.hstack([sign * Co[ok], np.zeros((ok.sum(), 1))]))
            rhs.append(sign * bound[ok])
    bounds = [(None if not np.isfinite(a) else a, None if not np.isfinite(b) else b)
              for a, b in zip(problem.lower, problem.upper)] + [(None, 0.0)]
    A_eq = np.hstack([problem.A, np.zeros((problem.A.shape[0], 1))]) if problem.A.size else None
    out = linprog(np.r_[np.zeros(ny), -1.0], A_ub=np.vstack(rows), b_ub=np.concatenate(rhs),
                  A_eq=A_eq, b_eq=problem.b if problem.A.size else None, bounds=bounds,
                  method="highs")
    if out.status != 0:
        return None
    shortfall = float(out.x[-1])
    lowered = problem.l.copy()
    lowered[floor] += (shortfall - 1e-9 * max(1.0, abs(shortfall))) * scale
    return dataclasses.replace(problem, l=lowered)


def reexpand(model, trajectory, targets, build_kwargs, check: ExactCheck, at: Candidate, q0,
              rebuild):
    """Expand again at an accepted design; floors shifted to the exact values there."""
    _, tm = build_assignment(model, trajectory, targets,
                             **dict(build_kwargs, y0=at.y, q0=q0, taylor=None))
    rows = list(build_kwargs.get("floors", ()))
    if rows:
        rows = corrected_floors(model, check.Q, tm, at.y, rows, check.quantity,
                                check.reference, exact_hz=check.by_mode(at.exact))
    return rebuild(rows, tm, y0=at.y, q0=q0)


def hold_floors(check: ExactCheck, cand: Candidate, rebuild, trust=None) -> Candidate:
    """Shift floor rows by the exact-minus-predicted offsets at a candidate that breaks them.

    The polynomial meets the floors but the exact model does not: the floors are shifted so
    that the same Taylor model is exact at the candidate (plus a hair of margin) and the QP
    solved again, at most six times, while the exact violation shrinks.
    """
    if not check.floors or cand.viol <= FLOOR_RTOL or cand.taylor is None:
        return cand
    best = cand
    for _ in range(6):
        rows = [(m, np.asarray(f) + 1e-6 * np.abs(np.asarray(f)))
                for m, f in corrected_floors(check.model, check.Q, cand.taylor, best.y,
                                             check.floors, check.quantity, check.reference,
                                             exact_hz=check.by_mode(best.exact))]
        problem, tm = rebuild(rows, cand.taylor)
        if trust is not None:
            problem = trust_box(problem, trust)
        try:
            solution = solve_assignment_qp(problem)
        except AssignmentInfeasible:
            break
        new = check.evaluate(design_from(check.model, tm, solution.dy), tm, problem, solution,
                             "taylor+exact")
        if not new.viol < best.viol:
            break
        best = new
        if new.viol <= FLOOR_RTOL:
            break
    return best


def design_from(model: FlexibleModel, taylor: TaylorModel | PiecewiseTaylor, dy: np.ndarray
                ) -> np.ndarray:
    """The design of a QP step ``dy`` from the expansion design, inside the bounds."""
    y = taylor.y0.copy()
    y[list(taylor.design_idx)] += dy
    lo = np.array([d.lower for d in model.design])
    hi = np.array([d.upper for d in model.design])
    return np.clip(y, lo, hi)  # the QP keeps the box to 1e-10; clip round-off only
