r"""Paper 001's definitions, computed beside pinflex's (Vedant and Allison 2020).

Two readings of the paper are offered, each as a named set of :class:`Definitions`:

``"paper-text"`` (:data:`PAPER_TEXT`), the text as printed:

* **Stiffness law** eq. (14): :math:`K_j(i) = k_i\sqrt{E I_j/\hat m_j}`, one correction factor
  per pose i, :math:`I_j` the second moment of area and :math:`\hat m_j` the mass of link j.
  For a planform of uniform thickness t, :math:`I_j = t^3\bar w_j/12` and
  :math:`\hat m_j = \rho t \bar w_j L_j` with the same mean width :math:`\bar w_j`, so
  :math:`\sqrt{E I_j/\hat m_j} = \sqrt{E t^2/(12\rho L_j)}`: **the width drops out**, and the
  springs depend on the link lengths only. The scale's unit is
  :math:`\sqrt{\mathrm{Pa\,m^4/kg}} = \mathrm{m^{1.5}/s}`, not a stiffness: the factor k
  carries the rest.
* **Poses** eq. (10)-(11): every joint at :math:`\xi + i\epsilon`, i = 0, 1, ... while the end
  link's world angle stays at or below :math:`\pi/2`; :math:`\xi = 0.05`, :math:`\epsilon = 0.1`
  for single-objective fits (Sec. 4.1.1) and :math:`\epsilon = 0.01` for the Pareto search
  (Sec. 3).
* **Frequency loss** eq. (15a) with eq. (16): the **sum** over the m poses of
  :math:`\|f_{FEA} - f_{PRBDM}(\theta_i)\|_2/\|f_{FEA}\|_2`, frequencies compared (eq. 24 lists
  its "eigenvalues" as frequencies).
* **Deflection loss** eq. (19): :math:`\|P_{FEA} - P_{PRBDM}\|_2/\|P_{FEA}\|_2` (over the tip
  *position*); loads not given: ours are dead transverse tip forces at
  :math:`\alpha = PL^2/EI_{eq}` = 0.5, 1, 2, 5 (RMS over them), the statics with the mean
  factor (eq. 25).
* **Combined** eq. (27): :math:`\sqrt{\delta^2 + \lambda^2}`.

``"paper-code"`` (:data:`PAPER_CODE`), what the paper's public code computes (its conference
code for the eigen-only fits, its journal code for the Pareto search):

* **Eigenvalues**: the eigenvalues of :math:`M^{-1}K` (squared angular frequencies) are compared
  with :math:`\omega^2`, per pose :math:`\|\lambda - \omega^2\|_2/\|\omega^2\|_2`, and the loss
  is the **mean** over poses.
* **Poses**: 0.1 : 0.01 : :math:`\pi/(2n)` rad, every joint at the same angle (43 / 30 / 22
  poses for 3R / 4R / 5R).
* **Eq. 14's** :math:`I_j` is the link's rotational (mass) moment of inertia about the bending
  axis, the one its dynamics use, so the springs depend on the planform's width. (The helper
  the code calls for the polygon moments is in neither repository; we take the inertia about
  the link's centre of mass, as the code's Lagrangian uses it.) Unit of the scale:
  :math:`\sqrt{\mathrm{Pa\,kg\,m^2/kg}} = \sqrt{\mathrm{N}}`.
* **Deflection**: the tip *position* error over the position,
  :math:`\|P - P_{FEA}\|/\|P_{FEA}\|`, with pose i's springs, averaged over the loads and the
  poses. The load is one vertical tip force; the code's (1 MN on beam 17,572) put the tip at
  (0.9917, -0.1437) L. On another beam the same case is carried over as the downward tip force
  under which the beam's elastica deflects by 0.1437 L (:func:`code_tip_force`); a force in
  newtons can be given instead. (In the stored journal code the tip position is computed with
  the design vector's first entries, the link masses, in place of the link lengths; pinflex
  computes it from the lengths.)
* **Combined**: :math:`\sqrt{\delta^2 + \lambda^2}` of the two means (the point of the Pareto
  front closest to the origin).

Both eigen-only losses are scale-free: with one free factor per pose, the best factor follows
in closed form and the pose's loss is the sine of the angle between the chain's unit-factor
vector and the truth's (:mod:`pinflex.prbdm.perpose`). The unit of the truth frequencies
therefore does not matter.

pinflex's own losses (:mod:`pinflex.prbdm.problem`) are stricter: per-mode relative frequency
errors (eq. 16 is dominated by the highest mode: under the :math:`\omega^2` norm mode 1 can be
off by tens of percent while the loss is a fraction of a percent) and tip errors over the tip
*displacement*.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq, minimize

from ..exceptions import InvalidChain
from .beams import Planform, equivalent_bending_stiffness
from .massmatrix import ChainWorkspace
from .options import DEFINITIONS
from .problem import (
    MappingProblem,
    TruthData,
    build_problem,
    design_bounds,
    evaluate,
    paper_poses,
)
from .sensitivity import evaluate_with_jacobian
from .truth import elastica_tip

#: The code's deflection case: the tip position its load produced, relative to L (x, z).
CODE_TIP_TARGET = (1.0 - 0.0083, -0.1437)

#: Pose offset xi of eq. (11) [rad].
PAPER_XI = 0.05
#: Pose step epsilon of eq. (11) for single-objective fits [rad].
PAPER_EPS_SINGLE = 0.1
#: Pose step epsilon of eq. (11) for the Pareto search [rad].
PAPER_EPS_PARETO = 0.01


@dataclass(frozen=True)
class Definitions:
    r"""One reading of paper 001's losses.

    Attributes:
        name: ``"paper-text"`` or ``"paper-code"``.
        inertia: Eq. (14)'s :math:`I_j`: ``"area"`` (second moment of area, the text) or
            ``"mass"`` (the link's rotational inertia about its centre of mass, the code).
        compare: ``"hz"`` (frequencies, eq. 16 as printed) or ``"omega2"`` (eigenvalues of
            :math:`M^{-1}K` against :math:`\omega^2`).
        aggregate: Over poses, ``"sum"`` (eq. 15a as printed) or ``"mean"``.
        pose_offset: First pose angle [rad].
        pose_step: Pose step [rad].
        deflection: ``"mean-factor"`` (statics with the mean factor, eq. 19 RMS over loads)
            or ``"per-pose"`` (statics with each pose's springs, eq. 19 averaged over loads
            and poses).
    """

    name: str
    inertia: str
    compare: str
    aggregate: str
    pose_offset: float
    pose_step: float
    deflection: str

    def poses(self, n_joints: int, step: float | None = None) -> np.ndarray:
        """The pose sweep, shape (m, n) [rad]; ``step`` overrides the pose step."""
        return paper_poses(n_joints, self.pose_offset, self.pose_step if step is None else step)

    def combine(self, per_pose: np.ndarray) -> np.ndarray:
        """Aggregate per-pose losses (last axis) by this reading's rule."""
        return per_pose.sum(-1) if self.aggregate == "sum" else per_pose.mean(-1)


PAPER_TEXT = Definitions("paper-text", "area", "hz", "sum", 0.05, 0.1, "mean-factor")
PAPER_CODE = Definitions("paper-code", "mass", "omega2", "mean", 0.1, 0.01, "per-pose")


def definitions_named(name: str) -> Definitions:
    """The :class:`Definitions` called ``name`` (``"paper-text"`` or ``"paper-code"``).

    Raises:
        InvalidChain: For any other name.
    """
    found = {d.name: d for d in (PAPER_TEXT, PAPER_CODE)}.get(name)
    if found is None:
        raise InvalidChain(f"definitions = {name!r}; expected one of {DEFINITIONS}")
    return found


def code_tip_force(planform: Planform) -> float:
    """Downward tip force [N] under which the beam's elastica tip deflects by 0.1437 L.

    The code's deflection case (1 MN on beam 17,572, tip at (0.9917, -0.1437) L) carried over
    to another beam by its deflection.
    """
    ei = equivalent_bending_stiffness(planform)
    length = planform.length_m
    target = -CODE_TIP_TARGET[1] * length

    def miss(alpha: float) -> float:
        tip = elastica_tip(planform, np.array([0.0, -alpha * ei / length**2])).tip_m
        return float(-tip[1] - target)

    alpha = brentq(miss, 0.01, 5.0, xtol=1e-13, rtol=1e-13)
    return float(alpha * ei / length**2)


def eq14_reference(planform: Planform, link_lengths_m: np.ndarray) -> np.ndarray:
    r"""Eq. (14)'s scale for uniform thickness, :math:`\sqrt{E t^2/(12\rho L_j)}` (width-free)."""
    e = planform.material.youngs_modulus_pa
    rho = planform.material.density_kg_m3
    t = planform.thickness_m
    return np.sqrt(e * t**2 / (12.0 * rho * np.asarray(link_lengths_m, dtype=float)))


def paper_problem(planform: Planform, n_joints: int, truth: TruthData,
                  n_modes: int | None = None, epsilon: float = PAPER_EPS_SINGLE,
                  stiffness_law: str = "paper", metrics: str = "paper") -> MappingProblem:
    """The mapping problem with the paper's poses (xi = 0.05, the given epsilon)."""
    poses = paper_poses(n_joints, PAPER_XI, epsilon)
    return build_problem(planform, n_joints, n_modes, poses, stiffness_law, truth, metrics)


@dataclass(frozen=True)
class PaperLosses:
    """Losses of one design by paper 001's definitions (fractions, not percent).

    Attributes:
        epsilon: Pose step of the sweep used [rad].
        n_poses: Number of poses m.
        eq15a_sum: Eq. (15a) with eq. (16): sum over poses.
        eq15a_mean: The same divided by m.
        eq19_rms: Eq. (19) RMS over our loads.
        eq27_sum: Eq. (27) with eq15a_sum.
        eq27_mean: Eq. (27) with eq15a_mean.
    """

    epsilon: float
    n_poses: int
    eq15a_sum: float
    eq15a_mean: float
    eq19_rms: float
    eq27_sum: float
    eq27_mean: float

    def as_percent(self) -> dict:
        """The losses in percent, keyed by name."""
        return {k: 100.0 * getattr(self, k) for k in
                ("eq15a_sum", "eq15a_mean", "eq19_rms", "eq27_sum", "eq27_mean")}


def paper_losses(problem: MappingProblem, x: np.ndarray,
                 epsilon: float = PAPER_EPS_SINGLE) -> PaperLosses:
    """Paper-defined losses of design x of ``problem``, over the paper's pose sweep.

    A ``"segment"``-law design has pose-independent springs and is evaluated at the paper's
    poses; a ``"paper"``-law design must already be posed on that sweep (one factor per pose).
    """
    poses = paper_poses(problem.n_joints, PAPER_XI, epsilon)
    if problem.stiffness_law == "paper" and (problem.poses.shape != poses.shape
                                             or not np.allclose(problem.poses, poses)):
        raise InvalidChain("a paper-law design has one factor per pose of its own sweep; "
                           "evaluate it on that sweep")
    ev = evaluate(replace(problem, poses=poses, metrics="paper"), x)
    eq19 = float(np.sqrt(np.mean(ev.eq19_per_load**2)))
    s, m = ev.eq15a_sum, ev.eq15a_mean
    return PaperLosses(float(epsilon), int(poses.shape[0]), s, m, eq19,
                       float(np.hypot(s, eq19)), float(np.hypot(m, eq19)))


def polish_eq15a(problem: MappingProblem, x0: np.ndarray, max_iter: int = 200) -> np.ndarray:
    r"""Minimise eq. (15a) literally, :math:`\sum_i \|r_i\|`, from x0 (SLSQP, exact gradient).

    The least-squares fits minimise the mean of the squares; the literal sum of norms has a
    slightly different minimiser. Bounds are eq. (15c-d) and the simplex is an equality.
    """
    if problem.metrics != "paper":
        raise InvalidChain("polish_eq15a needs a problem built with metrics='paper'")
    workspace = ChainWorkspace(problem.planform, problem.n_joints)
    n1 = problem.n_joints + 1
    m = problem.poses.shape[0]
    k = problem.n_modes

    def fun(x):
        je = evaluate_with_jacobian(problem, x, workspace, deflection=False, pinocchio=False)
        blocks = je.evaluation.residuals[: m * k].reshape(m, k) * np.sqrt(m)
        jac = je.jacobian[: m * k].reshape(m, k, -1) * np.sqrt(m)
        norms = np.linalg.norm(blocks, axis=1)
        safe = np.where(norms > 0, norms, 1.0)
        grad = np.einsum("mk,mkp->p", blocks / safe[:, None], jac)
        return float(norms.sum()), grad

    lower, upper = design_bounds(problem)
    cons = {"type": "eq", "fun": lambda x: np.sum(x[:n1]) - 1.0,
            "jac": lambda x: np.concatenate([np.ones(n1), np.zeros(x.size - n1)])}
    x_start = np.array(x0, dtype=float)
    x_start[:n1] /= x_start[:n1].sum()
    result = minimize(fun, x_start, jac=True, method="SLSQP", bounds=list(zip(lower, upper)),
                      constraints=[cons], options={"maxiter": max_iter, "ftol": 1e-14})
    x = np.asarray(result.x if fun(result.x)[0] <= fun(x_start)[0] else x_start, dtype=float)
    x[:n1] = np.clip(x[:n1], lower[:n1], upper[:n1])
    x[:n1] /= x[:n1].sum()
    return x
