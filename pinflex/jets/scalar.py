"""Scalar jets with Python operators, for formulas written once for numbers and jets.

Section and material formulas (``A = π d² / 4``, ``I = π (D⁴ − d⁴) / 64``, ``ρ A``, ``E / (2 (1 +
ν))``, ...) are plain arithmetic. Written with ``+ − * / **`` they run on floats for the exact
model and, with :class:`Scalar` operands, on truncated Taylor series for the parametric model,
so the Taylor coefficients of section properties in the design parameters are exact.
"""

from __future__ import annotations

import numpy as np

from pinflex.jets.arithmetic import constant, mul, variable
from pinflex.jets.space import JetSpace


class Scalar:
    """A scalar jet ``(ncoef,)`` in a :class:`JetSpace`, with arithmetic operators.

    Mixing with Python numbers lifts the number to a constant jet.
    """

    __slots__ = ("space", "c")

    def __init__(self, space: JetSpace, coefficients: np.ndarray):
        self.space = space
        self.c = np.asarray(coefficients, dtype=float)

    @classmethod
    def variable(cls, space: JetSpace, k: int, value0: float) -> Scalar:
        """The variable ``x_k = value0 + δx_k``."""
        return cls(space, variable(space, k, float(value0)))

    @classmethod
    def constant(cls, space: JetSpace, value: float) -> Scalar:
        """A constant."""
        return cls(space, constant(space, float(value)))

    @property
    def value(self) -> float:
        """The constant coefficient (the value at the expansion point)."""
        return float(self.c[0])

    def _lift(self, other) -> Scalar:
        if isinstance(other, Scalar):
            return other
        return Scalar.constant(self.space, float(other))

    def __add__(self, other):
        return Scalar(self.space, self.c + self._lift(other).c)

    __radd__ = __add__

    def __sub__(self, other):
        return Scalar(self.space, self.c - self._lift(other).c)

    def __rsub__(self, other):
        return Scalar(self.space, self._lift(other).c - self.c)

    def __neg__(self):
        return Scalar(self.space, -self.c)

    def __mul__(self, other):
        if isinstance(other, Scalar):
            return Scalar(self.space, mul(self.space, self.c, other.c))
        return Scalar(self.space, self.c * float(other))

    __rmul__ = __mul__

    def reciprocal(self) -> Scalar:
        """``1 / f`` for ``f(x0) ≠ 0``: the geometric series of ``δ = f − f0`` to the order."""
        f0 = self.value
        if f0 == 0.0:
            raise ZeroDivisionError("reciprocal of a jet with a zero constant term")
        d = Scalar(self.space, self.c.copy())
        d.c[0] = 0.0
        u = d * (-1.0 / f0)  # f = f0 (1 − u), 1/f = (1/f0) Σ u^k
        out = Scalar.constant(self.space, 1.0)
        term = Scalar.constant(self.space, 1.0)
        for _ in range(self.space.order):
            term = term * u
            out = out + term
        return out * (1.0 / f0)

    def __truediv__(self, other):
        if isinstance(other, Scalar):
            return self * other.reciprocal()
        return Scalar(self.space, self.c / float(other))

    def __rtruediv__(self, other):
        return self.reciprocal() * float(other)

    def __pow__(self, n):
        if int(n) != n or n < 0:
            raise ValueError(f"only non-negative integer powers of jets, got {n!r}")
        out = Scalar.constant(self.space, 1.0)
        base = self
        n = int(n)
        while n:  # square and multiply
            if n & 1:
                out = out * base
            n >>= 1
            if n:
                base = base * base
        return out

    def __repr__(self) -> str:
        return f"Scalar(value={self.value:g}, order={self.space.order})"


def value_of(x) -> float:
    """The value of a number or of a :class:`Scalar` at its expansion point."""
    return x.value if isinstance(x, Scalar) else float(x)


def coefficients(space: JetSpace, x) -> np.ndarray:
    """Coefficients ``(ncoef,)`` of a number (a constant) or of a :class:`Scalar`."""
    return x.c if isinstance(x, Scalar) else constant(space, float(x))
