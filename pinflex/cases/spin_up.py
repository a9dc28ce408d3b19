"""Kane, Ryan and Banerjee's spin-up beam: the fast-arm case of the validity indicator.

A uniform beam (L = 10 m, EI = 1.4e4 N m², ρA = 1.2 kg/m, EA = 1.4e7 N) clamped to a hub that
spins up as ``θ(t) = (Ωs/Ts)[t²/2 + (Ts/2π)²(cos 2πt/Ts − 1)]`` over ``Ts = 15 s`` and then turns
at ``Ωs``. Eq. (1) and ``terms="full"`` differ on it as the speed grows
(``benchmarks/bench_spin_up.py``, ``docs/speed.md``).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

from pinflex.dynamics.motion import JointMotion

#: The beam on a hub joint (planar model: in-plane bending and stretching).
KANE_URDF = """<?xml version="1.0"?>
<robot name="kane" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="beam"/>
  <joint name="hub" type="revolute"><parent link="base"/><child link="beam"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1e4" upper="1e4" effort="1" velocity="100"/></joint>
  <pinflex:flexible link="beam" elements="10" normal="0 0 1" tip="10 0 0">
    <pinflex:material E="7e10" linear_density="1.2"/>
    <pinflex:section A="2e-4" Iy="2e-7" Iz="2e-7" J="4e-7"/>
  </pinflex:flexible>
</robot>
"""

#: Spin-up time Ts [s].
SPIN_UP_S = 15.0

#: First clamped-free bending frequency of the beam [rad/s] (1.8751² √(EI / ρA L⁴)).
OMEGA1_RAD_S = 1.875104068711961**2 * math.sqrt(1.4e4 / (1.2 * 10.0**4))


class SpinUp(JointMotion):
    """The hub motion θ(t) with exact rates (a :class:`JointMotion` without a spline).

    Args:
        omega_s: Final hub speed Ωs [rad/s].
        knots_s: Spacing of the samples in ``trajectory`` [s] (the drive's grid).
    """

    def __init__(self, omega_s: float, knots_s: float = 0.1):
        self.omega_s = float(omega_s)
        self.t0, self.t1 = 0.0, SPIN_UP_S
        times = np.arange(0.0, SPIN_UP_S + 1e-9, knots_s)
        self.trajectory = SimpleNamespace(times_s=times, q=self.theta(times)[:, None])
        self.q_start, self.q_end = np.zeros(1), np.array([self.theta(SPIN_UP_S)])

    def theta(self, t):
        """Hub angle [rad] (held at its final value after Ts)."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, SPIN_UP_S)
        c = (SPIN_UP_S / (2 * math.pi)) ** 2
        return self.omega_s / SPIN_UP_S * (t**2 / 2 + c * (np.cos(2 * math.pi * t / SPIN_UP_S)
                                                              - 1))

    def rates(self, t):
        """Hub rate [rad/s] and acceleration [rad/s²]."""
        t = np.clip(np.asarray(t, dtype=float), 0.0, SPIN_UP_S)
        w = self.omega_s / SPIN_UP_S
        qd = w * (t - SPIN_UP_S / (2 * math.pi) * np.sin(2 * math.pi * t / SPIN_UP_S))
        return qd, w * (1 - np.cos(2 * math.pi * t / SPIN_UP_S))

    def __call__(self, t):
        """``(q, q̇, q̈)`` at one time."""
        qd, qdd = self.rates(t)
        return np.array([self.theta(t)]), np.array([qd]), np.array([qdd])

    def sample(self, times):
        """``(q, q̇, q̈)`` at many times, each (n, 1)."""
        qd, qdd = self.rates(times)
        return self.theta(times)[:, None], np.asarray(qd)[:, None], np.asarray(qdd)[:, None]


def spin_up_model(path):
    """Write the beam's URDF to ``path`` and return its planar :class:`~pinflex.FlexibleModel`."""
    from pathlib import Path

    from pinflex.erls import FlexibleModel
    from pinflex.outputs import write_text

    p = Path(path)
    write_text(p, KANE_URDF, "URDF")
    return FlexibleModel(p, planar=True)
