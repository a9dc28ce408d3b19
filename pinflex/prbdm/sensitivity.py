r"""Losses of a PRBDM design and their exact Jacobian, on one Pinocchio model kept in place.

:func:`pinflex.prbdm.problem.evaluate` rebuilds a chain for every design; a finite-difference
Jacobian then costs n_params + 1 rebuilds and Newton solves. Here one Pinocchio model per
problem is updated in place (link inertias, joint placements, tip frame) and the residuals come
with their derivatives:

* **Frequencies.** For :math:`K\phi_k = \lambda_k M\phi_k` with :math:`\phi_k^T M \phi_k = 1`,
  :math:`\partial\lambda_k/\partial c = \phi_k^T(\partial K/\partial c
  - \lambda_k\,\partial M/\partial c)\phi_k` (distinct eigenvalues).
* **Mass matrix.** :math:`\partial M/\partial s` from the closed form
  :math:`M = S^T(C\circ G)S` of :mod:`pinflex.prbdm.massmatrix`; the chain's Pinocchio CRBA
  is what the reported evaluations use.
* **Statics.** Implicit derivatives at the converged equilibria
  (:func:`pinflex.prbdm.planar.tip_derivative`).

Warm starts are explicit (:class:`~pinflex.prbdm.warmstarts.WarmStarts`, owned by the caller).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..exceptions import InvalidChain
from .beams import compliance_between, partial_integrals_and_widths
from .massmatrix import ChainWorkspace, chain_indices, link_moments, mass_g, mass_structure
from .planar import planar_indices, planar_statics, tip_derivative
from .problem import FAILED_LOAD_ERROR, Evaluation, MappingProblem
from .warmstarts import WarmStarts


def design_geometry(problem: MappingProblem, gamma: np.ndarray):
    """Joint positions, lengths, link properties and uncorrected stiffness in one pass.

    The same numbers as :meth:`ChainWorkspace.update` (``pinocchio=False``) followed by
    :func:`reference_stiffness_and_derivative` without the derivative: the beam's cumulative
    integrals are evaluated once at the link ends and at the segment-law bounds together.
    The link tuple holds (mass, com, None, iyy, None, mean area moment, None); the widths
    are those at s_1..s_n, L and, for the segment law, at the midpoints between joints.
    """
    planform = problem.planform
    length = planform.length_m
    n = gamma.size - 1
    lengths = gamma * length
    s = np.cumsum(lengths)[:-1]
    segment = problem.stiffness_law == "segment"
    ends = np.empty(n + 1)
    ends[:n], ends[n] = s, length
    if segment:
        points = np.concatenate([ends, 0.5 * (ends[:n - 1] + ends[1:n])])
    else:
        points = ends
    cumulative, widths = partial_integrals_and_widths(planform, points)
    seg = cumulative[1:n + 1] - cumulative[:n]
    m0, m1, m2 = seg[:, 0], seg[:, 1], seg[:, 2]
    t = planform.thickness_m
    rho_t = planform.material.density_kg_m3 * t
    mass = rho_t * m0
    com = m1 / m0
    iyy = rho_t * (m2 - com * m1) + mass * t**2 / 12.0
    ell = ends[1:] - ends[:-1]
    mean_i = m0 * t**3 / 12.0 / ell
    e = planform.material.youngs_modulus_pa
    if segment:
        inv = np.empty(n + 1)
        inv[0], inv[1:n], inv[n] = 0.0, cumulative[n + 1:, 4], cumulative[n, 4]
        k_ref = e / (inv[1:] - inv[:-1])
    else:
        k_ref = np.sqrt(e * mean_i / mass)
    return s, lengths, (mass, com, None, iyy, None, mean_i, None), k_ref, widths



def reference_stiffness_and_derivative(problem: MappingProblem, s: np.ndarray,
                                       lengths: np.ndarray, links: tuple,
                                       derivative: bool = True,
                                       known: tuple[np.ndarray, np.ndarray] | None = None):
    """Uncorrected stiffness (n,) and its derivative with respect to s, shape (n, n).

    With ``derivative=False`` the derivative is None (not computed). ``known``: the stiffness
    and the widths of :func:`_design_geometry` when already found (uniform thickness only).
    """
    planform = problem.planform
    n = s.size
    length = planform.length_m
    e = planform.material.youngs_modulus_pa
    cubed = planform.thickness_m**3 / 12.0
    ends = np.concatenate([s, [length]])
    if problem.stiffness_law == "segment":
        if known is None:
            bounds = np.concatenate([[0.0], 0.5 * (ends[:-1] + ends[1:])[: n - 1], [length]])
            k = 1.0 / compliance_between(planform, bounds)
        else:
            k, widths = known
        if not derivative:
            return k, None
        if known is None:
            inv_ei = 1.0 / (e * planform.area_moment_m4(bounds))
        else:
            bound_w = np.empty(n + 1)
            bound_w[0], bound_w[1:n], bound_w[n] = 2.0 * planform.half_width_m[0], \
                widths[n + 1:], widths[n]
            inv_ei = 1.0 / ((e * cubed) * bound_w)
        db = chain_indices(n).db
        # The root and the tip bounds are fixed.
        dcomp = inv_ei[1:, None] * db[1:] - inv_ei[:-1, None] * db[:-1]
        return k, -(k**2)[:, None] * dcomp
    ell = ends[1:] - ends[:-1]
    mass, mean_i = links[0], links[5]
    k = np.sqrt(e * mean_i / mass) if known is None else known[0]
    if not derivative:
        return k, None
    if known is None:
        i_end = planform.area_moment_m4(ends)
        rho_a = planform.material.density_kg_m3 * planform.area_m2(ends)
    else:
        end_w = known[1][: n + 1]
        i_end = cubed * end_w
        rho_a = (planform.material.density_kg_m3 * planform.thickness_m) * end_w
    # Link j spans ends[j] .. ends[j + 1] (ends[n] = L fixed); moving an end by +1 changes
    # the link's integral of I by -/+ I(end), its length by -/+ 1 and its mass by -/+ rho A.
    half = 0.5 * k

    def rate(side: np.ndarray) -> np.ndarray:
        return half * ((i_end[side] - mean_i) / (ell * mean_i) - rho_a[side] / mass)

    idx = np.arange(n)
    dk = np.zeros((n, n))
    dk[idx, idx] = -rate(idx)
    dk[idx[:-1], idx[1:]] = rate(idx + 1)[:-1]
    return k, dk



@dataclass(frozen=True)
class JacobianEvaluation:
    """An :class:`~pinflex.prbdm.problem.Evaluation` with the Jacobian of its residuals."""

    evaluation: Evaluation
    jacobian: np.ndarray


def evaluate_with_jacobian(problem: MappingProblem, x: np.ndarray, workspace: ChainWorkspace,
                           warm: WarmStarts | None = None, deflection: bool = True,
                           load_steps: int = 4, want_jacobian: bool = True,
                           pinocchio: bool = True) -> JacobianEvaluation:
    r"""Losses of design x (as :func:`~pinflex.prbdm.problem.evaluate`) and d residuals / d x.

    Args:
        problem: The mapping problem.
        x: Design vector (raw fractions, log correction factors), shape (n_params,).
        workspace: The problem's chain, updated in place.
        warm: Explicit warm starts of the tip statics (updated with the new angles).
        deflection: Whether to solve tip statics.
        load_steps: Load increments of a cold Newton solve.
        want_jacobian: Skip the derivative work when False.
        pinocchio: Mass matrices by CRBA on the in-place Pinocchio model (default) or, when
            False, by the closed form :math:`S^T(C\circ G)S` (the same matrix to round-off,
            without the per-design model update; the fits' inner loop uses it).

    Returns:
        Losses and the Jacobian, shape (len(residuals), n_params).
    """
    out = _evaluate(problem, x, workspace, warm, deflection, load_steps, bool(want_jacobian),
                    pinocchio, summary=True)
    assert isinstance(out, JacobianEvaluation)
    return out


def residuals_and_jacobian(problem: MappingProblem, x: np.ndarray, workspace: ChainWorkspace,
                           warm: WarmStarts | None = None, deflection: bool = True,
                           load_steps: int = 4) -> tuple[np.ndarray, Callable[..., np.ndarray]]:
    """The residuals of :func:`evaluate_with_jacobian` and a function giving their Jacobian.

    The inner loop of a fit: the closed-form mass matrix, no Pinocchio update, no loss
    summaries (the same numbers to round-off as :func:`evaluate_with_jacobian`). The
    Jacobian is formed only when the returned function is called (a trust-region solver
    needs it at accepted steps only), from the state of this evaluation. Called with
    ``out`` (rows: the frequency residuals, optionally followed by the deflection ones), it
    writes the Jacobian's first ``len(out)`` rows there and returns ``out``; with as many rows
    as there are frequency residuals, the deflection rows are not formed.
    """
    out = _evaluate(problem, x, workspace, warm, deflection, load_steps, None, False,
                    summary=False)
    assert isinstance(out, tuple)
    return out


def _evaluate(problem: MappingProblem, x: np.ndarray, workspace: ChainWorkspace,
              warm: WarmStarts | None, deflection: bool, load_steps: int,
              want_jacobian: bool | None, pinocchio: bool, summary: bool
              ) -> JacobianEvaluation | tuple[np.ndarray, Callable[..., np.ndarray]]:
    """Residuals, and the losses when ``summary``.

    The Jacobian is formed now (``want_jacobian`` True), never (False) or on demand (None: a
    closure over this evaluation's state is returned with the residuals).
    """
    if deflection and problem.end_loads:
        raise InvalidChain("end moments and fixed-guided ends are solved by the reference path "
                           "only: use pinflex.prbdm.problem.evaluate (fits: "
                           "jacobian='finite-difference', chosen by fit_prbdm for such loads)")
    n = problem.n_joints
    n1 = n + 1
    ix = chain_indices(n)
    x = np.array(x, dtype=float)
    raw = x[:n1]
    total = raw.sum()
    gamma = raw / total
    factors = np.exp(x[n1:])
    length = problem.planform.length_m
    widths: np.ndarray | None = None
    if pinocchio:
        s, lengths, links = workspace.update(gamma, True)
        k_ref = reference_stiffness_and_derivative(problem, s, lengths, links, False)[0]
    else:
        s, lengths, links, k_ref, widths = design_geometry(problem, gamma)
    n_p = problem.n_params
    poses = problem.poses
    m_poses = poses.shape[0]
    law_segment = problem.stiffness_law == "segment"
    cos = workspace.pose_cosines(poses)
    if not pinocchio:
        g = mass_g(lengths[1:], links, s)
    nm = problem.n_modes
    if law_segment:
        k_pose = np.empty((m_poses, n))
        k_pose[:] = factors * k_ref
    else:
        k_pose = factors[:, None] * k_ref[None, :]
    # K phi = lam M phi with K diagonal: y = K^(1/2) phi solves A y = (1/lam) y,
    # A = K^(-1/2) M K^(-1/2); phi = K^(-1/2) y / sqrt(1/lam) is M-normalised.
    if pinocchio:
        mass = np.array([workspace.mass_matrix(pose) for pose in poses])
    else:
        mass = ix.tri_t @ (cos * g) @ ix.tri
    k_isqrt = 1.0 / np.sqrt(k_pose)
    a_mat = mass * k_isqrt[:, :, None] * k_isqrt[:, None, :]
    mu_all, y_all = np.linalg.eigh(a_mat)
    mu_top = mu_all[:, ::-1][:, :nm]
    lam = 1.0 / mu_top                                    # ascending eigenvalues (m, nm)
    phi = k_isqrt[:, :, None] * y_all[:, :, ::-1][:, :, :nm] / np.sqrt(mu_top)[:, None, :]
    model_hz = np.sqrt(lam) / (2.0 * np.pi)
    truth_hz = problem.truth_hz
    paper = problem.metrics == "paper"
    if paper:
        norm_f = np.sqrt(np.sum(truth_hz**2))
        eig_res = ((model_hz - truth_hz) / norm_f).ravel() / np.sqrt(m_poses)
        eig_scale = np.full(nm, norm_f * np.sqrt(m_poses))
    else:
        rel = model_hz / truth_hz - 1.0
        eig_res = rel.ravel() / np.sqrt(rel.size)
        eig_scale = truth_hz * np.sqrt(rel.size)
    forces = problem.forces_n
    n_loads = forces.shape[0]
    truth_tips = problem.truth_tips_m
    tips = np.full((n_loads, 2), np.nan)
    defl_res = np.zeros((n_loads, 2))
    ok = np.zeros(n_loads, dtype=bool)
    undeformed = np.array([length, 0.0])
    solved = deflection and n_loads > 0
    k_static = factors * k_ref if law_segment else float(np.mean(factors)) * k_ref
    theta = np.zeros((n_loads, n))
    scale = np.ones(n_loads)
    if solved:
        ell = lengths[1:]
        if warm is not None:
            theta0, have = warm.starts(x, n_loads, n)
        else:
            theta0, have = np.zeros((n_loads, n)), np.zeros(n_loads, dtype=bool)
        if have.all():
            theta, ok = planar_statics(k_static, ell, forces, theta0, 1)
        elif have.any():
            theta[have], ok[have] = planar_statics(k_static, ell, forces[have], theta0[have], 1)
        retry = ~ok
        if retry.any():
            theta_c, ok_c = planar_statics(k_static, ell, forces[retry],
                                           np.zeros((int(retry.sum()), n)), load_steps)
            theta[retry], ok[retry] = theta_c, ok_c
        offset = truth_tips if paper else truth_tips - undeformed
        scale = np.sqrt(np.sum(offset**2, axis=1))
        defl_res[~ok] = FAILED_LOAD_ERROR / np.sqrt(2.0)
        if warm is not None:
            for k_load in np.flatnonzero(ok):
                warm.angles[int(k_load)] = theta[k_load].copy()
        if ok.any():
            qs = theta[ok] @ planar_indices(n).prefix
            tips[ok, 0] = s[0] + np.cos(qs) @ ell
            tips[ok, 1] = -(np.sin(qs) @ ell)
            defl_res[ok] = (tips[ok] - truth_tips[ok]) / scale[ok, None]
    norm_l = np.sqrt(max(n_loads, 1))
    residuals = np.concatenate([eig_res, defl_res.ravel() / norm_l])

    def jacobian(out: np.ndarray | None = None) -> np.ndarray:
        # ds/dx: s_j = L sum_{i<j} gamma_i; gamma = raw / sum(raw).
        dgamma = (ix.eye1 - gamma[:, None]) / total
        ds_dx = length * (ix.cum_gamma @ dgamma)
        dfreq = np.zeros((m_poses, nm, n_p))
        known = None if widths is None else (k_ref, widths)
        dk_ref = reference_stiffness_and_derivative(problem, s, lengths, links, known=known)[1]
        mu, dmu = link_moments(problem.planform, s, links,
                               None if widths is None else widths[:n1])
        dg = mass_structure(lengths[1:], mu, dmu)[1]
        dg_dx = dg @ ds_dx                                  # (n, n, n + 1): fractions only
        psi = ix.tri @ phi                                  # (m, n, nm)
        # dM/dx_p = S^T (C o dG/dx_p) S, contracted with phi on both sides.
        psi_t = psi.transpose(0, 2, 1)
        weights = (psi_t[:, :, :, None] * psi_t[:, :, None, :]
                   * cos[:, None, :, :]).reshape(m_poses, nm, n * n)
        dm_quad = weights @ dg_dx.reshape(n * n, n1)          # (m, nm, n1)
        dk_frac = dk_ref @ ds_dx                              # (n, n1) per unit factor
        phi2 = phi**2                                         # (m, n, nm)
        # d lam / d fractions: phi^T dK phi - lam phi^T dM phi; k_pose / k_ref = factor.
        f_pose = k_pose / k_ref
        dfreq[:, :, :n1] = np.swapaxes(phi2 * f_pose[:, :, None], 1, 2) @ dk_frac \
            - lam[:, :, None] * dm_quad
        if law_segment:
            dfreq[:, :, n1:] = np.swapaxes(phi2 * k_pose[:, :, None], 1, 2)
        else:
            dfreq[np.arange(m_poses), :, n1 + np.arange(m_poses)] = \
                (phi2 * k_pose[:, :, None]).sum(1)
        dfreq /= 8.0 * np.pi**2 * model_hz[:, :, None]
        n_eig = m_poses * nm
        full = np.empty((residuals.size, n_p)) if out is None else out
        np.divide(dfreq, eig_scale[None, :, None], out=full[:n_eig].reshape(m_poses, nm, n_p))
        if full.shape[0] == n_eig:
            return full
        jac_defl = full[n_eig:].reshape(n_loads, 2, n_p)
        jac_defl[...] = 0.0
        if solved and ok.any():
            dtip, dtheta = tip_derivative(k_static, theta[ok], forces[ok], lengths, k_ref,
                                           dk_ref, factors, ds_dx, law_segment, n1)
            jac_defl[ok] = dtip / scale[ok, None, None]
            jac_defl /= norm_l
            if warm is not None:
                warm.set_base(x, {int(k): theta[k] for k in np.flatnonzero(ok)},
                              {int(k): dtheta[row] for row, k in enumerate(np.flatnonzero(ok))})
        return full

    if not summary:
        assert want_jacobian is None
        return residuals, jacobian
    jac = jacobian() if want_jacobian else np.zeros((residuals.size, n_p))
    rel = model_hz / truth_hz - 1.0
    pose_err = np.sqrt(np.mean(rel**2, axis=1))
    eig = float(np.sqrt(np.mean(rel**2)))
    eq16 = np.linalg.norm(model_hz - truth_hz, axis=1) / np.linalg.norm(truth_hz)
    load_err = np.full(n_loads, np.nan)
    pos_err = np.full(n_loads, np.nan)
    failed = 0
    if solved:
        failed = int(np.count_nonzero(~ok))
        load_err[~ok] = FAILED_LOAD_ERROR
        pos_err[~ok] = FAILED_LOAD_ERROR
        if ok.any():
            miss = tips[ok] - truth_tips[ok]
            load_err[ok] = np.linalg.norm(miss, axis=1) / np.linalg.norm(
                truth_tips[ok] - undeformed, axis=1)
            pos_err[ok] = np.linalg.norm(miss, axis=1) / np.linalg.norm(truth_tips[ok], axis=1)
    defl = float(np.sqrt(np.mean(load_err**2))) if solved else float("nan")
    defl_pos = float(np.sqrt(np.mean(pos_err**2))) if solved else float("nan")
    combined = float(np.hypot(eig, defl)) if solved else float("nan")
    ev = Evaluation(eig, defl, defl_pos, combined, pose_err, load_err, model_hz, tips, failed,
                    residuals, float(np.sqrt(np.mean(eq16**2))), eq16, pos_err)
    return JacobianEvaluation(ev, jac)

