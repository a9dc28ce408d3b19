"""Torque drive of eq. (1): forward dynamics of the whole system under motor torques.

Forward dynamics of the whole system ``[x; q]`` with motor torques ``τ`` acting on the
physical joint angle: the generalized force is ``[−Aᵀ τ; Cᵀ τ]`` (the stator reaction loads
the parent attachment). With zero torque the residual vibration has the free-joint
frequencies. ``torque="computed"`` feeds forward the rigid model's inverse dynamics along the
trajectory (the joint rows of eq. (1) at ``x = 0``), optionally with PD feedback on the
physical joint angles.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from pinflex.checks import check_q
from pinflex.dynamics.damping import Damping, check_damping
from pinflex.dynamics.integrators import NewmarkRun, newmark
from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.result import Simulation, check_positive, output_times
from pinflex.dynamics.terms import ErlsDynamics
from pinflex.dynamics.torque_linear import (
    LINEARISATION_THRESHOLD,
    computed_torque,
    motor_rows,
    simulate_torque_linear,
)
from pinflex.exceptions import ConfigurationError
from pinflex.linalg import held_rayleigh
from pinflex.resources import check_series
from pinflex.trajectory.samples import in_model_order
from pinflex.validation import require_number


#: The adaptive route's error estimate compares the run with one at this many times its
#: ``rtol`` (see :func:`simulate_torque`).
ESTIMATE_FACTOR = 10.0


def simulate_torque(
    dyn: ErlsDynamics,
    *,
    q0,
    duration_s: float,
    qd0=None,
    x0=None,
    xd0=None,
    torque=None,
    trajectory=None,
    kp: float = 0.0,
    kd: float = 0.0,
    damping: Damping | None = None,
    sample_hz: float = 5000.0,
    rtol: float = 1e-5,
    atol: float = 1e-14,
    atol_q: float = 1e-12,
    rho_inf: float = 0.9,
    corrections: int = 4,
    coefficient_step_s: float = 0.0,
    step_s: float | None = None,
    strict: bool = False,
    validity_threshold: float | None = None,
    route: str | None = None,
    steps: int | None = None,
    tol: float | None = None,
    linearisation_threshold: float | None = None,
) -> Simulation:
    """Forward dynamics of eq. (1) under motor torques (free joints between the motors).

    A motor torque ``τ`` (Pinocchio's joint convention) does work on the physical joint angle
    ``r = G [x; q]`` (``G = [−C A, C]``), so the generalized force is ``Gᵀ τ``: it loads the
    joint coordinate and, through ``A``, the parent attachment (the stator's reaction). Joint
    springs, if the model has them, are at rest at the initial pose.

    Args:
        dyn: Equations of motion.
        q0: Initial ERLS joint coordinates (user convention).
        duration_s: Simulated time [s].
        qd0: Initial joint rates (default zero).
        x0: Initial elastic coordinates (default zero).
        xd0: Initial elastic rates (default zero).
        torque: ``f(t, q, qd, x, xd) -> τ`` (nv,) [N m]; default zero (free vibration).
        trajectory: With no ``torque``: computed torque of the rigid model along these
            samples (the joint rows of eq. (1) at ``x = 0``, fed forward), plus PD feedback
            ``kp (r_d − r) + kd (ṙ_d − ṙ)`` on the physical joint angles; after the last
            sample the reference holds.
        kp: Proportional gain of the feedback [N m/rad].
        kd: Derivative gain [N m s/rad].
        damping: Rayleigh damping of the elastic motion (``"modal"`` is not available here:
            the modes change with the pose).
        sample_hz: Output rate [Hz].
        rtol: Relative tolerance of the adaptive steps' local error, relative to the largest
            ``|x|`` (and ``|q|``) so far in the run. The route's result converges to the
            equations' solution as ``rtol`` shrinks (benchmark A's first 50 ms against
            ``scipy``'s Radau at rtol 1e-8: 3.3e-4, 1.0e-4, 1.4e-5, 3.2e-6 of the largest
            elastic coordinate at rtol 1e-4 … 1e-7); the global error is some 3-30 times
            ``rtol``: read ``Simulation.error_estimate``.
        atol: Absolute floor of the tolerance on ``x`` [m, rad] (where the run has not moved
            yet).
        atol_q: Absolute floor of the tolerance on ``q`` [rad].
        rho_inf: Generalized-α high-frequency spectral radius (1: no numerical damping).
        corrections: At most this many corrector evaluations of eq. (1) per step; the
            iteration stops when converged and a step that does not converge is retried at
            half the size (see :func:`.newmark`). The servo's feedback is solved implicitly
            (its ``k_p GᵀG``, ``k_d GᵀG`` in the step's matrices); a ``torque`` function is a
            load evaluated at the corrector's state (a stiff feedback in it makes the steps
            small).
        coefficient_step_s: The pose-dependent terms ``M(q)``, ``C_k(q)``, ``F(q)`` and the
            joint rows are evaluated exactly at most every ``coefficient_step_s`` of simulated
            time, at the integrator's current state, and extrapolated in time in between by
            the quadratic through the last three evaluations (the joint motion is smooth on
            that scale; the velocities multiply ``C_k`` exactly at every step). ``0`` (the
            default) evaluates them at every call. Measured on a 0.03 s servo move of
            benchmark A's arm: 1 ms halves the CPU time but doubles the steps and the tip
            error (1.3 % against 0.63 % of the peak at rtol 1e-4, both against rtol 1e-5), and
            with fixed steps (``step_s`` 0.2 ms) it turns unstable for stiff servos (kp ≥ 1e4).
            The rigid computed torque is precomputed along the trajectory (exact every ≤ 5 ms,
            cubic spline in time).
        step_s: Fixed steps instead of the adaptive control: two runs at about ``step_s`` and
            ``step_s / 2`` (equal steps over ``duration_s``), Richardson-extrapolated like the
            prescribed drive; ``Simulation.error_estimate`` is ``max |x_fine − x_coarse| / 3``
            relative to ``max |x|`` (``rtol``, ``atol`` unused). There is no stability
            guarantee for this nonlinear drive at a fixed step: a diverging run raises
            :class:`SimulationError`.
        strict: Refuse a reference ``trajectory`` too fast for eq. (1) (its validity
            indicator above ``validity_threshold``;
            :class:`~pinflex.exceptions.ModelValidityError`, before the run).
        validity_threshold: Threshold of the indicator (default
            :data:`pinflex.erls.validity.VALIDITY_THRESHOLD`). ``Simulation.validity`` holds
            the indicator of the reference motion, or of the simulated one without it.
        route: ``"linear"`` (the default with a reference ``trajectory`` and ``kp > 0``):
            the equations linearised about the rigid computed-torque motion, integrated like
            the prescribed drive, with the estimate of their linearisation error
            (``Simulation.linearisation_error``; :mod:`pinflex.dynamics.torque_linear`);
            ``rtol``, ``atol``, ``atol_q``, ``rho_inf``, ``corrections``,
            ``coefficient_step_s`` and ``step_s`` belong to the other route.
            ``"nonlinear"`` (the default otherwise): the nonlinear equations of motion by
            generalized-α (adaptive or ``step_s``); adaptive, ``Simulation.error_estimate``
            is ``max |x − x'| / max |x|`` against a second run at :data:`ESTIMATE_FACTOR`
            times ``rtol`` (on the safe side while the error shrinks at least twice per
            factor; benchmark A's first 50 ms against Radau: 3-8 times the error at rtol
            1e-4 … 1e-7).
        steps: ``route="linear"``: trapezoidal steps ``N`` of the coarser run over the motion
            (default ``motion × sample_hz / 2``, at least 8).
        tol: ``route="linear"``: halve the steps until the Richardson estimate is at most
            ``tol`` and the ladder shows the asymptotic order (see :func:`.richardson_fixed`);
            without it one pair of runs, whose estimate can fall short of the error when the
            motor torques excite modes the steps do not resolve (benchmark A's first 50 ms at
            the default steps: 9.4e-5 against an estimate of 6.4e-5).
        linearisation_threshold: ``route="linear"``: estimate above which the route warns
            (:class:`~pinflex.exceptions.LinearisationWarning`; with ``strict`` it refuses,
            :class:`~pinflex.exceptions.LinearisationError`); default
            :data:`pinflex.dynamics.torque_linear.LINEARISATION_THRESHOLD`.
    """
    check_positive(duration_s=duration_s, sample_hz=sample_hz, rtol=rtol, atol=atol,
                    atol_q=atol_q)
    check_series(duration_s * sample_hz, 4 * dyn.model.ndof + 8, "the simulation's output",
                 "lower sample_hz or duration_s")
    check_damping(damping)
    for name, gain in (("kp", kp), ("kd", kd)):
        require_number(gain, f"{name} (PD gain)", ge=0.0)
    damping = damping or Damping()
    if damping.kind == "modal":
        raise ConfigurationError("the torque drive takes Rayleigh damping or none")
    if dyn.locked:
        raise ConfigurationError(
            f"the torque drive integrates every joint coordinate; joints "
            f"{[n for n, _ in dyn.locked]} are locked in this model: model a brake as a stiff "
            "spring (joints={name: stiffness}), or hold the joints with the prescribed drive "
            "(drive = 'prescribed', the trajectory constant in them)")
    nx, nv, nd = dyn.nx, dyn.nv, dyn.ndof
    Cm = dyn.model.coord_map
    q0 = check_q(dyn.model, q0).astype(float)
    z0 = np.concatenate([np.zeros(nx) if x0 is None else np.asarray(x0, float), q0])
    zd0 = np.concatenate([np.zeros(nx) if xd0 is None else np.asarray(xd0, float),
                          np.zeros(nv) if qd0 is None else np.asarray(qd0, float)])
    z_ref = np.concatenate([np.zeros(nx), q0])
    motion = None
    if torque is None and trajectory is not None:
        motion = trajectory if isinstance(trajectory, JointMotion) else JointMotion(
            in_model_order(dyn.model, trajectory))

    indicator = None
    if motion is not None:  # the reference motion, before the run (strict refuses here)
        from pinflex.dynamics.prescribed import motion_validity
        from pinflex.erls.validity import VALIDITY_THRESHOLD

        indicator = motion_validity(
            dyn, motion, strict=strict,
            threshold=VALIDITY_THRESHOLD if validity_threshold is None else validity_threshold)
    if route is None:
        route = "linear" if motion is not None and kp > 0.0 else "nonlinear"
    if route not in ("linear", "nonlinear"):
        raise ConfigurationError(f"route = {route!r} must be 'linear' or 'nonlinear'")
    if route == "linear":
        if motion is None:
            raise ConfigurationError(
                "route = 'linear' linearises about a reference motion: give trajectory= (and "
                "no torque function), or use route = 'nonlinear'")
        if step_s is not None:
            raise ConfigurationError("step_s belongs to route = 'nonlinear'; the linear route "
                                     "takes steps=")
        if tol is not None and not (np.isfinite(tol) and 0.0 < tol < 1.0):
            raise ConfigurationError(f"tol = {tol!r} must lie in (0, 1)")
        if steps is not None and not (isinstance(steps, (int, np.integer)) and steps >= 2):
            raise ConfigurationError(f"steps = {steps!r} must be an integer >= 2")
        return simulate_torque_linear(
            dyn, motion, duration_s=duration_s, kp=kp, kd=kd, damping=damping,
            sample_hz=sample_hz, z0=z0, zd0=zd0, steps=steps, tol=tol,
            threshold=(LINEARISATION_THRESHOLD if linearisation_threshold is None
                       else linearisation_threshold), strict=strict, validity=indicator)
    if not (np.isfinite(coefficient_step_s) and coefficient_step_s >= 0.0):
        raise ConfigurationError(f"coefficient_step_s = {coefficient_step_s!r} must be >= 0")

    def joint_rows(q):
        return motor_rows(dyn, q)

    ff = computed_torque(dyn, motion) if motion is not None else None

    def applied(t, z, zd, G, terms):
        if torque is not None:
            return np.asarray(torque(t, z[nx:], zd[nx:], z[:nx], zd[:nx]), dtype=float)
        if motion is None or ff is None:
            return np.zeros(nv)
        qr, qdr, _ = motion(t)
        return ff(t) + kp * (Cm @ qr - G @ z) + kd * (Cm @ qdr - G @ zd)

    history: list = []  # (t, M, Ck, K, F, G) of the last exact evaluations (one run)

    def pose_terms(t, q):
        if coefficient_step_s > 0.0 and history and t < history[-1][0] + coefficient_step_s:
            if len(history) < 3:
                return history[-1][1:]
            (t0, *a), (t1, *b), (t2, *c) = history[-3:]
            l0 = (t - t1) * (t - t2) / ((t0 - t1) * (t0 - t2))
            l1 = (t - t0) * (t - t2) / ((t1 - t0) * (t1 - t2))
            l2 = (t - t0) * (t - t1) / ((t2 - t0) * (t2 - t1))
            return tuple(l0 * u + l1 * v + l2 * w for u, v, w in zip(a, b, c))
        M, Ck, K, F = dyn.linear_terms(q)
        out = (M, Ck, K, F, joint_rows(q))
        if coefficient_step_s > 0.0 and (not history or t > history[-1][0]):
            history.append((t, *out))
            del history[:-3]
        return out

    def coeff(t, z, zd):
        M, Ck, K, F, G = pose_terms(t, z[nx:])
        C = np.tensordot(zd[nx:], Ck, axes=(0, 0))
        if damping.kind == "rayleigh":  # the deformation's, motors held (linalg.held_rayleigh)
            C += held_rayleigh(M, K, G, nx, damping.alpha, damping.beta)
        C += dyn.joint_damping(z[nx:])  # joint dampers (zero without them)
        f = F + K @ z_ref
        if torque is None and motion is not None and ff is not None:
            # the servo's feedback Gᵀ(k_p (C q_r − G z) + k_d (C q̇_r − G ż)) goes into the
            # step's matrices (k_p GᵀG, k_d GᵀG at this pose), so the corrector solves it
            # implicitly: a stiff servo (k_d on the first element: ~1e6 1/s on benchmark A)
            # made the fixed-point corrector diverge unless h was about a microsecond
            qr, qdr, _ = motion(t)
            GG = G.T @ G
            f = f + G.T @ (ff(t) + kp * (Cm @ qr) + kd * (Cm @ qdr))
            return M, C + kd * GG, K + kp * GG, f
        return M, C, K, f + G.T @ applied(t, z, zd, G, None)

    tic = time.perf_counter()
    kw: dict[str, Any] = {"rtol": rtol, "atol": atol, "h0": min(1.0 / sample_hz, duration_s / 10),
          "rho_inf": rho_inf, "corrections": max(1, int(corrections)),
          "groups": [(slice(0, nx), atol), (slice(nx, nd), atol_q)], "scale": "peak"}
    run: Any
    estimate = float("nan")
    if step_s is None:
        run = newmark(coeff, 0.0, duration_s, z0, zd0, **kw)
        # its error estimate: the change from a run at ESTIMATE_FACTOR x looser rtol
        history.clear()
        loose = newmark(coeff, 0.0, duration_s, z0, zd0,
                        **{**kw, "rtol": min(ESTIMATE_FACTOR * rtol, 0.1)})
        history.clear()
        tt = np.union1d(run.t, loose.t)
        xr, xl = run(tt)[:, :nx], loose(tt)[:, :nx]
        estimate = float(np.abs(xr - xl).max() / max(float(np.abs(xr).max()), 1e-300))
        run.nfev += loose.nfev
    else:
        check_positive(step_s=step_s)
        n = max(2, int(np.ceil(duration_s / step_s - 1e-9)))
        history.clear()
        coarse = newmark(coeff, 0.0, duration_s, z0, zd0, fixed_steps=n, **kw)
        history.clear()
        fine = newmark(coeff, 0.0, duration_s, z0, zd0, fixed_steps=2 * n, **kw)
        d = fine.x[::2] - coarse.x
        estimate = float(np.abs(d[:, :nx]).max()
                         / (3.0 * max(float(np.abs(fine.x[:, :nx]).max()), 1e-300)))
        run = NewmarkRun(coarse.t, (4.0 * fine.x[::2] - coarse.x) / 3.0,
                          (4.0 * fine.v[::2] - coarse.v) / 3.0, coarse.a,
                          coarse.nfev + fine.nfev)
        run.steps = fine.steps
    elapsed = time.perf_counter() - tic
    times = output_times(0.0, duration_s, sample_hz)
    Y = run(times)
    z, zd = Y[:, :nd], Y[:, nd:]
    q_phys = np.empty((times.size, nv))
    for i in range(times.size):
        G = joint_rows(z[i, nx:])
        q_phys[i] = np.linalg.solve(Cm, G @ z[i])
    stop = motion.t1 if motion is not None else 0.0
    t_tau = np.asarray(motion.trajectory.times_s, float) if motion is not None else times[:1]
    tau = np.array([applied(t, *(lambda y: (y[:nd], y[nd:]))(run(np.array([t]))[0]),
                            joint_rows(run(np.array([t]))[0][nx:nd]), None) for t in t_tau])
    return Simulation(
        times_s=times, x=z[:, :nx], xd=zd[:, :nx], q=z[:, nx:], qd=zd[:, nx:],
        q_physical=q_phys, stop_s=stop, drive="torque",
        joint_condition="servo" if (motion is not None and kp > 0.0) else "free",
        servo_stiffness=float(kp) if motion is not None else 0.0,
        torque_times_s=t_tau, torques=tau, steps=run.steps, nfev=run.nfev, time_s=elapsed,
        method="newmark" if step_s is None else "fixed", error_estimate=estimate,
        validity=indicator if indicator is not None else _run_validity(
            dyn, times, z[:, nx:], zd[:, nx:], validity_threshold),
    )


def _run_validity(dyn, times, q, qd, threshold):
    """The indicator of a torque-driven run without a reference motion (its own rates)."""
    from pinflex.dynamics.response import locked_validity

    qdd = np.gradient(qd, times, axis=0, edge_order=2) if times.size >= 3 else np.zeros_like(qd)
    return locked_validity(dyn, times, q, qd, qdd, threshold=threshold,
                           what="the torque-driven motion")


def energy(dyn: ErlsDynamics, z: np.ndarray, zd: np.ndarray) -> float:
    """Kinetic plus strain energy ``½ żᵀ M(q) ż + ½ xᵀ K x`` [J] of one state ``[x; q]``."""
    M, _, K, _ = dyn.linear_terms(z[dyn.nx:])
    x = z[: dyn.nx]
    return float(0.5 * zd @ M @ zd + 0.5 * x @ K[: dyn.nx, : dyn.nx] @ x)

