r"""PRBDM mapping problem: truth data, parameterisation and losses (paper 001, eq. 10-19, 27).

Design variables are the link-length fractions :math:`\gamma` (links 0..n, on the simplex,
each >= 0.02, eq. 15) and stiffness correction factors, stored as logarithms. Two stiffness
laws are offered:

* ``"paper"`` (eq. 14): :math:`K_j(i) = k_i \sqrt{E I_j / \hat m_j}`, one factor :math:`k_i` per
  pose i, :math:`I_j` the mean second moment of area and :math:`\hat m_j` the mass of link j.
  Tip statics use the mean factor (eq. 25), the paper leaving this open.
* ``"segment"`` (pinflex default): :math:`K_j = c_j / \int_{piece\ j} dx / EI(x)`, one factor
  per joint, pose independent. Piece j is the stretch of beam that joint j stands for, from the
  middle of link j-1 (the root for j = 1, link 0 being clamped) to the middle of link j (the tip
  for j = n); :math:`c_j = 1` is already a physical spring, so the optimiser only corrects it.

Losses (fractions, not percent):

* eigen: the root mean square, over poses and the first ``n_modes`` modes, of the per-mode
  relative frequency error :math:`f_{model,k}(\theta_i)/f_{truth,k} - 1`. Eq. (16),
  :math:`\|f_{truth} - f_{model}\|_2 / \|f_{truth}\|_2`, is dominated by the highest mode and
  lets a lower mode drift by far more than the loss says; it is kept as ``eigen_error_eq16``.
* deflection: per load, :math:`\|P_{truth} - P_{model}\|_2 / \|P_{truth} - P_0\|_2` with
  :math:`P_0` the undeformed tip, i.e. normalised by the tip *displacement*. Eq. (19) normalises by
  the tip position vector, which is about :math:`L/|\Delta|` times more lenient; that value is
  kept as ``deflection_error_position``. The loss is the root mean square over loads.
* combined: :math:`\sqrt{e_{eig}^2 + e_{defl}^2}` (eq. 27).

Loads are, by default, dead tip forces perpendicular to the undeformed beam with
:math:`\alpha = P L^2 / EI_{eq}` (:func:`~pinflex.prbdm.beams.equivalent_bending_stiffness`);
:func:`compute_truth` also takes load cases (:mod:`pinflex.prbdm.loads`: inclined forces, end
moments, fixed-guided ends), whose problems are evaluated by :func:`evaluate` (the chain's own
statics, :func:`~pinflex.prbdm.chain.solve_tip_statics`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field, replace

import numpy as np
import pinocchio as pin

from ..exceptions import InvalidChain, NewtonDivergence
from .beams import Planform, chain_segments, equivalent_bending_stiffness
from .chain import PrbdmChain, build_chain, chain_frequencies, solve_tip_statics
from .loads import LoadCase, case_truth
from .options import DEFAULT_ALPHAS, STIFFNESS_LAWS
from .truth import BeamModes, beam_frequencies, elastica_tip

MIN_FRACTION = 0.02
#: Loss assigned to a load whose Newton solve fails (100 % error), so optimisers move away.
FAILED_LOAD_ERROR = 1.0


def paper_poses(n_joints: int, offset_rad: float = 0.05, step_rad: float = 0.1) -> np.ndarray:
    r"""Pose sweep of eq. (10)-(11): all joints at :math:`\xi + i\epsilon`, shape (m, n) [rad].

    Poses are added while the end link's world angle :math:`n(\xi + i\epsilon)` stays at or
    below :math:`\pi/2`.
    """
    count = int(np.floor((np.pi / 2 / n_joints - offset_rad) / step_rad + 1e-12)) + 1
    angles = offset_rad + step_rad * np.arange(max(count, 1))
    return np.repeat(angles[:, None], n_joints, axis=1)


@dataclass(frozen=True)
class MappingProblem:
    r"""Truth data and settings of one PRBDM mapping.

    Attributes:
        planform: The beam.
        n_joints: Number of revolute joints n.
        n_modes: Number of bending modes matched (<= n).
        truth_hz: Beam frequencies, shape (n_modes,) [Hz].
        poses: Poses where frequencies are compared, shape (m, n) [rad].
        forces_n: Tip forces (Fx, Fz), shape (l, 2) [N].
        truth_tips_m: Elastica tip positions (x, z), shape (l, 2) [m].
        stiffness_law: ``"segment"`` or ``"paper"``.
        alphas: Load levels :math:`\alpha = PL^2/EI_{eq}`, shape (l,).
        metrics: ``"pinflex"`` (the residuals are the per-mode relative frequency errors and
            the displacement-normalised tip errors) or ``"paper"`` (eq. 16's
            :math:`(f_{model} - f_{truth})/\|f_{truth}\|` per pose and eq. 19's tip error over
            :math:`\|P_{truth}\|`). Only what is minimised changes; every loss is reported.

    The problem holds no state: warm starts of the tip statics are an explicit argument of
    :func:`evaluate` (a :class:`~pinflex.prbdm.sensitivity.WarmStarts`).
    """

    planform: Planform
    n_joints: int
    n_modes: int
    truth_hz: np.ndarray
    poses: np.ndarray
    forces_n: np.ndarray
    truth_tips_m: np.ndarray
    stiffness_law: str
    alphas: np.ndarray
    metrics: str = "pinflex"
    moments_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    guided: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))
    load_labels: tuple[str, ...] = ()

    @property
    def end_loads(self) -> bool:
        """True when a load carries an end moment or a fixed-guided end (reference path only)."""
        return bool(np.any(self.moments_nm != 0.0) or np.any(self.guided))

    def load(self, index: int) -> tuple[np.ndarray, float, str]:
        """Force [N], end moment [N m] and boundary of load ``index``."""
        moment = float(self.moments_nm[index]) if self.moments_nm.size else 0.0
        guided = bool(self.guided[index]) if self.guided.size else False
        return self.forces_n[index], moment, "fixed-guided" if guided else "cantilever"

    @property
    def n_stiffness_params(self) -> int:
        """Number of stiffness correction factors."""
        return self.n_joints if self.stiffness_law == "segment" else int(self.poses.shape[0])

    @property
    def n_params(self) -> int:
        """Length of the design vector: n + 1 fractions and the log correction factors."""
        return self.n_joints + 1 + self.n_stiffness_params


@dataclass(frozen=True)
class TruthData:
    """Precomputed truth for one beam, reusable across mappings.

    Attributes:
        modes: Converged beam frequencies.
        alphas: Load levels, shape (l,).
        forces_n: Tip forces, shape (l, 2) [N].
        tips_m: Elastica tip positions, shape (l, 2) [m].
        cases: The load cases (:class:`~pinflex.prbdm.loads.LoadCase`) when given; empty for
            the transverse forces at ``alphas``.
        moments_nm: End moments, shape (l,) [N m] (empty: none).
        guided: Fixed-guided ends, shape (l,) (empty: none).
    """

    modes: BeamModes
    alphas: np.ndarray
    forces_n: np.ndarray
    tips_m: np.ndarray
    cases: tuple[LoadCase, ...] = ()
    moments_nm: np.ndarray = field(default_factory=lambda: np.zeros(0))
    guided: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool))


def compute_truth(planform: Planform, n_modes: int = 5,
                  alphas: tuple[float, ...] = DEFAULT_ALPHAS,
                  loads: Sequence[LoadCase] | None = None) -> TruthData:
    r"""Converged beam frequencies and elastica tips under dead end loads.

    Args:
        planform: The beam.
        n_modes: Number of bending modes.
        alphas: Load levels :math:`\alpha = PL^2/EI_{eq}` (downward tip force), used when
            ``loads`` is None (paper 001's loads).
        loads: Load cases (:mod:`pinflex.prbdm.loads`: inclined forces, end moments,
            fixed-guided ends) replacing ``alphas``.
    """
    modes = beam_frequencies(planform, n_modes)
    if loads is not None:
        cases = tuple(loads)
        if not all(isinstance(c, LoadCase) for c in cases):
            raise InvalidChain("loads must be a sequence of pinflex.prbdm.loads.LoadCase")
        solutions = [case_truth(planform, case) for case in cases]
        return TruthData(
            modes, np.array([c.alpha for c in cases]),
            np.array([c.force_n(planform) for c in cases]).reshape(-1, 2),
            np.array([s.tip_m for s in solutions]).reshape(-1, 2), cases,
            np.array([c.moment_nm(planform) for c in cases]),
            np.array([c.boundary == "fixed-guided" for c in cases], dtype=bool))
    ei = equivalent_bending_stiffness(planform)
    alpha = np.asarray(alphas, dtype=float)
    forces = np.column_stack([np.zeros_like(alpha), -alpha * ei / planform.length_m**2])
    tips = np.array([elastica_tip(planform, f).tip_m for f in forces]).reshape(-1, 2)
    return TruthData(modes, alpha, forces, tips)


def build_problem(planform: Planform, n_joints: int, n_modes: int | None = None,
                  poses: str | np.ndarray = "straight", stiffness_law: str = "segment",
                  truth: TruthData | None = None, metrics: str = "pinflex") -> MappingProblem:
    """Assemble a mapping problem.

    Args:
        planform: The beam.
        n_joints: Number of revolute joints n (>= 1).
        n_modes: Modes to match; default n (capped at the modes in ``truth``).
        poses: ``"straight"`` (theta = 0, where the beam's frequencies are defined),
            ``"paper"`` (the sweep of :func:`paper_poses`), or an array of shape (m, n) [rad].
        stiffness_law: ``"segment"`` or ``"paper"`` (see the module docstring).
        truth: Precomputed truth; computed with :func:`compute_truth` if omitted.
        metrics: What the residuals measure, ``"pinflex"`` or ``"paper"`` (see
            :class:`MappingProblem`).

    Raises:
        InvalidChain: For an unknown law or pose set, or too many modes.
    """
    if int(n_joints) != n_joints or n_joints < 1:
        raise InvalidChain(f"n_joints = {n_joints!r} must be a positive integer")
    if metrics not in METRICS:
        raise InvalidChain(f"metrics = {metrics!r}; expected one of {METRICS}")
    if stiffness_law not in STIFFNESS_LAWS:
        raise InvalidChain(f"stiffness_law = {stiffness_law!r}; expected one of {STIFFNESS_LAWS}")
    n_modes = n_joints if n_modes is None else int(n_modes)
    if not 1 <= n_modes <= n_joints:
        raise InvalidChain(f"an {n_joints}R chain has {n_joints} modes; n_modes = {n_modes}")
    if truth is None:
        truth = compute_truth(planform, n_modes)
    if n_joints < 2 and np.any(truth.guided):
        raise InvalidChain("a fixed-guided load holds the end link's angle: a 1R chain cannot "
                           "deflect under it; use 2 or more joints or drop the guided cases")
    if truth.modes.freq_hz.size < n_modes:
        raise InvalidChain(f"truth has {truth.modes.freq_hz.size} modes, {n_modes} requested")
    if isinstance(poses, str):
        if poses == "straight":
            pose_array = np.zeros((1, n_joints))
        elif poses == "paper":
            pose_array = paper_poses(n_joints)
        else:
            raise InvalidChain(f"poses = {poses!r}; expected 'straight', 'paper' or an array")
    else:
        pose_array = np.atleast_2d(np.asarray(poses, dtype=float))
        if pose_array.shape[1] != n_joints:
            raise InvalidChain(f"poses have {pose_array.shape[1]} columns, need {n_joints}")
    return MappingProblem(planform, int(n_joints), n_modes, truth.modes.freq_hz[:n_modes].copy(),
                          pose_array, truth.forces_n, truth.tips_m, stiffness_law, truth.alphas,
                          metrics, truth.moments_nm, truth.guided,
                          tuple(c.label for c in truth.cases))


def design_bounds(problem: MappingProblem) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds of the design vector.

    Eq. (15c-d) on the fractions, and +-25 on the log correction factors.
    """
    n1 = problem.n_joints + 1
    n_k = problem.n_stiffness_params
    lower = np.concatenate([np.full(n1, MIN_FRACTION), np.full(n_k, -25.0)])
    upper = np.concatenate([np.full(n1, 1.0 - MIN_FRACTION), np.full(n_k, 25.0)])
    return lower, upper


def joint_pieces(planform: Planform, gamma: np.ndarray) -> np.ndarray:
    """Boundaries of the beam pieces the joints stand for, shape (n + 1,) [m]."""
    lengths = np.asarray(gamma) * planform.length_m
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    mids = starts + 0.5 * lengths
    return np.concatenate([[0.0], mids[1:-1], [planform.length_m]])


def reference_stiffness(problem: MappingProblem, gamma: np.ndarray) -> np.ndarray:
    """Uncorrected spring stiffness of each joint for the problem's law, shape (n,)."""
    planform = problem.planform
    if problem.stiffness_law == "segment":
        pieces = chain_segments(planform, joint_pieces(planform, gamma))
        return np.array([1.0 / seg.compliance_1_n_m for seg in pieces])
    lengths = np.asarray(gamma) * planform.length_m
    starts = np.cumsum(lengths)[:-1]
    links = chain_segments(planform, np.concatenate([starts, [planform.length_m]]))
    e = planform.material.youngs_modulus_pa
    return np.array([np.sqrt(e * seg.mean_area_moment_m4 / seg.mass_kg) for seg in links])


@dataclass(frozen=True)
class Evaluation:
    r"""Losses of one design.

    Attributes:
        eigen_error: RMS over poses and modes of the per-mode relative frequency error [-].
        deflection_error: RMS over loads of the displacement-normalised tip error [-].
        deflection_error_position: Same, normalised by the tip position vector (eq. 19) [-].
        combined_error: :math:`\sqrt{e_{eig}^2 + e_{defl}^2}` (eq. 27) [-].
        pose_errors: RMS per-mode relative frequency error at each pose, shape (m,).
        load_errors: Displacement-normalised tip error per load, shape (l,).
        model_hz: Chain frequencies at each pose, shape (m, n_modes) [Hz].
        model_tips_m: Chain tip positions, shape (l, 2) [m] (NaN where Newton failed).
        failed_loads: Number of loads whose Newton solve failed.
        residuals: Weighted residual vector whose squared norm is
            :math:`e_{eig}^2 + e_{defl}^2` (eigen part first, shape (m n_modes + 2 l,)).
        eigen_error_eq16: RMS over poses of eq. (16),
            :math:`\|f_{truth} - f_{model}\|_2 / \|f_{truth}\|_2` [-].
        eq16_per_pose: Eq. (16) at each pose, shape (m,) [-]; eq. (15a) is their sum.
        eq19_per_load: Eq. (19), tip error over the tip position vector, per load (l,) [-].
    """

    eigen_error: float
    deflection_error: float
    deflection_error_position: float
    combined_error: float
    pose_errors: np.ndarray
    load_errors: np.ndarray
    model_hz: np.ndarray
    model_tips_m: np.ndarray
    failed_loads: int
    residuals: np.ndarray
    eigen_error_eq16: float
    eq16_per_pose: np.ndarray = field(default_factory=lambda: np.zeros(0))
    eq19_per_load: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def eq15a_sum(self) -> float:
        """Eq. (15a) with eq. (16): the sum over poses (not a mean) [-]."""
        return float(np.sum(self.eq16_per_pose))

    @property
    def eq15a_mean(self) -> float:
        """Eq. (16) averaged over poses (eq. 15a divided by the number of poses) [-]."""
        return float(np.mean(self.eq16_per_pose))


def decode(problem: MappingProblem, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Split a design vector into fractions (n + 1,) and correction factors."""
    n1 = problem.n_joints + 1
    return np.asarray(x[:n1], dtype=float), np.exp(np.asarray(x[n1:], dtype=float))


def stiffness_per_pose(problem: MappingProblem, gamma: np.ndarray, factors: np.ndarray,
                       ref: np.ndarray | None = None) -> np.ndarray:
    """Spring stiffness at every pose, shape (m, n) [N m/rad]."""
    ref = reference_stiffness(problem, gamma) if ref is None else ref
    if problem.stiffness_law == "segment":
        return np.repeat((factors * ref)[None, :], problem.poses.shape[0], axis=0)
    return factors[:, None] * ref[None, :]


def static_stiffness(problem: MappingProblem, gamma: np.ndarray, factors: np.ndarray,
                     ref: np.ndarray | None = None) -> np.ndarray:
    """Spring stiffness used for tip statics, shape (n,) [N m/rad] (mean factor for 'paper')."""
    ref = reference_stiffness(problem, gamma) if ref is None else ref
    if problem.stiffness_law == "segment":
        return factors * ref
    return float(np.mean(factors)) * ref


def design_chain(problem: MappingProblem, x: np.ndarray) -> PrbdmChain:
    """The chain of a design vector, with its static stiffness."""
    gamma, factors = decode(problem, x)
    gamma = gamma / gamma.sum()
    return build_chain(problem.planform, gamma, static_stiffness(problem, gamma, factors))


def evaluate(problem: MappingProblem, x: np.ndarray, deflection: bool = True,
             load_steps: int = 4, warm=None) -> Evaluation:
    """Losses of design vector x (see the module docstring).

    Args:
        problem: The mapping problem.
        x: Design vector, shape (n_params,).
        deflection: Whether to solve tip statics (skipped for eigen-only searches).
        load_steps: Load increments of each cold Newton solve; warm starts from the last
            converged angles of the same load use one step.
        warm: Optional :class:`~pinflex.prbdm.sensitivity.WarmStarts` (explicit state of the
            caller: the last converged angles per load, updated here).

    This reference path builds a new chain for every design; the fits use
    :func:`~pinflex.prbdm.sensitivity.evaluate_with_jacobian` (same numbers, one model
    updated in place, exact Jacobian).
    """
    gamma, factors = decode(problem, x)
    gamma = gamma / gamma.sum()
    ref = reference_stiffness(problem, gamma)
    k_pose = stiffness_per_pose(problem, gamma, factors, ref)
    chain = build_chain(problem.planform, gamma, static_stiffness(problem, gamma, factors, ref))
    data = chain.model.createData()
    model_hz = np.empty((problem.poses.shape[0], problem.n_modes))
    for i, pose in enumerate(problem.poses):
        posed = replace(chain, stiffness_nm_rad=k_pose[i])
        model_hz[i] = chain_frequencies(posed, pose, data)[: problem.n_modes]
    rel = model_hz / problem.truth_hz - 1.0
    pose_err = np.sqrt(np.mean(rel**2, axis=1))
    eig = float(np.sqrt(np.mean(rel**2)))
    eq16 = np.linalg.norm(model_hz - problem.truth_hz, axis=1) / np.linalg.norm(problem.truth_hz)
    eig_res = _eigen_residuals(problem, model_hz)
    n_loads = problem.forces_n.shape[0]
    tips = np.full((n_loads, 2), np.nan)
    load_err = np.full(n_loads, np.nan)
    defl_res = np.zeros((n_loads, 2))
    pos_err = np.full(n_loads, np.nan)
    failed = 0
    if deflection and n_loads:
        undeformed = np.array([problem.planform.length_m, 0.0])
        for ell in range(n_loads):
            tips[ell], ok = _solve_load(chain, data, ell, problem.load(ell), load_steps, warm)
            failed += not ok
            truth = problem.truth_tips_m[ell]
            miss = np.linalg.norm(tips[ell] - truth) if ok else np.nan
            load_err[ell] = miss / np.linalg.norm(truth - undeformed) if ok else FAILED_LOAD_ERROR
            norm = np.linalg.norm(truth if problem.metrics == "paper" else truth - undeformed)
            defl_res[ell] = ((tips[ell] - truth) / norm if ok
                             else np.full(2, FAILED_LOAD_ERROR / np.sqrt(2.0)))
            pos_err[ell] = miss / np.linalg.norm(truth) if ok else FAILED_LOAD_ERROR
    defl = float(np.sqrt(np.mean(load_err**2))) if deflection and n_loads else float("nan")
    defl_pos = float(np.sqrt(np.mean(pos_err**2))) if deflection and n_loads else float("nan")
    combined = float(np.hypot(eig, defl)) if deflection and n_loads else float("nan")
    residuals = np.concatenate([eig_res, defl_res.ravel() / np.sqrt(max(n_loads, 1))])
    return Evaluation(eig, defl, defl_pos, combined, pose_err, load_err, model_hz, tips, failed,
                      residuals, float(np.sqrt(np.mean(eq16**2))), eq16, pos_err)


METRICS = ("pinflex", "paper")


def _eigen_residuals(problem: MappingProblem, model_hz: np.ndarray) -> np.ndarray:
    """Frequency residuals whose squared norm is the mean square of the problem's metric."""
    if problem.metrics == "paper":
        return ((model_hz - problem.truth_hz) / np.linalg.norm(problem.truth_hz)).ravel() \
            / np.sqrt(model_hz.shape[0])
    rel = model_hz / problem.truth_hz - 1.0
    return rel.ravel() / np.sqrt(rel.size)


def _solve_load(chain: PrbdmChain, data: pin.Data, index: int,
                load: tuple[np.ndarray, float, str], load_steps: int,
                warm) -> tuple[np.ndarray, bool]:
    """Tip of one load, warm-started from ``warm`` (if given) and cold otherwise.

    A force with an end moment has no branch check in the chain statics, so it is always
    solved cold (by the load steps from rest), never from another design's angles.
    """
    force, moment, boundary = load
    start = None if warm is None or (moment != 0.0 and np.any(force)) \
        else warm.angles.get(index)
    attempts = [(start, 1), (None, load_steps)] if start is not None else [(None, load_steps)]
    for theta0, steps in attempts:
        try:
            result = solve_tip_statics(chain, force, theta0, load_steps=steps, data=data,
                                       moment_nm=moment, boundary=boundary)
        except NewtonDivergence:
            continue
        if warm is not None:
            warm.angles[index] = np.array(result.theta)
        return result.tip_m, True
    return np.full(2, np.nan), False
