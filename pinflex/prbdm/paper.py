r"""Paper 001's own definitions, computed beside pinflex's (Vedant and Allison 2020).

What the paper defines, and what it leaves open:

* **Stiffness law** eq. (14): :math:`K_j(i) = k_i\sqrt{E I_j/\hat m_j}`, one correction factor
  per pose i, :math:`I_j` the second moment of area and :math:`\hat m_j` the mass of link j.
  For a planform of uniform thickness t, :math:`I_j = t^3\bar w_j/12` and
  :math:`\hat m_j = \rho t \bar w_j L_j` with the same mean width :math:`\bar w_j`, so
  :math:`\sqrt{E I_j/\hat m_j} = \sqrt{E t^2/(12\rho L_j)}`: **the width drops out**, and the
  springs of eq. 14 depend on the link lengths only (and are not stiffnesses: N m/rad needs the
  factor k to carry kg m^2/s).
* **Poses** eq. (10)-(11): every joint at :math:`\xi + i\epsilon`, i = 0, 1, ... while the end
  link's world angle stays at or below :math:`\pi/2`; :math:`\xi = 0.05`, :math:`\epsilon = 0.1`
  for single-objective fits (Sec. 4.1.1) and :math:`\epsilon = 0.01` for the Pareto search
  (Sec. 3). (Sec. 2.3 also says :math:`\epsilon = \pi/2n` "in the implementation"; the
  numbers of Sec. 3-4 are used here.)
* **Frequency loss** eq. (15a) with eq. (16): the **sum** over the m poses of
  :math:`\|\lambda_{FEA} - \lambda_{PRBDM}(\theta_i)\|_2/\|\lambda_{FEA}\|_2`; the paper's
  eq. (24) lists its "eigenvalues" in Hz, so frequencies are compared. Whether its printed
  losses are that sum or a mean over poses is not said: the two differ by the factor m, and
  both are reported.
* **Deflection loss** eq. (19): :math:`\|P_{FEA} - P_{PRBDM}\|_2/\|P_{FEA}\|_2` (normalised by
  the tip *position*). The paper's loads are not given; ours are dead transverse tip forces at
  :math:`\alpha = PL^2/EI_{eq}` = 0.5, 1, 2, 5, and the RMS over them is reported.
* **Combined** eq. (27): :math:`\sqrt{\delta^2 + \lambda^2}`.

pinflex's own losses (:mod:`pinflex.prbdm.problem`) are stricter: per-mode relative frequency
errors (eq. 16 is dominated by the highest mode) and tip errors over the tip *displacement*.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize

from ..exceptions import InvalidChain
from .beams import Planform
from .massmatrix import ChainWorkspace
from .problem import (
    MappingProblem,
    TruthData,
    build_problem,
    design_bounds,
    evaluate,
    paper_poses,
)
from .sensitivity import evaluate_with_jacobian

#: Pose offset xi of eq. (11) [rad].
PAPER_XI = 0.05
#: Pose step epsilon of eq. (11) for single-objective fits [rad].
PAPER_EPS_SINGLE = 0.1
#: Pose step epsilon of eq. (11) for the Pareto search [rad].
PAPER_EPS_PARETO = 0.01


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
