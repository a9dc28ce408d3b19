r"""Global fits with one stiffness correction factor per pose, the factors solved exactly.

The objective of a design is evaluated at its best factors (:func:`best_factors`):

* **eigen-only**: the closed form of :mod:`pinflex.prbdm.perpose`;
* **deflection** (the code's definitions: pose i's statics use pose i's springs): the error
  d(k) depends on the factor alone, and one factor, d's minimum, serves every pose;
* **combined** (eq. 27, :math:`F = \sqrt{A^2 + B^2}` of the aggregated frequency loss A and
  deflection loss B): F is stationary where every pose's factor minimises
  :math:`e_i(k) + \rho\,d(k)` with :math:`\rho = B/A`. For a given :math:`\rho` each pose's
  factor is the root of :math:`e_i' + \rho\,d'` between its frequency optimum and d's
  minimum (safeguarded Newton); B/A falls as :math:`\rho` grows, and :math:`\rho = B/A` is
  found by bisection on :math:`\log\rho`.

d(k) is computed by batched Newton statics on a grid of factors, uniform in log k and
widened until it holds d's minimum and every pose's frequency optimum, and interpolated by
cubic Hermite pieces with spline slopes. The reported losses are recomputed with exact
statics at the factors found; since the factors are stationary, an interpolation error
enters the value only to second order.

The fractions are searched globally (:func:`fit_posed`): a sample of the feasible simplex
(eq. 15b-d; with deflection a quarter on its faces) evaluated in batches, and SLSQP polishes
of its best distinct samples until two of them agree on the best value. With deflection the
polish's gradient is taken at the design's best factors held fixed (the envelope theorem):
the interpolated factor search is accurate in value but not differentiable at a difference
step. Every polished value is kept, so the stability of the optimum over starts is part of
the result.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.optimize import minimize

from ..exceptions import InvalidChain, MappingFailed, OptimumNotConfirmedWarning
from ..progress import ProgressBar
from .perpose import (
    PosedProblem,
    deflection_errors,
    eigen_loss,
    eigen_terms,
    per_mode_errors,
    pose_errors,
)
from .problem import MIN_FRACTION

#: Objectives of a per-pose-factor fit.
PER_POSE_OBJECTIVES = ("eigen", "deflection", "combined")
#: Statics grid of the factor per design (uniform in log k).
GRID = 40


@dataclass(frozen=True)
class PoseFactors:
    """The best factors of designs and their losses under the problem's definitions.

    Attributes:
        value: The objective (eigen, deflection or eq. 27 combined), (S,) [-].
        factors: Correction factor per pose, (S, m).
        frequency: Aggregated frequency loss, (S,) [-].
        deflection: Aggregated deflection loss, (S,) (NaN when not computed) [-].
        pose_frequency: Frequency loss per pose, (S, m).
        pose_deflection: Deflection error per pose, (S, m) (NaN when not computed).
    """

    value: np.ndarray
    factors: np.ndarray
    frequency: np.ndarray
    deflection: np.ndarray
    pose_frequency: np.ndarray
    pose_deflection: np.ndarray


class _Curves:
    """d(u) of S designs, u = log k, as cubic Hermite pieces on a uniform grid per design."""

    def __init__(self, lo: np.ndarray, hi: np.ndarray, values: np.ndarray):
        self.u0 = np.log(lo)
        self.h = np.log(hi / lo) / (GRID - 1)
        self.y = values
        t = np.arange(GRID, dtype=float)
        self.dy = CubicSpline(t, values, axis=1)(t, 1)       # slopes per grid step

    def __call__(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Values and first and second derivatives by u at u (S, ...), clamped to the grid."""
        shape = u.shape
        t = np.clip((u.reshape(shape[0], -1) - self.u0[:, None]) / self.h[:, None], 0.0,
                    GRID - 1.0)
        j = np.minimum(t.astype(int), GRID - 2)
        x = t - j
        rows = np.arange(shape[0])[:, None]
        y0, y1 = self.y[rows, j], self.y[rows, j + 1]
        m0, m1 = self.dy[rows, j], self.dy[rows, j + 1]
        x2, x3 = x * x, x * x * x
        value = (2 * x3 - 3 * x2 + 1) * y0 + (x3 - 2 * x2 + x) * m0 \
            + (-2 * x3 + 3 * x2) * y1 + (x3 - x2) * m1
        slope = (6 * x2 - 6 * x) * y0 + (3 * x2 - 4 * x + 1) * m0 \
            + (-6 * x2 + 6 * x) * y1 + (3 * x2 - 2 * x) * m1
        curve = (12 * x - 6) * (y0 - y1) + (6 * x - 4) * m0 + (6 * x - 2) * m1
        h = self.h[:, None]
        return value.reshape(shape), (slope / h).reshape(shape), (curve / h**2).reshape(shape)

    def minimum(self) -> np.ndarray:
        """Log factor of each design's minimum of d (best grid node refined by bisection)."""
        j = np.clip(np.argmin(self.y, axis=1), 1, GRID - 2)
        a = self.u0 + (j - 1) * self.h
        b = self.u0 + (j + 1) * self.h
        return _bisect(lambda u: self(u)[1:], a[:, None], b[:, None], 40)[:, 0]


def _bisect(slope: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]], a: np.ndarray,
            b: np.ndarray, iterations: int = 12) -> np.ndarray:
    """Root of an increasing function between a and b (elementwise): safeguarded Newton.

    ``slope(u)`` returns the function and its derivative. A Newton step that leaves the
    bracket, or meets a non-positive derivative, is replaced by the bracket's midpoint.
    """
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    x = 0.5 * (lo + hi)
    for _ in range(iterations):
        f, df = slope(x)
        lo, hi = np.where(f < 0.0, x, lo), np.where(f < 0.0, hi, x)
        step = x - f / np.where(df > 0.0, df, 1.0)
        good = (df > 0.0) & (step > lo) & (step < hi)
        x = np.where(good, step, 0.5 * (lo + hi))
    return x


def _deflection_curves(problem: PosedProblem, gammas: np.ndarray, lo: np.ndarray,
                       hi: np.ndarray) -> _Curves:
    """The deflection error of each design on a log grid holding its minimum and [lo, hi]."""
    lo, hi = lo / 1.5, hi * 1.5
    t = np.linspace(0.0, 1.0, GRID)
    d = np.empty((gammas.shape[0], GRID))
    todo = np.arange(gammas.shape[0])
    for _ in range(6):
        grid = lo[todo, None] * (hi[todo, None] / lo[todo, None]) ** t
        d[todo] = deflection_errors(problem, gammas[todo], grid)
        best = np.argmin(d[todo], axis=1)
        low_edge, high_edge = best == 0, best == GRID - 1
        lo[todo[low_edge]] /= 4.0
        hi[todo[high_edge]] *= 4.0
        todo = todo[low_edge | high_edge]
        if todo.size == 0:
            break
    return _Curves(lo, hi, d)


def best_factors(problem: PosedProblem, gammas: np.ndarray, objective: str) -> PoseFactors:
    """Optimal factors of designs (S, n + 1) for an objective, with exact losses."""
    gammas = np.atleast_2d(np.asarray(gammas, dtype=float))
    per_pose, k_eig, v = eigen_terms(problem, gammas)
    combine = problem.definitions.combine
    n_d, m = k_eig.shape
    if objective == "eigen":
        value = combine(per_pose)
        return PoseFactors(value, k_eig, value, np.full(n_d, np.nan), per_pose,
                           np.full((n_d, m), np.nan))
    curves = _deflection_curves(problem, gammas, k_eig.min(1), k_eig.max(1))
    u_d = curves.minimum()
    if objective == "deflection":
        u = np.repeat(u_d[:, None], m, axis=1)
    else:
        u = _combined_factors(problem, v, np.log(k_eig), u_d, curves)
    factors = np.exp(u)
    d_pose = deflection_errors(problem, gammas, factors)
    e_pose = pose_errors(problem, v, factors)
    freq, defl = combine(e_pose), combine(d_pose)
    value = defl if objective == "deflection" else np.hypot(freq, defl)
    return PoseFactors(value, factors, freq, defl, e_pose, d_pose)


def _combined_factors(problem: PosedProblem, v: np.ndarray, u_eig: np.ndarray,
                      u_d: np.ndarray, curves: _Curves) -> np.ndarray:
    """Per-pose log factors minimising eq. (27) (see the module docstring), (S, m)."""
    w = problem.target
    ww = float(w @ w)
    vv, vw = np.einsum("smk,smk->sm", v, v), v @ w
    hz = problem.definitions.compare == "hz"
    combine = problem.definitions.combine
    lower = np.minimum(u_eig, u_d[:, None])
    upper = np.maximum(u_eig, u_d[:, None])

    def frequency(u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        # e(c) = sqrt(c^2 v.v - 2 c v.w + w.w) / |w| with c = k (or sqrt(k)) = exp(kappa u).
        kappa = 0.5 if hz else 1.0
        c = np.exp(kappa * u)
        e = np.sqrt(np.clip(c * c * vv - 2.0 * c * vw + ww, 0.0, None) / ww)
        safe = np.maximum(e, 1e-300)
        de_dc = (c * vv - vw) / (ww * safe)
        d2e_dc2 = (vv - de_dc**2 * ww) / (ww * safe)
        return e, de_dc * kappa * c, d2e_dc2 * (kappa * c) ** 2 + de_dc * kappa**2 * c

    def factors_for(log_rho: np.ndarray) -> np.ndarray:
        rho = np.exp(log_rho)[:, None]

        def slope(u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
            _, de, d2e = frequency(u)
            _, dd, d2d = curves(u)
            return de + rho * dd, d2e + rho * d2d

        return _bisect(slope, lower, upper)

    # At the optimum rho = B / A; B / A falls as rho grows (the factors move towards d's
    # minimum), so the root of log(B / A) - log(rho) is found by bisection on log(rho).
    n_d = u_eig.shape[0]
    a, b = np.full(n_d, -20.0), np.full(n_d, 20.0)
    for _ in range(36):
        mid = 0.5 * (a + b)
        u = factors_for(mid)
        ratio = combine(curves(u)[0]) / np.maximum(combine(frequency(u)[0]), 1e-300)
        above = np.log(np.maximum(ratio, 1e-300)) > mid
        a, b = np.where(above, mid, a), np.where(above, b, mid)
    return factors_for(0.5 * (a + b))


@dataclass(frozen=True)
class PosedFit:
    """Result of a per-pose-factor fit.

    Attributes:
        gamma: Link fractions of links 0..n, (n + 1,).
        factors: Correction factor per pose, (m,).
        value: The objective at the optimum [-].
        frequency: Aggregated frequency loss [-].
        deflection: Aggregated deflection loss (NaN for eigen-only) [-].
        pose_frequency: Frequency loss per pose, (m,).
        mode_errors: Relative frequency error f / f_truth - 1 per pose and mode, (m, n_modes).
        start_values: The polished value of every start, ascending [-].
        n_samples: Designs of the global sample.
        n_evaluations: Designs evaluated by the sample and the polishes.
    """

    gamma: np.ndarray
    factors: np.ndarray
    value: float
    frequency: float
    deflection: float
    pose_frequency: np.ndarray
    mode_errors: np.ndarray
    start_values: np.ndarray
    n_samples: int
    n_evaluations: int

    @property
    def n_starts(self) -> int:
        """Number of polished starts."""
        return int(self.start_values.size)

    @property
    def starts_at_best(self) -> int:
        """Polished starts within :data:`SAME_OPTIMUM` of the best: 1 means found once."""
        return self.within(SAME_OPTIMUM)

    def within(self, fraction: float) -> int:
        """Number of starts whose value is within ``fraction`` (relative) of the best."""
        best = self.start_values[0]
        return int(np.count_nonzero(self.start_values <= best * (1.0 + fraction)))


def _confirmed(results: list[tuple[float, np.ndarray]]) -> bool:
    """True when at least CONFIRMATIONS polished values are within SAME_OPTIMUM of the best."""
    if not results:
        return False
    best = min(r[0] for r in results)
    return sum(r[0] <= best * (1.0 + SAME_OPTIMUM) for r in results) >= CONFIRMATIONS


def cube_to_fractions(u: np.ndarray) -> np.ndarray:
    """Map points of the unit cube (S, n) onto the feasible fractions (S, n + 1), uniformly.

    Stick breaking with Beta(1, n - i) quantiles maps the uniform cube onto the uniform
    simplex; the fractions are then 0.02 + (1 - 0.02 (n + 1)) times a simplex point.
    """
    u = np.atleast_2d(u)
    n_d, n = u.shape
    free = 1.0 - MIN_FRACTION * (n + 1)
    if free <= 0.0:
        raise InvalidChain(f"{n}R needs {n + 1} links of at least {MIN_FRACTION} of the "
                           "length; use fewer joints")
    out = np.empty((n_d, n + 1))
    rest = np.ones(n_d)
    for i in range(n):
        piece = rest * (1.0 - (1.0 - np.clip(u[:, i], 0.0, 1.0)) ** (1.0 / (n - i)))
        out[:, i] = piece
        rest = rest - piece
    out[:, n] = rest
    return MIN_FRACTION + free * out


#: Share of the global sample with deflection drawn on the faces of the feasible set (one
#: link at 0.02); the eigen-only sample stays uniform over the set.
FACE_SHARE = 0.25


def feasible_sample(n_joints: int, count: int, seed: int, face_share: float = 0.0
                    ) -> np.ndarray:
    """Sample of the feasible fractions: the simplex with every fraction >= 0.02.

    ``1 - face_share`` of the designs are uniform over the set; the rest are uniform over
    its faces, one fraction at its bound 0.02 (the faces taken in turn). The combined
    optimum often lies on a face (a link at its 0.02 minimum: random beam 0's 4R, beam 1's
    3R), in a narrow basin that a uniform sample of the set rarely enters.
    """
    rng = np.random.default_rng(seed)
    n = int(n_joints)
    on_faces = int(round(count * face_share)) if n >= 2 else 0
    inside = cube_to_fractions(rng.uniform(size=(count - on_faces, n)))
    if on_faces == 0:
        return inside
    # n fractions >= 0.02 summing to 1 - 0.02, with 0.02 inserted at the face's index.
    rest = cube_to_fractions(rng.uniform(size=(on_faces, n - 1)))
    rest = MIN_FRACTION + (rest - MIN_FRACTION) * (1.0 - MIN_FRACTION * (n + 1)) \
        / (1.0 - MIN_FRACTION * n)
    face = np.arange(on_faces) % (n + 1)
    faces = np.empty((on_faces, n + 1))
    for j in range(n + 1):
        rows = face == j
        faces[rows] = np.insert(rest[rows], j, MIN_FRACTION, axis=1)
    return np.concatenate([inside, faces])


def objective_values(problem: PosedProblem, gammas: np.ndarray, objective: str) -> np.ndarray:
    """The objective of designs (S, n + 1) at their best factors, (S,)."""
    if objective == "eigen":
        return eigen_loss(problem, gammas)
    return best_factors(problem, gammas, objective).value


def project_fractions(points: np.ndarray) -> np.ndarray:
    """Euclidean projection of first-n fractions (S, n) onto the feasible set.

    The set is every fraction >= 0.02 with the last one, 1 - sum, >= 0.02 too: with
    y = z - 0.02 it is {y >= 0, sum y <= r}, r = 1 - 0.02 (n + 1), whose projection is the
    clipped point when that is inside, else the projection onto the face sum y = r.
    """
    points = np.atleast_2d(np.asarray(points, dtype=float))
    n = points.shape[1]
    r = 1.0 - MIN_FRACTION * (n + 1)
    y = points - MIN_FRACTION
    out = np.clip(y, 0.0, None)
    for i in np.flatnonzero(out.sum(1) > r):
        u = np.sort(y[i])[::-1]
        cum = np.cumsum(u) - r
        rho = np.flatnonzero(u - cum / np.arange(1, n + 1) > 0)[-1]
        out[i] = np.clip(y[i] - cum[rho] / (rho + 1), 0.0, None)
    return out + MIN_FRACTION


#: Weight of the squared distance to the feasible set added to a polish's objective outside it.
OUTSIDE_PENALTY = 1e3


def fixed_factor_values(problem: PosedProblem, gammas: np.ndarray, factors: np.ndarray,
                        objective: str) -> np.ndarray:
    """The objective of designs (S, n + 1) at given factors per pose (S, m), (S,).

    At a design's best factors this is its objective; since those factors are stationary,
    the design gradient of the objective is the gradient of this function at fixed factors
    (the envelope theorem), which is smooth where the factor search is only accurate to
    its interpolation.
    """
    gammas = np.atleast_2d(np.asarray(gammas, dtype=float))
    factors = np.asarray(factors, dtype=float).reshape(gammas.shape[0], -1)
    combine = problem.definitions.combine
    _, _, v = eigen_terms(problem, gammas)
    freq = combine(pose_errors(problem, v, factors))
    if objective == "eigen":
        return freq
    defl = combine(deflection_errors(problem, gammas, factors))
    return defl if objective == "deflection" else np.hypot(freq, defl)


def _polish(problem: PosedProblem, objective: str, gamma0: np.ndarray, tol: float,
            counter: list[int]) -> tuple[float, np.ndarray]:
    """SLSQP on the first n fractions (the last one closes the simplex) from gamma0.

    Eigen-only, the objective is a closed form of the fractions and its gradient a forward
    difference, its n + 1 designs evaluated in one batch. With deflection, the objective's
    best factors come from an interpolated search whose value is accurate to about 1e-5
    relative but not differentiable at the scale of a difference step (a step of 1e-6 gave
    slopes of either sign); the gradient is then the central difference of the objective
    at the design's own best factors held fixed (:func:`fixed_factor_values`, exact
    statics), which is the objective's gradient because the factors are stationary.
    SLSQP may step outside the feasible set (its line search and the difference steps at a
    bound): there a design is evaluated at its projection onto the set, plus a penalty on
    the squared distance, so no link gets a length at or below zero (which has no mass
    matrix).
    """
    n = problem.n_joints
    eigen = objective == "eigen"
    step = 1e-7

    def designs(points: np.ndarray) -> np.ndarray:
        return np.column_stack([points, 1.0 - points.sum(1)])

    cache: dict[bytes, tuple[float, np.ndarray]] = {}

    def value_and_grad(z: np.ndarray) -> tuple[float, np.ndarray]:
        key = z.tobytes()
        if key not in cache:
            if eigen:
                points = np.repeat(z[None], n + 1, axis=0)
                points[1:] += step * np.eye(n)
                inside = project_fractions(points)
                values = objective_values(problem, designs(inside), objective) \
                    + OUTSIDE_PENALTY * np.sum((points - inside) ** 2, axis=1)
                counter[0] += n + 1
                value, grad = float(values[0]), (values[1:] - values[0]) / step
            else:
                inside = project_fractions(z[None])[0]
                best = best_factors(problem, designs(inside[None]), objective)
                # Central differences at fixed factors; the steps (1e-7) may leave the
                # feasible set by that much, which every link length survives.
                points = inside[None] + step * np.concatenate([np.eye(n), -np.eye(n)])
                around = fixed_factor_values(problem, designs(points),
                                             np.repeat(best.factors, 2 * n, axis=0), objective)
                counter[0] += 1 + 2 * n
                outside = z - inside
                value = float(best.value[0]) + OUTSIDE_PENALTY * float(outside @ outside)
                grad = (around[:n] - around[n:]) / (2.0 * step) + 2.0 * OUTSIDE_PENALTY * outside
            cache.clear()
            cache[key] = (value, grad)
        return cache[key]

    cons = [{"type": "ineq", "fun": lambda z: 1.0 - z.sum() - MIN_FRACTION,
             "jac": lambda z: -np.ones_like(z)}]
    bounds = [(MIN_FRACTION, 1.0 - MIN_FRACTION * n)] * n
    z0 = np.asarray(gamma0[:n], dtype=float)
    res = minimize(lambda z: value_and_grad(z)[0], z0, jac=lambda z: value_and_grad(z)[1],
                   method="SLSQP", bounds=bounds, constraints=cons,
                   options={"maxiter": 200, "ftol": tol})
    z = project_fractions(res.x)[0]
    candidates = designs(np.array([z, z0]))
    values = objective_values(problem, candidates, objective)
    counter[0] += 2
    best = int(np.argmin(values))
    return float(values[best]), candidates[best]


#: Global sample and polished starts of the eigen-only and the deflection objectives.
EIGEN_SAMPLES, EIGEN_STARTS = 65536, 48
DEFLECTION_SAMPLES, DEFLECTION_STARTS = 4096, 16
#: Starts polished at most by default when the best value is not yet confirmed.
EIGEN_MAX_STARTS, DEFLECTION_MAX_STARTS = 48, 48
#: Polished values within this relative distance of the best count as the same optimum.
SAME_OPTIMUM = 1e-3
#: Polished starts that must reach the best value for the optimum to count as confirmed.
CONFIRMATIONS = 2


def fit_posed(problem: PosedProblem, objective: str = "eigen", n_samples: int | None = None,
              n_starts: int | None = None, seed: int = 0, progress: bool = False,
              tol: float | None = None, max_starts: int | None = None) -> PosedFit:
    """Global search over the link fractions, the factors solved per pose.

    A sample of the feasible fractions is evaluated in batches (uniform eigen-only; with
    deflection a quarter of it on the set's faces, :func:`feasible_sample`); the best samples
    that lie more than 0.02 (in every fraction) from a better chosen one are polished by
    SLSQP, in the order of their sampled values. After ``n_starts`` polishes the search
    stops if the best value has been reached by :data:`CONFIRMATIONS` starts (within
    :data:`SAME_OPTIMUM`, relative); otherwise it polishes further samples, one at a time,
    until it is or ``max_starts`` have been polished; if it is not, it warns
    (:class:`~pinflex.exceptions.OptimumNotConfirmedWarning`). The best polished design is
    the fit. Every start's polished value is kept (:attr:`PosedFit.start_values`,
    :attr:`PosedFit.starts_at_best`), so the stability of the optimum is part of the result.
    The landscape has a few to a dozen narrow basins whose best samples score alike, so
    which basin a start falls into is close to a draw; the sample's cost is a batched
    eigenvalue problem (and, with deflection, batched statics) per design.

    Args:
        problem: The fit.
        objective: ``"eigen"``, ``"deflection"`` or ``"combined"`` (eq. 27).
        n_samples: Sample size; default 65,536 for eigen-only and 4,096 with deflection.
        n_starts: Starts polished at least; default 48 for eigen-only and 16 with deflection.
        seed: Seed of the sample.
        progress: Show a progress bar on stderr.
        tol: Function tolerance of the polish (default 1e-12 eigen-only, 1e-10 with
            deflection, whose value is accurate to about 1e-5 relative).
        max_starts: Starts polished at most while the best is unconfirmed; default 48
            (eigen-only: no extension of its 48) when ``n_starts`` is defaulted, else
            ``n_starts`` (no extension).

    Raises:
        InvalidChain: For an unknown objective or missing loads.
        MappingFailed: If no start gives a finite loss.
    """
    if objective not in PER_POSE_OBJECTIVES:
        raise InvalidChain(f"objective = {objective!r}; expected one of {PER_POSE_OBJECTIVES}")
    if objective != "eigen" and problem.forces_n.shape[0] == 0:
        raise InvalidChain(f"the {objective} objective needs loads (forces_n)")
    eigen = objective == "eigen"
    count = int(n_samples if n_samples is not None
                else EIGEN_SAMPLES if eigen else DEFLECTION_SAMPLES)
    starts = int(n_starts if n_starts is not None else EIGEN_STARTS if eigen
                 else DEFLECTION_STARTS)
    most = int(max_starts if max_starts is not None else starts if n_starts is not None
               else EIGEN_MAX_STARTS if eigen else DEFLECTION_MAX_STARTS)
    if count < 1 or starts < 1 or most < starts:
        raise InvalidChain(f"n_samples = {count} and n_starts = {starts} must be positive, "
                           f"max_starts = {most} at least n_starts")
    if tol is None:
        tol = 1e-12 if eigen else 1e-10
    n = problem.n_joints
    sample = feasible_sample(n, count, seed, 0.0 if eigen else FACE_SHARE)
    chunk = 1024 if eigen else 64
    pieces = np.array_split(sample, max(1, -(-count // chunk)))
    bar = ProgressBar(len(pieces) + starts, f"{n}R {objective}", progress)
    values = []
    for piece in pieces:
        values.append(objective_values(problem, piece, objective))
        bar.update(best=float(np.nanmin(values[-1])))
    value_all = np.concatenate(values)
    counter = [count]
    results: list[tuple[float, np.ndarray]] = []
    chosen: list[np.ndarray] = []
    for i in np.argsort(np.where(np.isfinite(value_all), value_all, np.inf)):
        if not np.isfinite(value_all[i]) or len(chosen) == most:
            break
        if len(chosen) >= starts and _confirmed(results):
            break
        if any(np.max(np.abs(sample[i] - c)) <= 0.02 for c in chosen):
            continue
        chosen.append(sample[i])
        value, gamma = _polish(problem, objective, sample[i], tol, counter)
        if np.isfinite(value):
            results.append((value, gamma))
        if len(chosen) > starts:
            bar.total += 1
        bar.update(best=min((r[0] for r in results), default=np.inf))
    if not results:
        raise MappingFailed(f"no start of the {objective} fit of {n}R gave a finite loss")
    if not _confirmed(results):
        warnings.warn(
            f"{n}R {objective} fit: the best value {min(r[0] for r in results):.6g} was "
            f"reached by one of {len(results)} polished starts (fewer than {CONFIRMATIONS} "
            f"within {SAME_OPTIMUM:g}); another sample may find a lower optimum: raise "
            "n_samples or max_starts", OptimumNotConfirmedWarning, stacklevel=2)
    results.sort(key=lambda r: r[0])
    gamma = results[0][1]
    best = best_factors(problem, gamma[None], objective)
    _, _, v = eigen_terms(problem, gamma[None])
    factors = best.factors[0]
    return PosedFit(gamma, factors, float(best.value[0]), float(best.frequency[0]),
                    float(best.deflection[0]), best.pose_frequency[0],
                    per_mode_errors(problem, v[0], factors),
                    np.array([r[0] for r in results]), count, counter[0])
