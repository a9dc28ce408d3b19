r"""Losses of a PRBDM design and their exact Jacobian, on one Pinocchio model kept in place.

:func:`pinflex.prbdm.problem.evaluate` rebuilds a chain for every design; a finite-difference
Jacobian then costs n_params + 1 rebuilds and Newton solves. Here one Pinocchio model per
problem is updated in place (link inertias, joint placements, tip frame) and the residuals come
with their derivatives:

* **Frequencies.** For :math:`K\phi_k = \lambda_k M\phi_k` with :math:`\phi_k^T M \phi_k = 1`,
  :math:`\partial\lambda_k/\partial c = \phi_k^T(\partial K/\partial c
  - \lambda_k\,\partial M/\partial c)\phi_k` (distinct eigenvalues).
* **Mass matrix.** For the planar chain (all joint axes parallel), in absolute link angles
  :math:`q = S\theta` (S lower triangular ones), :math:`M(\theta) = S^T (C(q) \circ G) S` with
  :math:`C_{ab} = \cos(q_a - q_b)` and a pose-independent G:
  :math:`G_{aa} = \ell_a^2 T_a + \mu_{2,a}`, :math:`G_{ab} = \ell_a(\ell_b T_b + \mu_{1,b})`
  for a < b, where :math:`\ell_a` is the length of link a, :math:`T_b` the mass outboard of
  link b, and :math:`\mu_{1}, \mu_{2}` the first and second mass moments of a link about its
  own joint. G is polynomial in the link lengths and the links' inertia integrals, whose
  derivatives with respect to the joint positions are the integrands at the link ends. The
  chain's Pinocchio CRBA is what is evaluated; this form supplies :math:`\partial M/\partial s`.
* **Statics.** At the converged equilibrium :math:`R(\theta, c) = K\theta - J^T F = 0`, so
  :math:`d\theta/dc = -T^{-1}\partial R/\partial c` with the tangent T of Newton's method, and
  the tip moves by :math:`J\,d\theta/dc + \partial P/\partial c`.

Warm starts are explicit: a :class:`WarmStarts` object, owned by the caller, keeps each load's
last converged joint angles. It never changes an answer beyond the Newton tolerance, because
every answer passes the same convergence and branch checks.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin

from .beams import Planform, compliance_between, segment_arrays
from .chain import PrbdmChain
from .problem import FAILED_LOAD_ERROR, Evaluation, MappingProblem


@dataclass
class WarmStarts:
    """Last converged joint angles per load index, passed explicitly to evaluations."""

    angles: dict[int, np.ndarray] = field(default_factory=dict)

    def clear(self) -> None:
        """Forget every stored start."""
        self.angles.clear()


def _thickness(planform: Planform, s: np.ndarray) -> np.ndarray:
    return np.asarray(planform.thickness_at(s), dtype=float)


class ChainWorkspace:
    """One Pinocchio nR chain for a beam, updated in place for each design.

    Args:
        planform: The beam.
        n_joints: Number of revolute joints n.
    """

    def __init__(self, planform: Planform, n_joints: int):
        self.planform = planform
        self.n = int(n_joints)
        model = pin.Model()
        model.name = "prbdm"
        parent = 0
        for j in range(1, self.n + 1):
            joint = model.addJoint(parent, pin.JointModelRY(), pin.SE3.Identity(), f"joint_{j}")
            model.appendBodyToJoint(joint, pin.Inertia.Zero(), pin.SE3.Identity())
            model.addFrame(pin.Frame(f"link_{j}", joint, pin.SE3.Identity(), pin.FrameType.BODY))
            parent = joint
        self.tip_frame_id = int(model.addFrame(
            pin.Frame("tip", parent, pin.SE3.Identity(), pin.FrameType.OP_FRAME)))
        self.model = model
        self.data = model.createData()

    def update(self, gamma: np.ndarray, pinocchio: bool = True
               ) -> tuple[np.ndarray, np.ndarray, tuple]:
        """Set link lengths and inertias of fractions gamma in place.

        Returns:
            Joint positions s_1..s_n [m], lengths of links 0..n [m], and the links' property
            arrays (mass, com, ixx, iyy, izz, mean area moment, compliance) of
            :func:`~pinflex.prbdm.beams.segment_arrays`. With ``pinocchio=False`` the
            Pinocchio model is left as it was (the closed-form mass matrix is used instead).
        """
        length = self.planform.length_m
        lengths = np.asarray(gamma, dtype=float) * length
        s = np.cumsum(lengths)[:-1]
        links = segment_arrays(self.planform, np.concatenate([s, [length]]))
        if not pinocchio:
            return s, lengths, links
        mass, com, ixx, iyy, izz = links[:5]
        eye = np.eye(3)
        for j in range(1, self.n + 1):
            self.model.jointPlacements[j] = pin.SE3(eye, np.array([lengths[j - 1], 0.0, 0.0]))
            self.model.inertias[j] = pin.Inertia(
                float(mass[j - 1]), np.array([com[j - 1] - s[j - 1], 0.0, 0.0]),
                np.diag([ixx[j - 1], iyy[j - 1], izz[j - 1]]))
        self.model.frames[self.tip_frame_id].placement = pin.SE3(
            eye, np.array([lengths[-1], 0.0, 0.0]))
        return s, lengths, links

    def chain(self, lengths: np.ndarray, stiffness: np.ndarray, links: tuple) -> PrbdmChain:
        """A :class:`PrbdmChain` view of the current model (no copy of the model)."""
        return PrbdmChain(self.model, lengths, np.asarray(stiffness, dtype=float),
                          self.tip_frame_id, np.asarray(links[0]))

    def mass_matrix(self, theta: np.ndarray) -> np.ndarray:
        """CRBA mass matrix of the current model at theta, symmetric (n, n)."""
        m = pin.crba(self.model, self.data, np.asarray(theta, dtype=float))
        return np.triu(m) + np.triu(m, 1).T


def link_moments(planform: Planform, s: np.ndarray, links: tuple):
    r"""Inertia integrals of links 1..n about their joints and their joint-position derivatives.

    For link j on :math:`[s_j, s_{j+1}]` (:math:`s_{n+1} = L`):
    :math:`\mu_0 = \int\rho A`, :math:`\mu_1 = \int (x - s_j)\rho A`,
    :math:`\mu_2 = \int ((x - s_j)^2 + t^2/12)\rho A`.

    Returns:
        (mu, dmu) with mu shape (3, n) and dmu shape (3, n, n) = d mu_k[j] / d s_i.
    """
    n = s.size
    length = planform.length_m
    rho = planform.material.density_kg_m3
    mass, com, _, iyy = links[:4]
    arm = com - s
    mu = np.array([mass, mass * arm, iyy + mass * arm**2])
    ends = np.concatenate([s, [length]])
    rho_a = rho * planform.area_m2(ends)
    t2 = _thickness(planform, ends) ** 2 / 12.0
    dmu = np.zeros((3, n, n))
    for j in range(n):
        a = ends[j]
        # Start of link j moves: the integrand leaves, and the reference point moves.
        dmu[:, j, j] = [-rho_a[j], -mu[0, j], -rho_a[j] * t2[j] - 2.0 * mu[1, j]]
        if j + 1 < n:
            b = ends[j + 1]
            dmu[:, j, j + 1] = rho_a[j + 1] * np.array([1.0, b - a, (b - a) ** 2 + t2[j + 1]])
    return mu, dmu


def mass_structure(lengths: np.ndarray, mu: np.ndarray, dmu: np.ndarray):
    r"""The pose-independent matrix G of :math:`M = S^T(C\circ G)S` and dG/ds, shape (n, n, n).

    Args:
        lengths: Link lengths of links 1..n, shape (n,) [m] (link n ends at the tip).
        mu: Link moments (3, n) from :func:`link_moments`.
        dmu: Their derivatives (3, n, n).
    """
    n = lengths.size
    m0, m1, m2 = mu
    outboard = np.concatenate([np.cumsum(m0[::-1])[::-1][1:], [0.0]])  # T_b = sum_{j>b} m_j
    h = lengths * outboard + m1
    idx = np.arange(n)
    lower = np.minimum.outer(idx, idx)
    upper = np.maximum.outer(idx, idx)
    g = lengths[lower] * h[upper]
    g[idx, idx] = lengths**2 * outboard + m2
    # d l_a / d s_i: l_a = s_{a+1} - s_a (s_{n+1} = L).
    dl = np.zeros((n, n))
    dl[idx, idx] = -1.0
    dl[idx[:-1], idx[1:]] = 1.0
    later = (idx[None, :] > idx[:, None]).astype(float)  # later[b, c] = c > b
    d_out = later @ dmu[0]                                # (b, i)
    dh = dl * outboard[:, None] + lengths[:, None] * d_out + dmu[1]
    dg = dl[lower] * h[upper][:, :, None] + lengths[lower][:, :, None] * dh[upper]
    dg[idx, idx] = (2.0 * lengths * outboard)[:, None] * dl + (lengths**2)[:, None] * d_out \
        + dmu[2]
    return g, dg


def pose_mass_matrix(g: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """M(theta) = S^T (C o G) S from the pose-independent G, and the cosine matrix C."""
    q = np.cumsum(theta)
    c = np.cos(q[:, None] - q[None, :])
    s_mat = np.tril(np.ones((theta.size, theta.size)))
    return s_mat.T @ (c * g) @ s_mat, c


def reference_stiffness_and_derivative(problem: MappingProblem, s: np.ndarray,
                                       lengths: np.ndarray, links: tuple):
    """Uncorrected stiffness (n,) and its derivative with respect to s, shape (n, n)."""
    planform = problem.planform
    n = s.size
    length = planform.length_m
    e = planform.material.youngs_modulus_pa
    if problem.stiffness_law == "segment":
        ends = np.concatenate([s, [length]])
        bounds = np.concatenate([[0.0], 0.5 * (ends[:-1] + ends[1:])[: n - 1], [length]])
        k = 1.0 / compliance_between(planform, bounds)
        inv_ei = 1.0 / (e * planform.area_moment_m4(bounds))
        # Interior bound j = 1..n-1 is (s_j + s_{j+1}) / 2; the root and the tip are fixed.
        db = np.zeros((n + 1, n))
        for j in range(1, n):
            db[j, j - 1] = db[j, j] = 0.5
        dcomp = inv_ei[1:, None] * db[1:] - inv_ei[:-1, None] * db[:-1]
        return k, -(k**2)[:, None] * dcomp
    ends = np.concatenate([s, [length]])
    ell = np.diff(ends)
    mass, mean_i = links[0], links[5]
    k = np.sqrt(e * mean_i / mass)
    i_end = planform.area_moment_m4(ends)
    rho_a = planform.material.density_kg_m3 * planform.area_m2(ends)
    dk = np.zeros((n, n))
    for j in range(n):
        # link j spans ends[j] .. ends[j + 1]; ends[n] = L is fixed.
        for side, sign in ((j, -1.0), (j + 1, 1.0)):
            if side >= n:
                continue
            d_int = sign * i_end[side]
            d_ell = sign
            d_mass = sign * rho_a[side]
            d_mean = (d_int - mean_i[j] * d_ell) / ell[j]
            dk[j, side] += 0.5 * k[j] * (d_mean / mean_i[j] - d_mass / mass[j])
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
    n = problem.n_joints
    n1 = n + 1
    raw = np.asarray(x[:n1], dtype=float)
    total = raw.sum()
    gamma = raw / total
    factors = np.exp(np.asarray(x[n1:], dtype=float))
    length = problem.planform.length_m
    s, lengths, links = workspace.update(gamma, pinocchio)
    k_ref, dk_ref = reference_stiffness_and_derivative(problem, s, lengths, links)
    # ds/dx: s_j = L sum_{i<j} gamma_i; gamma = raw / sum(raw).
    dgamma = (np.eye(n1) - gamma[:, None]) / total
    ds_dx = length * np.tril(np.ones((n, n1)), 0) @ dgamma
    n_p = problem.n_params
    m_poses = problem.poses.shape[0]
    law_segment = problem.stiffness_law == "segment"
    if want_jacobian or not pinocchio:
        mu, dmu = link_moments(problem.planform, s, links)
        g, dg = mass_structure(lengths[1:], mu, dmu)
        dg_dx = dg @ ds_dx                                  # (n, n, n + 1): fractions only
    nm = problem.n_modes
    if law_segment:
        k_pose = np.broadcast_to(factors * k_ref, (m_poses, n))
    else:
        k_pose = factors[:, None] * k_ref[None, :]
    # K phi = lam M phi with K diagonal: y = K^(1/2) phi solves A y = (1/lam) y,
    # A = K^(-1/2) M K^(-1/2); phi = K^(-1/2) y / sqrt(1/lam) is M-normalised.
    if pinocchio:
        mass = np.array([workspace.mass_matrix(pose) for pose in problem.poses])
    else:
        q_all = np.cumsum(problem.poses, axis=1)
        tri = np.tril(np.ones((n, n)))
        mass = tri.T @ (np.cos(q_all[:, :, None] - q_all[:, None, :]) * g) @ tri
    k_isqrt = 1.0 / np.sqrt(k_pose)
    a_mat = mass * k_isqrt[:, :, None] * k_isqrt[:, None, :]
    mu_all, y_all = np.linalg.eigh(a_mat)
    mu_top = mu_all[:, ::-1][:, :nm]
    lam = 1.0 / mu_top                                    # ascending eigenvalues (m, nm)
    phi = k_isqrt[:, :, None] * y_all[:, :, ::-1][:, :, :nm] / np.sqrt(mu_top)[:, None, :]
    model_hz = np.sqrt(lam) / (2.0 * np.pi)
    dfreq = np.zeros((m_poses, nm, n_p))
    if want_jacobian:
        q = np.cumsum(problem.poses, axis=1)
        cos = np.cos(q[:, :, None] - q[:, None, :])
        psi = np.einsum("ab,mbk->mak", np.tril(np.ones((n, n))), phi)
        # dM/dx_p = S^T (C o dG/dx_p) S, contracted with phi on both sides.
        weights = np.einsum("mak,mbk,mab->mkab", psi, psi, cos).reshape(m_poses, nm, n * n)
        dm_quad = weights @ dg_dx.reshape(n * n, n1)          # (m, nm, n1)
        dk_frac = dk_ref @ ds_dx                              # (n, n1) per unit factor
        f_pose = k_pose / k_ref                               # correction factor per (pose, j)
        phi2 = phi**2                                         # (m, n, nm)
        dfreq[:, :, :n1] = np.einsum("mjk,mj,jp->mkp", phi2, f_pose, dk_frac) \
            - lam[:, :, None] * dm_quad
        if law_segment:
            dfreq[:, :, n1:] = np.swapaxes(phi2 * k_pose[:, :, None], 1, 2)
        else:
            dfreq[np.arange(m_poses), :, n1 + np.arange(m_poses)] = np.einsum(
                "mjk,mj->mk", phi2, k_pose)
        dfreq /= 8.0 * np.pi**2 * model_hz[:, :, None]
    rel = model_hz / problem.truth_hz - 1.0
    pose_err = np.sqrt(np.mean(rel**2, axis=1))
    eig = float(np.sqrt(np.mean(rel**2)))
    eq16 = np.linalg.norm(model_hz - problem.truth_hz, axis=1) / np.linalg.norm(problem.truth_hz)
    paper = problem.metrics == "paper"
    if paper:
        norm_f = np.linalg.norm(problem.truth_hz)
        eig_res = ((model_hz - problem.truth_hz) / norm_f).ravel() / np.sqrt(m_poses)
        jac_eig = (dfreq / norm_f).reshape(-1, n_p) / np.sqrt(m_poses)
    else:
        eig_res = rel.ravel() / np.sqrt(rel.size)
        jac_eig = (dfreq / problem.truth_hz[None, :, None]).reshape(-1, n_p) / np.sqrt(rel.size)
    n_loads = problem.forces_n.shape[0]
    tips = np.full((n_loads, 2), np.nan)
    load_err = np.full(n_loads, np.nan)
    pos_err = np.full(n_loads, np.nan)
    defl_res = np.zeros((n_loads, 2))
    jac_defl = np.zeros((n_loads, 2, n_p))
    failed = 0
    if deflection and n_loads:
        k_static = factors * k_ref if law_segment else float(np.mean(factors)) * k_ref
        ell = lengths[1:]
        theta0 = np.zeros((n_loads, n))
        have = np.zeros(n_loads, dtype=bool)
        if warm is not None:
            for index, angles in warm.angles.items():
                if index < n_loads:
                    theta0[index], have[index] = angles, True
        theta = np.zeros((n_loads, n))
        ok = np.zeros(n_loads, dtype=bool)
        if np.any(have):
            theta[have], ok[have] = planar_statics(k_static, ell, problem.forces_n[have],
                                                   theta0[have], 1)
        retry = ~ok
        if np.any(retry):
            theta_c, ok_c = planar_statics(k_static, ell, problem.forces_n[retry],
                                           np.zeros((int(retry.sum()), n)), load_steps)
            theta[retry], ok[retry] = theta_c, ok_c
        undeformed = np.array([length, 0.0])
        scale = np.linalg.norm(problem.truth_tips_m - (0.0 if paper else undeformed), axis=1)
        failed = int(np.count_nonzero(~ok))
        load_err[~ok] = FAILED_LOAD_ERROR
        pos_err[~ok] = FAILED_LOAD_ERROR
        defl_res[~ok] = FAILED_LOAD_ERROR / np.sqrt(2.0)
        if warm is not None:
            for k_load in np.flatnonzero(ok):
                warm.angles[int(k_load)] = theta[k_load].copy()
        if np.any(ok):
            q = np.cumsum(theta[ok], axis=1)
            tips[ok] = np.column_stack([s[0] + (ell * np.cos(q)).sum(1),
                                        -(ell * np.sin(q)).sum(1)])
            miss = tips[ok] - problem.truth_tips_m[ok]
            load_err[ok] = np.linalg.norm(miss, axis=1) / np.linalg.norm(
                problem.truth_tips_m[ok] - undeformed, axis=1)
            pos_err[ok] = np.linalg.norm(miss, axis=1) / np.linalg.norm(
                problem.truth_tips_m[ok], axis=1)
            defl_res[ok] = miss / scale[ok, None]
            if want_jacobian:
                jac_defl[ok] = _tip_derivative(k_static, theta[ok], problem.forces_n[ok],
                                               lengths, k_ref, dk_ref, factors, ds_dx,
                                               law_segment, n1) / scale[ok, None, None]
    defl = float(np.sqrt(np.mean(load_err**2))) if deflection and n_loads else float("nan")
    defl_pos = float(np.sqrt(np.mean(pos_err**2))) if deflection and n_loads else float("nan")
    combined = float(np.hypot(eig, defl)) if deflection and n_loads else float("nan")
    norm_l = np.sqrt(max(n_loads, 1))
    residuals = np.concatenate([eig_res, defl_res.ravel() / norm_l])
    jac = np.vstack([jac_eig, jac_defl.reshape(-1, n_p) / norm_l])
    ev = Evaluation(eig, defl, defl_pos, combined, pose_err, load_err, model_hz, tips, failed,
                    residuals, float(np.sqrt(np.mean(eq16**2))), eq16, pos_err)
    return JacobianEvaluation(ev, jac)


def _tip_derivative(k_static: np.ndarray, theta: np.ndarray, forces: np.ndarray,
                    lengths: np.ndarray, k_ref: np.ndarray, dk_ref: np.ndarray,
                    factors: np.ndarray, ds_dx: np.ndarray, law_segment: bool,
                    n1: int) -> np.ndarray:
    """Derivatives of the tips (x, z) with respect to x at equilibria, shape (l, 2, n_params).

    Args:
        k_static: Static spring stiffness (n,).
        theta: Converged angles, one row per load (l, n).
        forces: The loads (l, 2).
        lengths: Lengths of links 0..n.
        k_ref: Uncorrected stiffness (n,) and ``dk_ref`` its derivative (n, n) by s.
        dk_ref: See ``k_ref``.
        factors: Correction factors.
        ds_dx: Joint positions' derivative by the fractions (n, n + 1).
        law_segment: Whether the law is ``"segment"``.
        n1: n + 1.
    """
    n_l, n = theta.shape
    n_p = ds_dx.shape[1] + factors.size
    q = np.cumsum(theta, axis=1)
    ell = lengths[1:]
    c, sn = np.cos(q), np.sin(q)
    fx, fz = forces[:, :1], forces[:, 1:]
    s_mat = np.tril(np.ones((n, n)))
    # Tip Jacobian rows: d x_tip / d q_a = -l_a sin q_a, d z_tip / d q_a = -l_a cos q_a.
    jac_x = (-ell * sn) @ s_mat
    jac_z = (-ell * c) @ s_mat
    work = -sn * fx - c * fz                               # u'(q_a) . F
    idx = np.arange(n)
    arm = ell * (c * fx - sn * fz)                         # l_a u(q_a) . F
    suffix = np.cumsum(arm[:, ::-1], axis=1)[:, ::-1]
    tangent = suffix[:, np.maximum.outer(idx, idx)]
    tangent[:, idx, idx] += k_static
    dl_ds = np.zeros((n, n))                               # links 1..n: l_a = s_{a+1} - s_a
    dl_ds[idx, idx] = -1.0
    dl_ds[idx[:-1], idx[1:]] = 1.0
    dl_dx = dl_ds @ ds_dx                                  # (n, n1)
    scale = factors if law_segment else np.full(n, float(np.mean(factors)))
    dk_dx = np.zeros((n, n_p))
    dk_dx[:, :n1] = scale[:, None] * dk_ref @ ds_dx
    if law_segment:
        dk_dx[idx, n1 + idx] = k_static
    else:
        dk_dx[:, n1:] = k_ref[:, None] * (factors / factors.size)[None, :]
    dr = dk_dx[None, :, :] * theta[:, :, None]
    # (J^T F)_i = sum_{a >= i} l_a u'(q_a) . F depends on the lengths directly.
    dr[:, :, :n1] -= np.einsum("ia,la,ap->lip", s_mat.T, work, dl_dx)
    dtheta = -np.linalg.solve(tangent, dr)
    dtip = np.stack([np.einsum("la,lap->lp", jac_x, dtheta),
                     np.einsum("la,lap->lp", jac_z, dtheta)], axis=1)
    # Direct dependence on the geometry: P = (s_1, 0) + sum_a l_a u(q_a).
    dtip[:, 0, :n1] += c @ dl_dx + ds_dx[0]
    dtip[:, 1, :n1] += -sn @ dl_dx
    return dtip


def planar_tip(root_m: float, ell: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """Tip (x, z) of the chain: link 0 of length root_m along +X, links 1..n of lengths ell."""
    q = np.cumsum(theta)
    return np.array([root_m + np.sum(ell * np.cos(q)), -np.sum(ell * np.sin(q))])


def planar_statics(k: np.ndarray, ell: np.ndarray, forces: np.ndarray, theta0: np.ndarray,
                   load_steps: int, max_iter: int = 30, tol: float = 1e-10
                   ) -> tuple[np.ndarray, np.ndarray]:
    r"""Newton's method for :math:`K\theta = J^T F` on several dead loads at once.

    The planar closed form of :func:`~pinflex.prbdm.chain.solve_tip_statics` (the same
    residual, tangent, tolerance and acceptance checks: converged, tangent positive definite,
    every absolute link angle between the axis and the force), vectorised over loads.

    Args:
        k: Spring stiffness (n,) [N m/rad].
        ell: Lengths of links 1..n (n,) [m].
        forces: Tip forces (l, 2) [N].
        theta0: Starting angles (l, n) [rad].
        load_steps: Equal load increments.
        max_iter: Newton iterations allowed per load step.
        tol: Convergence tolerance on the residual relative to its terms' norms.

    Returns:
        (theta (l, n), ok (l,)) with ok False where a check failed.
    """
    theta = np.array(theta0, dtype=float)
    n_l, n = theta.shape
    idx = np.arange(n)
    top = np.maximum.outer(idx, idx)
    ok = np.ones(n_l, dtype=bool)

    def terms(th: np.ndarray, f: np.ndarray):
        q = np.cumsum(th, axis=1)
        c, sn = np.cos(q), np.sin(q)
        w = ell * (-sn * f[:, :1] - c * f[:, 1:])             # l_a u'(q_a) . F
        tau = np.cumsum(w[:, ::-1], axis=1)[:, ::-1]
        arm = ell * (c * f[:, :1] - sn * f[:, 1:])            # l_a u(q_a) . F
        suffix = np.cumsum(arm[:, ::-1], axis=1)[:, ::-1]
        tangent = suffix[:, top]
        tangent[:, idx, idx] += k
        return k * th - tau, tangent, tau

    for step in range(1, int(load_steps) + 1):
        f_step = forces * step / load_steps
        active = ok.copy()
        for iteration in range(max_iter + 1):
            residual, tangent, tau = terms(theta, f_step)
            norm = np.sqrt(np.einsum("li,li->l", residual, residual))
            kt = k * theta
            scale = np.sqrt(np.einsum("li,li->l", kt, kt)) \
                + np.sqrt(np.einsum("li,li->l", tau, tau)) + 1e-300
            done = norm <= tol * scale
            bad = ~np.isfinite(norm)
            ok &= ~bad
            active &= ~done & ~bad
            if not np.any(active):
                break
            if iteration == max_iter:
                ok &= ~active
                break
            try:
                delta = np.linalg.solve(tangent[active], residual[active][:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                ok &= ~active
                break
            theta[active] -= delta
    _, tangent, _ = terms(theta, forces)
    eig_min = np.linalg.eigvalsh(0.5 * (tangent + np.swapaxes(tangent, 1, 2)))[:, 0]
    ok &= eig_min > 0.0
    angle = np.arctan2(-forces[:, 1], forces[:, 0])
    absolute = np.cumsum(theta, axis=1)
    low, high = np.minimum(0.0, angle), np.maximum(0.0, angle)
    slack = 1e-9 + 1e-12 * np.abs(absolute).max(axis=1, initial=0.0)
    ok &= np.all(absolute >= (low - slack)[:, None], axis=1)
    ok &= np.all(absolute <= (high + slack)[:, None], axis=1)
    ok &= np.all(np.isfinite(theta), axis=1)
    return theta, ok
