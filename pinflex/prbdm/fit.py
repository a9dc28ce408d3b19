"""The result of a PRBDM mapping (:class:`PrbdmFit`), shared by every way of fitting."""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass, field

import numpy as np

from ..summaries import dataclass_summary
from .beams import Planform
from .chain import PrbdmChain, build_chain
from .problem import Evaluation, MappingProblem, decode, static_stiffness


@dataclass(frozen=True)
class PrbdmFit:
    r"""Result of a PRBDM mapping.

    Attributes:
        beam: Beam label.
        n_joints: Number of revolute joints n.
        n_modes: Number of matched modes.
        objective: Objective that was minimised.
        stiffness_law: ``"segment"`` or ``"paper"``.
        link_fractions: Link-length fractions :math:`\gamma` of links 0..n, (n + 1,) [-].
        link_lengths_m: Link lengths, (n + 1,) [m].
        stiffness: Static spring stiffness of joints 1..n, (n,) [N m/rad].
        correction_factors: Stiffness correction factors (per joint or per pose) [-].
        truth_hz: Beam frequencies, (n_modes,) [Hz].
        model_hz: Chain frequencies at the first comparison pose, (n_modes,) [Hz].
        eigen_error: RMS per-mode relative frequency error over poses and modes [-].
        eigen_error_eq16: RMS over poses of eq. (16)'s norm-relative error [-].
        deflection_error: RMS displacement-normalised tip error over loads [-].
        deflection_error_position: Same, normalised by the tip position (eq. 19) [-].
        combined_error: :math:`\sqrt{e_{eig}^2 + e_{defl}^2}` (eq. 27) [-].
        pose_errors: Relative frequency error per pose, (m,) [-].
        load_errors: Displacement-normalised tip error per load, (l,) [-].
        alphas: Load levels :math:`PL^2/EI_{eq}`, (l,) [-].
        truth_tips_m: Elastica tip positions, (l, 2) [m].
        model_tips_m: Chain tip positions, (l, 2) [m].
        n_starts: Multistart points per search.
        n_poses: Number of comparison poses m.
        pareto: Front points (eigen_error, deflection_error), sorted by deflection error.
        n_free_parameters: Free design parameters (fractions less the simplex, factors).
        n_matched: Matched quantities (frequencies over poses, plus two tip coordinates per
            load when the objective uses deflection).
        determinacy: ``"exactly determined"`` (n_free >= n_matched: the residual is zero up to
            round-off on a manifold and says nothing of quality) or ``"over-determined"``.
        metrics: What was minimised, ``"pinflex"`` or ``"paper"`` (see
            :class:`~pinflex.prbdm.problem.MappingProblem`).
        eq15a_sum: Eq. (15a) with eq. (16) summed over this fit's own poses [-].
        eq15a_mean: The same divided by the number of poses [-].
        n_evaluations: Residual evaluations spent by all searches of the fit (finite
            differences included; one analytic evaluation yields residuals and Jacobian).
        definitions: The definitions the fit was made by: ``"pinflex"`` (the default),
            ``"paper-text"`` or ``"paper-code"`` (:mod:`pinflex.prbdm.paper`). For the paper's
            definitions the fields above are pinflex's losses of the fitted chain with the
            mean factor (eq. 25) at the straight pose under pinflex's loads, and the paper's
            losses are in ``losses``.
        losses: The fit's losses by its own definitions, by name (fractions): for
            ``"paper-code"`` ``frequency`` (mean over poses of
            :math:`\|\lambda - \omega^2\|/\|\omega^2\|`), ``deflection`` (the code's
            tip-position error, mean over loads and poses) and ``combined`` (eq. 27); for
            ``"paper-text"`` ``eq15a_sum``, ``eq15a_mean``, ``eq19_rms`` and ``eq27_sum``.
        mode_errors: Per mode, the largest relative frequency error
            :math:`|f_k/f_{truth,k} - 1|` over the fit's poses [-] (paper definitions).
        start_values: The objective reached from every polished start, ascending [-]
            (paper definitions): how stable the optimum is.
        n_samples: Designs of the global sample (paper definitions).
        starts_at_best: Polished starts whose value is within 0.1 % of the best (paper
            definitions): 1 means the optimum was found once and another sample may find a
            lower one (the fit then warns, ``OptimumNotConfirmedWarning``).
        load_n: Tip forces of the paper definitions' deflection loss, (l, 2) [N].
        load_labels: Names of the load cases of ``load_errors`` when the fit was given load
            cases (:mod:`pinflex.prbdm.loads`), e.g. ``"b=1"``, ``"guided a=10 @90"``; empty
            for paper 001's transverse forces at ``alphas``.
    """

    __repr__ = dataclass_summary  # fields summarised: no array dumps

    beam: str
    n_joints: int
    n_modes: int
    objective: str
    stiffness_law: str
    link_fractions: tuple[float, ...]
    link_lengths_m: tuple[float, ...]
    stiffness: tuple[float, ...]
    correction_factors: tuple[float, ...]
    truth_hz: tuple[float, ...]
    model_hz: tuple[float, ...]
    eigen_error: float
    eigen_error_eq16: float
    deflection_error: float
    deflection_error_position: float
    combined_error: float
    pose_errors: tuple[float, ...]
    load_errors: tuple[float, ...]
    alphas: tuple[float, ...]
    truth_tips_m: tuple[tuple[float, float], ...]
    model_tips_m: tuple[tuple[float, float], ...]
    n_starts: int
    n_poses: int
    pareto: tuple[tuple[float, float], ...] = field(default=())
    n_free_parameters: int = 0
    n_matched: int = 0
    determinacy: str = ""
    metrics: str = "pinflex"
    eq15a_sum: float = float("nan")
    eq15a_mean: float = float("nan")
    n_evaluations: int = 0
    definitions: str = "pinflex"
    losses: dict[str, float] = field(default_factory=dict)
    mode_errors: tuple[float, ...] = ()
    start_values: tuple[float, ...] = ()
    n_samples: int = 0
    starts_at_best: int = 0
    load_n: tuple[tuple[float, float], ...] = ()
    load_labels: tuple[str, ...] = ()

    @property
    def exactly_determined(self) -> bool:
        """True when the free parameters are at least as many as the matched quantities.

        Such a fit can match its targets to round-off along a whole manifold of designs; its
        residual is not a measure of model quality and is not reported as a loss.
        """
        return self.determinacy == "exactly determined"

    def to_dict(self) -> dict:
        """Plain-Python dictionary (JSON-ready); ``link_lengths`` aliases the lengths [m]."""
        out = asdict(self)
        out["link_lengths"] = list(self.link_lengths_m)
        return out

    def to_json(self, indent: int | None = None) -> str:
        """JSON text of :meth:`to_dict` (NaN written as null).

        Args:
            indent: Indentation passed to :func:`json.dumps` (None: one line).

        Returns:
            The JSON text.
        """
        return json.dumps(_nan_to_none(self.to_dict()), indent=indent)

    def chain(self, planform: Planform) -> PrbdmChain:
        """Pinocchio chain of the fitted model (static stiffness).

        Args:
            planform: The beam the fit was made for (its mass and inertia go to the links).

        Returns:
            :class:`PrbdmChain` with the fitted link fractions (n + 1,) and spring
            stiffnesses (n,) [N m/rad].

        Raises:
            InvalidChain: The stored fractions or stiffnesses are not a valid chain.
            InvalidBeam: The planform cannot carry an nR chain (depth taper or zero tip width).
        """
        return build_chain(planform, np.array(self.link_fractions), np.array(self.stiffness))


def _nan_to_none(value):
    if isinstance(value, dict):
        return {k: _nan_to_none(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_nan_to_none(v) for v in value]
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def determinacy_counts(problem: MappingProblem, objective: str) -> tuple[int, int]:
    """(free parameters, matched quantities) of a mapping with the given objective."""
    n_free = problem.n_params - 1
    n_freq = int(problem.poses.shape[0]) * problem.n_modes
    n_tip = 2 * int(problem.forces_n.shape[0])
    matched = {"eigen": n_freq, "deflection": n_tip}.get(objective, n_freq + n_tip)
    return n_free, matched


def make_fit(problem: MappingProblem, x: np.ndarray, ev: Evaluation, objective: str,
              n_starts: int, front: list, n_evaluations: int = 0, **extra) -> PrbdmFit:
    """The :class:`PrbdmFit` of design x of ``problem`` with its evaluation ``ev``.

    ``extra`` sets the fields of the paper's definitions (``definitions``, ``losses``, ...).
    """
    gamma, factors = decode(problem, x)
    gamma = gamma / gamma.sum()
    stiffness = static_stiffness(problem, gamma, factors)

    def tup(a) -> tuple:
        return tuple(float(v) for v in np.asarray(a).ravel())

    n_free, n_matched = determinacy_counts(problem, objective)

    return PrbdmFit(
        beam=problem.planform.name, n_joints=problem.n_joints, n_modes=problem.n_modes,
        objective=objective, stiffness_law=problem.stiffness_law, link_fractions=tup(gamma),
        link_lengths_m=tup(gamma * problem.planform.length_m), stiffness=tup(stiffness),
        correction_factors=tup(factors), truth_hz=tup(problem.truth_hz),
        model_hz=tup(ev.model_hz[0]), eigen_error=ev.eigen_error,
        eigen_error_eq16=ev.eigen_error_eq16,
        deflection_error=ev.deflection_error,
        deflection_error_position=ev.deflection_error_position,
        combined_error=ev.combined_error, pose_errors=tup(ev.pose_errors),
        load_errors=tup(ev.load_errors), alphas=tup(problem.alphas),
        truth_tips_m=tuple(tup(t) for t in problem.truth_tips_m),
        model_tips_m=tuple(tup(t) for t in ev.model_tips_m), n_starts=n_starts,
        n_poses=int(problem.poses.shape[0]),
        pareto=tuple((float(p[1].eigen_error), float(p[1].deflection_error)) for p in front),
        n_free_parameters=n_free, n_matched=n_matched,
        determinacy="exactly determined" if n_free >= n_matched else "over-determined",
        metrics=problem.metrics, eq15a_sum=ev.eq15a_sum, eq15a_mean=ev.eq15a_mean,
        n_evaluations=int(n_evaluations), load_labels=problem.load_labels, **extra,
    )
