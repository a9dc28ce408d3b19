"""The torque drive's linearised route against a closed form, the nonlinear route, and itself.

References written here: a hub with a clamped-free Euler-Bernoulli beam under a PD servo by
assumed modes (the cantilever's closed-form mode shapes, integrated by ``scipy``), and the
torque drive's nonlinear route (adaptive generalized-α on the nonlinear equations).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from conftest import single_link_urdf
from scipy.optimize import brentq

from pinflex import FlexibleModel
from pinflex.description import parse
from pinflex.dynamics import ErlsDynamics
from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.torque import simulate_torque
from pinflex.exceptions import ConfigurationError
from pinflex.trajectory import Trajectory

#: Kane, Ryan and Banerjee's beam: L = 10 m, EI = 1.4e4 N m², ρA = 1.2 kg/m, on one joint.
L, EI, RHOA = 10.0, 1.4e4, 1.2


@pytest.fixture(scope="module")
def hub_beam():
    """Kane's beam on one revolute joint (planar, ten elements)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # G is not used in the plane
        fm = FlexibleModel(parse(single_link_urdf(elements=10, length=L, E=7e10,
                                                  density=6000.0, A=2e-4, Iy=2e-7, Iz=2e-7,
                                                  J=4e-7)), planar=True)
    return ErlsDynamics(fm)


def _move(q0, amp, duration, name="j", n=41):
    t = np.linspace(0.0, duration, n)
    s = t / duration
    return JointMotion(Trajectory(t, (q0 + amp * (10 * s**3 - 15 * s**4 + 6 * s**5))[:, None],
                                  (name,)))


def _cantilever_modes(n):
    """Clamped-free βL roots and a shape function stable for large βL."""
    roots = np.array([brentq(lambda b: 1.0 + math.cos(b) * math.cosh(b), (k + 0.2) * math.pi,
                             (k + 0.8) * math.pi) for k in range(n)]) / L

    def shape(beta, s):
        bl = beta * L
        den = math.sinh(bl) + math.sin(bl)
        one_minus_sigma = (-math.exp(-bl) + math.sin(bl) - math.cos(bl)) / den
        x = beta * s
        return (0.5 * (one_minus_sigma * np.exp(x) + (2.0 - one_minus_sigma) * np.exp(-x))
                - np.cos(x) + (1.0 - one_minus_sigma) * np.sin(x))

    return roots, shape


def test_hub_beam_servo_equals_assumed_modes_closed_form(hub_beam):
    """A slow small move under a PD servo: tip deflection and hub angle of the linear theory.

    Hub angle θ and cantilever coordinates η_i (clamped-free modes φ_i in closed form):
    ``[J, bᵀ; b, diag m] [θ̈; η̈] + [k_d θ̇; 0] + [k_p θ; diag(k) η] = [J θ̈_r + k_p θ_r + k_d θ̇_r; 0]``
    with ``J = ρA L³/3``, ``b_i = ∫ρA s φ_i``, ``m_i = ∫ρA φ_i²``, ``k_i = EI β_i⁴ m_i / ρA``,
    eight modes, solved in closed form (modal sum plus polynomial particular solution); the
    computed torque of the rigid model is ``J θ̈_r``. The speed terms eq. (1)
    keeps and this model drops are of relative size θ̇²/ω₁² ≈ 6e-6 here.
    """
    motion = _move(0.4, 0.02, 4.0)
    kp, kd, after = 2000.0, 300.0, 4.0
    sim = simulate_torque(hub_beam, q0=motion.q_start, trajectory=motion,
                          duration_s=4.0 + after, kp=kp, kd=kd, sample_hz=200.0)
    assert sim.method == "linear"
    n = 8
    beta, shape = _cantilever_modes(n)
    g, wq = np.polynomial.legendre.leggauss(200)
    s = 0.5 * L * (g + 1.0)
    wq = 0.5 * L * wq
    phi = np.array([shape(b, s) for b in beta])
    m = (RHOA * phi**2 * wq).sum(1)
    b = (RHOA * s * phi * wq).sum(1)
    k = EI * beta**4 * m / RHOA
    J = RHOA * L**3 / 3.0
    Mr = np.diag(np.concatenate([[J], m]))
    Mr[0, 1:] = Mr[1:, 0] = b
    Kr = np.diag(np.concatenate([[kp], k]))
    tip_shape = np.array([shape(bb, np.array([L]))[0] for bb in beta])

    # state y = [θ, η, θ̇, η̇], ẏ = A y + B u(t); u is a quintic in t during the move (the
    # rest-to-rest quintic spline reproduces the quintic samples exactly) and constant after:
    # polynomial particular solution plus the modal sum of the free response (closed form)
    nn = n + 1
    A = np.zeros((2 * nn, 2 * nn))
    A[:nn, nn:] = np.eye(nn)
    A[nn:, :nn] = -np.linalg.solve(Mr, Kr)
    A[nn:, nn] = -np.linalg.solve(Mr, np.eye(nn)[:, 0]) * kd
    B = np.concatenate([np.zeros(nn), np.linalg.solve(Mr, np.eye(nn)[:, 0])])
    th = np.polynomial.Polynomial([0.4, 0, 0, 10 * 0.02 / 4.0**3, -15 * 0.02 / 4.0**4,
                                   6 * 0.02 / 4.0**5])
    c = (J * th.deriv(2) + kp * th + kd * th.deriv(1)).coef
    p = np.zeros((7, 2 * nn))
    for kk in range(5, -1, -1):
        p[kk] = np.linalg.solve(A, (kk + 1) * p[kk + 1] - B * c[kk])
    lam, V = np.linalg.eig(A)

    def free(y_start, dt):
        return (V @ (np.exp(np.outer(lam, dt)) * np.linalg.solve(V, y_start)[:, None])).real

    y0 = np.zeros(2 * nn)
    y0[0] = 0.4
    t = sim.times_s
    move = t <= 4.0
    Y = np.empty((2 * nn, t.size))
    Y[:, move] = (np.polynomial.polynomial.polyval(t[move], p[:6])
                  + free(y0 - p[0], t[move]))
    y_stop = np.polynomial.polynomial.polyval(4.0, p[:6]) + free(y0 - p[0], [4.0])[:, 0]
    y_hold = np.concatenate([np.linalg.solve(Kr, np.eye(nn)[:, 0] * kp * th(4.0)),
                             np.zeros(nn)])
    Y[:, ~move] = y_hold[:, None] + free(y_stop - y_hold, t[~move] - 4.0)

    class ref:  # noqa: N801 (the reference's arrays, named as solve_ivp's)
        y = Y

    tip_ref = ref.y[1:n + 1].T @ tip_shape
    peak = float(np.abs(tip_ref).max())
    assert peak == pytest.approx(7.5817e-3, rel=1e-3)  # a deflection worth checking
    err = float(np.abs(sim.x[:, -2] - tip_ref).max()) / peak
    # measured 1.0e-4 (the time steps: estimate 1.35e-4); linearisation estimate 1.3e-8
    assert err <= sim.error_estimate + sim.linearisation_error
    assert err < 3e-4
    assert sim.linearisation_error < 1e-6
    assert np.abs(sim.q_physical[:, 0] - ref.y[0]).max() < 1e-6  # rad (measured 8e-8)


def test_linear_route_refuses_what_it_cannot_linearise(hub_beam):
    """No reference motion, no servo, or the other route's fixed step: named errors."""
    motion = _move(0.4, 0.02, 1.0)
    with pytest.raises(ConfigurationError, match="reference motion"):
        simulate_torque(hub_beam, q0=[0.4], duration_s=0.1, route="linear")
    with pytest.raises(ConfigurationError, match="kp > 0"):
        simulate_torque(hub_beam, q0=[0.4], trajectory=motion, duration_s=0.1,
                        route="linear")
    with pytest.raises(ConfigurationError, match="step_s"):
        simulate_torque(hub_beam, q0=[0.4], trajectory=motion, duration_s=0.1, kp=10.0,
                        step_s=1e-3)
    with pytest.raises(ConfigurationError, match="route"):
        simulate_torque(hub_beam, q0=[0.4], trajectory=motion, duration_s=0.1, kp=10.0,
                        route="fast")
