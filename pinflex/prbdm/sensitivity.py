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

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cache

import numpy as np
import pinocchio as pin

from .beams import Planform, _partial_integrals_and_widths, compliance_between, segment_arrays
from .chain import PrbdmChain
from .problem import FAILED_LOAD_ERROR, Evaluation, MappingProblem


@dataclass
class WarmStarts:
    """Last converged joint angles per load index, passed explicitly to evaluations.

    ``angles`` are the last answers. When a Jacobian was formed, its design ``base_x``, the
    angles there and their implicit-function derivatives ``slopes`` by the design are kept,
    and the next start is the first-order prediction ``base + slopes (x_new - base_x)``.
    """

    angles: dict[int, np.ndarray] = field(default_factory=dict)
    base: dict[int, np.ndarray] = field(default_factory=dict)
    slopes: dict[int, np.ndarray] = field(default_factory=dict)
    base_x: np.ndarray | None = None
    # (loads, base angles, slopes) of the base stacked for one prediction of every load.
    _stacked: tuple[np.ndarray, np.ndarray, np.ndarray] | None = field(
        default=None, repr=False, compare=False)

    def clear(self) -> None:
        """Forget every stored start."""
        self.angles.clear()
        self.base.clear()
        self.slopes.clear()
        self.base_x = None
        self._stacked = None

    def set_base(self, x: np.ndarray, angles: dict[int, np.ndarray],
                 slopes: dict[int, np.ndarray]) -> None:
        """Keep the angles at design x and their derivatives (n, n_params) per load."""
        self.base_x = np.array(x, dtype=float)
        self.base = {k: np.array(v) for k, v in angles.items()}
        self.slopes = slopes
        keys = np.array(sorted(k for k in slopes if k in self.base), dtype=int)
        self._stacked = (keys, np.array([self.base[k] for k in keys]),
                         np.array([slopes[k] for k in keys])) if keys.size else None

    def start(self, index: int, x: np.ndarray) -> np.ndarray:
        """Start angles of load ``index`` for design x (requires ``index in angles``)."""
        slope = self.slopes.get(index)
        if slope is None or self.base_x is None or self.base_x.shape != x.shape:
            return self.angles[index]
        step = slope @ (x - self.base_x)
        # A long extrapolation is no better than the last answer: keep predictions small.
        return self.base[index] + step if np.max(np.abs(step)) < 0.2 else self.angles[index]

    def starts(self, x: np.ndarray, n_loads: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`start` of loads 0..n_loads-1 at once: angles (n_loads, n) and which exist."""
        theta0 = np.zeros((n_loads, n))
        have = np.zeros(n_loads, dtype=bool)
        for index, angles in self.angles.items():
            if index < n_loads:
                theta0[index], have[index] = angles, True
        stacked = self._stacked
        if stacked is None or self.base_x is None or self.base_x.shape != x.shape:
            return theta0, have
        keys, base, slopes = stacked
        step = slopes @ (x - self.base_x)
        use = (np.abs(step).max(axis=1) < 0.2) & (keys < n_loads)
        theta0[keys[use]] = base[use] + step[use]
        return theta0, have


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
        self._cosines: tuple[np.ndarray, np.ndarray] | None = None

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

    def pose_cosines(self, poses: np.ndarray) -> np.ndarray:
        """cos(q_a - q_b) of absolute link angles q at each pose, (m, n, n), kept per poses."""
        cached = self._cosines
        if cached is not None and cached[0] is poses:
            return cached[1]
        q = np.cumsum(poses, axis=1)
        cos = np.cos(q[:, :, None] - q[:, None, :])
        self._cosines = (poses, cos)
        return cos

    def chain(self, lengths: np.ndarray, stiffness: np.ndarray, links: tuple) -> PrbdmChain:
        """A :class:`PrbdmChain` view of the current model (no copy of the model)."""
        return PrbdmChain(self.model, lengths, np.asarray(stiffness, dtype=float),
                          self.tip_frame_id, np.asarray(links[0]))

    def mass_matrix(self, theta: np.ndarray) -> np.ndarray:
        """CRBA mass matrix of the current model at theta, symmetric (n, n)."""
        m = pin.crba(self.model, self.data, np.asarray(theta, dtype=float))
        return np.triu(m) + np.triu(m, 1).T


def link_moments(planform: Planform, s: np.ndarray, links: tuple,
                 end_widths: np.ndarray | None = None):
    r"""Inertia integrals of links 1..n about their joints and their joint-position derivatives.

    For link j on :math:`[s_j, s_{j+1}]` (:math:`s_{n+1} = L`):
    :math:`\mu_0 = \int\rho A`, :math:`\mu_1 = \int (x - s_j)\rho A`,
    :math:`\mu_2 = \int ((x - s_j)^2 + t^2/12)\rho A`.

    ``end_widths``: the widths at s_1..s_n, L when already known (uniform thickness only).

    Returns:
        (mu, dmu) with mu shape (3, n) and dmu shape (3, n, n) = d mu_k[j] / d s_i.
    """
    n = s.size
    length = planform.length_m
    rho = planform.material.density_kg_m3
    mass, com, _, iyy = links[:4]
    arm = com - s
    mu = np.array([mass, mass * arm, iyy + mass * arm**2])
    if end_widths is None:
        ends = np.concatenate([s, [length]])
        rho_a = rho * planform.area_m2(ends)
        t2 = _thickness(planform, ends) ** 2 / 12.0
    else:
        rho_a = (rho * planform.thickness_m) * end_widths
        t2 = np.full(n + 1, planform.thickness_m**2 / 12.0)
    dmu = np.zeros((3, n, n))
    idx = np.arange(n)
    # Start of link j moves: the integrand leaves, and the reference point moves.
    dmu[0, idx, idx] = -rho_a[:n]
    dmu[1, idx, idx] = -mu[0]
    dmu[2, idx, idx] = -rho_a[:n] * t2[:n] - 2.0 * mu[1]
    # End of link j (the start of link j + 1) moves: the integrand joins at arm b - a.
    arm_end = s[1:] - s[:-1]
    rho_end = rho_a[1:n]
    dmu[0, idx[:-1], idx[1:]] = rho_end
    dmu[1, idx[:-1], idx[1:]] = rho_end * arm_end
    dmu[2, idx[:-1], idx[1:]] = rho_end * (arm_end**2 + t2[1:n])
    return mu, dmu


def mass_structure(lengths: np.ndarray, mu: np.ndarray, dmu: np.ndarray):
    r"""The pose-independent matrix G of :math:`M = S^T(C\circ G)S` and dG/ds, shape (n, n, n).

    Args:
        lengths: Link lengths of links 1..n, shape (n,) [m] (link n ends at the tip).
        mu: Link moments (3, n) from :func:`link_moments`.
        dmu: Their derivatives (3, n, n).
    """
    n = lengths.size
    ix = _indices(n)
    m0, m1, m2 = mu
    outboard = np.zeros(n)
    outboard[:-1] = np.cumsum(m0[:0:-1])[::-1]          # T_b = sum_{j>b} m_j
    h = lengths * outboard + m1
    idx, lower, upper = ix.idx, ix.lower, ix.upper
    lengths_low = lengths[lower]
    g = lengths_low * h[upper]
    g[idx, idx] = lengths**2 * outboard + m2
    # d l_a / d s_i: l_a = s_{a+1} - s_a (s_{n+1} = L).
    dl = ix.dl
    d_out = ix.later @ dmu[0]                          # (b, i)
    dh = dl * outboard[:, None] + lengths[:, None] * d_out + dmu[1]
    dg = dl[lower] * h[upper][:, :, None] + lengths_low[:, :, None] * dh[upper]
    dg[idx, idx] = (2.0 * lengths * outboard)[:, None] * dl + (lengths**2)[:, None] * d_out \
        + dmu[2]
    return g, dg


def _design_geometry(problem: MappingProblem, gamma: np.ndarray):
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
    cumulative, widths = _partial_integrals_and_widths(planform, points)
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


def _mass_g(lengths: np.ndarray, links: tuple, s: np.ndarray) -> np.ndarray:
    """G of :func:`mass_structure` alone (no derivatives), from the links' properties."""
    ix = _indices(lengths.size)
    mass, com, _, iyy = links[:4]
    arm = com - s
    m1 = mass * arm
    outboard = np.zeros(lengths.size)
    outboard[:-1] = np.cumsum(mass[:0:-1])[::-1]        # T_b = sum_{j>b} m_j
    h = lengths * outboard + m1
    g = lengths[ix.lower] * h[ix.upper]
    g[ix.idx, ix.idx] = lengths**2 * outboard + iyy + mass * arm**2
    return g


def pose_mass_matrix(g: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """M(theta) = S^T (C o G) S from the pose-independent G, and the cosine matrix C."""
    q = np.cumsum(theta)
    c = np.cos(q[:, None] - q[None, :])
    s_mat = np.tril(np.ones((theta.size, theta.size)))
    return s_mat.T @ (c * g) @ s_mat, c


class _Indices:
    """Index arrays and triangular matrices of an n-joint chain (built once per n)."""

    def __init__(self, n: int):
        idx = np.arange(n)
        self.idx = idx
        self.tri = np.tril(np.ones((n, n)))                 # S: q = S theta
        self.tri_t = np.ascontiguousarray(self.tri.T)
        self.lower = np.minimum.outer(idx, idx)
        self.upper = np.maximum.outer(idx, idx)
        self.cum_gamma = np.tril(np.ones((n, n + 1)))       # s_j = L sum_{i<j} gamma_i
        self.eye1 = np.eye(n + 1)
        dl = np.zeros((n, n))                               # d l_a / d s_i, l_a = s_{a+1} - s_a
        dl[idx, idx] = -1.0
        dl[idx[:-1], idx[1:]] = 1.0
        self.dl = dl
        self.later = (idx[None, :] > idx[:, None]).astype(float)
        db = np.zeros((n + 1, n))       # segment-law bounds: interior bound j = (s_j + s_{j+1})/2
        for j in range(1, n):
            db[j, j - 1] = db[j, j] = 0.5
        self.db = db


@cache
def _indices(n: int) -> _Indices:
    return _Indices(n)


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
        db = _indices(n).db
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
    n = problem.n_joints
    n1 = n + 1
    ix = _indices(n)
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
        s, lengths, links, k_ref, widths = _design_geometry(problem, gamma)
    n_p = problem.n_params
    poses = problem.poses
    m_poses = poses.shape[0]
    law_segment = problem.stiffness_law == "segment"
    cos = workspace.pose_cosines(poses)
    if not pinocchio:
        g = _mass_g(lengths[1:], links, s)
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
            qs = theta[ok] @ _planar_indices(n).prefix
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
            dtip, dtheta = _tip_derivative(k_static, theta[ok], forces[ok], lengths, k_ref,
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


def _tip_derivative(k_static: np.ndarray, theta: np.ndarray, forces: np.ndarray,
                    lengths: np.ndarray, k_ref: np.ndarray, dk_ref: np.ndarray,
                    factors: np.ndarray, ds_dx: np.ndarray, law_segment: bool,
                    n1: int) -> tuple[np.ndarray, np.ndarray]:
    """Derivatives of the tips (x, z) and of the angles with respect to x at equilibria.

    Returns:
        (d tip / d x of shape (l, 2, n_params), d theta / d x of shape (l, n, n_params)).

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
    ix = _indices(n)
    n_p = ds_dx.shape[1] + factors.size
    planar = _planar_indices(n)
    q = theta @ planar.prefix
    ell = lengths[1:]
    c, sn = np.cos(q), np.sin(q)
    fx, fz = forces[:, :1], forces[:, 1:]
    s_mat = ix.tri
    # Tip Jacobian rows: d x_tip / d q_a = -l_a sin q_a, d z_tip / d q_a = -l_a cos q_a.
    tip_jac = np.empty((n_l, 2, n))
    tip_jac[:, 0] = (-ell * sn) @ s_mat
    tip_jac[:, 1] = (-ell * c) @ s_mat
    work = -sn * fx - c * fz                               # u'(q_a) . F
    idx = ix.idx
    arm = ell * (c * fx - sn * fz)                         # l_a u(q_a) . F
    tangent = (arm @ planar.suffix)[:, planar.top] + planar.eye * k_static
    dl_dx = ix.dl @ ds_dx                                  # (n, n1)
    scale = factors if law_segment else np.full(n, float(np.mean(factors)))
    dk_dx = np.zeros((n, n_p))
    dk_dx[:, :n1] = scale[:, None] * dk_ref @ ds_dx
    if law_segment:
        dk_dx[idx, n1 + idx] = k_static
    else:
        dk_dx[:, n1:] = k_ref[:, None] * (factors / factors.size)[None, :]
    dr = dk_dx[None, :, :] * theta[:, :, None]
    # (J^T F)_i = sum_{a >= i} l_a u'(q_a) . F depends on the lengths directly.
    dr[:, :, :n1] -= s_mat.T @ (work[:, :, None] * dl_dx[None, :, :])
    dtheta = -np.linalg.solve(tangent, dr)
    dtip = tip_jac @ dtheta
    # Direct dependence on the geometry: P = (s_1, 0) + sum_a l_a u(q_a).
    dtip[:, 0, :n1] += c @ dl_dx + ds_dx[0]
    dtip[:, 1, :n1] += -sn @ dl_dx
    return dtip, dtheta


class _PlanarIndices:
    """Index and summation matrices of the planar Newton for n joints (built once per n)."""

    def __init__(self, n: int):
        idx = np.arange(n)
        self.top = np.maximum.outer(idx, idx)          # max(i, j)
        self.prefix = np.triu(np.ones((n, n)))         # (x @ prefix)_j = sum_{a <= j} x_a
        self.suffix = np.ascontiguousarray(self.prefix.T)  # (x @ suffix)_i = sum_{a >= i} x_a
        self.eye = np.eye(n)


@cache
def _planar_indices(n: int) -> _PlanarIndices:
    return _PlanarIndices(n)


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
    ix = _planar_indices(n)
    top, prefix, suffix_sum = ix.top, ix.prefix, ix.suffix
    ok = np.ones(n_l, dtype=bool)
    k_diag = ix.eye * k
    fx_all, fz_all = forces[:, :1], forces[:, 1:]
    # Rows: the residual K theta - tau, then its two terms K theta and tau (one reduction
    # gives the three norms of the convergence test).
    terms = np.empty((3, n_l, n))
    residual, kt, tau = terms[0], terms[1], terms[2]

    steps = max(1, int(load_steps))
    for step in range(1, steps + 1):
        if step == steps:
            fx, fz = fx_all, fz_all
        else:
            fx, fz = fx_all * (step / steps), fz_all * (step / steps)
        active = ok.copy()
        for iteration in range(max_iter + 1):
            q = theta @ prefix
            lc, ls = ell * np.cos(q), ell * np.sin(q)
            # tau_i = sum_{a >= i} l_a u'(q_a) . F; the tangent's (i, j) entry is the suffix
            # sum from max(i, j) of l_a u(q_a) . F, plus k on the diagonal.
            np.matmul(-ls * fx - lc * fz, suffix_sum, out=tau)
            tangent = ((lc * fx - ls * fz) @ suffix_sum)[:, top] + k_diag
            np.multiply(k, theta, out=kt)
            np.subtract(kt, tau, out=residual)
            norms = np.sqrt((terms * terms).sum(2))
            finite = np.isfinite(norms[0])
            ok &= finite
            active &= (norms[0] > tol * (norms[1] + norms[2] + 1e-300)) & finite
            if not active.any():
                break
            if iteration == max_iter:
                ok &= ~active
                break
            try:
                if active.all():
                    theta -= np.linalg.solve(tangent, residual[:, :, None])[:, :, 0]
                else:
                    theta[active] -= np.linalg.solve(tangent[active],
                                                     residual[active][:, :, None])[:, :, 0]
            except np.linalg.LinAlgError:
                ok &= ~active
                break
    # The last tangent was formed at the final angles and the full load (symmetric): it is
    # positive definite exactly when its Cholesky factorisation exists (per load on failure).
    try:
        np.linalg.cholesky(tangent)
    except np.linalg.LinAlgError:
        ok &= np.linalg.eigvalsh(tangent)[:, 0] > 0.0
    angle = np.arctan2(-forces[:, 1], forces[:, 0])
    absolute = q  # every exit of the Newton loop leaves q = theta @ prefix of the final angles
    low, high = np.minimum(0.0, angle), np.maximum(0.0, angle)
    slack = 1e-9 + 1e-12 * np.abs(absolute).max(axis=1, initial=0.0)
    inside = (absolute >= (low - slack)[:, None]) & (absolute <= (high + slack)[:, None])
    ok &= inside.all(axis=1) & np.isfinite(theta).all(axis=1)
    return theta, ok
