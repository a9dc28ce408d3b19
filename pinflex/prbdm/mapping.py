"""Fit PRBDM parameters to a beam (paper 001, eq. 15-19, 22-23, 27).

Objectives (losses defined in :mod:`pinflex.prbdm.problem`):

* ``"eigen"``: frequencies only (eq. 17);
* ``"deflection"``: tip positions only (eq. 18);
* ``"combined"``: :math:`e_{eig}^2 + e_{defl}^2`, the squared distance to the origin of eq. 27;
* ``"pareto"``: eigen-only multistart; combined searches started from the eigen solutions
  that deflect best (a homotopy from the frequency-matching manifold); the deflection anchor
  from there; a weighted-sum sweep between the anchors; the design closest to the origin
  (eq. 27) is returned.

Each search is a multistart (eq. 23: fractions sampled uniformly on the simplex above the 0.02
floor as in Smith and Tromble; correction factors scaled so the first frequency matches, then
perturbed) of a bounded trust-region least-squares solver (scipy ``least_squares``, 'trf'):
the losses are root-mean-square norms, so their squares are sums of squared residuals, which
Gauss-Newton steps reduce far faster than a general NLP solver. Bounds are eq. (15c-d); the
simplex equality (15b) is a residual on the fractions' sum, to which the losses are blind
(they use the normalised fractions).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from scipy.optimize import least_squares

from ..exceptions import InvalidChain, MappingFailed
from ..progress import ProgressBar
from .beams import Planform
from .fit import PrbdmFit, make_fit
from .loads import LoadCase
from .massmatrix import ChainWorkspace
from .options import DEFINITIONS, OBJECTIVES
from .paper import PAPER_EPS_SINGLE, PAPER_TEXT, paper_losses
from .paperfit import fit_by_definitions
from .problem import (
    MIN_FRACTION,
    Evaluation,
    MappingProblem,
    TruthData,
    build_problem,
    compute_truth,
    design_bounds,
    evaluate,
)
from .sensitivity import evaluate_with_jacobian, residuals_and_jacobian
from .warmstarts import WarmStarts

JACOBIANS = ("analytic", "finite-difference")


def _weights(problem: MappingProblem, kind: str, weight: float | None) -> tuple[float, float]:
    """Weights (eigen, deflection) on the squared losses of an objective."""
    if weight is not None:
        return weight, 1.0 - weight
    return {"eigen": (1.0, 0.0), "deflection": (0.0, 1.0)}.get(kind, (1.0, 1.0))


class Objective:
    r"""Residuals :math:`r(x)` with :math:`\|r\|^2 = w_e e_{eig}^2 + w_d e_{defl}^2` + gauge term.

    The losses only see the normalised fractions :math:`\gamma/\sum\gamma`, so the residual
    :math:`\sum\gamma - 1` pins the scale and enforces eq. (15b).

    ``jacobian="analytic"`` (default) evaluates on one chain updated in place and returns the
    exact Jacobian (:mod:`pinflex.prbdm.sensitivity`); ``"finite-difference"`` is the reference
    path (a new chain per evaluation, scipy's 2-point differences). The warm starts of the
    tip statics are this object's explicit state, one per search.
    """

    def __init__(self, problem: MappingProblem, kind: str, weight: float | None = None,
                 jacobian: str = "analytic"):
        if jacobian not in JACOBIANS:
            raise InvalidChain(f"jacobian = {jacobian!r}; expected one of {JACOBIANS}")
        self.problem = problem
        self.w_eig, self.w_defl = _weights(problem, kind, weight)
        self.jacobian_kind = jacobian
        self.warm = WarmStarts()
        self.workspace = ChainWorkspace(problem.planform, problem.n_joints) \
            if jacobian == "analytic" else None
        self.n_eig = problem.poses.shape[0] * problem.n_modes
        self.n_evaluations = 0
        self._cache: tuple[np.ndarray, np.ndarray, Callable[..., np.ndarray]] | None = None
        self._jac: tuple[tuple, np.ndarray] | None = None
        self._jac_buffer: np.ndarray | None = None

    def _weighted(self, res: np.ndarray, x: np.ndarray) -> np.ndarray:
        n1 = self.problem.n_joints + 1
        n_eig = self.n_eig
        rows = res.size if self.w_defl > 0.0 else n_eig
        out = np.empty(rows + 1)
        out[:n_eig] = res[:n_eig] if self.w_eig == 1.0 else np.sqrt(self.w_eig) * res[:n_eig]
        if self.w_defl > 0.0:
            out[n_eig:rows] = res[n_eig:] if self.w_defl == 1.0 \
                else np.sqrt(self.w_defl) * res[n_eig:]
        out[rows] = x[:n1].sum() - 1.0
        return out

    def _compute(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray, Callable[..., np.ndarray]]:
        if self._cache is not None and np.array_equal(self._cache[0], x):
            return self._cache
        self.n_evaluations += 1
        assert self.workspace is not None
        res, jacobian = residuals_and_jacobian(self.problem, x, self.workspace, self.warm,
                                               deflection=self.w_defl > 0.0)
        self._cache = (np.array(x), self._weighted(res, x), jacobian)
        self._jac = None
        return self._cache

    def fun(self, x: np.ndarray) -> np.ndarray:
        """Residual vector at x."""
        if self.workspace is not None:
            return self._compute(x)[1]
        self.n_evaluations += 1
        ev = evaluate(self.problem, x, deflection=self.w_defl > 0.0, warm=self.warm)
        return self._weighted(ev.residuals, x)

    def jac(self, x: np.ndarray) -> np.ndarray:
        """Exact Jacobian of :meth:`fun` at x (analytic path only), formed on first request."""
        cached = self._compute(x)
        if self._jac is not None and self._jac[0] is cached:
            return self._jac[1]
        n_eig = self.n_eig
        rows = cached[1].size - 1
        full = self._jac_buffer
        if full is None or full.shape != (rows + 1, x.size):
            # One buffer per search: scipy copies the Jacobian it is given, and the last row
            # (the derivative of the simplex residual) never changes.
            full = np.zeros((rows + 1, x.size))
            full[rows, :self.problem.n_joints + 1] = 1.0
            self._jac_buffer = full
        cached[2](full[:rows])
        if self.w_eig != 1.0:
            full[:n_eig] *= np.sqrt(self.w_eig)
        if self.w_defl > 0.0 and self.w_defl != 1.0:
            full[n_eig:rows] *= np.sqrt(self.w_defl)
        self._jac = (cached, full)
        return full


def start_points(problem: MappingProblem, n_starts: int, seed: int) -> np.ndarray:
    """Multistart designs (eq. 23), shape (n_starts, n_params)."""
    rng = np.random.default_rng(seed)
    n1 = problem.n_joints + 1
    free = 1.0 - MIN_FRACTION * n1
    if free <= 0.0:
        raise InvalidChain(f"{problem.n_joints}R needs {n1} links of at least {MIN_FRACTION} "
                           "of the length; use fewer joints")
    starts = []
    for _ in range(n_starts):
        gamma = MIN_FRACTION + free * rng.dirichlet(np.ones(n1))
        x = np.concatenate([gamma, np.zeros(problem.n_stiffness_params)])
        ev = final_evaluation(problem, x, "analytic", deflection=False)
        scale = problem.truth_hz[0] / ev.model_hz[:, 0]
        log_k = 2.0 * np.log(scale)
        if problem.stiffness_law == "segment":
            log_k = np.full(problem.n_joints, float(np.mean(log_k)))
        x[n1:] = log_k + rng.normal(0.0, 0.2, problem.n_stiffness_params)
        starts.append(x)
    return np.array(starts)


#: Tolerance of the eigen-only searches that only seed a combined search: they stop on the
#: frequency-matching manifold at 1e-6 instead of round-off (fewer evaluations; the combined
#: search then leaves the manifold anyway, and its optimum is the same).
SEED_TOL = 1e-6


def _local(problem: MappingProblem, kind: str, x0: np.ndarray, weight: float | None = None,
           max_nfev: int | None = None, jacobian: str = "analytic",
           tol: float | None = None, counter: list[int] | None = None) -> np.ndarray:
    """Bounded trust-region least squares (scipy ``least_squares``, 'trf') from x0.

    ``counter[0]`` (when given) is increased by the residual evaluations spent, including
    those of finite differences.
    """
    lower, upper = design_bounds(problem)
    x0 = np.clip(x0, lower + 1e-12, upper - 1e-12)
    # A perfect frequency fit is reachable, so eigen-only runs to round-off; with deflection the
    # optimum has a non-zero residual and a relative cost change of 1e-9 is plenty.
    if tol is None:
        tol = 1e-12 if kind == "eigen" else 1e-9
    objective = Objective(problem, kind, weight, jacobian)
    jac = objective.jac if jacobian == "analytic" else "2-point"
    result = least_squares(objective.fun, x0, jac=jac, bounds=(lower, upper),
                           method="trf", ftol=tol, xtol=tol, gtol=tol,
                           max_nfev=max_nfev or (40 if kind == "eigen" else 10) * problem.n_params)
    if counter is not None:
        counter[0] += objective.n_evaluations
    x = np.asarray(result.x, dtype=float)
    n1 = problem.n_joints + 1
    x[:n1] = np.clip(x[:n1], MIN_FRACTION, 1.0 - MIN_FRACTION)
    x[:n1] /= x[:n1].sum()
    return x


def final_evaluation(problem: MappingProblem, x: np.ndarray, jacobian: str = "analytic",
                     deflection: bool = True) -> Evaluation:
    """Losses of a found design from a cold start (no warm starts): the reported numbers.

    The analytic path evaluates on a fresh in-place chain; the finite-difference path on a
    newly built chain (:func:`~pinflex.prbdm.problem.evaluate`); both give the same numbers.
    """
    if jacobian == "analytic":
        return evaluate_with_jacobian(problem, x, ChainWorkspace(problem.planform,
                                                                 problem.n_joints),
                                      deflection=deflection, want_jacobian=False).evaluation
    return evaluate(problem, x, deflection=deflection)


def _score(ev: Evaluation, kind: str, metrics: str = "pinflex") -> float:
    if metrics == "paper":
        return {"eigen": ev.eigen_error_eq16, "deflection": ev.deflection_error_position}.get(
            kind, float(np.hypot(ev.eigen_error_eq16, ev.deflection_error_position)))
    if kind == "eigen":
        return ev.eigen_error
    if kind == "deflection":
        return ev.deflection_error
    return ev.combined_error


def multistart(problem: MappingProblem, kind: str, n_starts: int = 16, seed: int = 0,
               progress: bool = False, starts: np.ndarray | None = None,
               keep_all: bool = False, jacobian: str = "analytic", tol: float | None = None,
               counter: list[int] | None = None):
    """Best local least-squares solution over multistart points for one objective.

    Args:
        problem: The mapping problem.
        kind: ``"eigen"``, ``"deflection"`` or ``"combined"``.
        n_starts: Number of random start points (eq. 23) when ``starts`` is not given.
        seed: Seed of the start points.
        progress: Show a progress bar on stderr.
        starts: Explicit start designs, shape (k, n_params).
        keep_all: Return every successful local solution, best first, instead of the best.
        jacobian: ``"analytic"`` or ``"finite-difference"`` (see :class:`Objective`).
        tol: Optimiser tolerances (ftol = xtol = gtol); default 1e-12 for eigen-only, 1e-9
            with deflection.
        counter: ``counter[0]`` is increased by the residual evaluations spent.

    Returns:
        ``(x, evaluation)`` of the best solution, or the list of all of them.

    Raises:
        MappingFailed: If every start fails to produce finite losses.
    """
    points = start_points(problem, n_starts, seed) if starts is None else np.atleast_2d(starts)
    found: list[tuple[np.ndarray, Evaluation]] = []
    bar = ProgressBar(len(points), f"{problem.n_joints}R {kind}", progress)
    for x0 in points:
        try:
            x = _local(problem, kind, x0, jacobian=jacobian, tol=tol, counter=counter)
            ev = final_evaluation(problem, x, jacobian)
        except (InvalidChain, np.linalg.LinAlgError, ValueError):
            bar.update(best=min((_score(e, kind, problem.metrics) for _, e in found),
                            default=np.inf))
            continue
        if np.isfinite(_score(ev, kind, problem.metrics)):
            found.append((x, ev))
        bar.update(best=min((_score(e, kind, problem.metrics) for _, e in found),
                            default=np.inf))
    if not found:
        raise MappingFailed(f"all {len(points)} starts of the {kind} mapping failed for "
                            f"{problem.n_joints}R; try more starts or another seed")
    found.sort(key=lambda p: _score(p[1], kind, problem.metrics))
    return found if keep_all else found[0]


def pareto_front(problem: MappingProblem, eigen_x: np.ndarray, deflection_x: np.ndarray,
                 n_points: int = 7, progress: bool = False,
                 extra: list | None = None,
                 jacobian: str = "analytic", counter: list[int] | None = None
                 ) -> list[tuple[np.ndarray, Evaluation]]:
    """Weighted-sum Pareto front between the eigen and deflection anchors.

    For weights w evenly spaced in (0, 1), minimise :math:`w e_{eig}^2 + (1 - w) e_{defl}^2`,
    starting from the previous front point and from the best ``extra`` design; dominated
    points are dropped. (A weighted sum finds the convex hull of the front; the anchors close
    its ends.) ``extra`` designs, as (x, evaluation) pairs, join the front.
    """
    points = [(eigen_x, final_evaluation(problem, eigen_x, jacobian)),
              (deflection_x, final_evaluation(problem, deflection_x, jacobian))] \
        + list(extra or [])
    hub = min(points, key=lambda p: p[1].combined_error)[0]
    bar = ProgressBar(n_points, f"{problem.n_joints}R pareto", progress)
    previous = eigen_x
    for weight in np.linspace(1.0, 0.0, n_points + 2)[1:-1]:
        best = None
        for x0 in (previous, hub):
            try:
                x = _local(problem, "weighted", x0, weight=weight, jacobian=jacobian,
                           counter=counter)
            except (InvalidChain, np.linalg.LinAlgError, ValueError):
                continue
            ev = final_evaluation(problem, x, jacobian)
            value = weight * ev.eigen_error**2 + (1.0 - weight) * ev.deflection_error**2
            if best is None or value < best[0]:
                best = (value, x, ev)
        if best is not None:
            points.append((best[1], best[2]))
            previous = best[1]
        bar.update(best=min(p[1].combined_error for p in points))

    def dominated(p, q) -> bool:
        return (q[1].eigen_error <= p[1].eigen_error and q[1].deflection_error
                <= p[1].deflection_error and (q[1].eigen_error < p[1].eigen_error
                                              or q[1].deflection_error < p[1].deflection_error))

    kept = [p for p in points if not any(dominated(p, q) for q in points)]
    return sorted(kept, key=lambda p: p[1].deflection_error)


def fit_prbdm(planform: Planform, n_joints: int, n_modes: int | None = None,
              objective: str = "combined", stiffness_law: str = "segment",
              poses: str | np.ndarray = "straight", n_starts: int | None = None,
              seed: int = 0, truth: TruthData | None = None, pareto_points: int = 7,
              progress: bool = False, jacobian: str = "analytic",
              metrics: str = "pinflex", definitions: str = "pinflex",
              epsilon: float | None = None, code_force_n: float | None = None,
              n_samples: int | None = None,
              loads: Sequence[LoadCase] | None = None) -> PrbdmFit:
    """Fit an nR PRBDM to a beam.

    Args:
        planform: The beam.
        n_joints: Number of revolute joints n.
        n_modes: Modes to match; default n.
        objective: ``"combined"`` (default: frequencies and large tip deflections, an
            over-determined fit), ``"eigen"``, ``"deflection"`` or ``"pareto"``; combined and
            pareto start from the eigen-only solutions. An eigen-only fit of n modes at one
            pose has 2n free parameters: it is exactly determined and says so.
        stiffness_law: ``"segment"`` (pose-independent physical springs with per-joint factors)
            or ``"paper"`` (eq. 14, per-pose factors).
        poses: Comparison poses for frequencies, see :func:`~pinflex.prbdm.problem.build_problem`.
        n_starts: Multistart points per search (default 16); with the paper's definitions,
            the polished starts of the global search (default 48 eigen-only; 16 otherwise,
            extended up to 48 until two agree on the best, else
            :class:`~pinflex.exceptions.OptimumNotConfirmedWarning`).
        seed: Seed of the start points.
        truth: Precomputed truth (:func:`~pinflex.prbdm.problem.compute_truth`).
        pareto_points: Interior weights of the Pareto sweep.
        progress: Show a progress bar on stderr.
        jacobian: ``"analytic"`` (exact derivatives on one chain updated in place, default) or
            ``"finite-difference"`` (the reference path, several times slower).
        metrics: ``"pinflex"`` (default) or ``"paper"`` (minimise eq. 16 / eq. 19 residuals).
        definitions: ``"pinflex"`` (default: the settings above), ``"paper-code"`` (what the
            paper's code computes: eq. 14 with the links' rotational inertia, poses 0.1 :
            0.01 : pi/(2n), eigenvalues against omega^2, means over poses, its deflection
            case; objectives eigen, deflection, combined) or ``"paper-text"`` (the text as
            printed: eq. 14 with the second moment of area, xi = 0.05 and epsilon, eq. 15a
            summed over poses on frequencies, eq. 19 with the mean factor). Both readings
            fit one factor per pose by a global search over the link fractions
            (:mod:`pinflex.prbdm.posedfit`), except the text reading's objectives with
            deflection, which are this function's least-squares searches with the paper's
            law, poses and metrics. ``stiffness_law``, ``poses`` and ``metrics`` must then be
            left at their defaults; the paper's losses are in ``fit.losses``.
        epsilon: Pose step of the paper's definitions [rad] (default: text 0.1, code 0.01).
        code_force_n: Tip force of the code's deflection case [N] (default: the force that
            deflects the beam's tip by 0.1437 L, as the code's 1 MN did on its beam).
        n_samples: Global sample size of the paper's definitions' search.
        loads: Load cases of the deflection loss (:mod:`pinflex.prbdm.loads`: inclined
            forces, end moments, fixed-guided ends; default: paper 001's transverse forces at
            alpha = 0.5, 1, 2, 5). With an end moment or a fixed-guided end the fit runs on the
            reference path (``jacobian="finite-difference"``: the chain's own statics); the
            per-case errors are ``fit.load_errors`` beside ``fit.load_labels``. Pinflex's
            definitions only; not with ``truth``.

    Returns:
        The fit; for ``"pareto"`` the front is in ``fit.pareto`` and the returned model is the
        design closest to the origin (eq. 27) among the front and the combined search started
        from the eigen-only solutions.

    Raises:
        InvalidChain: For bad settings.
        MappingFailed: If no start succeeds.
    """
    if objective not in OBJECTIVES:
        raise InvalidChain(f"objective = {objective!r}; expected one of {OBJECTIVES}")
    if definitions not in DEFINITIONS:
        raise InvalidChain(f"definitions = {definitions!r}; expected one of {DEFINITIONS}")
    if loads is not None:
        if definitions != "pinflex" or truth is not None:
            raise InvalidChain("loads are pinflex definitions' load cases and make their own "
                               "truth: leave definitions='pinflex' and truth=None")
        truth = compute_truth(planform, n_joints if n_modes is None else int(n_modes),
                              loads=loads)
    elif truth is not None and definitions != "pinflex" and truth.cases:
        raise InvalidChain("the paper's definitions use their own loads: give a truth "
                           "without load cases")
    if definitions != "pinflex":
        if (stiffness_law, metrics) != ("segment", "pinflex") or not isinstance(poses, str) \
                or poses != "straight":
            raise InvalidChain(f"definitions = {definitions!r} sets the law, poses and metrics; "
                               "leave stiffness_law, poses and metrics at their defaults")
        if definitions == "paper-code" or objective == "eigen":
            return fit_by_definitions(planform, n_joints, n_modes, objective, definitions,
                                      truth, epsilon, code_force_n, n_samples, n_starts, seed,
                                      progress)
        step = PAPER_EPS_SINGLE if epsilon is None else float(epsilon)
        poses, stiffness_law, metrics = PAPER_TEXT.poses(n_joints, step=step), "paper", "paper"
    n_starts = 16 if n_starts is None else int(n_starts)
    problem = build_problem(planform, n_joints, n_modes, poses, stiffness_law, truth, metrics)
    if problem.end_loads:
        # End moments and guided ends: the chain's own statics (sensitivity.py refuses them).
        jacobian = "finite-difference"
    front: list[tuple[np.ndarray, Evaluation]] = []
    count = [0]
    if objective in ("pareto", "combined"):
        eigen_all = multistart(problem, "eigen", n_starts, seed, progress, keep_all=True,
                               jacobian=jacobian, counter=count,
                               tol=SEED_TOL if objective == "combined" else None)
        x_e = eigen_all[0][0]
        # Homotopy from the frequency-matching manifold: the eigen solutions that already
        # deflect best are the starts of the combined search.
        seeds = sorted(eigen_all, key=lambda p: p[1].combined_error)[: max(2, n_starts // 2)]
        x, ev = multistart(problem, "combined", starts=np.array([p[0] for p in seeds]),
                           progress=progress, jacobian=jacobian, counter=count)
        if objective == "pareto":
            x_d, _ = multistart(problem, "deflection", progress=progress,
                                starts=np.array([x, seeds[0][0]]), jacobian=jacobian,
                                counter=count)
            front = pareto_front(problem, x_e, x_d, pareto_points, progress, extra=[(x, ev)],
                                 jacobian=jacobian, counter=count)
            x, ev = min(front + [(x, ev)], key=lambda p: p[1].combined_error)
    else:
        x, ev = multistart(problem, objective, n_starts, seed, progress, jacobian=jacobian,
                           counter=count)
    if definitions == "paper-text":
        losses = paper_losses(problem, x, step)
        return make_fit(problem, x, ev, objective, n_starts, front, count[0],
                        definitions=definitions,
                        losses={k: getattr(losses, k) for k in
                                ("eq15a_sum", "eq15a_mean", "eq19_rms", "eq27_sum")})
    return make_fit(problem, x, ev, objective, n_starts, front, count[0])
