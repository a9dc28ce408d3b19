r"""Pareto front of the frequency and deflection losses by the epsilon-constraint method.

A weighted sum :math:`w e_{eig}^2 + (1-w) e_{defl}^2` only reaches the convex hull of the
front. The epsilon-constraint method reaches every Pareto-optimal point: for a ladder of
bounds :math:`\varepsilon_k` on the deflection loss it solves

.. math:: \min_x e_{eig}(x)^2 \quad\text{s.t.}\quad e_{defl}(x)^2 \le \varepsilon_k^2,\
          \textstyle\sum\gamma = 1,\ \text{bounds of eq. (15c-d)},

with SLSQP and the exact gradients of :mod:`pinflex.prbdm.sensitivity`, each solve started
from the best feasible design found so far. The front's quality is measured by its
hypervolume (the area it dominates up to a reference point), computed exactly in 2D.
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize

from .massmatrix import ChainWorkspace
from .problem import Evaluation, MappingProblem, design_bounds
from .sensitivity import evaluate_with_jacobian
from .warmstarts import WarmStarts


def hypervolume_2d(points: np.ndarray, reference: tuple[float, float]) -> float:
    """Area dominated by a set of 2D points (both objectives minimised) up to ``reference``."""
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    ref = np.asarray(reference, dtype=float)
    pts = pts[np.all(pts < ref, axis=1)]
    if pts.size == 0:
        return 0.0
    pts = pts[np.argsort(pts[:, 0])]
    area, best_y = 0.0, ref[1]
    for x, y in pts:
        if y < best_y:
            area += (ref[0] - x) * (best_y - y)
            best_y = y
    return float(area)


def nondominated(points: np.ndarray) -> np.ndarray:
    """Mask of the non-dominated rows of an (k, 2) array (both minimised)."""
    pts = np.asarray(points, dtype=float)
    keep = np.ones(len(pts), dtype=bool)
    for i, p in enumerate(pts):
        dominated = np.all(pts <= p, axis=1) & np.any(pts < p, axis=1)
        keep[i] = not np.any(dominated)
    return keep


def epsilon_constraint_front(problem: MappingProblem, starts: list[np.ndarray],
                             bounds_eps: np.ndarray, max_iter: int = 150
                             ) -> list[tuple[np.ndarray, Evaluation]]:
    """Minimise the frequency loss under each deflection bound in ``bounds_eps``.

    Args:
        problem: The mapping problem (its own loss definitions are used).
        starts: Candidate start designs (e.g. the weighted-sum front); for each bound the
            feasible candidate with the lowest frequency loss is the start.
        bounds_eps: Deflection-loss bounds, any order.
        max_iter: SLSQP iterations per bound.

    Returns:
        (design, evaluation) per bound that SLSQP solved feasibly.
    """
    workspace = ChainWorkspace(problem.planform, problem.n_joints)
    warm = WarmStarts()
    n1 = problem.n_joints + 1
    n_eig = problem.poses.shape[0] * problem.n_modes
    lower, upper = design_bounds(problem)
    cache: dict = {}

    def parts(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            je = evaluate_with_jacobian(problem, x, workspace, warm, pinocchio=False)
            r, jac = je.evaluation.residuals, je.jacobian
            cache[key] = (r[:n_eig], jac[:n_eig], r[n_eig:], jac[n_eig:], je.evaluation)
        return cache[key]

    def f(x):
        re, je_, _, _, _ = parts(x)
        return float(re @ re), 2.0 * je_.T @ re

    candidates = [np.array(s, dtype=float) for s in starts]
    evaluations = [evaluate_with_jacobian(problem, c, workspace, pinocchio=False,
                                          want_jacobian=False).evaluation for c in candidates]
    found: list[tuple[np.ndarray, Evaluation]] = []
    for eps in sorted(np.asarray(bounds_eps, dtype=float), reverse=True):
        feasible = [(ev.eigen_error, c) for c, ev in zip(candidates, evaluations)
                    if ev.deflection_error <= eps]
        pool = feasible or [(ev.deflection_error, c) for c, ev in zip(candidates, evaluations)]
        x0 = min(pool, key=lambda p: p[0])[1].copy()
        x0[:n1] /= x0[:n1].sum()
        cons = [
            {"type": "ineq", "fun": lambda x, e=eps: e**2 - float(parts(x)[2] @ parts(x)[2]),
             "jac": lambda x: -2.0 * parts(x)[3].T @ parts(x)[2]},
            {"type": "eq", "fun": lambda x: np.sum(x[:n1]) - 1.0,
             "jac": lambda x: np.concatenate([np.ones(n1), np.zeros(x.size - n1)])},
        ]
        warm.clear()
        res = minimize(f, np.clip(x0, lower, upper), jac=True, method="SLSQP",
                       bounds=list(zip(lower, upper)), constraints=cons,
                       options={"maxiter": max_iter, "ftol": 1e-14})
        x = np.clip(np.asarray(res.x, dtype=float), lower, upper)
        x[:n1] /= x[:n1].sum()
        ev = evaluate_with_jacobian(problem, x, ChainWorkspace(problem.planform,
                                                               problem.n_joints),
                                    want_jacobian=False).evaluation
        if ev.failed_loads == 0 and ev.deflection_error <= eps * (1.0 + 1e-6):
            found.append((x, ev))
            candidates.append(x)
            evaluations.append(ev)
    return found
