r"""One stiffness correction factor per pose (paper 001's eq. 14): batched evaluations.

Under eq. (14) the springs at pose i are :math:`K(i) = k_i K^{ref}(\gamma)`, so the chain's
eigenvalues there are :math:`k_i` times those of the unit-factor chain,
:math:`\hat\lambda_i(\gamma)`. A frequency loss that compares a vector v (the eigenvalues, or
the frequencies :math:`\propto\sqrt{\lambda}`) with its target w by :math:`\|v - w\|/\|w\|`
is minimised over the pose's factor in closed form, and its minimum is the sine of the angle
between :math:`\hat v_i` and w: the eigen-only loss is a function of the link fractions
alone. Everything here is evaluated for many designs at once (the global search of
:mod:`pinflex.prbdm.posedfit` samples tens of thousands): eigenvalues of the closed-form mass
matrix, and the tip statics of the code's deflection loss, which uses each pose's springs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .beams import Planform, segment_arrays
from .massmatrix import chain_indices, mass_g
from .paper import Definitions
from .planar import planar_indices, planar_statics
from .problem import FAILED_LOAD_ERROR


@dataclass(frozen=True)
class PosedProblem:
    """A fit with one factor per pose, by one set of paper 001's definitions.

    Attributes:
        planform: The beam.
        n_joints: Number of joints n.
        n_modes: Modes compared (<= n).
        definitions: The reading of the paper (:class:`~pinflex.prbdm.paper.Definitions`).
        poses: Pose sweep, shape (m, n) [rad].
        truth_hz: Beam frequencies, shape (n_modes,) [Hz].
        forces_n: Tip forces of the deflection loss, shape (l, 2) [N].
        truth_tips_m: Their elastica tips, shape (l, 2) [m].
    """

    planform: Planform
    n_joints: int
    n_modes: int
    definitions: Definitions
    poses: np.ndarray
    truth_hz: np.ndarray
    forces_n: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    truth_tips_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))

    @property
    def target(self) -> np.ndarray:
        """The compared truth vector: frequencies [Hz] or squared angular frequencies."""
        if self.definitions.compare == "hz":
            return np.asarray(self.truth_hz, dtype=float)
        return (2.0 * np.pi * np.asarray(self.truth_hz, dtype=float)) ** 2


def link_arrays(planform: Planform, gammas: np.ndarray) -> tuple[np.ndarray, ...]:
    """Joint positions, lengths of links 1..n and their properties for designs (N, n + 1).

    Returns:
        (s, lengths, mass, com, iyy, mean area moment), each of shape (N, n).
    """
    length = planform.length_m
    ends = length * np.cumsum(gammas, axis=1)
    ends[:, -1] = length
    s = ends[:, :-1]
    bounds = np.concatenate([s, ends[:, -1:]], axis=1)
    mass, com, _, iyy, _, mean_i, _ = segment_arrays(planform, bounds)
    return s, np.diff(bounds, axis=1), mass, com, iyy, mean_i


def reference_springs(planform: Planform, inertia: str, mass: np.ndarray, iyy: np.ndarray,
                      mean_i: np.ndarray) -> np.ndarray:
    r"""Eq. (14)'s unit-factor springs :math:`\sqrt{E I_j/\hat m_j}` with the given :math:`I_j`."""
    moment = iyy if inertia == "mass" else mean_i
    return np.sqrt(planform.material.youngs_modulus_pa * moment / mass)


def unit_eigenvalues(problem: PosedProblem, gammas: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues of the unit-factor chains at every pose, ascending.

    Args:
        problem: The fit.
        gammas: Link fractions of N designs, shape (N, n + 1) (each row sums to 1).

    Returns:
        (eigenvalues (N, m, n) [rad^2/s^2], unit-factor springs (N, n)).
    """
    gammas = np.atleast_2d(np.asarray(gammas, dtype=float))
    n = problem.n_joints
    s, lengths, mass, com, iyy, mean_i = link_arrays(problem.planform, gammas)
    g = mass_g(lengths, (mass, com, None, iyy), s)                     # (N, n, n)
    ix = chain_indices(n)
    q = np.cumsum(problem.poses, axis=1)
    cos = np.cos(q[:, :, None] - q[:, None, :])                         # (m, n, n)
    m_mat = ix.tri_t @ (cos[None] * g[:, None]) @ ix.tri               # (N, m, n, n)
    k_ref = reference_springs(problem.planform, problem.definitions.inertia, mass, iyy, mean_i)
    scale = 1.0 / np.sqrt(k_ref)
    a_mat = m_mat * scale[:, None, :, None] * scale[:, None, None, :]
    mu = np.linalg.eigvalsh(a_mat)
    return 1.0 / mu[..., ::-1], k_ref


def compared(problem: PosedProblem, eigenvalues: np.ndarray) -> np.ndarray:
    """The first n_modes compared quantities from eigenvalues: Hz or the eigenvalues."""
    lam = eigenvalues[..., : problem.n_modes]
    return np.sqrt(lam) / (2.0 * np.pi) if problem.definitions.compare == "hz" else lam


def eigen_terms(problem: PosedProblem, gammas: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Best factors and per-pose losses of the frequency comparison.

    Returns:
        (per-pose loss (N, m), best factor k_i (N, m), unit-factor compared vectors
        (N, m, n_modes)). For frequencies the vector scales with :math:`\sqrt{k}`, for
        eigenvalues with k.
    """
    lam, _ = unit_eigenvalues(problem, gammas)
    v = compared(problem, lam)
    w = problem.target
    vw = v @ w
    vv = np.einsum("...k,...k->...", v, v)
    c = vw / vv
    ww = float(w @ w)
    sine2 = np.clip(1.0 - vw**2 / (vv * ww), 0.0, None)
    factor = c**2 if problem.definitions.compare == "hz" else c
    return np.sqrt(sine2), factor, v


def eigen_loss(problem: PosedProblem, gammas: np.ndarray) -> np.ndarray:
    """The eigen-only loss at the best factors, shape (N,)."""
    return problem.definitions.combine(eigen_terms(problem, gammas)[0])


def per_mode_errors(problem: PosedProblem, v_unit: np.ndarray, factors: np.ndarray
                    ) -> np.ndarray:
    """Relative frequency error of every mode at every pose, f / f_truth - 1, (m, n_modes)."""
    scale = np.sqrt(factors) if problem.definitions.compare == "hz" else factors
    v = scale[:, None] * v_unit
    hz = v if problem.definitions.compare == "hz" else np.sqrt(v) / (2.0 * np.pi)
    return hz / problem.truth_hz - 1.0


def tip_positions(problem: PosedProblem, gammas: np.ndarray, factors: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Chain tips under every load, designs (S, n + 1) with factors (S, F), statics batched.

    Returns:
        (tips (S, F, l, 2) [m], ok (S, F, l)).
    """
    gammas = np.atleast_2d(np.asarray(gammas, dtype=float))
    factors = np.asarray(factors, dtype=float).reshape(gammas.shape[0], -1)
    s, lengths, mass, com, iyy, mean_i = link_arrays(problem.planform, gammas)
    k_ref = reference_springs(problem.planform, problem.definitions.inertia, mass, iyy, mean_i)
    n_d, n_f = factors.shape
    n_l = problem.forces_n.shape[0]
    n = problem.n_joints
    shape = (n_d, n_f, n_l, n)
    rows_k = np.broadcast_to(factors[:, :, None, None] * k_ref[:, None, None, :], shape)
    rows_ell = np.broadcast_to(lengths[:, None, None, :], shape).reshape(-1, n)
    forces = np.broadcast_to(problem.forces_n[None, None], (n_d, n_f, n_l, 2)).reshape(-1, 2)
    theta, ok = planar_statics(rows_k.reshape(-1, n), rows_ell, forces,
                               np.zeros((rows_ell.shape[0], n)), 4)
    q = theta @ planar_indices(n).prefix
    root = np.broadcast_to(s[:, None, None, :1], (n_d, n_f, n_l, 1)).reshape(-1)
    tips = np.column_stack([root + np.einsum("rj,rj->r", np.cos(q), rows_ell),
                            -np.einsum("rj,rj->r", np.sin(q), rows_ell)])
    return tips.reshape(n_d, n_f, n_l, 2), ok.reshape(n_d, n_f, n_l)


def deflection_errors(problem: PosedProblem, gammas: np.ndarray, factors: np.ndarray
                      ) -> np.ndarray:
    r"""Deflection error d(k) of designs (S, n + 1) at factors (S, F): eq. (19) over loads.

    Eq. (19) is :math:`\|P - P_{truth}\|/\|P_{truth}\|` (tip position), averaged over the
    loads; a load whose Newton solve fails counts as a 100 % error. Shape (S, F).
    """
    tips, ok = tip_positions(problem, gammas, factors)
    truth = problem.truth_tips_m
    err = np.linalg.norm(tips - truth, axis=-1) / np.linalg.norm(truth, axis=1)
    err = np.where(ok, err, FAILED_LOAD_ERROR)
    return err.mean(axis=-1)


def pose_errors(problem: PosedProblem, v_unit: np.ndarray, factors: np.ndarray
                      ) -> np.ndarray:
    """Per-pose loss ||k v - w|| / ||w|| of designs, v_unit (S, m, n_modes), factors (S, m)."""
    scale = np.sqrt(factors) if problem.definitions.compare == "hz" else factors
    w = problem.target
    return np.linalg.norm(scale[..., None] * v_unit - w, axis=-1) / np.linalg.norm(w)
