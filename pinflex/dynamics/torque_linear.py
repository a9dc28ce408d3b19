"""The torque drive linearised about the rigid computed-torque motion (its fast route).

The torque drive (:mod:`pinflex.dynamics.torque`) drives the arm with the rigid model's
computed torque ``τ_ff(t)`` along a reference motion ``q_r(t)`` plus PD feedback on the motor
angles. While the arm stays near the reference, its motion is the reference plus a small
deviation ``w = [x; δ]``: the elastic coordinates ``x`` and the motor angles' deviation
``δ = q_phys − q_r`` (user convention). The ERLS coordinates are then

    z = [x; q_r + δ + A(q_r) x] = z_r + T w,   T = [[I, 0], [A, I]],  z_r = [0; q_r],

an exact change of variables at each instant. Eq. (1) with the motor torques,
``R(z, ż, z̈) = M z̈ + (C(q, q̇) + D) ż + K (z − z_0) − F − Gᵀ τ = 0`` with
``τ = τ_ff + k_p (C q_r − G z) + k_d (C q̇_r − G ż)``, is linearised in ``w`` about ``w = 0``:

    Tᵀ M T ẅ + Tᵀ (J T + 2 M Ṫ) ẇ + Tᵀ (J Ṫ + M T̈ + K T + P [A, I]) w + servo = −Tᵀ R(z_r),

``J = C(q̇_r) + D + [C_k ż_r]_k`` the velocity Jacobian, ``P = ∂R/∂q`` at the reference state
(the pose dependence of ``M``, ``C``, ``K``, ``F``, ``D`` and ``G``: forward differences), and
the servo's ``k_p Cᵀ C`` and ``k_d Cᵀ C`` on the ``δ`` rows and columns (``k_d Cᵀ C Ȧ`` on
``x``). The elastic block is the prescribed drive's locked-joint system (plus the pose
dependence of the terms, which eq. (1)'s prescribed drive leaves out); the joint rows are the
servo's. The motor torque does no work on ``Tᵀ``'s elastic rows, so with ``k_p → ∞`` the route
tends to the prescribed drive.

Integration: coefficients exact on a grid (at most 5 ms spacing, at least 2 points per sample
interval), cubic splines in time in between, the trapezoidal rule at ``N`` and ``2N`` uniform
steps (:func:`residual_steps`: each step solved from its own residual with the interpolated
coefficients, not from interpolated step operators), Richardson-extrapolated; after the stop
the system is constant and propagated exactly (eigenvectors of its state matrix).
``Simulation.error_estimate`` is the Richardson estimate of the finer run's error plus the
motion found in the modes the steps do not resolve (:func:`unresolved_content`: ``|λ| h ≥ 1``,
beyond their quasi-static share): a Richardson pair misrepresents such modes in both runs
alike and cannot see them.

Its own error estimate (``Simulation.linearisation_error``): the residual ``ρ = Tᵀ R`` of the
*nonlinear* equations is evaluated along the linear solution at a uniform grid (step about
``RESIDUAL_STRIDE × (motion / N)``, the stop and the hold included), and the linear system is
solved once more with ``−ρ`` as its load: that correction ``Δ`` is the linearisation error
of ``w`` to leading order (one Newton step on the whole run); ``max |Δx| / max |x|`` is
reported and the linear solution ``w`` returned (not corrected: see below). Above
``threshold`` (default :data:`LINEARISATION_THRESHOLD`) the route warns with
:class:`~pinflex.exceptions.LinearisationWarning` (``strict``:
:class:`~pinflex.exceptions.LinearisationError`): the motion strays too far from the rigid
computed-torque motion (a slow servo on a fast motion, large deflections) and
``route="nonlinear"`` must integrate it.

Measured against the nonlinear equations integrated by ``scipy``'s Radau at rtol 1e-8
(``tests/test_torque_linear.py``): benchmark A's first 50 ms at the default steps differ by
9.4e-5 of the largest elastic coordinate (Richardson estimate 6.4e-5, linearisation estimate
1.3e-5; at 4x the steps 2.4e-5 against 1.9e-5 + 1.3e-5). Ten times faster, the linear solution
is 0.29 % off (tip 0.88 %) while the estimate says 34 %: the residual samples alias the
products of the fast elastic rates (the motor's stiff modes), so the estimate errs on the safe
side there, and adding ``Δ`` to the result would make it worse; hence ``w`` is returned.

Stiff modes: a servo puts modes near 100 000 rad/s and a damped one near −1.8·10⁶ 1/s at the
motors (benchmark A, kp 3000, kd 30), far beyond the default 0.4 ms steps. Driven smoothly they
follow the motion quasi-statically, which the trapezoidal rule reproduces when each step is
solved from its residual: benchmark A's whole servo run at the default steps is 3.1e-6 of
the largest elastic coordinate from the same equations at 256x the steps (estimate 1.1e-4).
Interpolating the step operators instead (as the prescribed drive does, harmless there) put
an error of fixed size into every step, so the runs drifted further off the finer the steps
(2.5 % at 128x) while Richardson saw nothing. Started off the reference, or kicked, the
stiff modes ring: the result is then as wrong as that ringing is large and the estimate says
so (``tests/test_torque_linear.py``: a hub beam whose servo snaps by 1 mrad, 39 % off the
assumed-modes reference, estimate 58 %); with ``tol`` the steps are halved until the estimate
meets it.
"""

from __future__ import annotations

import time
import warnings

import numpy as np
from scipy.interpolate import CubicSpline

from pinflex.dynamics.damping import Damping
from pinflex.dynamics.integrators import NewmarkRun, fixed_step, lti_propagate, richardson_fixed
from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.result import Simulation, SimulationError, output_times
from pinflex.dynamics.terms import ErlsDynamics
from pinflex.exceptions import ConfigurationError, LinearisationError, LinearisationWarning
from pinflex.linalg import held_rayleigh

#: Linearisation error estimate (relative to the largest elastic coordinate) above which the
#: linearised torque drive warns (``strict``: refuses).
LINEARISATION_THRESHOLD = 1e-2
#: Largest spacing of the exact coefficient evaluations along the motion [s] (at least two per
#: trajectory sample interval), as the prescribed drive's default grid.
GRID_SPACING_S = 5e-3
#: High-frequency spectral radius of the generalized-α steps (1: the trapezoidal rule, whose
#: error expansion Richardson assumes).
RHO_INF = 1.0
#: Spacing of the residual samples of the linearisation estimate, in coarse steps of the
#: motion. Benchmark A's whole servo run: estimate 1.30e-2 at 2 (and 1.30e-2 with 8x the
#: steps), about 0.1 CPU-s per simulated second less at 4.
RESIDUAL_STRIDE = 4
#: Instants of the motion at which :func:`unresolved_content` looks for motion in the modes
#: the steps do not resolve.
UNRESOLVED_CHECKS = 64
#: Largest number of steps of the finer run of a ``tol`` ladder.
MAX_STEPS = 2_000_000


class ServoLinearisation:
    """The torque drive's equations about the rigid computed-torque motion (module doc).

    Args:
        dyn: Equations of motion.
        motion: The reference motion ``q_r(t)``.
        ff: Computed torque ``τ_ff(t)`` (:func:`pinflex.dynamics.torque.computed_torque`).
        kp: Proportional gain [N m/rad]; ``kd`` derivative gain [N m s/rad].
        damping: Rayleigh damping (or none) of the deformation.
        z_rest: Rest state of the joint springs ``z_0`` (ndof,).
        fd_step: Step of the forward differences of ``P`` [rad or m].
    """

    def __init__(self, dyn: ErlsDynamics, motion: JointMotion, ff, kp: float, kd: float,
                 damping: Damping, z_rest: np.ndarray, fd_step: float = 1e-7):
        self.dyn, self.motion, self.ff = dyn, motion, ff
        self.kp, self.kd = float(kp), float(kd)
        self.damping = damping
        self.z_rest = z_rest
        self.fd_step = float(fd_step)
        self.nx, self.nv, self.nd = dyn.nx, dyn.nv, dyn.ndof
        Cm = dyn.model.coord_map
        self.Cm = Cm
        self.servo = Cm.T @ Cm
        self._A_const = None if dyn.offsets_vary else dyn.joint_offsets(motion.q_start)[0]

    # ---------------------------------------------------------------- pieces
    def motor_rows(self, q) -> np.ndarray:
        """``G = [−C A(q), C]`` (nv, ndof) at the ERLS pose ``q``."""
        A = self._A_const if self._A_const is not None else self.dyn.joint_offsets(q)[0]
        return np.hstack([-(self.Cm @ A), self.Cm])

    def offsets(self, t: float):
        """``A``, ``Ȧ``, ``Ä`` (nv, nx) along the reference at time ``t``."""
        nv, nx = self.nv, self.nx
        if self._A_const is not None:
            return self._A_const, np.zeros((nv, nx)), np.zeros((nv, nx))
        q, qd, _ = self.motion(t)
        A, Adk = self.dyn.joint_offsets(q)
        Ad = np.tensordot(qd, Adk, axes=(0, 0))
        e = 1e-5 * max(1.0, self.motion.duration_s)
        Ap = np.tensordot(self.motion(t + e)[1], self.dyn.joint_offsets(self.motion(t + e)[0])[1],
                          axes=(0, 0))
        Am = np.tensordot(self.motion(t - e)[1], self.dyn.joint_offsets(self.motion(t - e)[0])[1],
                          axes=(0, 0))
        return A, Ad, (Ap - Am) / (2.0 * e)

    def transform(self, t: float):
        """``T``, ``Ṫ``, ``T̈`` (ndof, ndof) at time ``t``."""
        nx, nd = self.nx, self.nd
        A, Ad, Add = self.offsets(t)
        T = np.eye(nd)
        T[nx:, :nx] = A
        Td = np.zeros((nd, nd))
        Td[nx:, :nx] = Ad
        Tdd = np.zeros((nd, nd))
        Tdd[nx:, :nx] = Add
        return T, Td, Tdd

    def _damping(self, M, K, G, q) -> np.ndarray:
        d = self.damping
        D = self.dyn.joint_damping(q)
        if d.kind == "rayleigh":
            D = D + held_rayleigh(M, K, G, self.nx, d.alpha, d.beta)
        return D

    def equations(self, qc, z, zd, zdd, tau):
        """``R = M z̈ + (C + D) ż + K (z − z_0) − F − Gᵀ τ`` with the terms at pose ``qc``.

        Returns ``(R, (M, Ck, K, F, G, D))``.
        """
        dyn, nx = self.dyn, self.nx
        M, Ck, K, F = dyn.linear_terms(qc)
        G = self.motor_rows(qc)
        D = self._damping(M, K, G, qc)
        C = np.tensordot(zd[nx:], Ck, axes=(0, 0))
        R = M @ zdd + (C + D) @ zd + K @ (z - self.z_rest) - F - G.T @ tau
        return R, (M, Ck, K, F, G, D)

    def torque(self, t: float, z, zd) -> np.ndarray:
        """Motor torques (Pinocchio convention) at state ``(z, ż)``: ``τ_ff`` plus the PD."""
        q, qd, _ = self.motion(t)
        G = self.motor_rows(z[self.nx:])
        return (self.ff(t) + self.kp * (self.Cm @ q - G @ z)
                + self.kd * (self.Cm @ qd - G @ zd))

    def state(self, t: float, w, wd, wdd):
        """``(z, ż, z̈)`` of the deviation ``(w, ẇ, ẅ)`` at time ``t``."""
        nx = self.nx
        q, qd, qdd = self.motion(t)
        T, Td, Tdd = self.transform(t)
        zr = np.concatenate([np.zeros(nx), q])
        zdr = np.concatenate([np.zeros(nx), qd])
        zddr = np.concatenate([np.zeros(nx), qdd])
        return (zr + T @ w, zdr + T @ wd + Td @ w, zddr + T @ wdd + 2.0 * Td @ wd + Tdd @ w)

    # ---------------------------------------------------------------- linear system
    def coefficients(self, t: float):
        """``(M_w, C_w, K_w, f_w)`` of the linearised system at time ``t``."""
        nx, nv = self.nx, self.nv
        q, qd, qdd = self.motion(t)
        T, Td, Tdd = self.transform(t)
        zr = np.concatenate([np.zeros(nx), q])
        zdr = np.concatenate([np.zeros(nx), qd])
        zddr = np.concatenate([np.zeros(nx), qdd])
        tau = self.ff(t)
        R0, (M, Ck, K, _, _, D) = self.equations(q, zr, zdr, zddr, tau)
        P = np.empty((self.nd, nv))
        for k in range(nv):
            h = self.fd_step * max(1.0, abs(float(q[k])))
            qk = q.copy()
            qk[k] += h
            P[:, k] = (self.equations(qk, zr, zdr, zddr, tau)[0] - R0) / h
        J = np.tensordot(qd, Ck, axes=(0, 0)) + D
        if nv:
            J[:, nx:] += np.einsum("kij,j->ik", Ck, zdr)
        Mw = T.T @ M @ T
        Cw = T.T @ (J @ T + 2.0 * M @ Td)
        Kw = T.T @ (J @ Td + M @ Tdd + K @ T + P @ T[nx:])
        Cw[nx:, nx:] += self.kd * self.servo
        Kw[nx:, nx:] += self.kp * self.servo
        Kw[nx:, :nx] += self.kd * self.servo @ Td[nx:, :nx]
        return Mw, Cw, Kw, -T.T @ R0

    def residual(self, t: float, w, wd, wdd) -> np.ndarray:
        """``Tᵀ R`` of the nonlinear equations at the deviation ``(w, ẇ, ẅ)`` at time ``t``."""
        z, zd, zdd = self.state(t, w, wd, wdd)
        tau = self.torque(t, z, zd)
        T = self.transform(t)[0]
        return T.T @ self.equations(z[self.nx:], z, zd, zdd, tau)[0]


def motor_rows(dyn: ErlsDynamics, q) -> np.ndarray:
    """``G = [−C A, C]`` (nv, ndof): the physical joint angles ``r = G z`` at ``q``."""
    Cm = dyn.model.coord_map
    return np.hstack([-(Cm @ dyn.joint_offsets(q)[0]), Cm])


def computed_torque(dyn: ErlsDynamics, motion: JointMotion):
    """``τ_ff(t)``: the rigid model's inverse dynamics along ``motion`` (Pinocchio convention).

    The joint rows of eq. (1) at ``x = 0``, ``C⁻ᵀ (M_qq q̈ + C_qq q̇ − F_q)``, exact at a grid of
    at most 5 ms spacing (at least 2 points per sample interval) and a cubic spline in time in
    between; before the first and after the last grid point it holds the end value.
    """
    nx, Cm = dyn.nx, dyn.model.coord_map

    def feedforward(t):
        qr, qdr, qddr = motion(t)
        M, Ck, _, F = dyn.linear_terms(qr)
        Cr = np.tensordot(qdr, Ck, axes=(0, 0))
        return np.linalg.solve(Cm.T, M[nx:, nx:] @ qddr + Cr[nx:, nx:] @ qdr - F[nx:])

    knots = np.asarray(motion.trajectory.times_s, dtype=float)
    tg = np.unique(np.concatenate([
        np.linspace(a, b, max(2, int(np.ceil((b - a) / 5e-3 - 1e-9))) + 1)
        for a, b in zip(knots[:-1], knots[1:])]))
    ff_spline = CubicSpline(tg, np.array([feedforward(t) for t in tg]), axis=0)

    def ff(t):
        return ff_spline(min(max(t, tg[0]), tg[-1]))

    return ff


def _spline_system(lin: ServoLinearisation, grid: np.ndarray):
    """Vectorised ``coeffs(times) -> (M, C, K, f)`` by cubic splines through the grid."""
    nd = lin.nd
    n2 = nd * nd
    packed = np.stack([np.concatenate([c.ravel() if c.ndim == 2 else c for c in
                                       lin.coefficients(float(t))]) for t in grid])
    spline = CubicSpline(grid, packed, axis=0) if grid.size > 1 else None

    def coeffs(ts):
        ts = np.atleast_1d(np.asarray(ts, dtype=float))
        v = (spline(np.clip(ts, grid[0], grid[-1])) if spline is not None
             else np.repeat(packed, ts.size, axis=0))
        n = v.shape[0]
        return (v[:, :n2].reshape(n, nd, nd), v[:, n2:2 * n2].reshape(n, nd, nd),
                v[:, 2 * n2:3 * n2].reshape(n, nd, nd), v[:, 3 * n2:])

    return coeffs, packed[-1]


def residual_steps(coeffs, t0: float, t1: float, n_steps: int, x0, v0, *,
                   rho_inf: float = 1.0, grid=None, chunk: int = 512):
    """Generalized-α at ``n_steps`` uniform steps, each solved from its own residual.

    The same scheme as :func:`pinflex.dynamics.integrators.fixed_step` (``grid`` is accepted
    and not used), written so that every step is the scheme applied exactly to the
    coefficients ``coeffs`` returns: ``a_{n+1} = lhs⁻¹ (f − Q [x_n; v_n; a_n])`` with ``Q =
    [K, C + (1−α_f) h K, α_m M + (1−α_f)((1−γ) h C + (½−β) h² K)]`` and ``lhs = (1−α_m) M +
    (1−α_f)(γ h C + β h² K)``, both formed at each step from the interpolated coefficients
    (``lhs`` inverted in batches). Interpolating the step operators themselves in time
    (``fixed_step``'s ``grid``) breaks the balance ``K x ≈ f`` of the stiff modes (entries
    of size 1/h² that no longer cancel): on benchmark A's servo run its error grew with the
    number of steps (2.5 % of the largest elastic coordinate at 128x the default steps) while
    the steps' own error fell; here it falls as h² (5.6e-6 at 8x, 8e-8 at 64x). Returns
    ``(t, x, v, a)`` at the ``n_steps + 1`` grid points.
    """
    if not 0.0 <= rho_inf <= 1.0:
        raise ConfigurationError(f"rho_inf = {rho_inf!r} must lie in [0, 1]")
    n_steps = int(n_steps)
    am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
    af = rho_inf / (rho_inf + 1.0)
    gamma = 0.5 - am + af
    beta = 0.25 * (1.0 - am + af) ** 2
    t = np.linspace(t0, t1, n_steps + 1)
    h = (t1 - t0) / n_steps
    x = np.asarray(x0, dtype=float)
    v = np.asarray(v0, dtype=float)
    m = x.size
    M0, C0, K0, f0 = coeffs(np.array([t0]))
    a = np.linalg.solve(M0[0], f0[0] - C0[0] @ v - K0[0] @ x)
    b2, bh, g1, gh = (0.5 - beta) * h * h, beta * h * h, (1.0 - gamma) * h, gamma * h
    S = np.empty((n_steps + 1, 3 * m))
    S[0, :m], S[0, m:2 * m], S[0, 2 * m:] = x, v, a
    eye = np.eye(m)
    B = np.zeros((3 * m, 3 * m))
    B[:m, :m], B[:m, m:2 * m], B[:m, 2 * m:] = eye, h * eye, b2 * eye
    B[m:2 * m, m:2 * m], B[m:2 * m, 2 * m:] = eye, g1 * eye
    B[2 * m:, 2 * m:] = 0.0
    w = np.concatenate([np.full(m, bh), np.full(m, gh), np.ones(m)])
    rep = np.tile(np.arange(m), 3)
    for s0 in range(0, n_steps, chunk):
        s1 = min(n_steps, s0 + chunk)
        M, C, K, f = coeffs(t[s0:s1] + (1.0 - af) * h)
        lhs = (1.0 - am) * M + (1.0 - af) * (gamma * h * C + beta * h * h * K)
        L = np.linalg.inv(lhs)
        Q = np.concatenate([K, C + (1.0 - af) * h * K,
                            am * M + (1.0 - af) * ((1.0 - gamma) * h * C
                                                   + (0.5 - beta) * h * h * K)], axis=2)
        for k in range(s1 - s0):
            row = S[s0 + k]
            a1 = L[k] @ (f[k] - Q[k] @ row)
            np.add(B @ row, w * a1[rep], out=S[s0 + k + 1])
    return t, S[:, :m], S[:, m:2 * m], S[:, 2 * m:]


def unresolved_content(coeffs, t, y, h: float, nx: int, *, checks: int = UNRESOLVED_CHECKS):
    """Largest elastic displacement carried by the modes the steps do not resolve.

    At up to ``checks`` of the run's step times ``t`` (evenly spread, the last one
    included), the frozen state matrix ``Ā`` of ``ẏ = Ā y + b̄`` (``y = [w; ẇ]``) is split
    into its modes (``Ā = V Λ V⁻¹``); those with ``|λ| h ≥ 1`` are beyond the step ``h``
    (the trapezoidal rule turns their motion into a ringing near the step's Nyquist
    frequency, and both runs of a Richardson pair alike). Their content in the state,
    less what they carry quasi-statically (``−(V⁻¹ (b̄ − dȳ_s/dt))_k / λ_k``, with ``ȳ_s =
    −Ā⁻¹ b̄`` the frozen equilibrium, differenced in time), is their dynamic motion, which
    the steps misrepresent; the largest elastic part, ``max |Re V_x c|``, is returned
    (absolute, in the units of ``x``). ``y`` holds the states (n, 2 m) at ``t``.
    """
    n = t.size
    idx = np.unique(np.round(np.linspace(0, n - 1, min(n, max(2, int(checks))))).astype(int))
    worst = 0.0
    dt = max(0.25 * h, 1e-9)
    for i in idx:
        ti = float(t[i])
        M, C, K, f = coeffs(np.array([ti - dt, ti, ti + dt]))
        systems = [_state_matrix(M[k], C[k], K[k], f[k]) for k in range(3)]
        A, b = systems[1]
        lam, V = np.linalg.eig(A)
        stiff = np.abs(lam) * h >= 1.0
        if not np.any(stiff):
            continue
        ys_m = -np.linalg.solve(systems[0][0], systems[0][1])
        ys_p = -np.linalg.solve(systems[2][0], systems[2][1])
        c = np.linalg.solve(V, np.column_stack([y[i], b - (ys_p - ys_m) / (2.0 * dt)]))
        dyn_part = c[stiff, 0] + c[stiff, 1] / lam[stiff]
        worst = max(worst, float(np.abs((V[:nx, stiff] @ dyn_part).real).max()))
    return worst


def _state_matrix(M, C, K, f):
    nd = M.shape[0]
    H = np.linalg.solve(M, np.hstack([K, C, f[:, None]]))
    A = np.zeros((2 * nd, 2 * nd))
    A[:nd, nd:] = np.eye(nd)
    A[nd:, :nd] = -H[:, :nd]
    A[nd:, nd:] = -H[:, nd:2 * nd]
    return A, np.concatenate([np.zeros(nd), H[:, -1]])


def simulate_torque_linear(dyn: ErlsDynamics, motion: JointMotion, *, duration_s: float,
                           kp: float, kd: float, damping: Damping, sample_hz: float,
                           z0: np.ndarray, zd0: np.ndarray, steps: int | None = None,
                           tol: float | None = None, threshold: float = LINEARISATION_THRESHOLD,
                           strict: bool = False, validity=None) -> Simulation:
    """The torque drive by its linearisation about the rigid computed-torque motion.

    Called by :func:`pinflex.dynamics.torque.simulate_torque` (``route="linear"``), which
    checks the arguments; see the module doc for the method and its error estimates.

    Args:
        dyn: Equations of motion.
        motion: Reference motion (computed torque fed forward, PD on the motor angles).
        duration_s: Simulated time from ``t = 0`` [s].
        kp: Proportional gain [N m/rad] (> 0: the held arm must be restrained).
        kd: Derivative gain [N m s/rad].
        damping: Rayleigh damping or none.
        sample_hz: Output rate [Hz].
        z0: Initial ``[x; q]`` (ERLS coordinates); ``zd0`` their rates.
        zd0: Initial rates.
        steps: Steps ``N`` of the coarser trapezoidal run over the motion (default
            ``motion × sample_hz / 2``, at least 8).
        tol: Halve the step until the Richardson estimate is at most ``tol`` (see
            :func:`.richardson_fixed`).
        threshold: Linearisation error estimate above which the route warns.
        strict: Refuse (:class:`~pinflex.exceptions.LinearisationError`) above ``threshold``.
        validity: The reference motion's validity indicator (stored on the result).
    """
    if not kp > 0.0:
        raise ConfigurationError(
            "the linearised torque drive (route='linear') needs a servo (kp > 0): without it "
            "the held arm has no restoring force; use route='nonlinear'")
    tic = time.perf_counter()
    nx, nv, nd = dyn.nx, dyn.nv, dyn.ndof
    ff = computed_torque(dyn, motion)
    z_rest = np.asarray(z0, dtype=float).copy()
    z_rest[:nx] = 0.0
    lin = ServoLinearisation(dyn, motion, ff, kp, kd, damping, z_rest)
    t_end = float(duration_s)
    tm = min(max(motion.t1, 0.0), t_end)  # end of the moving part
    # initial deviation
    q_r0, qd_r0, _ = motion(0.0)
    T0, Td0, _ = lin.transform(0.0)
    w0 = np.linalg.solve(T0, np.asarray(z0, float) - np.concatenate([np.zeros(nx), q_r0]))
    wd0 = np.linalg.solve(T0, np.asarray(zd0, float) - np.concatenate([np.zeros(nx), qd_r0])
                          - Td0 @ w0)
    knots = np.asarray(motion.trajectory.times_s, dtype=float)
    knots = np.unique(np.concatenate([[0.0], knots[(knots > 0.0) & (knots < tm)], [tm]]))
    grid = np.unique(np.concatenate([
        np.linspace(a, b, max(2, int(np.ceil((b - a) / GRID_SPACING_S - 1e-9))) + 1)
        for a, b in zip(knots[:-1], knots[1:])])) if tm > 0.0 else np.array([0.0])
    coeffs, _ = _spline_system(lin, grid)
    nfev = grid.size * (1 + nv)
    run: NewmarkRun | None = None
    estimate, order = float("nan"), float("nan")
    if tm > 0.0:
        n0 = steps if steps is not None else max(8, int(np.ceil(tm * sample_hz / 2.0)))
        n_try = int(n0)
        while True:
            rr = richardson_fixed(coeffs, 0.0, tm, w0, wd0, n_steps=n_try, tol=tol,
                                  rho_inf=RHO_INF, stepper=residual_steps)
            nfev += rr.nfev
            # motion in the modes beyond the coarser run's step, which Richardson cannot see
            h_coarse = 2.0 * tm / rr.steps
            unresolved = unresolved_content(coeffs, rr.t, np.hstack([rr.x, rr.v]), h_coarse,
                                            nx) / max(float(np.abs(rr.x[:, :nx]).max()), 1e-300)
            estimate, order = rr.error_estimate + unresolved, rr.observed_order
            if tol is None or estimate <= tol:
                break
            if 2 * rr.steps > MAX_STEPS:
                raise SimulationError(
                    f"the time step needed for tol = {tol:g} exceeds {MAX_STEPS} steps "
                    f"(estimate {estimate:.3g} at {rr.steps} steps, of which {unresolved:.3g} "
                    "in modes the steps do not resolve): loosen tol or shorten the motion")
            n_try = rr.steps
        run = NewmarkRun(rr.t, rr.x, rr.v, rr.v, rr.nfev)
        y_stop = rr.y_end
        h_motion = h_coarse
        n_steps = rr.steps
    else:
        y_stop = np.concatenate([w0, wd0])
        h_motion = 2.0 / sample_hz
        n_steps = 0
    # hold: the reference at rest, constant coefficients, exact propagation
    Mh, Ch, Kh, fh = (c[0] for c in coeffs(np.array([tm])))
    Ah, bh = _state_matrix(Mh, Ch, Kh, fh)

    def linear_states(ts):
        """``(w, ẇ, ẅ)`` of the linearised run at times ``ts``."""
        ts = np.asarray(ts, dtype=float)
        W = np.empty((ts.size, 2 * nd))
        Wdd = np.empty((ts.size, nd))
        moving = ts <= tm
        if run is not None and np.any(moving):
            W[moving] = run(ts[moving])
            M, C, K, f = coeffs(ts[moving])
            rhs = (f - np.einsum("nij,nj->ni", C, W[moving, nd:])
                   - np.einsum("nij,nj->ni", K, W[moving, :nd]))
            Wdd[moving] = np.linalg.solve(M, rhs[:, :, None])[:, :, 0]
        elif np.any(moving):
            W[moving] = y_stop
            Wdd[moving] = np.linalg.solve(Mh, fh - Ch @ wd0 - Kh @ w0)
        if np.any(~moving):
            Y, Yd = lti_propagate(Ah, bh, y_stop, ts[~moving] - tm, rates=True)
            W[~moving] = Y
            Wdd[~moving] = Yd[:, nd:]
        return W[:, :nd], W[:, nd:], Wdd

    # the linearisation's error: nonlinear residual along the linear run, solved once more
    n_r = max(8, int(np.ceil(t_end / (RESIDUAL_STRIDE * h_motion) - 1e-9)))
    tr = np.linspace(0.0, t_end, n_r + 1)
    Wr, Wdr, Wddr = linear_states(tr)
    rho = np.array([lin.residual(float(t), w, wd, wdd)
                    for t, w, wd, wdd in zip(tr, Wr, Wdr, Wddr)])
    nfev += tr.size
    if not np.all(np.isfinite(rho)):
        raise SimulationError("the linearised torque drive's residual is not finite: the run "
                              "diverged; use route='nonlinear'")

    def correction_coeffs(ts):
        M, C, K, _ = coeffs(ts)
        f = -np.stack([np.interp(ts, tr, rho[:, i]) for i in range(nd)], axis=1)
        return M, C, K, f

    tc, Xc, Vc, _ = fixed_step(correction_coeffs, 0.0, t_end, n_r, np.zeros(nd), np.zeros(nd),
                               rho_inf=RHO_INF)
    nfev += n_r
    corr = NewmarkRun(tc, Xc, Vc, Vc, n_r)
    times = output_times(0.0, t_end, sample_hz)
    W, Wd, _ = linear_states(times)
    dW = corr(times)
    scale = max(float(np.abs(W[:, :nx]).max()), 1e-300)
    lin_error = float(np.abs(dW[:, :nx]).max()) / scale
    elapsed = time.perf_counter() - tic
    if lin_error > threshold:
        msg = (f"the linearised torque drive estimates its linearisation error at "
               f"{lin_error:.3g} of the largest elastic coordinate (threshold {threshold:g}): "
               "the arm strays too far from the rigid computed-torque motion (a slow servo "
               "on this motion, or large deflections); use route='nonlinear'")
        if strict:
            raise LinearisationError(msg, lin_error)
        warnings.warn(msg, LinearisationWarning, stacklevel=3)
    # back to the ERLS coordinates: z = z_r + T w, ż = ż_r + T ẇ + Ṫ w
    qr, qdr, _ = motion.sample(times)
    if lin._A_const is not None:
        A = lin._A_const
        x, xd = W[:, :nx], Wd[:, :nx]
        z = np.hstack([x, qr + W[:, nx:] + x @ A.T])
        zd = np.hstack([xd, qdr + Wd[:, nx:] + xd @ A.T])
    else:
        z = np.empty((times.size, nd))
        zd = np.empty((times.size, nd))
        for i, t in enumerate(times):
            z[i], zd[i], _ = lin.state(float(t), W[i], Wd[i], np.zeros(nd))
    Cm = dyn.model.coord_map
    q_phys = np.linalg.solve(Cm, np.array([lin.motor_rows(zi[nx:]) @ zi for zi in z]).T).T \
        if lin._A_const is None else z[:, nx:] - z[:, :nx] @ lin._A_const.T
    t_tau = knots if tm > 0.0 else np.array([0.0])
    zi = np.array([np.interp(t_tau, times, z[:, j]) for j in range(nd)]).T
    zdi = np.array([np.interp(t_tau, times, zd[:, j]) for j in range(nd)]).T
    tau = np.array([lin.torque(float(t), a, b) for t, a, b in zip(t_tau, zi, zdi)])
    return Simulation(
        times_s=times, x=z[:, :nx], xd=zd[:, :nx], q=z[:, nx:], qd=zd[:, nx:],
        q_physical=q_phys, stop_s=motion.t1, drive="torque", joint_condition="servo",
        servo_stiffness=float(kp), torque_times_s=t_tau, torques=tau,
        steps=n_steps + int((times > tm).sum()) + n_r, nfev=nfev, time_s=elapsed,
        method="linear", error_estimate=estimate, observed_order=order, validity=validity,
        linearisation_error=lin_error,
    )
