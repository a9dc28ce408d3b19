"""Taylor models of eigenvalues and frequencies: the entry point :func:`expand`.

The model itself is :class:`~pinflex.parametric.taylor.TaylorModel`; the expansion at one
order is :mod:`pinflex.parametric.expansion`, the order a tolerance needs
:mod:`pinflex.parametric.fidelity`, the evaluation :mod:`pinflex.parametric.evaluation`.
"""

from __future__ import annotations

from collections.abc import Sequence

from pinflex.erls import FlexibleModel
from pinflex.parametric.evaluation import RADIUS_TOL, prepare_kernel
from pinflex.parametric.expansion import expand_at_order
from pinflex.parametric.fidelity import expand_for_tolerance
from pinflex.parametric.taylor import TaylorModel

__all__ = ["RADIUS_TOL", "TaylorModel", "expand", "prepare_kernel"]


def expand(model: FlexibleModel, q0, y0=None, *, order: int = 4, modes: Sequence[int] = (1,),
           joints: Sequence[str] | None = None, design: Sequence[str] | None = None,
           tol: float | None = None, over=None) -> TaylorModel:
    """Build the Taylor model of the given non-rigid modes at ``(q0, y0)``.

    The eigenvalues ``λ_i(q, y) = ω_i²`` of ``K φ = λ M φ`` are expanded to order ``p`` in the
    listed joints and design variables, exactly (jets of M and K through the joint kinematics,
    then the eigenpair recursion of paper 000 eq. 5–6).

    Args:
        model: The flexible model.
        q0: Expansion pose, one value per moving joint (nv,), user coordinates [rad or m].
        y0: Expansion design values (ny,) [kg] or ``{name: value}`` (default: nominal).
        order: Truncation order p (>= 0).
        modes: Non-rigid mode numbers to expand, 1 = lowest (default: mode 1).
        joints: Names of the joints to expand (default: all moving joints).
        design: Names of the design variables to expand (default: all).
        tol: Pick the order instead: the lowest order up to ``order`` (at least 1, at most
            10) whose two-term estimate of the relative frequency error over ``over`` (the
            larger of the next two orders' relative terms) meets ``tol``
            (:func:`pinflex.parametric.fidelity.order_for_tolerance`); the choice and its
            estimate are in ``order_choice``.
        over: With ``tol``: the samples where the model will be used, joint values (n, nv)
            or ``(Q, Y)`` with design values (n, ny) or (ny,).

    Returns:
        A read-only :class:`TaylorModel`: jets of λ [rad²/s²] and of f [Hz], shape (ncoef, k)
        with ``k = len(modes)``, and the estimated convergence radius (nvars, k).

    Raises:
        ConfigurationError: Modes outside 1..n_elastic, unknown names, a bad order or pose.
        RepeatedEigenvalue: a requested mode is (nearly) repeated at the expansion point.
    """
    if tol is not None:
        return expand_for_tolerance(model, q0, y0, order, modes, joints, design, tol, over)
    return expand_at_order(model, q0, y0, order=order, modes=modes, joints=joints,
                           design=design)
