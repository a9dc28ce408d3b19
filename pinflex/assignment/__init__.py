"""Eigenfrequency assignment along a trajectory (paper 000, Sec. 2.4), verified exactly.

Modules:

* :mod:`~pinflex.assignment.problem`: the QP (eq. 10–14) built from sampled polynomials;
* :mod:`~pinflex.assignment.solve`: ProxQP with an active-set polish, and a SciPy check;
* :mod:`~pinflex.assignment.driver`: expansion, QP, exact verification, refinement;
* :mod:`~pinflex.assignment.brute`: exact grid search of the design box;
* :mod:`~pinflex.assignment.study`: studies described in a TOML file;
* :mod:`~pinflex.assignment.charts`: PNG charts of an assignment.
"""

from pinflex.assignment.brute import BruteForceResult, brute_force, exact_cost
from pinflex.assignment.driver import (
    AssignmentResult,
    Target,
    assign_frequencies,
    build_assignment,
    check_trajectory_limits,
    exact_errors,
)
from pinflex.assignment.problem import AssignmentQP, QPSolution, build_assignment_qp
from pinflex.assignment.solve import solve_assignment_qp, solve_assignment_qp_scipy

__all__ = [
    "AssignmentQP",
    "AssignmentResult",
    "BruteForceResult",
    "QPSolution",
    "Target",
    "assign_frequencies",
    "brute_force",
    "build_assignment",
    "build_assignment_qp",
    "check_trajectory_limits",
    "exact_cost",
    "exact_errors",
    "solve_assignment_qp",
    "solve_assignment_qp_scipy",
]
