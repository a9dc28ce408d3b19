"""Prescribed joint motion (kineto-elastodynamics) of eq. (1).

Prescribed motion
    The *physical* joint motion is imposed: each motor turns its joint by the trajectory's value
    between the parent's deformed attachment and the child, so the ERLS coordinates are
    ``q = q_traj(t) + A x`` (:meth:`ErlsDynamics.joint_offsets`). With ``Z = [I; A]`` the
    elastic coordinates obey the projected (locked-joint) equations

        Zᵀ M Z ẍ + C_L ẋ + Zᵀ K Z x = Zᵀ (F − M [0; q̈] − C(q̇) [0; q̇]),

    ``C_L = Zᵀ (C(q̇) Z + [C_k [0; q̇]]_k A + 2 M[:, q] Ȧ) + D``, all evaluated on the
    prescribed motion (the elastic offset ``A x`` moves the matrices only at second order).
    It is a linear time-varying system; its coefficients are computed exactly at a grid of
    ``grid_per_interval`` points per trajectory interval and interpolated by a cubic spline in
    time in between (``exact=True`` evaluates them at every step instead). After the last sample the
    joints hold still: the residual vibration is the free vibration of the locked-joint system
    at the final pose. The motor torques are the joint rows of eq. (1).

Damping acts on the elastic velocity (relative to the ERLS): ``D = blkdiag(Dxx, 0)``, Rayleigh
``Dxx = α Me + β Ke`` (``Me`` the elastic block of ``M``, ``Ke`` of ``K``, at each pose) or
modal ratios ``Dxx = Mr Φ diag(2 ζ_i ω_i) Φᵀ Mr`` from the locked-joint modes ``(ω_i, Φ)`` of
``(Zᵀ K Z, Mr = Zᵀ M Z)`` at the final pose (constant in time).

Integrators of the prescribed motion:

* ``"fixed"`` (default): the trapezoidal rule (generalized-α with ρ∞ = 1) at a uniform step on
  the motion, run at ``N`` and ``2N`` steps on nested grids. Its global error is ``c h² + O(h⁴)``
  (the rule is symmetric), so ``(X_2N − X_N) / 3`` estimates the error of the ``2N`` run
  (Richardson) and ``(4 X_2N − X_N) / 3`` (the result returned) removes the ``h²`` term. The
  coefficient matrices of every step are interpolated in one vectorised call and the step
  operators formed in batches; the remaining loop is one small matrix-vector product per step.
  With ``tol`` the step count doubles until the estimate meets it (see
  :func:`simulate_prescribed`).
* ``"newmark"``: generalized-α with adaptive steps (:func:`.newmark`);
* a ``scipy.integrate.solve_ivp`` method (``Radau``, ``BDF``, ...) with the exact Jacobian.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from pinflex.dynamics.damping import Damping, check_damping, modal_damping_matrix
from pinflex.dynamics.integrators import (
    integrate,
    lowest_eig,
    lti_propagate,
    modal_hold,
    newmark,
    richardson_fixed,
)
from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.result import Simulation, SimulationError, check_positive, output_times
from pinflex.dynamics.speed import (
    check_terms,
    has_levers,
    locked_speed_stiffness,
    speed_stiffness,
)
from pinflex.dynamics.terms import ErlsDynamics
from pinflex.erls.validity import VALIDITY_THRESHOLD, Validity
from pinflex.exceptions import ConfigurationError
from pinflex.resources import check_series
from pinflex.trajectory.samples import in_model_order


@dataclass
class _Coefficients:
    """Locked-joint (projected) linear system at one instant."""

    M: np.ndarray  # (nx, nx)
    C: np.ndarray
    K: np.ndarray
    f: np.ndarray  # (nx,)
    A: np.ndarray  # (nv, nx)
    full: tuple = field(default=())  # (M, Ck, K, F) of eq. (1), for the torques
    K_eq1: np.ndarray | None = None  # (nx, nx) K without the speed terms (Rayleigh β)



def check_locked_motion(model, trajectory) -> None:
    """Refuse a trajectory that turns a locked joint (a prescribed joint that does not move).

    Args:
        model: The :class:`~pinflex.FlexibleModel`.
        trajectory: Joint samples (``.q`` (n, nv), user convention).

    Raises:
        ConfigurationError: A locked joint's physical angle (or position) changes along the
            trajectory; the message names the joint and its span.
    """
    locked = [c.name for c in model.joint_conditions if c.kind == "locked"]
    if not locked:
        return
    Qp = np.asarray(trajectory.q, dtype=float) @ model.coord_map.T
    for name in locked:
        col = model.joint_index(name)
        span = float(np.ptp(Qp[:, col]))
        if span > 1e-9 * max(1.0, float(np.abs(Qp[:, col]).max())):
            raise ConfigurationError(
                f"joint '{name}' is locked but the trajectory turns it by {span:.3g} (rad "
                "or m): hold it constant in the trajectory, or do not lock it (joints='free'"
                " or a spring stiffness)")


def locked_coefficients(dyn: ErlsDynamics, q, qd, qdd, *, terms: str = "eq1",
                        force=0.0) -> _Coefficients:
    """The locked-joint system (undamped) of the elastic motion on a rigid state.

    ``Zᵀ M Z ẍ + C_L ẋ + Zᵀ K Z x = Zᵀ (F − M [0; q̈] − C(q̇) [0; q̇])`` of the module doc.
    With ``terms="full"`` the stiffness gains the speed terms: ``Zᵀ K_s Z``
    (:func:`pinflex.dynamics.speed.speed_stiffness`) when no joint has an elastic offset
    (``A = 0``: moving joints on rigid links) and no load is held off a beam's axis, else the
    locked system's second variation
    (:func:`pinflex.dynamics.speed.locked_speed_stiffness`, with the loads' static state for
    the forces the joints pass on). ``full`` carries ``K + K_s`` for the motor torques.

    Args:
        dyn: Equations of motion.
        q: Physical joint coordinates (nv,) [rad or m]; ``qd``, ``qdd`` their rates.
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).
        terms: ``"eq1"`` or ``"full"``.
        force: Generalized external force (ndof,) or 0.

    Returns:
        :class:`_Coefficients` (``full`` holds ``(M, Ck, K, F)`` over every coordinate, ``K``
        with ``K_s`` and ``F`` with the external force).
    """
    nx, nv = dyn.nx, dyn.nv
    q, qd, qdd = (np.asarray(v, dtype=float) for v in (q, qd, qdd))
    M, Ck, K, F = dyn.linear_terms(q)
    A, Adk = dyn.joint_offsets(q)
    Z = np.vstack([np.eye(nx), A])
    K_eq1 = Z.T @ K @ Z
    if terms == "full":
        K = K + speed_stiffness(dyn, q, qd, qdd)  # the joint rows' terms, for the torques
    C = np.tensordot(qd, Ck, axes=(0, 0))
    zq = np.concatenate([np.zeros(nx), qd])
    Cq = np.stack([Ck[k] @ zq for k in range(nv)], axis=1) if nv else np.zeros((dyn.ndof, 0))
    Ad = np.tensordot(qd, Adk, axes=(0, 0)) if nv else np.zeros((0, nx))
    ML = Z.T @ M @ Z
    CL = Z.T @ (C @ Z + Cq @ A + 2.0 * M[:, nx:] @ Ad)
    rigid = M[:, nx:] @ qdd + C[:, nx:] @ qd + K[:, nx:] @ q
    KL = K_eq1
    if terms == "full" and (np.any(A) or has_levers(dyn)):
        # joints on deforming links or loads held off the beam axes: the second variation of
        # the locked system, with the loads' static state for the root copies' turn
        statics = np.linalg.solve(K_eq1, Z.T @ (F - rigid)) if np.any(A) else None
        KL = K_eq1 + locked_speed_stiffness(dyn, q, qd, qdd, statics)
    elif terms == "full":
        KL = Z.T @ K @ Z  # no elastic joint offset: the terms of speed_stiffness are exact
    F = F + force
    return _Coefficients(ML, CL, KL, Z.T @ (F - rigid), A, (M, Ck, K, F), K_eq1)


class PrescribedSystem:
    """The locked-joint linear system of a prescribed motion (see module doc).

    Args:
        dyn: Equations of motion.
        motion: The joint motion.
        damping: Damping of the elastic motion.
        forces: External forces ``[(link, xyz, fn), ...]`` (see :func:`simulate_prescribed`).
        terms: ``"eq1"`` (paper 000 eq. 1) or ``"full"`` (:mod:`pinflex.dynamics.speed`).
    """

    def __init__(self, dyn: ErlsDynamics, motion: JointMotion, damping: Damping | None = None,
                 forces=(), terms: str = "eq1"):
        self.dyn = dyn
        self.terms = check_terms(terms)
        self.forces = [(dyn.frame_map(link, xyz), fn) for link, xyz, fn in forces]
        self.motion = motion
        self.damping = damping or Damping()
        self.nx, self.nv = dyn.nx, dyn.nv
        self._Dmodal: np.ndarray | None = None
        self._cache: dict = {}
        if self.damping.kind == "modal":
            c = self.coefficients(motion.t1 + 1.0, damped=False)
            self._Dmodal = modal_damping_matrix(c.M, c.K, self.damping.ratios)

    def coefficients(self, t: float, *, damped: bool = True) -> _Coefficients:
        """Exact coefficients of the projected system at time ``t`` [s] (cached by time)."""
        key = (float(t), bool(damped))
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        out = self._coefficients(t, damped)
        if len(self._cache) < 20000:
            self._cache[key] = out
        return out

    def _coefficients(self, t: float, damped: bool) -> _Coefficients:
        q, qd, qdd = self.motion(t)
        out = locked_coefficients(self.dyn, q, qd, qdd, terms=self.terms,
                                  force=external_forces(self.forces, q, t))
        if damped:
            out.C = out.C + self._damping(out.M, out.K if out.K_eq1 is None else out.K_eq1)
        return out

    def torque(self, t: float, y: np.ndarray, xdd: np.ndarray | None = None) -> np.ndarray:
        """Motor torques (Pinocchio convention) at time ``t``, state ``y = [x; ẋ]``.

        ``xdd`` is the elastic acceleration; by default it is solved from the projected
        equations, which loses digits on a very stiff arm (``K x`` nearly cancels the loads):
        the simulations pass the derivative of the integrated velocity instead.
        """
        nx = self.nx
        c = self.coefficients(t, damped=True)
        x, xd = y[:nx], y[nx:]
        if xdd is None:
            xdd = np.linalg.solve(c.M, c.f - c.C @ xd - c.K @ x)
        q, qd, qdd = self.motion(t)
        M, Ck, K, F = c.full
        _, Adk = self.dyn.joint_offsets(q)
        Ad = np.tensordot(qd, Adk, axes=(0, 0)) if self.nv else np.zeros((0, nx))
        z = np.concatenate([x, q + c.A @ x])
        zd = np.concatenate([xd, qd + c.A @ xd])
        zdd = np.concatenate([xdd, qdd + c.A @ xdd + 2.0 * Ad @ xd])
        r = M @ zdd + np.tensordot(zd[nx:], Ck, axes=(0, 0)) @ zd + K @ z - F
        return np.linalg.solve(self.dyn.model.coord_map.T, r[nx:])

    def _damping(self, ML, KL) -> np.ndarray:
        """Damping of the locked-joint system: Rayleigh ``α M_L + β K_L``, or modal ratios."""
        d, nx = self.damping, self.nx
        if d.kind == "rayleigh":
            return d.alpha * ML + d.beta * KL
        if d.kind == "modal" and self._Dmodal is not None:
            return self._Dmodal
        return np.zeros((nx, nx))

    def state_matrix(self, c: _Coefficients):
        """``(Ā, b̄)`` of ``ẏ = Ā y + b̄`` with ``y = [x; ẋ]``."""
        nx = self.nx
        MiK = np.linalg.solve(c.M, np.hstack([c.K, c.C, c.f[:, None]]))
        Abar = np.zeros((2 * nx, 2 * nx))
        Abar[:nx, nx:] = np.eye(nx)
        Abar[nx:, :nx] = -MiK[:, :nx]
        Abar[nx:, nx:] = -MiK[:, nx : 2 * nx]
        bbar = np.concatenate([np.zeros(nx), MiK[:, -1]])
        return Abar, bbar


def external_forces(forces, q, t) -> np.ndarray | float:
    """Generalized force of world forces ``fn(t)`` [N] at points of links (``frame_map``)."""
    out = None
    for at, fn in forces:
        f = np.asarray(fn(t), dtype=float)
        if f.shape != (3,) or not np.all(np.isfinite(f)):
            raise ConfigurationError(f"an external force must give 3 finite numbers [N], got {f!r}")
        Tw, Sw = at(q)
        g = np.concatenate([Tw[:3].T @ f, Sw[:3].T @ f])
        out = g if out is None else out + g
    return 0.0 if out is None else out



class _ReducedSystem:
    """Galerkin projection of a :class:`PrescribedSystem` on locked-joint modes of a few poses.

    The elastic coordinates are link-local and the unique-ERLS root copy turns with the joints,
    so the mode shapes of one pose, used at another, imply stiff (axial) deformation there: a
    basis of the final pose alone misses the motion's static response almost entirely (K-norm
    error ~100 % on benchmark A). The basis is therefore the ``k`` lowest locked-joint modes at
    ``n_poses`` poses evenly spread in time over the motion (start, ..., end), made
    M-orthonormal at the final pose (directions below 1e-10 of the largest singular value
    dropped). The K-norm error of the reduced static response against the full one is checked
    at 16 instants of the motion (``static_error``) and warned about above 10 %.
    """

    def __init__(self, full: PrescribedSystem, k: int, n_poses: int = 3):
        import scipy.linalg

        if not 1 <= k <= full.nx:
            raise ConfigurationError(f"modes = {k} must lie in [1, {full.nx}]")
        self.full = full
        mo = full.motion
        times = np.linspace(mo.t0, mo.t1, max(1, int(n_poses))) if n_poses > 1 else [mo.t1]
        cols = []
        for t in times:
            c = full.coefficients(t, damped=False)
            cols.append(scipy.linalg.eigh(c.K, c.M, subset_by_index=[0, k - 1])[1])
        V = np.hstack(cols)
        cend = full.coefficients(mo.t1 + 1.0, damped=False)
        L = np.linalg.cholesky(cend.M)
        U, sv, _ = np.linalg.svd(L.T @ V, full_matrices=False)
        U = U[:, sv > 1e-10 * sv[0]]
        phi = np.linalg.solve(L.T, U)  # M-orthonormal at the final pose
        # order by the final pose's reduced frequencies
        lam, R = scipy.linalg.eigh(phi.T @ cend.K @ phi)
        self.basis = phi @ R  # (nx, r)
        self.nx = self.basis.shape[1]
        self.nv = full.nv
        self.dyn = full.dyn
        self.motion = full.motion
        errs = []
        P = self.basis
        for t in np.linspace(mo.t0, mo.t1, 16):
            c = full.coefficients(t, damped=False)
            if not np.any(c.f):
                continue
            xf = np.linalg.solve(c.K, c.f)
            xr = P @ np.linalg.solve(P.T @ c.K @ P, P.T @ c.f)
            d = xr - xf
            errs.append(float(np.sqrt(max(d @ c.K @ d, 0.0) / max(xf @ c.K @ xf, 1e-300))))
        self.static_error = max(errs) if errs else 0.0
        if self.static_error > 0.1:
            import warnings

            from pinflex.exceptions import PinflexWarning

            warnings.warn(
                f"the reduced basis ({self.nx} vectors from {k} modes at {len(times)} poses) "
                f"misses {100 * self.static_error:.0f} % (K-norm) of the motion's static "
                "response: keep more modes or poses", PinflexWarning, stacklevel=3)

    def coefficients(self, t: float, *, damped: bool = True) -> _Coefficients:
        c = self.full.coefficients(t, damped=damped)
        P = self.basis
        return _Coefficients(P.T @ c.M @ P, P.T @ c.C @ P, P.T @ c.K @ P, P.T @ c.f,
                             c.A @ P, c.full)

    def state_matrix(self, c: _Coefficients):
        return PrescribedSystem.state_matrix(self, c)  # type: ignore[arg-type]  # same fields



def simulate_prescribed(
    dyn: ErlsDynamics,
    trajectory,
    *,
    after_s: float = 0.5,
    damping: Damping | None = None,
    sample_hz: float = 5000.0,
    method: str = "fixed",
    rtol: float = 1e-4,
    atol: float = 1e-9,
    grid_per_interval: int | None = None,
    exact: bool = False,
    start: str = "static",
    rho_inf: float | None = None,
    modes: int | None = None,
    basis_poses: int = 3,
    forces=(),
    tol: float | None = None,
    steps: int | None = None,
    terms: str = "eq1",
    strict: bool = False,
    validity_threshold: float = VALIDITY_THRESHOLD,
    progress: Callable[[int, int], None] | None = None,
) -> Simulation:
    """Kineto-elastodynamics: the joints follow ``trajectory``, the elastic coordinates respond.

    Args:
        dyn: Equations of motion (model, design, gravity).
        trajectory: Joint samples (user convention) or a :class:`JointMotion`.
        after_s: Simulated time after the last sample, joints holding still [s].
        damping: Damping of the elastic motion (default none).
        sample_hz: Output sampling rate [Hz].
        method: ``"fixed"`` (default: trapezoidal rule at uniform steps, two step sizes,
            Richardson estimate and extrapolation, see :func:`.richardson_fixed`),
            ``"newmark"`` (generalized-α, adaptive step, see :func:`.newmark`) or a
            ``solve_ivp`` method (``Radau``, ``BDF``, ``LSODA``, ``DOP853``: much slower, they
            resolve the highest beam modes).
        rtol: Relative tolerance of the adaptive step control (``"newmark"``, ``solve_ivp``).
        atol: Absolute tolerance of the adaptive step control [m and rad of ``x``].
        grid_per_interval: Exact coefficient evaluations per trajectory interval, interpolated
            by a cubic spline in time in between (ignored when ``exact``). Default: spacing at
            most 5 ms and at least 2 per interval. Measured against 8 per interval (tip
            deflection, relative to its peak): benchmark A (10 ms samples) 4.8e-3 at 1,
            5.3e-5 at 2, 3.4e-6 at 4; a 0.3 s move with 30 ms samples 0.16 at 1, 1.0e-2 at 2,
            4.9e-5 at 4.
        exact: Evaluate the coefficients exactly at every step instead of interpolating.
        start: ``"static"`` starts from the static deflection at the first pose (zero without
            gravity) or ``"rest"`` from ``x = 0``.
        rho_inf: High-frequency spectral radius of the generalized-α scheme (``1`` conserves
            energy, no numerical damping; see :func:`.newmark`). Default 1 for ``"fixed"``
            (the symmetric rule whose error expansion Richardson assumes), 0.9 for
            ``"newmark"``.
        modes: Reduced simulation (modal truncation, ``x = Φ η``, Galerkin projection) on the
            ``modes`` lowest locked-joint modes of ``basis_poses`` poses along the motion
            (:class:`_ReducedSystem`); ``None`` keeps every elastic coordinate.
        basis_poses: Poses whose modes make the reduced basis (evenly spread in time).
        forces: External forces ``[(link, xyz, fn), ...]``: ``fn(t)`` is a world force [N]
            at the point ``xyz`` of ``link`` (it does work on the point's elastic and ERLS
            motion); the coefficient grid samples it, so it should be smooth on the grid; after
            the stop it keeps its value at the stop.
        tol: ``"fixed"`` only: the step count doubles (from ``steps``) until the Richardson
            estimate of the finer run's error (``max |x_2N − x_N| / 3`` relative to ``max |x|``)
            is at most ``tol``; reported as ``Simulation.error_estimate``. ``None``: one pair.
        steps: ``"fixed"`` only: steps ``N`` of the coarser run over the motion (default
            ``duration × sample_hz / 2``, at least 8).
        terms: ``"eq1"`` (default, paper 000 eq. 1) or ``"full"``: adds the centrifugal and
            Euler terms of the elastic displacement and the geometric stiffness of the axial
            inertial and gravity loads (:mod:`pinflex.dynamics.speed`).
        strict: Refuse (:class:`~pinflex.exceptions.ModelValidityError`, before the
            integration) a motion whose validity indicator exceeds ``validity_threshold``
            with ``terms="eq1"``; otherwise such a motion is warned about
            (:class:`~pinflex.exceptions.ModelValidityWarning`).
        validity_threshold: Threshold of the indicator (:mod:`pinflex.erls.validity`).
        progress: Called as ``progress(done, total)`` as the work advances: once after the
            validity indicator, once per coefficient on the interpolation grid (the
            dynamics' matrices, usually the larger part of the cost), once after the
            integration and once after the motor torques; ``total`` is the grid's size
            plus three (three alone with ``exact``).

    The hold phase after the stop is a constant-coefficient system, propagated exactly by its
    modes at the output rate (:func:`.modal_hold`); its ``steps`` are the output samples.
    """
    check_damping(damping)
    motion = trajectory if isinstance(trajectory, JointMotion) else JointMotion(
        in_model_order(dyn.model, trajectory))
    check_positive(after_s=after_s, sample_hz=sample_hz, rtol=rtol, atol=atol)
    check_series((motion.duration_s + after_s) * sample_hz, 4 * dyn.model.ndof + 8,
                 "the simulation's output", "lower sample_hz or after_s")
    check_locked_motion(dyn.model, motion.trajectory)
    if start not in ("static", "rest"):
        raise ConfigurationError(f"start = {start!r} must be 'static' or 'rest'")
    if dyn.nx == 0:
        raise SimulationError("the model has no flexible link: nothing vibrates")
    if grid_per_interval is not None and not (isinstance(grid_per_interval, (int, np.integer))
                                              and grid_per_interval >= 1):
        raise ConfigurationError(f"grid_per_interval = {grid_per_interval!r} must be an "
                                 "integer >= 1")
    if tol is not None and not (np.isfinite(tol) and 0.0 < tol < 1.0):
        raise ConfigurationError(f"tol = {tol!r} must lie in (0, 1)")
    tic = time.perf_counter()
    indicator = motion_validity(dyn, motion, terms=check_terms(terms), strict=strict,
                                threshold=validity_threshold)
    system: Any = PrescribedSystem(dyn, motion, damping, forces, terms)
    if modes is not None:
        system = _ReducedSystem(system, int(modes), int(basis_poses))
    nx = system.nx
    c0 = system.coefficients(motion.t0)
    x0 = np.zeros(nx)
    if start == "static" and np.any(c0.f):
        x0 = np.linalg.solve(c0.K, c0.f)
    knots = np.asarray(motion.trajectory.times_s, dtype=float)
    nx2 = nx * nx
    total = 3
    if exact:
        if progress is not None:
            progress(1, total)

        def coeff(t):
            c = system.coefficients(t)
            return c.M, c.C, c.K, c.f
    else:
        def per_interval(a, b):
            if grid_per_interval is not None:
                return int(grid_per_interval)
            return max(2, int(np.ceil((b - a) / 5e-3 - 1e-9)))

        grid = np.unique(np.concatenate([
            np.linspace(a, b, per_interval(a, b) + 1) for a, b in zip(knots[:-1], knots[1:])]))
        total = grid.size + 3
        if progress is not None:
            progress(1, total)
        cs = []
        for k, t in enumerate(grid):
            cs.append(system.coefficients(t))
            if progress is not None:
                progress(k + 2, total)
        nx2 = nx * nx
        packed = np.stack([np.concatenate([c.M.ravel(), c.C.ravel(), c.K.ravel(), c.f])
                           for c in cs])
        spline = CubicSpline(grid, packed, axis=0)
        pc = spline.c  # (4, n - 1, ncol) piecewise cubics

        def coeff(t):
            t = min(max(t, grid[0]), grid[-1])
            k = min(max(int(np.searchsorted(grid, t, side="right")) - 1, 0), grid.size - 2)
            d = t - grid[k]
            v = ((pc[0, k] * d + pc[1, k]) * d + pc[2, k]) * d + pc[3, k]
            return (v[:nx2].reshape(nx, nx), v[nx2 : 2 * nx2].reshape(nx, nx),
                    v[2 * nx2 : 3 * nx2].reshape(nx, nx), v[3 * nx2 :])

    def coeffs(ts):
        if exact:
            cc = [system.coefficients(float(t)) for t in ts]
            return (np.array([c.M for c in cc]), np.array([c.C for c in cc]),
                    np.array([c.K for c in cc]), np.array([c.f for c in cc]))
        v = spline(np.clip(ts, grid[0], grid[-1]))
        n = v.shape[0]
        return (v[:, :nx2].reshape(n, nx, nx), v[:, nx2 : 2 * nx2].reshape(n, nx, nx),
                v[:, 2 * nx2 : 3 * nx2].reshape(n, nx, nx), v[:, 3 * nx2 :])

    run1: Any
    estimate, order = float("nan"), float("nan")
    if method == "fixed":
        n0 = steps if steps is not None else max(8, int(np.ceil(motion.duration_s * sample_hz
                                                                 / 2.0)))
        if int(n0) < 2:
            raise ConfigurationError(f"steps = {steps!r} must be at least 2")
        run1 = richardson_fixed(coeffs, motion.t0, motion.t1, x0, np.zeros(nx),
                                n_steps=int(n0), tol=tol, grid=None if exact else grid,
                                rho_inf=1.0 if rho_inf is None else rho_inf)
        estimate, order = run1.error_estimate, run1.observed_order
    elif tol is not None or steps is not None:
        raise ConfigurationError("tol and steps belong to method = 'fixed'")
    elif method == "newmark":
        run1 = newmark(coeff, motion.t0, motion.t1, x0, np.zeros(nx), rtol=rtol, atol=atol,
                       h0=min(1.0 / sample_hz, motion.duration_s / 10),
                       rho_inf=0.9 if rho_inf is None else rho_inf)
    else:
        def fun(t, y):
            M, C, K, f = coeff(t)
            return np.concatenate([y[nx:], np.linalg.solve(M, f - C @ y[nx:] - K @ y[:nx])])

        def jac(t, y):
            M, C, K, _ = coeff(t)
            J = np.zeros((2 * nx, 2 * nx))
            J[:nx, nx:] = np.eye(nx)
            J[nx:] = -np.linalg.solve(M, np.hstack([K, C]))
            return J

        omega1 = float(np.sqrt(max(lowest_eig(c0.K, c0.M), 1e-30)))
        atol_vec = np.concatenate([np.full(nx, atol), np.full(nx, atol * omega1)])
        run1 = integrate(fun, jac, motion.t0, motion.t1, np.concatenate([x0, np.zeros(nx)]),
                         method=method, rtol=rtol, atol=atol_vec)
    if progress is not None:
        progress(total - 1, total)
    # hold phase: constant coefficients at the final pose, exact propagation
    cend = system.coefficients(motion.t1)  # joints at rest there; forces frozen from here
    Aend, bend = system.state_matrix(cend)
    t_end = motion.t1 + after_s
    times = output_times(motion.t0, t_end, sample_hz)
    hold = times > motion.t1
    dts = times[hold] - motion.t1
    held = modal_hold(cend, run1.y_end, dts)
    Yh, Ydh = held if held is not None else lti_propagate(Aend, bend, run1.y_end, dts,
                                                           rates=True)
    elapsed = time.perf_counter() - tic
    Y = np.empty((times.size, 2 * nx))
    Y[~hold] = run1(times[~hold])
    Y[hold] = Yh
    x, xd = Y[:, :nx], Y[:, nx:]
    if modes is not None:
        x, xd = x @ system.basis.T, xd @ system.basis.T
    q_phys, qd_phys, _ = motion.sample(times)
    A_end = dyn.joint_offsets(motion.q_end)[0]
    q = q_phys + x @ A_end.T
    qd = qd_phys + xd @ A_end.T
    if dyn.offsets_vary:
        for i in np.flatnonzero(~hold):
            A = dyn.joint_offsets(q_phys[i])[0]
            q[i] = q_phys[i] + A @ x[i]
            qd[i] = qd_phys[i] + A @ xd[i]
    # motor torques at the trajectory samples and at the end
    t_tau = np.concatenate([knots, [t_end]])
    y_tau = np.vstack([run1(knots), Yh[-1:] if Yh.size else run1.y_end[None]])
    delta = float(np.median(np.diff(run1.t))) if run1.t.size > 1 else 1e-6
    a_tau = np.vstack([
        (run1(np.minimum(knots + delta, motion.t1)) - run1(np.maximum(knots - delta, motion.t0)))
        [:, nx:] / (np.minimum(knots + delta, motion.t1) - np.maximum(knots - delta, motion.t0))
        [:, None],
        Ydh[-1:, nx:] if Yh.size else np.zeros((1, nx))])
    if modes is not None:
        P = system.basis
        y_tau = np.hstack([y_tau[:, :nx] @ P.T, y_tau[:, nx:] @ P.T])
        a_tau = a_tau @ P.T
        system = system.full
    tau = np.array([system.torque(t, y, a) for t, y, a in zip(t_tau, y_tau, a_tau)])
    if progress is not None:
        progress(total, total)
    return Simulation(
        times_s=times, x=x, xd=xd, q=q, qd=qd, q_physical=q_phys, stop_s=motion.t1,
        drive="prescribed", joint_condition="locked", torque_times_s=t_tau, torques=tau,
        steps=run1.steps + int(hold.sum()), nfev=run1.nfev, time_s=elapsed, method=method,
        error_estimate=estimate, observed_order=order, validity=indicator, terms=terms,
    )


def motion_validity(dyn: ErlsDynamics, motion: JointMotion, *, terms: str = "eq1",
                    strict: bool = False, threshold: float = VALIDITY_THRESHOLD,
                    n_modes: int = 3, times=None) -> Validity:
    """The validity indicator of eq. (1) along a joint motion, against the locked modes.

    At the trajectory samples (or ``times``) with the motion's exact rates
    (:func:`pinflex.dynamics.response.locked_validity`). With ``terms="full"`` the indicator
    is reported but not warned about (the left-out terms are in).

    Raises:
        ModelValidityError: ``strict`` with ``terms="eq1"`` and the indicator above
            ``threshold``.
    """
    from pinflex.dynamics.response import locked_validity

    t = np.asarray(motion.trajectory.times_s if times is None else times, dtype=float)
    q, qd, qdd = motion.sample(t)
    return locked_validity(dyn, t, q, qd, qdd, terms=terms, strict=strict,
                           threshold=threshold, n_modes=n_modes, what="the prescribed motion")
