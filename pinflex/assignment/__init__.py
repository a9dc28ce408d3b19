"""Eigenfrequency assignment along a trajectory (paper 000, Sec. 2.4), verified exactly.

Modules:

* :mod:`~pinflex.assignment.targets`: target frequency histories, trajectory checks;
* :mod:`~pinflex.assignment.problem`: the QP (eq. 10–14) built from sampled polynomials;
* :mod:`~pinflex.assignment.build`: the QP of a Taylor model sampled on a trajectory;
* :mod:`~pinflex.assignment.solve`: ProxQP with an active-set polish, and a SciPy check;
* :mod:`~pinflex.assignment.driver`: the QP confirmed on the exact model, re-expanded until
  it is (or refused);
* :mod:`~pinflex.assignment.result`: the answer and its status (exit status 3 when unmet);
* :mod:`~pinflex.assignment.verify`, :mod:`~pinflex.assignment.floors`: exact checks of
  tracked modes, floors, bands and budgets;
* :mod:`~pinflex.assignment.sizing`: least design mass under frequency floors;
* :mod:`~pinflex.assignment.brute`: exact grid search of the design box;
* :mod:`~pinflex.assignment.study`: studies described in a TOML file;
* :mod:`~pinflex.assignment.charts`: PNG charts of an assignment.
"""

from pinflex.assignment.brute import BruteForceResult, brute_force, exact_cost
from pinflex.assignment.build import build_assignment
from pinflex.assignment.driver import assign_frequencies, exact_errors
from pinflex.assignment.result import EXIT_NOT_MET, AssignmentResult
from pinflex.assignment.targets import Target, check_trajectory_limits
from pinflex.assignment.problem import AssignmentQP, QPSolution, build_assignment_qp
from pinflex.assignment.solve import solve_assignment_qp, solve_assignment_qp_scipy

__all__ = [
    "AssignmentQP",
    "AssignmentResult",
    "BruteForceResult",
    "EXIT_NOT_MET",
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
