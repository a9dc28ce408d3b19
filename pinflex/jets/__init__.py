"""Truncated multivariate Taylor ("jet") arithmetic, vectorised with NumPy.

This module carries the Taylor polynomials of paper 000, eq. (3)–(4), through exact
arithmetic, so that the coefficients of M(q, y) and K(q, y) are exact to round-off rather
than finite differences, and it splits a jet into the partially linear polynomial of
eq. (7)–(9).

Conventions:
    A *jet* of a function ``f: R^nvars -> R^shape`` at an expansion point ``x0``, truncated at
    order ``p``, is a plain ndarray of shape ``(ncoef, *shape)``. Its row ``c`` holds the
    Taylor coefficient ``∂^α f(x0) / α!`` (not the raw derivative) of the multi-index
    ``α = space.multi_indices[c]``, so that ``f(x0 + δx) ≈ Σ_c jet[c] · δx^α``.

    Coefficients are in *graded* order: every ``|α| = 0``, then every ``|α| = 1``, ...,
    then every ``|α| = p``. Within one degree the multi-indices are in *descending
    lexicographic* order, i.e. the exponent of the first variable is largest first. For two
    variables and order 2 the order is ``(0,0), (1,0), (0,1), (2,0), (1,1), (0,2)``. Because
    the order is graded, the jet of a lower order (same variables) is a prefix of the jet.

    Linear operations act coefficient by coefficient, so sums, scalings and products with a
    constant matrix are plain NumPy (``a + b``, ``2.0 * a``, ``C @ a``,
    ``a.swapaxes(-1, -2)``); only products of two jets need :func:`mul` or :func:`matmul`.
    Add a constant through :func:`constant` (``a + constant(space, 2.0)``): a bare scalar
    added to a jet would be added to every coefficient.
"""

from pinflex.jets.arithmetic import (
    constant,
    matmul,
    mul,
    sin_cos_of_variable,
    sqrt,
    variable,
)
from pinflex.jets.evaluation import (
    derivative,
    design_split,
    evaluate,
    monomials,
    partially_linear,
    partially_linear_mask,
    ray_coefficients,
    restrict,
    truncate,
)
from pinflex.jets.space import (
    JetSpace,
)

__all__ = [
    "JetSpace",
    "constant",
    "derivative",
    "design_split",
    "evaluate",
    "matmul",
    "monomials",
    "mul",
    "partially_linear",
    "partially_linear_mask",
    "ray_coefficients",
    "restrict",
    "sin_cos_of_variable",
    "sqrt",
    "truncate",
    "variable",
]
