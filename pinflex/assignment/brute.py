"""Exact grid search of the design box: the check of the QP's answer (paper 000 Sec. 3.3).

Every design on the grid is judged with the exact ERLS model along the whole trajectory, by
the assignment's cost (10) with exact frequencies and by the largest relative target error.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pinflex.assignment.targets import Target, target_matrix
from pinflex.checks import check_q
from pinflex.erls import FlexibleModel, assembly, kinematics, modal
from pinflex.erls.assembly import add_design_masses
from pinflex.exceptions import ConfigurationError
from pinflex.summaries import dataclass_summary
from pinflex.trajectory import Trajectory


@dataclass(frozen=True)
class BruteForceResult:
    """Best designs on a grid, judged with the exact model.

    Attributes:
        y_best_cost: Design minimising the exact cost (the QP's cost, exact frequencies) [kg].
        best_cost: Its exact cost.
        y_best_max_error: Design minimising the largest relative target error [kg].
        best_max_error: That error (fraction).
        evaluations: Number of designs evaluated.
        spacing: Final grid spacing per variable [kg].
    """

    __repr__ = dataclass_summary  # fields summarised: no array dumps

    y_best_cost: np.ndarray
    best_cost: float
    y_best_max_error: np.ndarray
    best_max_error: float
    evaluations: int
    spacing: np.ndarray


def exact_cost(model: FlexibleModel, trajectory: Trajectory, targets: Sequence[Target],
               Y: np.ndarray, quantity: str = "freq_hz"):
    """Exact cost (10) and largest relative target error for designs Y (n, ny).

    ``M`` is affine in the point masses, so the matrices are assembled once per pose and only
    the eigenproblems are solved per design.

    Args:
        model: The flexible model.
        trajectory: Joint samples in the model's user coordinates (``times_s`` (ns,) [s],
            ``q`` (ns, nv) [rad or m]).
        targets: Desired frequency histories (1-based ``mode``, ``freq_hz`` [Hz], ``weight``).
        Y: Designs (n, ny) [kg] (one design (ny,) is taken as n = 1); not bound-checked.
        quantity: ``'freq_hz'`` (cost on frequency errors [Hz²·s]) or ``'eigval'`` (on
            eigenvalue errors [(rad²/s²)²·s]); the cost is trapezoidal in time.

    Returns:
        ``(costs, errors)``, each (n,): the cost (10) and the largest relative frequency error
        ``|f/f* − 1|`` over targets and samples (dimensionless).

    Raises:
        ConfigurationError: Invalid joint samples, or a target that is not positive
            frequencies.
        EigenSolverError: A design makes the eigenproblem singular or unrestrained.
    """
    Q = check_q(model, trajectory.in_order(model.joint_names))
    ns = Q.shape[0]
    w = trajectory.trapezoid_weights()
    M0, Md, K = assembly.assemble(model, kinematics.pose_terms(model, Q), _batch(ns))
    tgt = target_matrix(targets, ns)
    nmax = max(t.mode for t in targets)
    costs, errs = np.empty(len(Y)), np.empty(len(Y))
    for i, y in enumerate(np.atleast_2d(Y)):
        M = add_design_masses(M0, Md, y)
        lam = modal.eigvals_from(model, M, K)[:, :nmax]
        f = np.sqrt(lam) / (2 * np.pi)
        cost, err = 0.0, 0.0
        for t, row in zip(targets, tgt):
            fi = f[:, t.mode - 1]
            if quantity == "eigval":
                d = (2 * np.pi * fi) ** 2 - (2 * np.pi * row) ** 2
            else:
                d = fi - row
            cost += 0.5 * t.weight * float(np.sum(w * d**2))
            err = max(err, float(np.max(np.abs(fi / row - 1))))
        costs[i], errs[i] = cost, err
    return costs, errs


def _batch(n):
    from pinflex.erls import BatchAlgebra

    return BatchAlgebra(n)


def brute_force(model: FlexibleModel, trajectory: Trajectory, targets: Sequence[Target], *,
                points: int = 26, zoom_levels: int = 2, quantity: str = "freq_hz"
                ) -> BruteForceResult:
    """Search the design box on a grid with the exact model, then zoom around the best.

    Each zoom level re-grids ``points`` per variable over ±2 spacings around the current best
    (clipped to the bounds), so the final spacing is ``range / (points − 1) · (4 / (points −
    1))^zoom_levels``.

    Args:
        model: The flexible model (at most three design variables, finite upper bounds).
        trajectory: Joint samples in the model's user coordinates (``times_s`` (ns,) [s],
            ``q`` (ns, nv) [rad or m]).
        targets: Desired frequency histories (1-based ``mode``, ``freq_hz`` [Hz], ``weight``).
        points: Grid points per variable and level (``points ** ny`` designs per level).
        zoom_levels: Number of zoomed re-grids after the first grid.
        quantity: ``'freq_hz'`` or ``'eigval'``, as for :func:`exact_cost`.

    Returns:
        :class:`BruteForceResult`: the designs [kg] of least cost and of least largest error,
        their values, the number of designs evaluated and the final spacing (ny,) [kg].

    Raises:
        ConfigurationError: An infinite upper bound or more than three design variables.
    """
    lo = np.array([d.lower for d in model.design])
    hi = np.array([d.upper for d in model.design])
    if not np.all(np.isfinite(hi)):
        raise ConfigurationError("brute force needs finite upper bounds on every design variable")
    if model.ny > 3:
        raise ConfigurationError("brute force is limited to three design variables")
    best: dict[str, tuple[np.ndarray, float]] = {}
    total = 0
    a, b = lo.copy(), hi.copy()
    spacing = (b - a) / (points - 1)
    for level in range(zoom_levels + 1):
        axes = [np.linspace(a[j], b[j], points) for j in range(model.ny)]
        Y = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, model.ny)
        costs, errs = exact_cost(model, trajectory, targets, Y, quantity)
        total += len(Y)
        for key, vals in (("cost", costs), ("err", errs)):
            i = int(np.argmin(vals))
            if key not in best or vals[i] < best[key][1]:
                best[key] = (Y[i].copy(), float(vals[i]))
        spacing = (b - a) / (points - 1)
        centre = best["cost"][0]
        a = np.maximum(lo, centre - 2 * spacing)
        b = np.minimum(hi, centre + 2 * spacing)
    return BruteForceResult(best["cost"][0], best["cost"][1], best["err"][0], best["err"][1],
                            total, spacing)
