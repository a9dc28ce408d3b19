"""Integrators of the linear (time-varying) and nonlinear second-order systems of eq. (1).

* :func:`fixed_step` / :func:`richardson_fixed`: generalized-α at uniform steps, vectorised
  step operators; two step sizes extrapolated (Richardson) with an error estimate;
* :func:`newmark`: generalized-α with adaptive steps (state-dependent systems too);
* :func:`integrate`: a ``scipy.integrate`` solver with dense output;
* :func:`modal_hold` / :func:`lti_propagate`: exact propagation of a constant system.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from pinflex.dynamics.result import SimulationError
from pinflex.exceptions import ConfigurationError


def lowest_eig(K, M) -> float:
    """The lowest eigenvalue of ``(K, M)`` (symmetric, ``M`` positive definite)."""
    import scipy.linalg

    return float(scipy.linalg.eigh(K, M, eigvals_only=True, subset_by_index=[0, 0])[0])


def modal_hold(c, y0: np.ndarray, dts: np.ndarray):
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


def lti_propagate(A: np.ndarray, b: np.ndarray, y0: np.ndarray, dts: np.ndarray,
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


class NewmarkRun:
    """Steps of a Newmark run; call with times -> states [x, ẋ] (cubic Hermite in between).

    The output is sampled between steps by cubic Hermite interpolation of ``(x, ẋ)``; the steps
    are short against the resolved periods (the error control keeps ``h² Δa`` small).
    """

    def __init__(self, t, x, v, a, nfev):
        self.t, self.x, self.v, self.a = t, x, v, a
        self.steps = t.size - 1
        self.nfev = nfev
        self.rejected_corrector = 0  # steps halved because the corrector did not converge
        self.y_end = np.concatenate([x[-1], v[-1]])

    def __call__(self, times):
        """States ``[x, ẋ]`` (n, 2 m) at ``times`` (n,) [s]."""
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


#: A state-dependent step's corrector has converged when its last change of the displacements
#: is at most this fraction of the step's error tolerance (:func:`newmark`).
CORRECTOR_TOLERANCE = 1e-2


def newmark(coeff, t0: float, t1: float, x0, v0, *, rtol=1e-4, atol=1e-9, h0=1e-4,
            h_min=1e-9, rho_inf: float = 0.9, corrections: int = 0,
            groups=None, fixed_steps: int | np.ndarray | None = None,
            scale: str = "step") -> NewmarkRun:
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
            predicted state and then at most this many times at the corrected one (each time
            the step is solved again with the new coefficients: a fixed-point iteration)
            until the last correction changes the displacements by at most
            :data:`CORRECTOR_TOLERANCE` of the error tolerance; a step whose corrector has not
            converged is retried at half the size (with ``fixed_steps``:
            :class:`SimulationError`). Stiff state-dependent forces belong in ``C`` and ``K``
            (solved implicitly), not in ``f``: a fixed-point iteration on them converges only
            for steps below their time constant. 0 for a linear system ``coeff(t)``.
        groups: Optional ``[(rows, atol), ...]``: coordinate groups with their own absolute
            tolerance, each controlled separately (default: all with ``atol``).
        fixed_steps: Take this many equal steps, or steps between these times (from ``t0``
            to ``t1``), and no error control (``rtol``, ``atol``, ``h0`` unused).
        scale: What ``rtol`` is relative to: ``"step"`` the step's own ``|x|`` (largest of
            both ends, per group), ``"peak"`` the largest ``|x|`` of the group so far in the
            run (errors relative to the peak deflection; ``atol`` only a floor).
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
    rejected_corrector, change = 0, float("nan")
    if scale not in ("step", "peak"):
        raise ConfigurationError(f"scale = {scale!r} must be 'step' or 'peak'")
    peak = [float(np.abs(x[r]).max(initial=0.0)) if scale == "peak" else 0.0
            for r, _ in groups]

    def norm(e, x_new):
        """Largest ``|e|`` over ``atol + rtol · scale`` of each group."""
        return max(float(np.abs(e[r]).max(initial=0.0))
                   / (tol + rtol * max(float(np.abs(x_new[r]).max(initial=0.0)),
                                       float(np.abs(x[r]).max(initial=0.0)), p))
                   for (r, tol), p in zip(groups, peak))

    step_grid = None
    if fixed_steps is not None and np.ndim(fixed_steps) == 1:
        step_grid = np.asarray(fixed_steps, dtype=float)
        if not (step_grid[0] == t0 and step_grid[-1] == t1 and np.all(np.diff(step_grid) > 0)):
            raise ConfigurationError("fixed_steps (times) must rise from t0 to t1")
    elif fixed_steps is not None:
        h = (t1 - t0) / int(fixed_steps)
    while t < t1 - 1e-14 * max(1.0, abs(t1)):
        if step_grid is not None:
            h = step_grid[len(T)] - t
        h = min(h, t1 - t)
        xp = x + h * v + (0.5 - beta) * h * h * a
        vp = v + (1 - gamma) * h * a
        x1, v1, a1 = xp, vp, a
        converged = not corrections
        for it in range(corrections + 1):
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
            x_new = xp + beta * h * h * a1
            if it:  # the corrector's change, in the error norm: converged well below it
                change = norm(x_new - x1, x_new)
                converged = change <= CORRECTOR_TOLERANCE
            x1 = x_new
            v1 = vp + gamma * h * a1
            if converged:
                break
        if not converged:  # the corrector (a fixed-point iteration) has not converged
            if fixed_steps is not None:
                raise SimulationError(
                    f"the step at t = {t:.6g} s did not converge in {corrections} corrections "
                    f"(last change {change:.3g} of the tolerance): take smaller or adaptive "
                    "steps, or more corrections")
            if h > h_min:
                h = max(0.5 * h, h_min)
                rejected_corrector += 1
                continue
        err = norm((beta - 1.0 / 6.0) * h * h * (a1 - a), x1)
        if fixed_steps is not None:
            t = (step_grid[len(T)] if step_grid is not None
                 else t0 + len(T) * (t1 - t0) / int(fixed_steps))
            x, v, a = x1, v1, a1
            T.append(t)
            X.append(x)
            V.append(v)
            Aa.append(a)
            continue
        if err <= 1.0 or h <= h_min:
            t += h
            x, v, a = x1, v1, a1
            if scale == "peak":
                peak = [max(p, float(np.abs(x[r]).max(initial=0.0)))
                        for (r, _), p in zip(groups, peak)]
            T.append(t)
            X.append(x)
            V.append(v)
            Aa.append(a)
        h *= min(2.0, max(0.3, 0.9 * (1.0 / max(err, 1e-12)) ** (1.0 / 3.0)))
        h = max(h, h_min)
    run = NewmarkRun(np.array(T), np.array(X), np.array(V), np.array(Aa), nfev)
    run.rejected_corrector = rejected_corrector
    return run


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
    """Extrapolated fixed-step run: dense output like :class:`NewmarkRun` plus estimates.

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
        self._dense = NewmarkRun(self.t, self.x, self.v, self.v, self.nfev)
        self.y_end = self._dense.y_end

    def __call__(self, times):
        """States ``[x, ẋ]`` (n, 2 m) at ``times`` (cubic Hermite between grid points)."""
        return self._dense(times)


def richardson_fixed(coeffs, t0: float, t1: float, x0, v0, *, n_steps: int,
                     tol: float | None = None, rho_inf: float = 1.0, grid=None,
                     max_steps: int = 2_000_000, stepper=None) -> RichardsonRun:
    """Trapezoidal runs at ``N`` and ``2N`` steps, extrapolated; doubling ``N`` until ``tol``.

    With ``tol`` the pair ``(N, 2N)`` is replaced by ``(2N, 4N)`` (the finer run reused) until
    the Richardson estimate of the finer run's error is at most ``tol`` (relative to the
    largest ``|x|``) *and* the last two differences of the ladder shrink at least as
    ``h^1.5`` (observed order ≥ 1.5: the asymptotic range where the estimate holds; so at
    least three runs); ``max_steps`` bounds the finer run. Without ``tol`` one pair is run and
    its estimate is not checked for the asymptotic range (``observed_order`` NaN): too coarse
    a ``N`` can then be off by more than its estimate. ``stepper`` replaces :func:`fixed_step`
    (same arguments and returns).

    Raises:
        SimulationError: ``tol`` not met within ``max_steps``.
    """
    step = fixed_step if stepper is None else stepper
    n = max(2, int(n_steps))
    coarse = step(coeffs, t0, t1, n, x0, v0, rho_inf=rho_inf, grid=grid)
    nfev = n
    ladder: list = []
    diffs: list[float] = []
    while True:
        fine = step(coeffs, t0, t1, 2 * n, x0, v0, rho_inf=rho_inf, grid=grid)
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

