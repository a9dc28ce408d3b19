"""Parametric modal model: exact Taylor expansion of eigenvalues in pose and design.

Paper 000 eq. (3)–(9). The Taylor coefficients of ``M(q, y)`` and ``K(q, y)`` come from the
same ERLS assembly as the exact model (:func:`pinflex.erls.assembly.assemble`), run in
truncated Taylor arithmetic (:mod:`pinflex.jets`) instead of on numbers: the joint
kinematics are propagated down the URDF tree as jets (a revolute joint's rotation is the
exact series of ``I + sin θ [a]× + (1 − cos θ) [a]×²``, a prismatic joint's offset is linear),
so every coefficient is exact to round-off. Design variables (point masses) enter ``M``
linearly. The eigenvalue jets follow from the recursion of :mod:`pinflex.parametric.eigen`.

What is expanded: the eigenvalue ``λ = ω²`` [rad²/s²] of paper 000 eq. (2). The frequency
polynomial ``f = √λ / 2π`` [Hz] is derived from it by exact jet arithmetic
(:func:`pinflex.jets.sqrt`) and is available with ``quantity="freq_hz"``; which of the two is
more linear in ``y`` is measured in ``benchmarks/bench_taylor.py``.

Variables are user coordinates (see :class:`~pinflex.erls.FlexibleModel`): joint values in
the model's convention, then design values [kg]. Only the joints and design variables asked
for are expanded; the others stay at their expansion values.
"""

from pinflex.parametric.algebra import JetAlgebra
from pinflex.parametric.along import SampledTaylor, TrajectoryExpansion, expand_along, sample
from pinflex.parametric.eigen import radius_estimate
from pinflex.parametric.matrices import matrix_jets, pose_jets
from pinflex.parametric.model import TaylorModel, expand

__all__ = [
    "JetAlgebra",
    "SampledTaylor",
    "TaylorModel",
    "TrajectoryExpansion",
    "expand",
    "expand_along",
    "matrix_jets",
    "pose_jets",
    "radius_estimate",
    "sample",
]
