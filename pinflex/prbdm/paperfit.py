"""Fits made and scored by paper 001's definitions (``"paper-code"`` or ``"paper-text"``).

:func:`fit_by_definitions` runs the global per-pose-factor search of
:mod:`pinflex.prbdm.posedfit` under a reading of the paper (:mod:`pinflex.prbdm.paper`) and
returns a :class:`~pinflex.prbdm.fit.PrbdmFit` whose ``losses`` are the paper's, beside
pinflex's own losses of the same chain (with the mean factor, eq. 25, at the straight pose).
"""

from __future__ import annotations

import warnings
from dataclasses import replace

import numpy as np

from ..exceptions import InvalidChain, UnsolvedLoadWarning
from .beams import Planform
from .fit import PrbdmFit, make_fit
from .paper import Definitions, code_tip_force, definitions_named
from .perpose import (
    PosedProblem,
    deflection_errors,
    link_arrays,
    reference_springs,
    tip_positions,
)
from .posedfit import PER_POSE_OBJECTIVES, PosedFit, fit_posed
from .problem import (
    TruthData,
    build_problem,
    compute_truth,
    evaluate,
    reference_stiffness,
)
from .truth import elastica_tip


def posed_problem(planform: Planform, n_joints: int, n_modes: int, truth: TruthData,
                  definitions: Definitions, epsilon: float | None = None,
                  code_force_n: float | None = None) -> PosedProblem:
    """The per-pose-factor problem of a reading of the paper.

    Args:
        planform: The beam.
        n_joints: Number of joints n.
        n_modes: Modes compared.
        truth: pinflex's truth (its frequencies; its loads serve the text reading).
        definitions: The reading.
        epsilon: Pose step [rad]; default the reading's (text 0.1, code 0.01).
        code_force_n: The code reading's tip force [N]; default :func:`code_tip_force`.
    """
    poses = definitions.poses(n_joints, step=epsilon)
    if definitions.deflection == "per-pose":
        force = code_tip_force(planform) if code_force_n is None else abs(float(code_force_n))
        forces = np.array([[0.0, -force]])
        tips = elastica_tip(planform, forces[0]).tip_m[None]
    else:
        forces, tips = truth.forces_n, truth.tips_m
    return PosedProblem(planform, int(n_joints), int(n_modes), definitions, poses,
                        truth.modes.freq_hz[:n_modes].copy(), forces, tips)


def static_springs(problem: PosedProblem, gamma: np.ndarray, factors: np.ndarray) -> np.ndarray:
    """The chain's springs with the mean factor (eq. 25), (n,) [N m/rad]."""
    _, _, mass, _, iyy, mean_i = link_arrays(problem.planform, np.asarray(gamma)[None])
    k_ref = reference_springs(problem.planform, problem.definitions.inertia, mass, iyy, mean_i)
    return float(np.mean(factors)) * k_ref[0]


def paper_losses_of(problem: PosedProblem, posed: PosedFit) -> dict[str, float]:
    """The reading's own losses of a per-pose fit, by name (fractions)."""
    gamma, factors = posed.gamma, posed.factors
    combine = problem.definitions.combine
    freq = float(combine(posed.pose_frequency))
    if problem.definitions.deflection == "per-pose":
        defl = float(combine(deflection_errors(problem, gamma[None], factors[None])[0]))
        _warn_unsolved(problem, tip_positions(problem, gamma[None], factors[None])[1])
        return {"frequency": freq, "deflection": defl, "combined": float(np.hypot(freq, defl))}
    per_pose = posed.pose_frequency
    # Eq. 19 with the mean factor (eq. 25), RMS over the loads, as the text reading's.
    mean_k = np.full((1, 1), float(np.mean(factors)))
    tips_err = _text_eq19(problem, gamma, mean_k)
    return {"eq15a_sum": float(per_pose.sum()), "eq15a_mean": float(per_pose.mean()),
            "eq19_rms": tips_err, "eq27_sum": float(np.hypot(per_pose.sum(), tips_err))}


def _text_eq19(problem: PosedProblem, gamma: np.ndarray, factor: np.ndarray) -> float:
    """Eq. (19) RMS over the loads of one design with one factor (the mean, eq. 25)."""
    tips, ok = tip_positions(problem, gamma[None], factor)
    truth = problem.truth_tips_m
    err = np.linalg.norm(tips[0, 0] - truth, axis=1) / np.linalg.norm(truth, axis=1)
    _warn_unsolved(problem, ok)
    err = np.where(ok[0, 0], err, 1.0)
    return float(np.sqrt(np.mean(err**2)))


def _warn_unsolved(problem: PosedProblem, ok: np.ndarray) -> None:
    """Warn when a reported deflection loss counts unsolved loads as 100 % errors."""
    failed = int(np.count_nonzero(~np.asarray(ok)))
    if failed:
        warnings.warn(f"{failed} of {np.asarray(ok).size} tip statics (loads x poses) found no "
                      f"equilibrium; the reported {problem.definitions.name} deflection loss "
                      "counts each as a 100 % error", UnsolvedLoadWarning, stacklevel=3)


def fit_by_definitions(planform: Planform, n_joints: int, n_modes: int | None = None,
                       objective: str = "eigen", definitions: str = "paper-code",
                       truth: TruthData | None = None, epsilon: float | None = None,
                       code_force_n: float | None = None, n_samples: int | None = None,
                       n_starts: int | None = None, seed: int = 0,
                       progress: bool = False) -> PrbdmFit:
    """Fit an nR PRBDM by a reading of paper 001 (one correction factor per pose).

    Args:
        planform: The beam.
        n_joints: Number of joints n.
        n_modes: Modes compared; default n.
        objective: ``"eigen"``; with ``"paper-code"`` also ``"deflection"`` and
            ``"combined"`` (eq. 27 of the two means: the Pareto front's point closest to the
            origin). The text reading's deflection uses the mean factor and is fitted by
            :func:`~pinflex.prbdm.mapping.fit_prbdm` instead.
        definitions: ``"paper-code"`` or ``"paper-text"``.
        truth: pinflex's truth (computed when omitted).
        epsilon: Pose step [rad]; default the reading's.
        code_force_n: Tip force of the code's deflection case [N] (default: the force that
            deflects the tip by 0.1437 L, :func:`~pinflex.prbdm.paper.code_tip_force`).
        n_samples: Global sample size (default of :func:`~pinflex.prbdm.posedfit.fit_posed`).
        n_starts: Polished starts (same).
        seed: Seed of the sample.
        progress: Show progress bars on stderr.

    Raises:
        InvalidChain: For unknown definitions, objectives or sizes.
        MappingFailed: If no start succeeds.

    Warns:
        OptimumNotConfirmedWarning: If the best value was reached by one polished start
            only (the fit's ``starts_at_best`` is then 1).
    """
    defs = definitions_named(definitions)
    if objective not in PER_POSE_OBJECTIVES or (defs.name == "paper-text"
                                               and objective != "eigen"):
        allowed = PER_POSE_OBJECTIVES if defs.name == "paper-code" else ("eigen",)
        raise InvalidChain(f"objective = {objective!r} under {defs.name}; expected one of "
                           f"{allowed}")
    n_modes = n_joints if n_modes is None else int(n_modes)
    if not 1 <= n_modes <= n_joints:
        raise InvalidChain(f"an {n_joints}R chain has {n_joints} modes; n_modes = {n_modes}")
    if truth is None:
        truth = compute_truth(planform, n_modes)
    problem = posed_problem(planform, n_joints, n_modes, truth, defs, epsilon, code_force_n)
    posed = fit_posed(problem, objective, n_samples, n_starts, seed, progress)
    ours = build_problem(planform, n_joints, n_modes, "straight", "segment", truth)
    springs = static_springs(problem, posed.gamma, posed.factors)
    x = np.concatenate([posed.gamma, np.log(springs / reference_stiffness(ours, posed.gamma))])
    ev = evaluate(ours, x)
    fit = make_fit(ours, x, ev, objective, posed.n_starts, [], posed.n_evaluations,
                   definitions=defs.name, losses=paper_losses_of(problem, posed),
                   mode_errors=tuple(float(v) for v in np.abs(posed.mode_errors).max(0)),
                   start_values=tuple(float(v) for v in posed.start_values),
                   n_samples=posed.n_samples, starts_at_best=posed.starts_at_best,
                   load_n=tuple((float(f[0]), float(f[1])) for f in problem.forces_n))
    return _as_paper_fit(fit, problem, posed)


def _as_paper_fit(fit: PrbdmFit, problem: PosedProblem, posed: PosedFit) -> PrbdmFit:
    """The fit with the paper's law, poses and per-pose factors recorded."""
    n_free = problem.n_joints + problem.poses.shape[0]
    n_matched = problem.poses.shape[0] * problem.n_modes
    if fit.objective != "eigen":
        n_matched += 2 * problem.forces_n.shape[0]
    return replace(fit, stiffness_law="paper", correction_factors=tuple(
        float(v) for v in posed.factors), n_poses=int(problem.poses.shape[0]),
        n_free_parameters=n_free, n_matched=n_matched,
        determinacy="exactly determined" if n_free >= n_matched else "over-determined",
        metrics="paper")
