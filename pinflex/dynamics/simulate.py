"""Time simulation of eq. (1): prescribed joint motion (kineto-elastodynamics) and torque drive.

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

Torque drive
    Forward dynamics of the whole system ``[x; q]`` with motor torques ``τ`` acting on the
    physical joint angle: the generalized force is ``[−Aᵀ τ; Cᵀ τ]`` (the stator reaction loads
    the parent attachment). With zero torque the residual vibration has the free-joint
    frequencies. ``torque="computed"`` feeds forward the rigid model's inverse dynamics along
    the trajectory (the joint rows of eq. (1) at ``x = 0``), optionally with PD feedback on the
    physical joint angles.

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
* ``"newmark"``: generalized-α with adaptive steps (:func:`newmark`);
* a ``scipy.integrate.solve_ivp`` method (``Radau``, ``BDF``, ...) with the exact Jacobian.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.interpolate import CubicSpline

from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.terms import ErlsDynamics
from pinflex.exceptions import ConfigurationError, PinflexError


class SimulationError(PinflexError):
    """A time simulation could not be set up or its integrator failed."""


@dataclass(frozen=True)
class Damping:
    """Damping of the elastic motion.

    Attributes:
        kind: ``"none"``, ``"rayleigh"`` (``α Me + β Ke``) or ``"modal"`` (ratios ζ).
        alpha: Mass-proportional coefficient α [1/s].
        beta: Stiffness-proportional coefficient β [s].
        ratios: Modal damping ratios ζ_i of the lowest locked-joint modes; the last value is
            used for the higher modes.
    """

    kind: str = "none"
    alpha: float = 0.0
    beta: float = 0.0
    ratios: tuple[float, ...] = ()

    def __post_init__(self):
        problems = []
        if self.kind not in ("none", "rayleigh", "modal"):
            problems.append(f"kind = {self.kind!r} must be 'none', 'rayleigh' or 'modal'")
        for name in ("alpha", "beta"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0.0:
                problems.append(f"{name} = {v!r} must be a finite number >= 0")
        if self.kind == "modal" and not self.ratios:
            problems.append("modal damping needs at least one ratio")
        for r in self.ratios:
            if not np.isfinite(r) or not 0.0 <= r < 1.0:
                problems.append(f"damping ratio {r!r} must lie in [0, 1)")
        if problems:
            raise ConfigurationError("invalid damping: " + "; ".join(problems))


def modal_damping_matrix(Mr: np.ndarray, Kr: np.ndarray, ratios) -> np.ndarray:
    """``Mr Φ diag(2 ζ_i ω_i) Φᵀ Mr`` for the mass-normalised modes of ``(Kr, Mr)``."""
    import scipy.linalg

    lam, phi = scipy.linalg.eigh(Kr, Mr)
    omega = np.sqrt(np.clip(lam, 0.0, None))
    z = np.asarray(ratios, dtype=float)
    zeta = np.concatenate([z, np.full(max(0, omega.size - z.size), z[-1])])[: omega.size]
    B = Mr @ phi
    return (B * (2.0 * zeta * omega)) @ B.T


@dataclass
class _Coefficients:
    """Locked-joint (projected) linear system at one instant."""

    M: np.ndarray  # (nx, nx)
    C: np.ndarray
    K: np.ndarray
    f: np.ndarray  # (nx,)
    A: np.ndarray  # (nv, nx)
    full: tuple = field(default=())  # (M, Ck, K, F) of eq. (1), for the torques


class PrescribedSystem:
    """The locked-joint linear system of a prescribed motion (see module doc).

    Args:
        dyn: Equations of motion.
        motion: The joint motion.
        damping: Damping of the elastic motion.
    """

    def __init__(self, dyn: ErlsDynamics, motion: JointMotion, damping: Damping | None = None,
                 forces=()):
        self.dyn = dyn
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
        dyn, nx = self.dyn, self.nx
        q, qd, qdd = self.motion(t)
        M, Ck, K, F = dyn.linear_terms(q)
        A, Adk = dyn.joint_offsets(q)
        Z = np.vstack([np.eye(nx), A])
        C = np.tensordot(qd, Ck, axes=(0, 0))
        zq = np.concatenate([np.zeros(nx), qd])
        Cq = np.stack([Ck[k] @ zq for k in range(self.nv)], axis=1) if self.nv else \
            np.zeros((dyn.ndof, 0))
        Ad = np.tensordot(qd, Adk, axes=(0, 0)) if self.nv else np.zeros((0, nx))
        ML = Z.T @ M @ Z
        CL = Z.T @ (C @ Z + Cq @ A + 2.0 * M[:, nx:] @ Ad)
        KL = Z.T @ K @ Z
        rigid = M[:, nx:] @ qdd + C[:, nx:] @ qd + K[:, nx:] @ q
        F = F + external_forces(self.forces, q, t)
        fL = Z.T @ (F - rigid)
        if damped:
            CL = CL + self._damping(M, K, ML, KL)
        return _Coefficients(ML, CL, KL, fL, A, (M, Ck, K, F))

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

    def _damping(self, M, K, ML, KL) -> np.ndarray:
        d, nx = self.damping, self.nx
        if d.kind == "rayleigh":
            return d.alpha * M[:nx, :nx] + d.beta * K[:nx, :nx]
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


@dataclass
class Simulation:
    """The raw result of a time simulation.

    Attributes:
        times_s: Output times [s], (nt,).
        x: Elastic coordinates (nt, nx); ``xd`` their rates.
        q: ERLS joint coordinates, user convention (nt, nv); ``qd`` their rates.
        q_physical: Physical (motor) joint coordinates, user convention (nt, nv).
        stop_s: Time the drive stops (last trajectory sample) [s].
        drive: ``"prescribed"`` or ``"torque"``.
        joint_condition: Joint condition of the vibration after the stop: ``"locked"``
            (prescribed motion), ``"free"`` (torque drive without feedback) or ``"servo"``
            (torque drive with PD feedback: joint springs of stiffness ``servo_stiffness``).
        torque_times_s: Times of ``torques`` (the trajectory samples and the end) [s].
        torques: Motor torques in Pinocchio's joint convention (nk, nv) [N m or N].
        steps: Accepted integrator steps; ``nfev`` right-hand-side evaluations.
        time_s: Wall time of the integration (and coefficient set-up) [s].
        method: Integrator.
        error_estimate: ``"fixed"`` integrator: Richardson estimate of the time-step error
            (:class:`RichardsonRun`), relative to the largest elastic coordinate; NaN otherwise.
        observed_order: ``"fixed"`` with a ``tol`` ladder: observed order of the step error.
    """

    times_s: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_physical: np.ndarray
    stop_s: float
    drive: str
    joint_condition: str
    torque_times_s: np.ndarray
    torques: np.ndarray
    steps: int
    nfev: int
    time_s: float
    method: str
    servo_stiffness: float = 0.0
    error_estimate: float = float("nan")
    observed_order: float = float("nan")


def _times(t0: float, t1: float, sample_hz: float) -> np.ndarray:
    n = max(2, int(round((t1 - t0) * sample_hz)) + 1)
    return np.linspace(t0, t1, n)


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
) -> Simulation:
    """Kineto-elastodynamics: the joints follow ``trajectory``, the elastic coordinates respond.

    Args:
        dyn: Equations of motion (model, design, gravity).
        trajectory: Joint samples (user convention) or a :class:`JointMotion`.
        after_s: Simulated time after the last sample, joints holding still [s].
        damping: Damping of the elastic motion (default none).
        sample_hz: Output sampling rate [Hz].
        method: ``"fixed"`` (default: trapezoidal rule at uniform steps, two step sizes,
            Richardson estimate and extrapolation, see :func:`richardson_fixed`),
            ``"newmark"`` (generalized-α, adaptive step, see :func:`newmark`) or a
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
            energy, no numerical damping; see :func:`newmark`). Default 1 for ``"fixed"``
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

    The hold phase after the stop is a constant-coefficient system, propagated exactly by its
    modes at the output rate (:func:`_modal_hold`); its ``steps`` are the output samples.
    """
    motion = trajectory if isinstance(trajectory, JointMotion) else JointMotion(trajectory)
    _check_positive(after_s=after_s, sample_hz=sample_hz, rtol=rtol, atol=atol)
    if dyn.locked:
        # a locked joint is a prescribed joint that does not move: the drive holds it
        Qp = np.asarray(motion.trajectory.q, dtype=float) @ dyn.model.coord_map.T
        for name, col in dyn.locked:
            span = float(np.ptp(Qp[:, col]))
            if span > 1e-9 * max(1.0, float(np.abs(Qp[:, col]).max())):
                raise ConfigurationError(
                    f"joint '{name}' is locked but the trajectory turns it by {span:.3g} (rad "
                    "or m): hold it constant in the trajectory, or do not lock it (joints='free'"
                    " or a spring stiffness)")
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
    system: Any = PrescribedSystem(dyn, motion, damping, forces)
    if modes is not None:
        system = _ReducedSystem(system, int(modes), int(basis_poses))
    nx = system.nx
    c0 = system.coefficients(motion.t0)
    x0 = np.zeros(nx)
    if start == "static" and np.any(c0.f):
        x0 = np.linalg.solve(c0.K, c0.f)
    knots = np.asarray(motion.trajectory.times_s, dtype=float)
    nx2 = nx * nx
    if exact:
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
        cs = [system.coefficients(t) for t in grid]
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

        omega1 = float(np.sqrt(max(_lowest_eig(c0.K, c0.M), 1e-30)))
        atol_vec = np.concatenate([np.full(nx, atol), np.full(nx, atol * omega1)])
        run1 = integrate(fun, jac, motion.t0, motion.t1, np.concatenate([x0, np.zeros(nx)]),
                         method=method, rtol=rtol, atol=atol_vec)
    # hold phase: constant coefficients at the final pose, exact propagation
    cend = system.coefficients(motion.t1)  # joints at rest there; forces frozen from here
    Aend, bend = system.state_matrix(cend)
    t_end = motion.t1 + after_s
    times = _times(motion.t0, t_end, sample_hz)
    hold = times > motion.t1
    dts = times[hold] - motion.t1
    held = _modal_hold(cend, run1.y_end, dts)
    Yh, Ydh = held if held is not None else _lti_propagate(Aend, bend, run1.y_end, dts,
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
    return Simulation(
        times_s=times, x=x, xd=xd, q=q, qd=qd, q_physical=q_phys, stop_s=motion.t1,
        drive="prescribed", joint_condition="locked", torque_times_s=t_tau, torques=tau,
        steps=run1.steps + int(hold.sum()), nfev=run1.nfev, time_s=elapsed, method=method,
        error_estimate=estimate, observed_order=order,
    )


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
    atol: float = 1e-10,
    atol_q: float = 1e-9,
    rho_inf: float = 0.9,
    corrections: int = 1,
    coefficient_step_s: float = 0.0,
    step_s: float | None = None,
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
        rtol: Relative tolerance.
        atol: Absolute tolerance on ``x`` [m, rad].
        atol_q: Absolute tolerance on ``q`` [rad].
        rho_inf: Generalized-α high-frequency spectral radius (1: no numerical damping).
        corrections: Corrector evaluations of eq. (1) per step (see :func:`newmark`).
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
    """
    _check_positive(duration_s=duration_s, sample_hz=sample_hz, rtol=rtol, atol=atol,
                    atol_q=atol_q)
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
    q0 = dyn.model.check_q(q0).astype(float)
    z0 = np.concatenate([np.zeros(nx) if x0 is None else np.asarray(x0, float), q0])
    zd0 = np.concatenate([np.zeros(nx) if xd0 is None else np.asarray(xd0, float),
                          np.zeros(nv) if qd0 is None else np.asarray(qd0, float)])
    z_ref = np.concatenate([np.zeros(nx), q0])
    motion = None
    if torque is None and trajectory is not None:
        motion = trajectory if isinstance(trajectory, JointMotion) else JointMotion(trajectory)

    if not (np.isfinite(coefficient_step_s) and coefficient_step_s >= 0.0):
        raise ConfigurationError(f"coefficient_step_s = {coefficient_step_s!r} must be >= 0")

    def joint_rows(q):
        A = dyn.joint_offsets(q)[0]
        return np.hstack([-(Cm @ A), Cm])

    def feedforward(t):
        qr, qdr, qddr = motion(t)
        M, Ck, _, F = dyn.linear_terms(qr)
        Cr = np.tensordot(qdr, Ck, axes=(0, 0))
        return np.linalg.solve(Cm.T, M[nx:, nx:] @ qddr + Cr[nx:, nx:] @ qdr - F[nx:])

    ff = None
    if motion is not None:
        knots = np.asarray(motion.trajectory.times_s, dtype=float)
        tg = np.unique(np.concatenate([
            np.linspace(a, b, max(2, int(np.ceil((b - a) / 5e-3 - 1e-9))) + 1)
            for a, b in zip(knots[:-1], knots[1:])]))
        ff_spline = CubicSpline(tg, np.array([feedforward(t) for t in tg]), axis=0)

        def ff(t):
            return ff_spline(min(max(t, tg[0]), tg[-1]))

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
        if damping.kind == "rayleigh":
            C[:nx, :nx] += damping.alpha * M[:nx, :nx] + damping.beta * K[:nx, :nx]
        f = F + G.T @ applied(t, z, zd, G, None) + K @ z_ref
        return M, C, K, f

    tic = time.perf_counter()
    kw: dict[str, Any] = {"rtol": rtol, "atol": atol, "h0": min(1.0 / sample_hz, duration_s / 10),
          "rho_inf": rho_inf, "corrections": max(1, int(corrections)),
          "groups": [(slice(0, nx), atol), (slice(nx, nd), atol_q)]}
    run: Any
    estimate = float("nan")
    if step_s is None:
        run = newmark(coeff, 0.0, duration_s, z0, zd0, **kw)
    else:
        _check_positive(step_s=step_s)
        n = max(2, int(np.ceil(duration_s / step_s - 1e-9)))
        history.clear()
        coarse = newmark(coeff, 0.0, duration_s, z0, zd0, fixed_steps=n, **kw)
        history.clear()
        fine = newmark(coeff, 0.0, duration_s, z0, zd0, fixed_steps=2 * n, **kw)
        d = fine.x[::2] - coarse.x
        estimate = float(np.abs(d[:, :nx]).max()
                         / (3.0 * max(float(np.abs(fine.x[:, :nx]).max()), 1e-300)))
        run = _NewmarkRun(coarse.t, (4.0 * fine.x[::2] - coarse.x) / 3.0,
                          (4.0 * fine.v[::2] - coarse.v) / 3.0, coarse.a,
                          coarse.nfev + fine.nfev)
        run.steps = fine.steps
    elapsed = time.perf_counter() - tic
    times = _times(0.0, duration_s, sample_hz)
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
    )


def energy(dyn: ErlsDynamics, z: np.ndarray, zd: np.ndarray) -> float:
    """Kinetic plus strain energy ``½ żᵀ M(q) ż + ½ xᵀ K x`` [J] of one state ``[x; q]``."""
    M, _, K, _ = dyn.linear_terms(z[dyn.nx:])
    x = z[: dyn.nx]
    return float(0.5 * zd @ M @ zd + 0.5 * x @ K[: dyn.nx, : dyn.nx] @ x)


def _lowest_eig(K, M) -> float:
    import scipy.linalg

    return float(scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, 0])[0])


def _modal_hold(c: _Coefficients, y0: np.ndarray, dts: np.ndarray):
    """Exact ``(y, ẏ)`` of the held arm ``M ẍ + C ẋ + K x = f`` (constant) after the stop.

    By its mass-normalised modes ``Φ`` (``scipy.linalg.eigh(K, M)``): with classical damping
    (none, Rayleigh, modal) ``Φᵀ C Φ`` is diagonal and every mode is a damped oscillator with
    a closed-form solution. ``None`` when the damping couples the modes.
    """
    import scipy.linalg

    nx = c.M.shape[0]
    lam, phi = scipy.linalg.eigh(c.K, c.M)
    cd = phi.T @ c.C @ phi
    if np.abs(cd - np.diag(np.diag(cd))).max() > 1e-9 * max(np.abs(cd).max(), 1e-300) + 1e-12:
        return None
    xs = np.linalg.solve(c.K, c.f)
    w = np.sqrt(np.clip(lam, 0.0, None))
    zeta = np.diag(cd) / (2.0 * np.maximum(w, 1e-300))
    e0 = phi.T @ c.M @ (y0[:nx] - xs)
    ed0 = phi.T @ c.M @ y0[nx:]
    t = dts[:, None]
    disc = np.sqrt((zeta**2 - 1.0).astype(complex))
    r1, r2 = w * (-zeta + disc), w * (-zeta - disc)
    crit = np.abs(r1 - r2) < 1e-9 * np.maximum(w, 1.0)
    dr = np.where(crit, 1.0, r1 - r2)
    a = (ed0 - r2 * e0) / dr
    b = e0 - a
    eta = (a * np.exp(r1 * t) + b * np.exp(r2 * t)).real
    etad = (a * r1 * np.exp(r1 * t) + b * r2 * np.exp(r2 * t)).real
    etadd = (a * r1**2 * np.exp(r1 * t) + b * r2**2 * np.exp(r2 * t)).real
    if np.any(crit):
        k = np.flatnonzero(crit)
        ex = np.exp(-w[k] * t)
        g = ed0[k] + w[k] * e0[k]
        eta[:, k] = (e0[k] + g * t) * ex
        etad[:, k] = (g - w[k] * (e0[k] + g * t)) * ex
        etadd[:, k] = (-2 * w[k] * g + w[k] ** 2 * (e0[k] + g * t)) * ex
    y = np.hstack([xs[None, :] + eta @ phi.T, etad @ phi.T])
    yd = np.hstack([etad @ phi.T, etadd @ phi.T])
    return y, yd


def _lti_propagate(A: np.ndarray, b: np.ndarray, y0: np.ndarray, dts: np.ndarray,
                   rates: bool = False):
    """Exact ``y(t)`` of ``ẏ = A y + b`` from ``y0`` at times ``dts`` (n,) after the start.

    By the eigen-decomposition of ``A`` (the modes of the held arm); with ``rates`` also
    ``ẏ(t)`` from the same modal sum (no cancellation of ``K x`` against the loads).
    """
    ys = -np.linalg.solve(A, b)  # equilibrium
    lam, V = np.linalg.eig(A)
    c = np.linalg.solve(V, y0 - ys)
    ex = np.exp(np.outer(dts, lam)) * c[None, :]
    out = (ex @ V.T).real + ys[None, :]
    if rates:
        return out, ((ex * lam[None, :]) @ V.T).real
    return out


class _NewmarkRun:
    """Steps of a Newmark run; call with times -> states [x, ẋ] (cubic Hermite in between).

    The output is sampled between steps by cubic Hermite interpolation of ``(x, ẋ)``; the steps
    are short against the resolved periods (the error control keeps ``h² Δa`` small).
    """

    def __init__(self, t, x, v, a, nfev):
        self.t, self.x, self.v, self.a = t, x, v, a
        self.steps = t.size - 1
        self.nfev = nfev
        self.y_end = np.concatenate([x[-1], v[-1]])

    def __call__(self, times):
        times = np.atleast_1d(np.asarray(times, dtype=float))
        k = np.clip(np.searchsorted(self.t, times) - 1, 0, self.t.size - 2)
        h = (self.t[k + 1] - self.t[k])[:, None]
        s = ((times - self.t[k])[:, None]) / h
        x0, x1, v0, v1 = self.x[k], self.x[k + 1], self.v[k], self.v[k + 1]
        # cubic Hermite on (x, v) at both ends for x, its derivative for v
        h00, h10 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s
        h01, h11 = -2 * s**3 + 3 * s**2, s**3 - s**2
        x = h00 * x0 + h * h10 * v0 + h01 * x1 + h * h11 * v1
        d00, d10 = 6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1
        d11 = 3 * s**2 - 2 * s
        v = (d00 * (x0 - x1)) / h + d10 * v0 + d11 * v1
        return np.hstack([x, v])


def newmark(coeff, t0: float, t1: float, x0, v0, *, rtol=1e-4, atol=1e-9, h0=1e-4,
            h_min=1e-9, rho_inf: float = 0.9, corrections: int = 0,
            groups=None, fixed_steps: int | None = None) -> _NewmarkRun:
    """Generalized-α (Chung–Hulbert 1993) integration of ``M(t) ẍ + C(t) ẋ + K(t) x = f(t)``.

    A Newmark scheme with ``α_m = (2ρ∞ − 1)/(ρ∞ + 1)``, ``α_f = ρ∞/(ρ∞ + 1)``,
    ``γ = ½ − α_m + α_f``, ``β = ¼ (1 − α_m + α_f)²``: unconditionally stable, second order, with
    the spectral radius ``ρ∞`` at infinite frequency. ``ρ∞ = 1`` is the average-acceleration
    (trapezoidal) rule, which conserves the energy of a constant linear system exactly;
    ``ρ∞ < 1`` damps the unresolved high beam modes (their numerical ringing would otherwise
    persist) and barely touches the resolved ones. The equation is enforced at
    ``t_{n+1−α_f}`` with the coefficients there. The step is adapted with the local error
    estimate of Zienkiewicz and Xie (1991), ``e = (β − 1/6) h² (a_{n+1} − a_n)`` in the
    displacements: a step is accepted when ``max |e| / (atol + rtol max|x|) <= 1`` and the next
    one scaled by ``0.9 (1/err)^{1/3}`` (bounded to [0.3, 2]).

    Args:
        coeff: ``t -> (M, C, K, f)``.
        t0: Start [s].
        t1: End [s].
        x0: Initial displacement.
        v0: Initial rate.
        rtol: Relative tolerance.
        atol: Absolute tolerance (units of ``x``).
        h0: First step [s].
        h_min: Smallest step [s]; a step this small is accepted whatever its error.
        rho_inf: Spectral radius at infinite frequency, in [0, 1].
        corrections: For a state-dependent system, ``coeff(t, x, v)`` is evaluated at the
            predicted state and then this many times at the corrected one (each time the
            step is solved again with the new coefficients); 0 for a linear system
            ``coeff(t)``.
        groups: Optional ``[(rows, atol), ...]``: coordinate groups with their own absolute
            tolerance, each controlled separately (default: all with ``atol``).
        fixed_steps: Take this many equal steps and no error control (``rtol``, ``atol``,
            ``h0`` unused).
    """
    if not 0.0 <= rho_inf <= 1.0:
        raise ConfigurationError(f"rho_inf = {rho_inf!r} must lie in [0, 1]")
    am = (2.0 * rho_inf - 1.0) / (rho_inf + 1.0)
    af = rho_inf / (rho_inf + 1.0)
    gamma = 0.5 - am + af
    beta = 0.25 * (1.0 - am + af) ** 2
    x, v = np.asarray(x0, float).copy(), np.asarray(v0, float).copy()
    M, C, K, f = coeff(t0, x, v) if corrections else coeff(t0)
    a = np.linalg.solve(M, f - C @ v - K @ x)
    groups = [(slice(None), atol)] if groups is None else groups
    T, X, V, Aa = [t0], [x], [v], [a]
    t, h, nfev = t0, min(h0, t1 - t0), 1
    if fixed_steps is not None:
        h = (t1 - t0) / int(fixed_steps)
    while t < t1 - 1e-14 * max(1.0, abs(t1)):
        h = min(h, t1 - t)
        xp = x + h * v + (0.5 - beta) * h * h * a
        vp = v + (1 - gamma) * h * a
        x1, v1, a1 = xp, vp, a
        for _ in range(corrections + 1):
            tm = t + (1.0 - af) * h
            if corrections:
                M, C, K, f = coeff(tm, (1 - af) * x1 + af * x, (1 - af) * v1 + af * v)
            else:
                M, C, K, f = coeff(tm)
            nfev += 1
            # (1−α_m) M a1 + α_m M a + (1−α_f)(C v1 + K x1) + α_f (C v + K x) = f(t_{n+1−α_f})
            lhs = (1.0 - am) * M + (1.0 - af) * (gamma * h * C + beta * h * h * K)
            rhs = (f - am * (M @ a) - (1.0 - af) * (C @ vp + K @ xp) - af * (C @ v + K @ x))
            try:
                a1 = np.linalg.solve(lhs, rhs)
            except np.linalg.LinAlgError as exc:
                raise SimulationError(
                    f"the step at t = {tm:.6g} s failed (singular system): the run diverged; "
                    "take smaller or adaptive steps") from exc
            if not np.all(np.isfinite(a1)):
                raise SimulationError(f"the run diverged at t = {tm:.6g} s: take smaller or "
                                      "adaptive steps")
            x1 = xp + beta * h * h * a1
            v1 = vp + gamma * h * a1
        est = np.abs((beta - 1.0 / 6.0) * h * h * (a1 - a))
        err = max(float(est[r].max()) / (tol + rtol * max(float(np.abs(x1[r]).max()),
                                                            float(np.abs(x[r]).max())))
                  for r, tol in groups)
        if fixed_steps is not None:
            t = t0 + len(T) * (t1 - t0) / int(fixed_steps)
            x, v, a = x1, v1, a1
            T.append(t)
            X.append(x)
            V.append(v)
            Aa.append(a)
            continue
        if err <= 1.0 or h <= h_min:
            t += h
            x, v, a = x1, v1, a1
            T.append(t)
            X.append(x)
            V.append(v)
            Aa.append(a)
        h *= min(2.0, max(0.3, 0.9 * (1.0 / max(err, 1e-12)) ** (1.0 / 3.0)))
        h = max(h, h_min)
    return _NewmarkRun(np.array(T), np.array(X), np.array(V), np.array(Aa), nfev)


def fixed_step(coeffs, t0: float, t1: float, n_steps: int, x0, v0, *, rho_inf: float = 1.0,
               grid=None, chunk: int = 256):
    """Generalized-α (see :func:`newmark`) at ``n_steps`` uniform steps on ``[t0, t1]``.

    ``coeffs(times) -> (M, C, K, f)`` evaluates the linear system at many times at once
    ((n, m, m) and (n, m)). Each step is ``a_{n+1} = G(t_{n+1−α_f}) [x_n; v_n; a_n; 1]`` with
    the step operator ``G = lhs⁻¹ [−K, …, f]`` of the scheme (``lhs = (1−α_m) M + (1−α_f)(γ h C
    + β h² K)``). With ``grid`` (times, covering ``[t0, t1]``) ``G`` is solved exactly at the
    grid times only and interpolated by a cubic spline in time, like the coefficients
    themselves (it is as smooth in time as they are); without it, it is solved at every step
    in batches of ``chunk``. The loop costs a few small vector operations per step. Returns
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
    x = np.asarray(x0, dtype=float).copy()
    v = np.asarray(v0, dtype=float).copy()
    m = x.size
    M0, C0, K0, f0 = coeffs(np.array([t0]))
    a = np.linalg.solve(M0[0], f0[0] - C0[0] @ v - K0[0] @ x)
    b2, bh, g1, gh = (0.5 - beta) * h * h, beta * h * h, (1.0 - gamma) * h, gamma * h
    # rhs = f − K x − (C + (1−α_f) h K) v − (α_m M + (1−α_f)((1−γ) h C + (½−β) h² K)) a and
    # α_m M = r lhs − r (1−α_f)(γ h C + β h² K), r = α_m / (1 − α_m): three solves suffice
    r = am / (1.0 - am)
    ca_C = (1.0 - af) * (r * gamma * h - g1)
    ca_K = (1.0 - af) * (r * beta * h * h - b2)

    def operators(ts):
        M, C, K, f = coeffs(ts)
        lhs = (1.0 - am) * M + (1.0 - af) * (gamma * h * C + beta * h * h * K)
        H = np.linalg.solve(lhs, np.concatenate([K, C, f[:, :, None]], axis=2))
        HK, HC = H[:, :, :m], H[:, :, m:2 * m]
        G = np.empty((ts.size, m, 3 * m + 1))
        G[:, :, :m] = -HK
        G[:, :, m:2 * m] = -HC - (1.0 - af) * h * HK
        G[:, :, 2 * m:3 * m] = ca_C * HC + ca_K * HK
        G[:, :, 2 * m:3 * m] -= r * np.eye(m)
        G[:, :, -1] = H[:, :, -1]
        return G

    if grid is not None:
        grid = np.asarray(grid, dtype=float)
        g_spline = CubicSpline(grid, operators(grid), axis=0)

        def step_operators(ts):
            return g_spline(np.clip(ts, grid[0], grid[-1]))
    else:
        step_operators = operators
    # state rows s = [x; v; a; 1]: [x; v; a]_{n+1} = B s_n + w ∘ (a_{n+1} repeated 3 times)
    S = np.empty((n_steps + 1, 3 * m + 1))
    S[:, -1] = 1.0
    S[0, :m], S[0, m:2 * m], S[0, 2 * m:3 * m] = x, v, a
    eye = np.eye(m)
    B = np.zeros((3 * m, 3 * m + 1))
    B[:m, :m], B[:m, m:2 * m], B[:m, 2 * m:3 * m] = eye, h * eye, b2 * eye
    B[m:2 * m, m:2 * m], B[m:2 * m, 2 * m:3 * m] = eye, g1 * eye
    w = np.concatenate([np.full(m, bh), np.full(m, gh), np.ones(m)])
    rep = np.tile(np.arange(m), 3)
    for s0 in range(0, n_steps, chunk):
        s1 = min(n_steps, s0 + chunk)
        G = step_operators(t[s0:s1] + (1.0 - af) * h)
        for k in range(s1 - s0):
            row = S[s0 + k]
            np.add(B @ row, w * (G[k] @ row)[rep], out=S[s0 + k + 1, :-1])
    X, V, A = S[:, :m], S[:, m:2 * m], S[:, 2 * m:3 * m]
    return t, X, V, A


@dataclass
class RichardsonRun:
    """Extrapolated fixed-step run: dense output like :class:`_NewmarkRun` plus estimates.

    Attributes:
        steps: Steps of the finer run (``2N``); ``nfev`` all step evaluations of the ladder.
        error_estimate: Richardson estimate of the finer run's error,
            ``max |x_2N − x_N| / 3`` over the grid and the coordinates, relative to
            ``max |x|``; the extrapolated result returned is at least this accurate where the
            error behaves as ``c h²`` (checked by ``observed_order``).
        observed_order: ``log2`` of the ratio of the last two differences of the ladder
            (``≈ 2`` in the asymptotic range; NaN with only two runs).
        ladder: ``[(steps, estimate), ...]`` of every pair tried.
    """

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    steps: int
    nfev: int
    error_estimate: float
    observed_order: float
    ladder: list

    def __post_init__(self):
        self._dense = _NewmarkRun(self.t, self.x, self.v, self.v, self.nfev)
        self.y_end = self._dense.y_end

    def __call__(self, times):
        """States ``[x, ẋ]`` (n, 2 m) at ``times`` (cubic Hermite between grid points)."""
        return self._dense(times)


def richardson_fixed(coeffs, t0: float, t1: float, x0, v0, *, n_steps: int,
                     tol: float | None = None, rho_inf: float = 1.0, grid=None,
                     max_steps: int = 2_000_000) -> RichardsonRun:
    """Trapezoidal runs at ``N`` and ``2N`` steps, extrapolated; doubling ``N`` until ``tol``.

    With ``tol`` the pair ``(N, 2N)`` is replaced by ``(2N, 4N)`` (the finer run reused) until
    the Richardson estimate of the finer run's error is at most ``tol`` (relative to the
    largest ``|x|``) *and* the last two differences of the ladder shrink at least as
    ``h^1.5`` (observed order ≥ 1.5: the asymptotic range where the estimate holds; so at
    least three runs); ``max_steps`` bounds the finer run. Without ``tol`` one pair is run and
    its estimate is not checked for the asymptotic range (``observed_order`` NaN): too coarse
    a ``N`` can then be off by more than its estimate.

    Raises:
        SimulationError: ``tol`` not met within ``max_steps``.
    """
    n = max(2, int(n_steps))
    coarse = fixed_step(coeffs, t0, t1, n, x0, v0, rho_inf=rho_inf, grid=grid)
    nfev = n
    ladder: list = []
    diffs: list[float] = []
    while True:
        fine = fixed_step(coeffs, t0, t1, 2 * n, x0, v0, rho_inf=rho_inf, grid=grid)
        nfev += 2 * n
        d = fine[1][::2] - coarse[1]
        scale = max(float(np.abs(fine[1]).max()), 1e-300)
        est = float(np.abs(d).max()) / (3.0 * scale)
        diffs.append(float(np.abs(d).max()))
        ladder.append((2 * n, est))
        order = (float(np.log2(diffs[-2] / diffs[-1])) if len(diffs) > 1 and diffs[-1] > 0
                 else float("nan"))
        # with tol: the estimate must meet it and the ladder must show the error shrinking at
        # least as h^1.5 (the asymptotic range where the estimate holds)
        if tol is None or (est <= tol and (order >= 1.5 or diffs[-1] == 0.0)):
            break
        if 4 * n > max_steps:
            raise SimulationError(
                f"the time step needed for tol = {tol:g} exceeds {max_steps} steps (estimate "
                f"{est:.3g} at {2 * n} steps): loosen tol or shorten the motion")
        coarse, n = fine, 2 * n
    t = coarse[0]
    x = (4.0 * fine[1][::2] - coarse[1]) / 3.0
    v = (4.0 * fine[2][::2] - coarse[2]) / 3.0
    return RichardsonRun(t, x, v, 2 * n, nfev, est, order, ladder)


def _affine(c, y):
    return c[0] @ y + c[1]


class _Run:
    """Dense output of one integration: call with times (n,) -> states (n, ny)."""

    def __init__(self, pieces, y_end, steps, nfev):
        self.pieces, self.y_end, self.steps, self.nfev = pieces, y_end, steps, nfev
        self._t = np.array([p.t_max for p in pieces])

    def __call__(self, times):
        times = np.atleast_1d(np.asarray(times, dtype=float))
        out = np.empty((times.size, self.y_end.size))
        idx = np.clip(np.searchsorted(self._t, times), 0, len(self.pieces) - 1)
        for k in np.unique(idx):
            sel = idx == k
            out[sel] = self.pieces[k](times[sel]).T
        return out


def integrate(fun, jac, t0, t1, y0, *, method="Radau", rtol=1e-8, atol=1e-12) -> _Run:
    """Step a ``scipy.integrate`` solver from ``t0`` to ``t1`` and keep its dense output.

    Counts the accepted steps (``solve_ivp`` does not report them).
    """
    from scipy.integrate import BDF, DOP853, LSODA, RK45, Radau

    solvers = {"Radau": Radau, "BDF": BDF, "LSODA": LSODA, "DOP853": DOP853, "RK45": RK45}
    if method not in solvers:
        raise ConfigurationError(f"method = {method!r}: choose one of {sorted(solvers)}")
    kw = {"jac": jac} if method in ("Radau", "BDF", "LSODA") else {}
    solver = solvers[method](fun, t0, np.asarray(y0, dtype=float), t1, rtol=rtol, atol=atol,
                             **kw)
    pieces, steps = [], 0
    if t1 <= t0:
        raise ConfigurationError(f"integration interval [{t0}, {t1}] is empty")
    while solver.status == "running":
        msg = solver.step()
        if solver.status == "failed":
            raise SimulationError(f"the integrator ({method}) failed at t = {solver.t:.6g} s: "
                                  f"{msg}")
        steps += 1
        pieces.append(solver.dense_output())
    return _Run(pieces, solver.y.copy(), steps, int(solver.nfev))


def _check_positive(**values) -> None:
    bad = [f"{k} = {v!r}" for k, v in values.items() if not (np.isfinite(v) and v > 0.0)]
    if bad:
        raise ConfigurationError("must be positive and finite: " + ", ".join(bad))
