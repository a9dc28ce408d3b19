r"""The (n+1)-link / nR pseudo-rigid-body chain as a Pinocchio model (paper 001, eq. 1-9).

Link 0 (length :math:`\gamma_0 L`) is clamped to the ground along +X. Joints 1..n are revolute
about +Y (the beam's width axis, so the chain moves in the X-Z plane as the beam bends out of
plane), joint j sitting at :math:`s_j = L\sum_{i<j}\gamma_i`; link j spans
:math:`[s_j, s_j + \gamma_j L]` and carries the mass, centre of mass and rotational inertia of
that stretch of the planform. A positive joint angle turns the chain from +X towards -Z.
Springs are diagonal, :math:`\tau = -K\theta` (eq. 12). Pinocchio supplies the mass matrix
(CRBA), forward kinematics and the tip frame Jacobian; everything else is small numpy code.

Paper 001 avoids :math:`\theta = 0` claiming the mass matrix is singular there. For a chain whose
links all have positive mass and rotational inertia, :math:`M(\theta)` is positive definite at
every pose, including :math:`\theta = 0`; what loses rank at :math:`\theta = 0` is the tip
*Jacobian* (all joints collinear, no axial tip velocity). See :func:`mass_matrix_condition`.
"""

from __future__ import annotations

from dataclasses import dataclass
from xml.sax.saxutils import quoteattr

import numpy as np
import pinocchio as pin
import scipy.linalg as sla

from pinflex.linalg import readonly as _readonly

from ..exceptions import ConfigurationError, InvalidChain, NewtonDivergence
from .beams import Planform, chain_segments
from .elastica import check_end_loads


@dataclass(frozen=True)
class PrbdmChain:
    """An nR pseudo-rigid-body chain.

    Attributes:
        model: Pinocchio model with n revolute joints about +Y and a ``tip`` frame.
        link_lengths_m: Lengths of links 0..n, shape (n + 1,) [m].
        stiffness_nm_rad: Torsional spring stiffness of joints 1..n, shape (n,) [N m/rad].
        tip_frame_id: Index of the tip operational frame in ``model.frames``.
        link_mass_kg: Masses of links 1..n, shape (n,) [kg] (link 0 is clamped).
    """

    model: pin.Model
    link_lengths_m: np.ndarray
    stiffness_nm_rad: np.ndarray
    tip_frame_id: int
    link_mass_kg: np.ndarray

    @property
    def n_joints(self) -> int:
        """Number of revolute joints n."""
        return int(self.stiffness_nm_rad.size)

    @property
    def length_m(self) -> float:
        """Total length of the chain [m]."""
        return float(self.link_lengths_m.sum())

    @property
    def stiffness_matrix(self) -> np.ndarray:
        """Diagonal spring matrix K, shape (n, n) [N m/rad]."""
        return np.diag(self.stiffness_nm_rad)



def validate_fractions(gamma: np.ndarray, min_fraction: float = 0.0) -> np.ndarray:
    """Check link-length fractions lie on the simplex; return them as an array.

    Args:
        gamma: Fractions of the beam length for links 0..n, shape (n + 1,), n >= 1.
        min_fraction: Smallest allowed fraction (paper eq. 15c uses 0.02).

    Raises:
        InvalidChain: If a fraction is not finite, below ``min_fraction`` or not positive, or if
            they do not sum to 1.
    """
    g = np.asarray(gamma, dtype=float)
    if g.ndim != 1 or g.size < 2:
        raise InvalidChain(f"gamma must list n + 1 >= 2 link-length fractions, got {gamma!r}")
    if not np.all(np.isfinite(g)):
        raise InvalidChain(f"gamma = {g.tolist()} contains non-finite values")
    if np.any(g <= 0.0) or np.any(g < min_fraction - 1e-12):
        raise InvalidChain(f"gamma = {np.round(g, 6).tolist()}: every link fraction must be "
                           f"positive and >= {min_fraction:g}")
    if abs(g.sum() - 1.0) > 1e-9:
        raise InvalidChain(f"gamma sums to {g.sum():.12g}; link fractions must sum to 1 "
                           "(eq. 15b): divide by their sum")
    return g


def build_chain(planform: Planform, gamma: np.ndarray, stiffness_nm_rad: np.ndarray) -> PrbdmChain:
    """Build the nR chain of a beam as a Pinocchio model.

    Args:
        planform: The beam whose planform gives each link's mass properties.
        gamma: Link-length fractions of links 0..n, shape (n + 1,), summing to 1.
        stiffness_nm_rad: Spring stiffness of joints 1..n, shape (n,) [N m/rad].

    Returns:
        The chain.

    Raises:
        InvalidChain: If the fractions are off the simplex or a stiffness is not positive.
    """
    g = validate_fractions(gamma)
    k = np.asarray(stiffness_nm_rad, dtype=float).reshape(-1)
    if k.size != g.size - 1:
        raise InvalidChain(f"{g.size} link fractions need {g.size - 1} spring stiffnesses, "
                           f"got {k.size}")
    if not np.all(np.isfinite(k)) or np.any(k <= 0.0):
        raise InvalidChain(f"spring stiffnesses must be finite and positive, got {k.tolist()} "
                           "[N m/rad]")
    lengths = g * planform.length_m
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    model = pin.Model()
    model.name = "prbdm"
    parent = 0
    placement = pin.SE3(np.eye(3), np.array([lengths[0], 0.0, 0.0]))
    masses = []
    segments = chain_segments(planform, np.concatenate([starts[1:], [planform.length_m]]))
    for j, seg in enumerate(segments, start=1):
        joint = model.addJoint(parent, pin.JointModelRY(), placement, f"joint_{j}")
        inertia = pin.Inertia(seg.mass_kg, np.array([seg.com_m - starts[j], 0.0, 0.0]),
                              np.diag(seg.inertia_com_kg_m2))
        model.appendBodyToJoint(joint, inertia, pin.SE3.Identity())
        model.addFrame(pin.Frame(f"link_{j}", joint, pin.SE3.Identity(), pin.FrameType.BODY))
        masses.append(seg.mass_kg)
        parent = joint
        placement = pin.SE3(np.eye(3), np.array([lengths[j], 0.0, 0.0]))
    tip = model.addFrame(pin.Frame("tip", parent, placement, pin.FrameType.OP_FRAME))
    return PrbdmChain(model, _readonly(lengths), _readonly(k), int(tip), _readonly(masses))


def _pose(chain: PrbdmChain, theta) -> np.ndarray:
    q = np.zeros(chain.n_joints) if theta is None else np.asarray(theta, dtype=float)
    if q.shape != (chain.n_joints,) or not np.all(np.isfinite(q)):
        raise ConfigurationError(f"theta must be {chain.n_joints} finite joint angles [rad], "
                                 f"got {theta!r}")
    return q


def mass_matrix(chain: PrbdmChain, theta: np.ndarray | None = None,
                data: pin.Data | None = None) -> np.ndarray:
    """Joint-space mass matrix M(theta) by CRBA, shape (n, n) [kg m^2]."""
    data = chain.model.createData() if data is None else data
    m = pin.crba(chain.model, data, _pose(chain, theta))
    return np.triu(m) + np.triu(m, 1).T


def chain_frequencies(chain: PrbdmChain, theta: np.ndarray | None = None,
                      data: pin.Data | None = None) -> np.ndarray:
    r"""Eigenfrequencies of small oscillations about pose theta, ascending, shape (n,) [Hz].

    Solves the symmetric generalized problem :math:`K\phi = \omega^2 M(\theta)\phi` with
    ``scipy.linalg.eigh`` (M is positive definite at every pose; no pseudo-inverse).

    Args:
        chain: The chain (n spring joints).
        theta: Joint angles (n,) [rad]; None for the straight pose (all zeros).
        data: Pinocchio data of ``chain.model`` to reuse (default: a new one).

    Returns:
        Frequencies (n,) ascending [Hz].

    Raises:
        ConfigurationError: ``theta`` is not n finite angles.
    """
    m = mass_matrix(chain, theta, data)
    eigval = sla.eigh(chain.stiffness_matrix, m, eigvals_only=True)
    return np.sqrt(np.clip(eigval, 0.0, None)) / (2.0 * np.pi)


def tip_position(chain: PrbdmChain, theta: np.ndarray | None = None,
                 data: pin.Data | None = None) -> np.ndarray:
    """Tip position (x, z) in the bending plane by forward kinematics [m]."""
    data = chain.model.createData() if data is None else data
    pin.framesForwardKinematics(chain.model, data, _pose(chain, theta))
    return data.oMf[chain.tip_frame_id].translation[[0, 2]].copy()


def tip_jacobian(chain: PrbdmChain, theta: np.ndarray | None = None,
                 data: pin.Data | None = None) -> np.ndarray:
    """Jacobian of the tip position (x, z) with respect to theta, shape (2, n) [m/rad]."""
    data = chain.model.createData() if data is None else data
    jac = pin.computeFrameJacobian(chain.model, data, _pose(chain, theta), chain.tip_frame_id,
                                   pin.LOCAL_WORLD_ALIGNED).reshape(6, -1)
    return jac[[0, 2], :].copy()


def mass_matrix_condition(chain: PrbdmChain, poses: np.ndarray) -> np.ndarray:
    """2-norm condition number of M(theta) at each pose, shape (m,).

    Args:
        chain: The chain.
        poses: Joint angles, shape (m, n) [rad].
    """
    data = chain.model.createData()
    return np.array([np.linalg.cond(mass_matrix(chain, q, data)) for q in np.atleast_2d(poses)])


@dataclass(frozen=True)
class StaticsResult:
    r"""Equilibrium of the chain under dead end loads.

    Attributes:
        theta: Joint angles, shape (n,) [rad].
        tip_m: Tip position (x, z) [m].
        iterations: Newton iterations summed over load steps.
        residual_nm: Final residual norm :math:`\|K\theta - J^T F - (M + \lambda) 1\|` [N m].
        end_moment_nm: Moment at the end [N m]: the applied moment of a free end, the guide's
            reaction :math:`\lambda` of a fixed-guided end.
    """

    theta: np.ndarray
    tip_m: np.ndarray
    iterations: int
    residual_nm: float
    end_moment_nm: float = 0.0


def _statics_terms(chain: PrbdmChain, data: pin.Data, theta: np.ndarray, force: np.ndarray,
                   moment: float = 0.0):
    """Residual, tangent stiffness and tip position at theta."""
    jac = pin.computeFrameJacobian(chain.model, data, theta, chain.tip_frame_id,
                                   pin.LOCAL_WORLD_ALIGNED).reshape(6, -1)
    tip = data.oMf[chain.tip_frame_id].translation
    # Joint axes are all +Y, so column j is y x (p - o_j) = ((p - o_j)_z, 0, -(p - o_j)_x) and
    # d(J_j)/d(theta_i) = -(p - o_max(i,j)): the tangent needs only the Jacobian itself. An end
    # moment M does the work M sum(theta) (the end link's absolute angle): a constant term.
    jx, jz = jac[0], jac[2]
    generalized = jx * force[0] + jz * force[1] + moment
    arm_work = jx * force[1] - jz * force[0]
    n = theta.size
    idx = np.arange(n)
    tangent = arm_work[np.maximum.outer(idx, idx)]
    tangent[idx, idx] += chain.stiffness_nm_rad
    residual = chain.stiffness_nm_rad * theta - generalized
    return residual, tangent, np.array([tip[0], tip[2]])


def solve_tip_statics(chain: PrbdmChain, force_n: np.ndarray, theta0: np.ndarray | None = None,
                      load_steps: int = 1, max_iter: int = 30, tol: float = 1e-10,
                      data: pin.Data | None = None, moment_nm: float = 0.0,
                      boundary: str = "cantilever") -> StaticsResult:
    r"""Solve :math:`K\theta = J^T(\theta) F + M\,1` (eq. 8) by Newton's method for dead end loads.

    The load is applied in ``load_steps`` equal increments, each solved by full Newton with
    the exact tangent :math:`K - \partial(J^T F)/\partial\theta` (an end moment M adds the
    constant :math:`M\,1`: its work is M times the end link's absolute angle). A
    ``"fixed-guided"`` end holds the end link's absolute angle at zero,
    :math:`1^T\theta = 0`, with the guide's moment :math:`\lambda` as a Lagrange multiplier
    (bordered Newton on :math:`(\theta, \lambda)`; at least 2 joints). An answer is returned only
    if it is (1) converged and (2) a stable equilibrium (tangent positive definite, on the
    constraint's null space for a guided end); under a force alone it must also be (3) on the
    physical branch: every link's absolute angle lies between the undeformed axis and the force
    direction (as the elastica's section rotation does). A pure end moment has one
    equilibrium (the energy is convex); under a force and a moment together the answer is the
    stable equilibrium reached by the load steps, without a branch check. Anything else raises,
    so a wrong branch of a force is never returned silently.

    Args:
        chain: The chain.
        force_n: End force (Fx, Fz) in the bending plane [N].
        theta0: Starting joint angles [rad]; default zeros (start of the first load step).
        load_steps: Number of equal load increments.
        max_iter: Newton iterations allowed per load step.
        tol: Convergence tolerance on the residual relative to :math:`\|K\theta\| + \|J^TF\|`.
        data: Optional Pinocchio data to reuse.
        moment_nm: End moment about +Y [N m] (positive turns +X towards -Z); free end only.
        boundary: ``"cantilever"`` (free end) or ``"fixed-guided"``.

    Returns:
        The equilibrium.

    Raises:
        NewtonDivergence: If Newton does not converge, converges to an unstable equilibrium or
            to a non-physical branch; the message suggests more load steps.
        ConfigurationError: If ``theta0`` has the wrong shape, the boundary is unknown, a moment
            is applied to a guided end, or a guided chain has fewer than 2 joints.
    """
    force, moment = check_end_loads(force_n, moment_nm, boundary, ConfigurationError)
    guided = boundary == "fixed-guided"
    if guided and chain.n_joints < 2:
        raise ConfigurationError(
            "a fixed-guided end holds the end link's angle: the chain needs at least 2 joints "
            f"(it has {chain.n_joints})")
    if int(load_steps) != load_steps or load_steps < 1:
        raise ConfigurationError(f"load_steps = {load_steps!r} must be a positive integer")
    data = chain.model.createData() if data is None else data
    theta = _pose(chain, theta0).copy()
    n = chain.n_joints
    ones = np.ones(n)
    reaction = 0.0
    iterations = 0
    for step in range(1, int(load_steps) + 1):
        f_step = force * step / load_steps
        m_step = moment * step / load_steps
        for iteration in range(max_iter + 1):
            residual, tangent, _ = _statics_terms(chain, data, theta, f_step, m_step)
            residual = residual - reaction * ones
            norm = float(np.linalg.norm(residual))
            scale = (np.linalg.norm(chain.stiffness_nm_rad * theta)
                     + np.linalg.norm(residual - chain.stiffness_nm_rad * theta) + 1e-300)
            closed = abs(float(theta.sum())) <= tol if guided else True
            if norm <= tol * scale and closed:
                break
            if iteration == max_iter or not np.isfinite(norm):
                raise NewtonDivergence(
                    f"Newton did not converge in {max_iter} iterations at load step "
                    f"{step}/{load_steps} for end force {force} N, end moment {moment:g} N m "
                    f"({boundary}; residual {norm:.3e} N m); increase load_steps or start "
                    "closer to the solution")
            try:
                if guided:
                    bordered = np.block([[tangent, -ones[:, None]], [ones[None, :], 0.0]])
                    delta = np.linalg.solve(bordered, np.concatenate([residual, [theta.sum()]]))
                    theta = theta - delta[:n]
                    reaction -= float(delta[n])
                else:
                    theta = theta - np.linalg.solve(tangent, residual)
            except np.linalg.LinAlgError as err:
                raise NewtonDivergence(
                    f"singular tangent stiffness at load step {step}/{load_steps} for end "
                    f"force {force} N ({boundary}); increase load_steps") from err
            iterations += 1
    residual, tangent, tip = _statics_terms(chain, data, theta, force, moment)
    residual = residual - reaction * ones
    _check_branch(chain, theta, tangent, force, load_steps, moment, guided)
    return StaticsResult(theta=_readonly(theta), tip_m=tip, iterations=iterations,
                         residual_nm=float(np.linalg.norm(residual)),
                         end_moment_nm=reaction if guided else moment)


def _check_branch(chain: PrbdmChain, theta: np.ndarray, tangent: np.ndarray, force: np.ndarray,
                  load_steps: int, moment: float = 0.0, guided: bool = False) -> None:
    """Raise NewtonDivergence unless theta is a stable equilibrium (on the physical branch)."""
    sym = 0.5 * (tangent + tangent.T)
    if guided:
        # The admissible variations keep sum(theta) = 0: d_j - d_n, j < n.
        basis = np.vstack([np.eye(theta.size - 1), -np.ones((1, theta.size - 1))])
        sym = basis.T @ sym @ basis
    try:
        np.linalg.cholesky(sym)
    except np.linalg.LinAlgError as err:
        raise NewtonDivergence(
            f"Newton converged to an unstable equilibrium for end force {force} N, end moment "
            f"{moment:g} N m (joint angles {np.round(theta, 4).tolist()} rad); increase "
            f"load_steps (now {load_steps})") from err
    if moment != 0.0 or not np.any(force):
        return
    force_angle = float(np.arctan2(-force[1], force[0]))
    absolute = np.cumsum(theta)
    low, high = min(0.0, force_angle), max(0.0, force_angle)
    slack = 1e-9 + 1e-12 * np.abs(absolute).max(initial=0.0)
    if np.any(absolute < low - slack) or np.any(absolute > high + slack):
        raise NewtonDivergence(
            f"Newton converged to a non-physical branch for tip force {force} N: absolute link "
            f"angles {np.round(absolute, 4).tolist()} rad leave the sector [{low:.4f}, "
            f"{high:.4f}] rad between the beam axis and the force; increase load_steps "
            f"(now {load_steps})")


def _num(value) -> str:
    """Shortest round-trip text of a number for URDF attributes."""
    return repr(float(value))


def to_urdf(chain: PrbdmChain, name: str = "prbdm") -> str:
    """URDF text of the chain; spring stiffnesses ride in ``<pinflex_spring>`` joint children.

    Plain URDF parsers (Pinocchio's included) ignore the unknown element, so the file loads
    unchanged; the joint ``<dynamics>`` element is left at zero damping.

    Args:
        chain: The chain to write (link masses [kg], inertias [kg m^2], stiffnesses
            [N m/rad]).
        name: The robot name of the URDF.

    Returns:
        The URDF text (links ``link_0`` .. ``link_n`` and ``tip``, revolute joints about y).
    """
    model = chain.model
    lines = ['<?xml version="1.0"?>', f"<robot name={quoteattr(name)}>",
             '  <link name="link_0"/>']
    for j in range(1, model.njoints):
        inertia = model.inertias[j]
        com = inertia.lever
        rot = inertia.inertia
        parent = "link_0" if model.parents[j] == 0 else f"link_{model.parents[j]}"
        origin = model.jointPlacements[j].translation
        lines += [
            f'  <link name="link_{j}">',
            "    <inertial>",
            f'      <origin xyz="{_num(com[0])} {_num(com[1])} {_num(com[2])}" rpy="0 0 0"/>',
            f'      <mass value="{_num(inertia.mass)}"/>',
            f'      <inertia ixx="{_num(rot[0, 0])}" ixy="0" ixz="0" '
            f'iyy="{_num(rot[1, 1])}" iyz="0" izz="{_num(rot[2, 2])}"/>',
            "    </inertial>",
            "  </link>",
            f'  <joint name="{model.names[j]}" type="revolute">',
            f'    <parent link="{parent}"/>',
            f'    <child link="link_{j}"/>',
            f'    <origin xyz="{_num(origin[0])} {_num(origin[1])} {_num(origin[2])}" '
            'rpy="0 0 0"/>',
            '    <axis xyz="0 1 0"/>',
            '    <limit lower="-3.14159" upper="3.14159" effort="1e9" velocity="1e3"/>',
            '    <dynamics damping="0" friction="0"/>',
            f'    <pinflex_spring stiffness="{_num(chain.stiffness_nm_rad[j - 1])}"/>',
            "  </joint>",
        ]
    tip = model.frames[chain.tip_frame_id].placement.translation
    n = model.njoints - 1
    lines += ['  <link name="tip"/>', '  <joint name="tip_joint" type="fixed">',
              f'    <parent link="link_{n}"/>', '    <child link="tip"/>',
              f'    <origin xyz="{_num(tip[0])} {_num(tip[1])} {_num(tip[2])}" rpy="0 0 0"/>',
              "  </joint>", "</robot>", ""]
    return "\n".join(lines)
