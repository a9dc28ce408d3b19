"""Data carried by the ERLS assembly: plans, attachments, pose terms, batch algebra."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Protocol

import numpy as np

from pinflex.description import FlexibleLink
from pinflex.linalg import axis_rotation, rotate_twist, skew, translate_twist

if TYPE_CHECKING:
    from pinflex.erls.design import DesignLayout
    from pinflex.erls.joints import JointLayout

PLANAR_NODE_DOFS = (0, 1, 5)  # ux, uy, θz in beam axes (beam z = plane normal)


@dataclass(frozen=True)
class DesignVariable:
    """A design variable: a point mass [kg] or a design parameter [its unit].

    Attributes:
        name: Name of the point mass or parameter.
        lower: Lower bound.
        upper: Upper bound.
        nominal: Value from the description (or ``values=`` / ``--set``).
        kind: 'mass' (a point mass with ``design="true"``) or 'parameter' (a
            ``<pinflex:parameter design="true">``: a section dimension or property, material
            constant, point-mass value or joint stiffness).
        unit: Its unit, from its use: ``kg`` for a mass, ``m`` for a section dimension,
            ``Pa`` for E or G, ``kg/m^3`` for a density, ``N m/rad`` or ``N/m`` for a joint
            stiffness (:attr:`pinflex.description.params.Parameter.unit`).
    """

    name: str
    lower: float
    upper: float
    nominal: float
    kind: str = "mass"
    unit: str = "kg"


@dataclass(frozen=True)
class Attachment:
    """Elastic twist (small motion, link axes) at a point of a link.

    ``twist = const + lin @ (elastic twist of the link root)``, linear in the elastic
    coordinates ``x``.

    Attributes:
        const: (6, nx) part from the link's own beam dofs, or None when the point has none.
        lin: (6, 6) map of the link root's twist, or None when the point does not see it.
    """

    const: np.ndarray | None
    lin: np.ndarray | None


@dataclass(frozen=True)
class BeamPlan:
    """Constant matrices of one flexible link (all arrays read-only).

    Node ``k = 0..N`` of a beam of ``N`` elements has 6 dofs ``(ux, uy, uz, θx, θy, θz)`` in
    the beam axes; node 0 is the root, attached to the parent link.

    Attributes:
        link: Link name.
        spec: The link's beam annotation (length, section, material, element count).
        x_cols: Columns of ``x`` owned by nodes 1..N, (n_own,) int.
        sel: (6(N+1), nx) selection of the node dofs from ``x``.
        root: (6(N+1), 6) places the root twist (link axes) at node 0 in beam axes.
        jac: (6(N+1), 6) link-origin velocity -> node velocities in beam axes.
        mass: (6(N+1), 6(N+1)) assembled consistent mass [kg, kg m, kg m²].
        stiffness: (6(N+1), 6(N+1)) assembled stiffness [N/m, N, N m].
        nodes: (N+1, 3) node positions in the link frame [m].
        rows: Node-dof rows kept in the assembly (the in-plane ones in planar mode), int.
    """

    link: str
    spec: FlexibleLink
    x_cols: np.ndarray
    sel: np.ndarray
    root: np.ndarray
    jac: np.ndarray
    mass: np.ndarray
    stiffness: np.ndarray
    nodes: np.ndarray
    rows: np.ndarray
    kept: tuple[np.ndarray, ...] = field(init=False, repr=False, compare=False)
    """``(sel, root, jac, mass, stiffness)`` restricted to :attr:`rows` (what the assembly
    uses; derived, read-only)."""

    def __post_init__(self) -> None:
        r = self.rows
        kept = (self.sel[r], self.root[r], self.jac[r], self.mass[np.ix_(r, r)],
                self.stiffness[np.ix_(r, r)])
        for array in kept:
            array.setflags(write=False)
        object.__setattr__(self, "kept", kept)


@dataclass(frozen=True)
class JointPlan:
    """A joint seen from its child link (all arrays read-only).

    Attributes:
        name: Joint name.
        parent: Parent link.
        child: Child link.
        kind: 'revolute', 'prismatic' or 'fixed'.
        user_col: Index of the joint in Pinocchio's velocity order (-1 when fixed).
        R_o: (3, 3) rotation of the joint origin in the parent frame.
        xyz: (3,) joint origin in the parent frame [m].
        axis: (3,) unit joint axis in the joint frame.
        attach: Elastic twist of the joint origin on the parent link.
        proj: (6, 6) removes the joint's motion subspace (in child axes).
    """

    name: str
    parent: str
    child: str
    kind: str
    user_col: int
    R_o: np.ndarray
    xyz: np.ndarray
    axis: np.ndarray
    attach: Attachment
    proj: np.ndarray

    @property
    def motion(self) -> JointKind:
        """What the joint's kind does (:data:`JOINT_KINDS`): the one dispatch on ``kind``."""
        return JOINT_KINDS[self.kind]


@dataclass(frozen=True)
class PointMassPlan:
    """A point mass on a link.

    Attributes:
        name: Name of the point mass (a design variable when declared so).
        link: Link carrying it.
        xyz: (3,) position in the link frame [m], read-only.
        attach: Elastic twist of that point.
    """

    name: str
    link: str
    xyz: np.ndarray
    attach: Attachment


@dataclass(frozen=True)
class BodyPlan:
    """A rigid body with full inertia on a beam (``<pinflex:body>`` or a kept URDF inertia).

    Bodies on rigid links are added to that link's entry of :attr:`ModelPlan.inertias`; on a
    beam a body moves with the cross-section at the axial station of its centre of mass.

    Attributes:
        name: Name of the body.
        link: The flexible link carrying it.
        xyz: (3,) centre of mass in the link frame [m], read-only.
        attach: Elastic twist of that point (the section's motion, rigid offset included).
        inertia: (6, 6) spatial inertia at ``xyz`` in link axes, ordering (linear, angular).
    """

    name: str
    link: str
    xyz: np.ndarray
    attach: Attachment
    inertia: np.ndarray


@dataclass(frozen=True)
class ModelPlan:
    """The fixed layout of a :class:`~pinflex.erls.FlexibleModel` (``model.plan``).

    Built once by :func:`pinflex.erls.plan.build_plan`; read-only: arrays cannot be written and
    mappings cannot be changed. This is the API other layers (previews, Taylor models) read.

    Attributes:
        links: Every link, breadth-first from the root (the root first).
        beams: Flexible links ``{link: BeamPlan}``, in the order of :attr:`links`.
        joints: Every joint as seen from its child, in the order of :attr:`links` [1:].
        inertias: Rigid links with mass ``{link: (6, 6) spatial inertia at the link origin}``.
        point_masses: Point masses, in the description's order.
        carriers: Links that carry mass (beams, rigid inertias, point masses or bodies), in
            order.
        frame_ids: Pinocchio BODY frame id of every link.
        nx: Number of elastic coordinates.
        x_names: Names of the elastic coordinates ``link.nK.{u,r}{x,y,z}``, (nx,).
        plane_normal: (3,) world normal of the plane of motion of a planar model, or None.
        conditions: The joint conditions and the modal coordinates they define
            (:class:`pinflex.erls.joints.JointLayout`).
        design: The design-dependent channels of ``M`` and ``K``
            (:class:`pinflex.erls.design.DesignLayout`).
        bodies: Rigid bodies with full inertia on beams (:class:`BodyPlan`).
    """

    links: tuple[str, ...]
    beams: Mapping[str, BeamPlan]
    joints: tuple[JointPlan, ...]
    inertias: Mapping[str, np.ndarray]
    point_masses: tuple[PointMassPlan, ...]
    carriers: tuple[str, ...]
    frame_ids: Mapping[str, int]
    nx: int
    x_names: tuple[str, ...]
    plane_normal: np.ndarray | None = None
    conditions: JointLayout = None  # type: ignore[assignment]  # set by FlexibleModel
    design: DesignLayout = None  # type: ignore[assignment]  # set by FlexibleModel
    bodies: tuple[BodyPlan, ...] = ()

    @property
    def root(self) -> str:
        """The root link (clamped to the ground)."""
        return self.links[0]

    def nodes(self, link: str) -> np.ndarray:
        """Node positions (N+1, 3) of a flexible link in its link frame [m].

        Args:
            link: Name of a flexible link (a key of :attr:`beams`); any other name raises
                ``KeyError``.

        Returns:
            Node positions (N+1, 3) [m], N the number of elements.
        """
        return self.beams[link].nodes


@dataclass
class PoseTerms:
    """Pose-dependent inputs of the assembly (leading axis: poses or Taylor coefficients).

    Attributes:
        jac: ``{link: (b, 6, nv)}`` LOCAL frame Jacobian of each carrier, user coordinates.
        rot: ``{moving joint: (b, 3, 3)}`` child-in-parent rotation.
        slide: ``{prismatic joint: (b, 3)}`` offset of the child origin [m].
    """

    jac: dict[str, np.ndarray]
    rot: dict[str, np.ndarray]
    slide: dict[str, np.ndarray] = field(default_factory=dict)


class Algebra(Protocol):
    """The arithmetic of the leading axis of the assembly: poses, or Taylor coefficients.

    :class:`BatchAlgebra` (poses) and the jet algebras of :mod:`pinflex.parametric.algebra`
    (Taylor coefficients) follow it; every assembly route runs on any of them.

    Attributes:
        size: Length of the leading axis (poses, or Taylor coefficients).
        const_at: Where a constant sits on it: ``slice(None)`` (every pose) or ``0`` (the
            constant coefficient only).
    """

    size: int
    const_at: int | slice

    def const(self, c: np.ndarray) -> np.ndarray:
        """A constant array on the leading axis, (size, *c.shape)."""
        ...

    def mm(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Product of two arrays that both vary along the leading axis."""
        ...


class BatchAlgebra:
    """Plain arrays with a leading pose axis (the :class:`Algebra` of poses)."""

    const_at: int | slice = slice(None)

    def __init__(self, size: int):
        """Algebra of arrays with ``size`` poses on the leading axis.

        Args:
            size: Number of poses ``b`` on the leading axis.
        """
        self.size = size

    def const(self, c: np.ndarray) -> np.ndarray:
        """Lift a constant array.

        Args:
            c: The constant, any shape.

        Returns:
            A read-only broadcast view (size, *c.shape).
        """
        return np.broadcast_to(c, (self.size,) + c.shape)

    @staticmethod
    def mm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Product of two pose-dependent matrices."""
        return a @ b


def twist_at(alg, att: Attachment, root_twist):
    """Elastic twist at an attachment point from its link's root twist, or None if zero.

    Args:
        alg: The algebra of the leading axis (``alg.const`` lifts a constant).
        att: The point's :class:`Attachment` (constant and root-linear parts).
        root_twist: The link's elastic root twist (b, 6, nx), or None where it is zero.

    Returns:
        ``att.lin @ root_twist + att.const`` (b, 6, nx), or None when both parts vanish.
    """
    if root_twist is None or att.lin is None:
        return None if att.const is None else alg.const(att.const)
    out = att.lin @ root_twist
    return out if att.const is None else out + alg.const(att.const)


def offset_block(p: np.ndarray) -> np.ndarray:
    """The part of ``translate_twist(p) - I`` (linear in ``p``), batched."""
    out = np.zeros(p.shape[:-1] + (6, 6))
    out[..., :3, 3:] = -skew(p)
    return out


class JointKind:
    """What one kind of joint does in the ERLS assembly (the one dispatch on joint kind).

    Every branch on a joint's kind lives here: the model's layers consult
    ``JointPlan.motion`` (a member of :data:`JOINT_KINDS`) for the joint's motion subspace,
    its pose terms and its unique-ERLS step. This base class is the fixed joint.

    Attributes:
        name: ``'revolute'``, ``'prismatic'`` or ``'fixed'``.
        moves: Whether the joint has a coordinate.
        rotates: Whether that coordinate is an angle [rad] (else a length [m]).
        rows: Rows of a twist ``[v; ω]`` along which the joint moves: ``3:6`` (rotation) for
            a revolute joint, ``0:3`` (translation) for a prismatic one, None when fixed. The
            joint's projection removes its axis there, and the joint's physical relative
            motion reads ``axisᵀ twist[rows]`` of its parent attachment.
    """

    name = "fixed"
    moves = False
    rotates = False
    rows: slice | None = None

    def __repr__(self) -> str:
        return f"<joint kind {self.name}>"

    def projection(self, axis: np.ndarray) -> np.ndarray:
        """``proj`` (6, 6): the identity without the joint's motion subspace (child axes)."""
        proj = np.eye(6)
        if self.rows is not None:
            proj[self.rows, self.rows] -= np.outer(axis, axis)
        return proj

    def rotation(self, j: JointPlan, qrel: np.ndarray) -> np.ndarray | None:
        """Child-in-parent rotation (3, 3) at one pose (revolute joints), or None.

        Args:
            j: The joint's plan.
            qrel: The arm's Pinocchio-order coordinates (nv,) [rad or m].
        """
        return None

    def slide(self, j: JointPlan, qrel: np.ndarray) -> np.ndarray | None:
        """Offset (..., 3) [m] of the child origin from its mount (prismatic joints), or None.

        Args:
            j: The joint's plan.
            qrel: The arm's Pinocchio-order coordinates (..., nv) [rad or m].
        """
        return None

    def step(self, j: JointPlan, rot=None, slide=None, alg=None) -> np.ndarray:
        """The joint's unique-ERLS step (:func:`joint_step`): ``proj Ad(R_oᵀ)``, constant."""
        return j.proj @ rotate_twist(j.R_o.T)

    def step_rate(self, j: JointPlan, rot=None, rate=None) -> np.ndarray | None:
        """The step's rate per joint rate (:func:`joint_step_rate`): None (constant)."""
        return None


class RevoluteKind(JointKind):
    """A revolute (or continuous) joint: its coordinate turns the child about ``axis``."""

    name = "revolute"
    moves = True
    rotates = True
    rows = slice(3, 6)

    def rotation(self, j, qrel):
        """``R_o Rot(axis, q)`` (3, 3), ``q`` the joint's angle [rad] in ``qrel``."""
        return j.R_o @ axis_rotation(j.axis, np.array([qrel[j.user_col]]))[0]

    def step(self, j, rot=None, slide=None, alg=None):
        """``proj Ad(Rᵀ)``, ``R`` the child-in-parent rotation (``rot``, (lead, 3, 3))."""
        return j.proj @ rotate_twist(np.swapaxes(rot, -1, -2))

    def step_rate(self, j, rot=None, rate=None):
        """``d step/dt`` per rate (k, 6, 6): ``d(Rᵀ)/dq = -[a]× Rᵀ``."""
        rate = np.asarray(rate, dtype=float)
        return j.proj @ rotate_twist(-rate[:, None, None] * (skew(j.axis) @ rot.T))


class PrismaticKind(JointKind):
    """A prismatic joint: its coordinate slides the child along ``R_o axis``."""

    name = "prismatic"
    moves = True
    rows = slice(0, 3)

    def slide(self, j, qrel):
        """``q · R_o axis`` (..., 3) [m], ``q`` the joint's value [m] in ``qrel``."""
        return (j.R_o @ j.axis) * qrel[..., j.user_col, None]

    def step(self, j, rot=None, slide=None, alg=None):
        """``proj Ad(R_oᵀ) (I + O(s))``, ``s`` the offset (``slide``, (lead, 3))."""
        base = j.proj @ rotate_twist(j.R_o.T)
        lifted = base if alg is None else alg.const(base)
        return lifted + base @ offset_block(slide)

    def step_rate(self, j, rot=None, rate=None):
        """``d step/dt`` per rate (k, 6, 6): ``proj Ad(R_oᵀ) O(rate · R_o axis)``."""
        rate = np.asarray(rate, dtype=float)
        s = j.R_o @ j.axis
        return (j.proj @ rotate_twist(j.R_o.T)) @ offset_block(rate[:, None] * s)


#: The kinds of joint of the ERLS model, by URDF type (``continuous`` is revolute).
JOINT_KINDS: Mapping[str, JointKind] = MappingProxyType({
    "revolute": RevoluteKind(), "prismatic": PrismaticKind(), "fixed": JointKind()})


def joint_kind(urdf_type: str) -> JointKind:
    """The :class:`JointKind` of a URDF joint type (``continuous`` joints are revolute)."""
    return JOINT_KINDS["revolute" if urdf_type == "continuous" else urdf_type]


def joint_step(j: JointPlan, rot=None, slide=None, alg=None) -> np.ndarray:
    """The unique-ERLS rule of one joint: ``child root twist = step @ attachment twist``.

    The child's root copies the elastic twist of its attachment point on the parent (parent
    axes), turned into the child axes, without the joint's own motion subspace (``j.proj``):

    * revolute: ``proj Ad(Rᵀ)``, ``R = R_o Rot(axis, q)`` the child-in-parent rotation
      (``rot``, pose-dependent);
    * prismatic: ``proj Ad(R_oᵀ) (I + O(s))``, ``s`` the child origin's offset from the guide's
      mount point (``slide``, pose-dependent), ``O`` its :func:`offset_block`;
    * fixed: ``proj Ad(R_oᵀ)`` (constant).

    Every route that propagates root twists (the nodal assembly, the solver-coordinate,
    factored and one-pose assemblies, the dynamics) applies this one rule
    (:meth:`JointKind.step` of the joint's kind).

    Args:
        j: The joint's plan.
        rot: Its rotation R (lead, 3, 3) (revolute joints).
        slide: Its offset s (lead, 3) [m] (prismatic joints).
        alg: The algebra of the leading axis (None: plain arrays without one).

    Returns:
        ``step`` (lead, 6, 6), or (6, 6) for a fixed joint.
    """
    return j.motion.step(j, rot, slide, alg)


def propagate_root_twists(plan: ModelPlan, terms: PoseTerms, alg, attach) -> dict:
    """Elastic root twist of every link, from the root down, by :func:`joint_step`.

    Args:
        plan: The model's plan (its root and joints, parents before children).
        terms: Pose terms (or their jets) of the leading axis.
        alg: The algebra of the leading axis.
        attach: ``attach(k, joint, parent_twist)``: the elastic twist of joint ``k``'s
            attachment point on its parent (parent axes) from the parent's root twist, or
            None where both vanish (nodal or solver coordinates).

    Returns:
        ``{link: twist or None}`` (lead, 6, nx), None where a root does not move elastically.
    """
    twist: dict = {plan.root: None}
    for k, j in enumerate(plan.joints):
        tau = attach(k, j, twist[j.parent])
        if tau is None:
            twist[j.child] = None
            continue
        step = joint_step(j, terms.rot.get(j.name), terms.slide.get(j.name), alg)
        twist[j.child] = step @ tau if step.ndim == 2 else alg.mm(step, tau)
    return twist


def joint_step_rate(j: JointPlan, rot=None, rate=None) -> np.ndarray | None:
    """Time derivative of :func:`joint_step` for joint rates ``rate`` (k,), (k, 6, 6).

    Args:
        j: The joint's plan.
        rot: Its rotation R (3, 3) at the pose (revolute joints).
        rate: Rates of the joint's (Pinocchio) coordinate, (k,) [rad/s or m/s].

    Returns:
        ``d step / dt`` per rate (k, 6, 6), or None for a fixed joint.
    """
    return j.motion.step_rate(j, rot, rate)


def carrier_rows(tau, jac: np.ndarray, xyz: np.ndarray, rows: int, nx: int) -> np.ndarray:
    """Motion of a point or body carried by a link, over the coordinates ``[x; q]``.

    The one map of a carrier's velocity for both mass routes (nodal and solver coordinates):
    the first ``rows`` rows (3: a point mass's velocity, 6: a rigid body's twist) of its
    elastic twist ``tau`` on the elastic coordinates, and of ``X(xyz) J`` on the joint
    coordinates, ``J`` the link's frame Jacobian and ``X`` the transport to the point.

    Args:
        tau: Elastic twist at the point (lead, 6, nx) (link axes), or None where it is zero.
        jac: Frame Jacobian of the link (lead, 6, nv).
        xyz: The point in the link frame (3,) [m].
        rows: 3 or 6.
        nx: Number of elastic coordinates.

    Returns:
        ``g`` (lead, rows, nx + nv).
    """
    g = np.zeros(jac.shape[:-2] + (rows, nx + jac.shape[-1]))
    if tau is not None:
        g[..., :nx] = tau[..., :rows, :]
    g[..., nx:] = (translate_twist(xyz) @ jac)[..., :rows, :]
    return g


def zeros_like(jac: np.ndarray, nx: int) -> np.ndarray:
    """Zeros of the shape of ``jac`` with ``nx`` columns (an absent elastic twist)."""
    return np.zeros(jac.shape[:-1] + (nx,))
