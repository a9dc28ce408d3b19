"""The eigenfrequency-assignment QP of paper 000 (Belotti et al. 2021, Sec. 2.4, eq. 10–14).

With the partially linearised model of eq. (9), mode ``i`` at sample ``k`` is predicted as
``l_{i,0}(q_k) + Σ_j l_{i,j}(q_k) δy_j``. The cost (10), summed over modes with weights
``w_i`` and integrated by a quadrature rule with weights ``ω_k`` (the trapezoidal rule on the
trajectory grid, as in the paper's Sec. 3.3), is

.. math::

    f(δy) = ½ Σ_i w_i Σ_k ω_k (l_{i,0,k} + L_{i,k} δy − λ_{i,d,k})²
          = ½ δyᵀ R δy + hᵀ δy + c,

with :math:`R = Σ_i w_i L_iᵀ Ω L_i` (eq. 13), :math:`h = Σ_i w_i L_iᵀ Ω (l_{i,0} − λ_{i,d})`
(eq. 14) and :math:`c = ½ Σ_i w_i (l_{i,0} − λ_{i,d})ᵀ Ω (l_{i,0} − λ_{i,d})`, so that
:meth:`AssignmentQP.cost` is the cost itself, not just up to a constant.

Units: this module is agnostic. It minimises the squared mismatch of whatever quantity the
``l`` arrays and the targets represent — eigenvalues ``λ = ω²`` [rad²/s²] or frequencies
[Hz] — as long as ``l0``, ``L``, ``targets``, ``floors`` and ``bands`` use the same one. The
cost then has units [quantity² · s] and ``δy`` the units of the design variables.

This module builds and solves the QP only; evaluating the modal model and verifying the
answer with the exact model belongs to the assignment driver.
"""

from pinflex.assignment_qp.problem import AssignmentQP, QPSolution, build_assignment_qp
from pinflex.assignment_qp.solve import solve_assignment_qp, solve_assignment_qp_scipy

__all__ = [
    "AssignmentQP",
    "QPSolution",
    "build_assignment_qp",
    "solve_assignment_qp",
    "solve_assignment_qp_scipy",
]
