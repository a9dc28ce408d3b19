"""Benchmark A of paper 000 (planar two-link arm), computed once for the demo and benchmarks.

``pinflex demo``, ``benchmarks/bench_taylor.py`` and ``benchmarks/bench_assign.py`` call these
functions, so the numbers they print beside the paper's come from one definition:

* :func:`taylor_errors`: largest relative error of the p = 4 Taylor model of mode 1 along the
  152-sample trajectory (y = 0) and over y ∈ [0, 0.25]² at q0 (26 × 26 grid), for the full and
  the partially linear polynomial (paper Sec. 3.2);
* :func:`assign_mode1`: mode 1 assigned to 190 Hz along the trajectory (paper Sec. 3.3);
* :func:`grid_check`: the exact zooming grid search that checks the QP's design.
"""

from __future__ import annotations

import warnings

import numpy as np

from pinflex.assignment.brute import BruteForceResult, brute_force, exact_cost
from pinflex.assignment.driver import AssignmentResult, Target, assign_frequencies
from pinflex.cases.benchmark_a_path import BENCHMARK_A_Q0_ABS
from pinflex.erls import FlexibleModel
from pinflex.parametric import TaylorModel, expand
from pinflex.trajectory import Trajectory

#: Expansion pose q0 [rad] (absolute link angles, the model's user coordinates).
Q0 = np.array(BENCHMARK_A_Q0_ABS)
#: Target frequency of mode 1 [Hz].
TARGET_HZ = 190.0
#: Paper 000's figures: Taylor errors [%] (Sec. 3.2), design [kg] and errors [%] (Sec. 3.3).
PAPER = {
    "taylor_traj_full": 0.09, "taylor_traj_lin": 1.64,
    "taylor_y_full": 0.05, "taylor_y_lin": 1.34,
    "m1": 0.2254, "m2": 0.0, "err_before": 8.31, "err_after": 1.48,
}


def benchmark_model(**kwargs) -> FlexibleModel:
    """The planar two-link flexible arm shipped as ``two_link.urdf`` (23 dof with free joints).

    Args:
        **kwargs: Passed to :class:`~pinflex.erls.FlexibleModel` (e.g. ``joints``, ``values``).
    """
    from pinflex.description.builtin import builtin_path

    return FlexibleModel(builtin_path("two_link.urdf"), planar=True, **kwargs)


def benchmark_trajectory(model: FlexibleModel) -> Trajectory:
    """The 152-sample pick-and-place trajectory in the model's user coordinates."""
    from pinflex.assignment.study import user_trajectory

    return user_trajectory(model, "benchmark_a")


def design_grid(points: int = 26, upper_kg: float = 0.25) -> np.ndarray:
    """Designs (points², 2) [kg] on the square grid [0, upper_kg]², m2 running fastest."""
    axis = np.linspace(0.0, upper_kg, points)
    return np.array([[a, b] for a in axis for b in axis])


def taylor_errors(model: FlexibleModel, trajectory: Trajectory, tm: TaylorModel, *,
                  quantity: str = "freq_hz") -> dict[str, float]:
    """Largest relative errors [%] of mode 1 of ``tm`` against the exact model.

    Args:
        model: The benchmark arm.
        trajectory: Benchmark A's trajectory (user coordinates).
        tm: Taylor model of mode 1 at ``(Q0, y0)``.
        quantity: 'freq_hz' (compare frequencies) or 'eigval' (compare λ = ω²).

    Returns:
        ``{"taylor_traj_full", "taylor_traj_lin", "taylor_y_full", "taylor_y_lin"}`` in
        percent: along the trajectory with y = 0, and at Q0 over the 26 × 26 design grid, for
        the full polynomial and the one linear in the design (eq. 7).
    """
    Q = trajectory.q
    Yg = design_grid()
    Qg = np.tile(Q0, (len(Yg), 1))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        exact = {"traj": model.frequencies(Q, np.zeros(2), n_modes=1)[:, 0],
                 "y": model.frequencies(Qg, Yg, n_modes=1)[:, 0]}
    out = {}
    for key, QQ, YY in (("traj", Q, np.zeros(2)), ("y", Qg, Yg)):
        ref = exact[key] if quantity == "freq_hz" else (2 * np.pi * exact[key]) ** 2
        for lin in (False, True):
            approx = tm.evaluate(QQ, YY, quantity=quantity, linear_in_design=lin)[:, 0]
            out[f"taylor_{key}_{'lin' if lin else 'full'}"] = 100 * float(
                np.max(np.abs(approx / ref - 1)))
    return out


def expand_mode1(model: FlexibleModel, order: int = 4) -> TaylorModel:
    """Taylor model of mode 1 at ``(Q0, y0)`` in both joints and both point masses."""
    return expand(model, Q0, model.y0, order=order)


def assign_mode1(model: FlexibleModel, trajectory: Trajectory, **kwargs) -> AssignmentResult:
    """Mode 1 assigned to :data:`TARGET_HZ` along the trajectory, expanded at ``(Q0, y0)``.

    Args:
        model: The benchmark arm.
        trajectory: Benchmark A's trajectory.
        **kwargs: Passed to :func:`~pinflex.assignment.assign_frequencies` (defaults: order 4,
            modes 2–4 reported).
    """
    kwargs = {"q0": Q0, "y0": model.y0, "order": 4, "report_modes": (2, 3, 4), **kwargs}
    return assign_frequencies(model, trajectory, [Target(1, TARGET_HZ)], **kwargs)


def grid_check(model: FlexibleModel, trajectory: Trajectory, result: AssignmentResult, *,
               points: int = 11, zoom_levels: int = 2) -> tuple[BruteForceResult, float]:
    """Exact zooming grid search of the design box, and the exact cost of the QP's design.

    Returns:
        ``(grid search result, exact cost (10) of result.y)``.
    """
    targets = [Target(1, TARGET_HZ)]
    brute = brute_force(model, trajectory, targets, points=points, zoom_levels=zoom_levels)
    ours, _ = exact_cost(model, trajectory, targets, result.y[None])
    return brute, float(ours[0])
