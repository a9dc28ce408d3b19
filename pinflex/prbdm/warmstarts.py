"""Explicit warm starts of the chain's tip statics, kept by a search and passed to evaluations.

A :class:`WarmStarts` holds each load's last converged joint angles and, once a Jacobian was
formed, the first-order prediction of the next design's angles. It never changes an answer
beyond the Newton tolerance: every answer passes the same convergence and branch checks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class WarmStarts:
    """Last converged joint angles per load index, passed explicitly to evaluations.

    ``angles`` are the last answers. When a Jacobian was formed, its design ``base_x``, the
    angles there and their implicit-function derivatives ``slopes`` by the design are kept,
    and the next start is the first-order prediction ``base + slopes (x_new - base_x)``.
    """

    angles: dict[int, np.ndarray] = field(default_factory=dict)
    base: dict[int, np.ndarray] = field(default_factory=dict)
    slopes: dict[int, np.ndarray] = field(default_factory=dict)
    base_x: np.ndarray | None = None
    # (loads, base angles, slopes) of the base stacked for one prediction of every load.
    _stacked: tuple[np.ndarray, np.ndarray, np.ndarray] | None = field(
        default=None, repr=False, compare=False)

    def clear(self) -> None:
        """Forget every stored start."""
        self.angles.clear()
        self.base.clear()
        self.slopes.clear()
        self.base_x = None
        self._stacked = None

    def set_base(self, x: np.ndarray, angles: dict[int, np.ndarray],
                 slopes: dict[int, np.ndarray]) -> None:
        """Keep the angles at design x and their derivatives (n, n_params) per load."""
        self.base_x = np.array(x, dtype=float)
        self.base = {k: np.array(v) for k, v in angles.items()}
        self.slopes = slopes
        keys = np.array(sorted(k for k in slopes if k in self.base), dtype=int)
        self._stacked = (keys, np.array([self.base[k] for k in keys]),
                         np.array([slopes[k] for k in keys])) if keys.size else None

    def start(self, index: int, x: np.ndarray) -> np.ndarray:
        """Start angles of load ``index`` for design x (requires ``index in angles``)."""
        slope = self.slopes.get(index)
        if slope is None or self.base_x is None or self.base_x.shape != x.shape:
            return self.angles[index]
        step = slope @ (x - self.base_x)
        # A long extrapolation is no better than the last answer: keep predictions small.
        return self.base[index] + step if np.max(np.abs(step)) < 0.2 else self.angles[index]

    def starts(self, x: np.ndarray, n_loads: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`start` of loads 0..n_loads-1 at once: angles (n_loads, n) and which exist."""
        theta0 = np.zeros((n_loads, n))
        have = np.zeros(n_loads, dtype=bool)
        for index, angles in self.angles.items():
            if index < n_loads:
                theta0[index], have[index] = angles, True
        stacked = self._stacked
        if stacked is None or self.base_x is None or self.base_x.shape != x.shape:
            return theta0, have
        keys, base, slopes = stacked
        step = slopes @ (x - self.base_x)
        use = (np.abs(step).max(axis=1) < 0.2) & (keys < n_loads)
        theta0[keys[use]] = base[use] + step[use]
        return theta0, have
