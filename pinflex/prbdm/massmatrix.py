r"""The chain's mass matrix in closed form, its design derivatives, and one in-place chain.

For the planar chain (all joint axes parallel), in absolute link angles :math:`q = S\theta`
(S lower triangular ones), :math:`M(\theta) = S^T (C(q) \circ G) S` with
:math:`C_{ab} = \cos(q_a - q_b)` and a pose-independent G:
:math:`G_{aa} = \ell_a^2 T_a + \mu_{2,a}`, :math:`G_{ab} = \ell_a(\ell_b T_b + \mu_{1,b})`
for a < b, where :math:`\ell_a` is the length of link a, :math:`T_b` the mass outboard of
link b, and :math:`\mu_{1}, \mu_{2}` the first and second mass moments of a link about its
own joint. G is polynomial in the link lengths and the links' inertia integrals, whose
derivatives with respect to the joint positions are the integrands at the link ends.
:class:`ChainWorkspace` keeps one Pinocchio model per problem, updated in place, whose CRBA
gives the same matrix.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pinocchio as pin

from .beams import Planform, segment_arrays
from .chain import PrbdmChain


def thickness_at_points(planform: Planform, s: np.ndarray) -> np.ndarray:
    """Thickness t(s) at the abscissae s as a float array [m]."""
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
        t2 = thickness_at_points(planform, ends) ** 2 / 12.0
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
    ix = chain_indices(n)
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


def mass_g(lengths: np.ndarray, links: tuple, s: np.ndarray) -> np.ndarray:
    """G of :func:`mass_structure` alone (no derivatives), from the links' properties.

    Leading dimensions (several designs) are carried through: lengths, s and the link
    arrays of shape (..., n) give G of shape (..., n, n).
    """
    ix = chain_indices(lengths.shape[-1])
    mass, com, _, iyy = links[:4]
    arm = com - s
    m1 = mass * arm
    outboard = np.zeros_like(mass)
    outboard[..., :-1] = np.cumsum(mass[..., :0:-1], axis=-1)[..., ::-1]   # T_b = sum_{j>b} m_j
    h = lengths * outboard + m1
    g = lengths[..., ix.lower] * h[..., ix.upper]
    g[..., ix.idx, ix.idx] = lengths**2 * outboard + iyy + mass * arm**2
    return g


def pose_mass_matrix(g: np.ndarray, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """M(theta) = S^T (C o G) S from the pose-independent G, and the cosine matrix C."""
    q = np.cumsum(theta)
    c = np.cos(q[:, None] - q[None, :])
    s_mat = np.tril(np.ones((theta.size, theta.size)))
    return s_mat.T @ (c * g) @ s_mat, c


class ChainIndices:
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
def chain_indices(n: int) -> ChainIndices:
    """The :class:`ChainIndices` of an n-joint chain (one per n)."""
    return ChainIndices(n)
