"""ERLS (equivalent rigid-link system) model of a flexible-link arm on Pinocchio.

Generalized coordinates are ``[x; q]``: ``x`` the independent elastic nodal coordinates of
all flexible links, ``q`` the ERLS joint coordinates (one value per moving joint, in the
model's user convention, see :class:`FlexibleModel`). With ``q̇ = 0`` the modal problem is
``K(q, y) φ = λ M(q, y) φ`` with ``K = blkdiag(Kₓₓ, 0)``.

Formulation (equivalent to the world-axes form of paper 000 eq. 1 by an orthogonal change of
elastic coordinates at each pose, hence the same eigenvalues):

* The elastic dofs of a beam node are a small translation and rotation in the *beam* axes of
  its link. Nodes 1..N of every flexible link are independent. Node 0 (the root, at the link
  origin) copies the elastic motion of the point it is attached to on the parent link, rotated
  into the child frame by the joint, **minus the joint's motion subspace** (a revolute joint's
  rotation about its axis, a prismatic joint's translation along it): this is the unique-ERLS
  rule. The root link of the URDF is clamped to the ground.
* A point on a flexible link moves with the beam's shape functions at its axial station plus a
  rigid offset; a rigid link moves rigidly with the elastic motion of its root. A prismatic
  joint's guide is attached at the joint origin.
* The ERLS velocity of each node is Pinocchio's LOCAL frame Jacobian of the link, moved to the
  node: ``S``. Kinetic energy uses the consistent beam mass, the URDF inertia of rigid links and
  the point masses; strain energy the beam stiffness.

Non-rigid eigenvalues are computed from the reduced problem
``Kₓₓ φₓ = λ (Mₓₓ − Mₓq Mqq⁻¹ Mqx) φₓ``, which has exactly the non-zero eigenvalues of the full
pair and no spurious near-zero ones; the ``nv`` rigid modes are counted, not computed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

from pinflex import beam
from pinflex.description import FlexibleLink, RobotDescription, load
from pinflex.exceptions import (
    ConfigurationError,
    DesignVariableNotFound,
    DesignVariableOutOfBounds,
    EigenSolverError,
    InvalidDescription,
    PlanarModelError,
)
from pinflex.kinematics import axis_rotation, rotate_twist, skew, translate_twist

PLANAR_NODE_DOFS = (0, 1, 5)  # ux, uy, θz in beam axes (beam z = plane normal)


@dataclass(frozen=True)
class DesignVariable:
    """A design variable: the mass of a declared point mass [kg].

    Attributes:
        name: Name of the point mass.
        lower: Lower bound [kg].
        upper: Upper bound [kg].
        nominal: Value from the description (or ``--set``) [kg].
    """

    name: str
    lower: float
    upper: float
    nominal: float


@dataclass(frozen=True)
class _FlexPlan:
    link: str
    spec: FlexibleLink
    x_cols: np.ndarray  # columns of x owned by nodes 1..N
    sel: np.ndarray  # (6(N+1), nx) constant selection of node dofs from x
    root: np.ndarray  # (6(N+1), 6) places the root twist (link axes) at node 0 in beam axes
    jac: np.ndarray  # (6(N+1), 6) link-origin velocity -> node velocities in beam axes
    mass: np.ndarray  # (6(N+1), 6(N+1)) assembled consistent mass
    stiffness: np.ndarray  # (6(N+1), 6(N+1)) assembled stiffness
    nodes: np.ndarray  # (N+1, 3) node positions in the link frame [m]
    rows: np.ndarray  # node-dof rows used in the assembly (in-plane ones in planar mode)


@dataclass(frozen=True)
class _Attachment:
    """Elastic twist at a point of a link = const + lin @ (twist of the link root)."""

    const: np.ndarray  # (6, nx)
    lin: np.ndarray | None  # (6, 6) or None when the point does not see the root twist


@dataclass(frozen=True)
class _ChildJoint:
    name: str
    parent: str
    child: str
    kind: str  # 'revolute', 'prismatic' or 'fixed'
    user_col: int  # index of the joint in pin velocity order (-1 when fixed)
    R_o: np.ndarray
    xyz: np.ndarray
    axis: np.ndarray
    attach: _Attachment
    proj: np.ndarray  # (6, 6) removes the motion subspace (in child axes)


@dataclass
class _PoseTerms:
    """Pose-dependent inputs of the assembly (leading axis: poses or Taylor coefficients)."""

    jac: dict[str, np.ndarray]  # link -> (b, 6, nv) LOCAL Jacobian in user coordinates
    rot: dict[str, np.ndarray]  # moving joint -> (b, 3, 3) child-in-parent rotation
    slide: dict[str, np.ndarray] = field(default_factory=dict)  # prismatic joint -> (b, 3)


class BatchAlgebra:
    """Plain arrays with a leading pose axis."""

    def __init__(self, size: int):
        self.size = size

    def const(self, c: np.ndarray) -> np.ndarray:
        """Lift a constant array."""
        return np.broadcast_to(c, (self.size,) + c.shape)

    @staticmethod
    def mm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Product of two pose-dependent matrices."""
        return a @ b


@dataclass(frozen=True)
class ModalResult:
    """Modal analysis at one pose.

    Attributes:
        q: Joint coordinates (user convention) [rad or m], (nv,).
        y: Design values [kg], (ny,).
        ndof: Number of generalized coordinates nx + nv.
        rigid_modes: Number of rigid (zero-frequency) modes.
        eigvals: Non-rigid eigenvalues λ = ω² ascending [rad²/s²], (k,).
        shapes: Mass-normalised mode shapes over ``[x; q]``, (ndof, k).
        node_positions: World positions of beam nodes per flexible link [m], (N+1, 3) each.
        node_motion: Per flexible link, the world-axes nodal translation and rotation of each
            mode, (k, N+1, 6); ``node_elastic`` the elastic part only (rigid ERLS motion removed).
    """

    q: np.ndarray
    y: np.ndarray
    ndof: int
    rigid_modes: int
    eigvals: np.ndarray
    shapes: np.ndarray
    node_positions: dict[str, np.ndarray]
    node_motion: dict[str, np.ndarray]
    node_elastic: dict[str, np.ndarray]

    @property
    def omega_rad_s(self) -> np.ndarray:
        """Angular eigenfrequencies [rad/s]."""
        return np.sqrt(self.eigvals)

    @property
    def freq_hz(self) -> np.ndarray:
        """Eigenfrequencies [Hz] of the non-rigid modes, ascending."""
        return np.sqrt(self.eigvals) / (2.0 * np.pi)


class FlexibleModel:
    """A URDF arm whose annotated links are finite-element beams (ERLS).

    Joint coordinates given by users are one value per moving joint in Pinocchio's velocity
    order (``joint_names``). By default they are Pinocchio's own (relative) joint values; a
    description with ``<pinflex:coordinates convention="absolute"/>`` uses absolute link
    angles ``q_abs`` of a planar serial arm instead, with ``q_rel = C q_abs`` (``C`` has ones on
    the diagonal and minus ones below it).

    Args:
        description: A parsed description or the path of an annotated URDF.
        planar: Keep only in-plane elastic dofs (all revolute axes parallel to one normal,
            beams normal to it).
        values: Overrides of point-mass values ``{name: kg}`` (checked against bounds).
        coordinates: 'relative' or 'absolute' to override the description's convention.
    """

    def __init__(
        self,
        description: RobotDescription | str | Path,
        *,
        planar: bool = False,
        values: dict[str, float] | None = None,
        coordinates: str | None = None,
    ):
        if not isinstance(description, RobotDescription):
            description = load(description)
        self.description = description
        self.planar = bool(planar)
        try:
            self.model = pin.buildModelFromXML(description.urdf_xml)
        except Exception as exc:  # Pinocchio raises plain RuntimeError/ValueError
            raise InvalidDescription(f"Pinocchio could not load the URDF: {exc}") from exc
        self.data = self.model.createData()
        self.joint_names = tuple(self.model.names[1:])
        self.nv = self.model.nv
        if self.nv != len(self.joint_names):
            raise InvalidDescription("only joints with one degree of freedom are supported")
        absolute = description.absolute_coordinates if coordinates is None else (
            coordinates == "absolute"
        )
        if coordinates not in (None, "relative", "absolute"):
            raise ConfigurationError(
                f"coordinates='{coordinates}': expected 'relative' or 'absolute'"
            )
        self.coordinates = "absolute" if absolute else "relative"
        self.coord_map = self._coordinate_map(absolute)
        self._pm_values = {p.name: p.mass for p in description.point_masses}
        self.design = tuple(
            DesignVariable(p.name, p.lower, p.upper, p.mass)
            for p in description.point_masses
            if p.design
        )
        for name, value in (values or {}).items():
            self.set_value(name, value)
        self._build_plan()

    # ------------------------------------------------------------------ set-up
    def set_value(self, name: str, value: float) -> None:
        """Set the nominal value of a point mass [kg]."""
        if name not in self._pm_values:
            raise DesignVariableNotFound(name, self._pm_values)
        value = float(value)
        for i, d in enumerate(self.design):
            if d.name == name:
                if not d.lower <= value <= d.upper:
                    raise DesignVariableOutOfBounds(name, value, d.lower, d.upper)
                self.design = (
                    self.design[:i]
                    + (DesignVariable(name, d.lower, d.upper, value),)
                    + self.design[i + 1 :]
                )
        if value < 0.0:
            raise DesignVariableOutOfBounds(name, value, 0.0, np.inf)
        self._pm_values[name] = value

    @property
    def design_names(self) -> tuple[str, ...]:
        """Names of the design variables in order."""
        return tuple(d.name for d in self.design)

    @property
    def y0(self) -> np.ndarray:
        """Nominal design values [kg], (ny,)."""
        return np.array([d.nominal for d in self.design])

    @property
    def ny(self) -> int:
        """Number of design variables."""
        return len(self.design)

    def _coordinate_map(self, absolute: bool) -> np.ndarray:
        C = np.eye(self.nv)
        if not absolute:
            return C
        model = self.model
        data = model.createData()
        pin.forwardKinematics(model, data, pin.neutral(model))
        axes = []
        for j in range(1, model.njoints):
            if model.parents[j] != j - 1:
                raise ConfigurationError(
                    "absolute coordinates need a serial chain; joint "
                    f"'{model.names[j]}' does not follow joint '{model.names[j - 1]}'"
                )
            jdesc = self.description.joints[model.names[j]]
            if jdesc.type not in ("revolute", "continuous"):
                raise ConfigurationError("absolute coordinates need revolute joints only")
            axes.append(data.oMi[j].rotation @ jdesc.axis)
        for a in axes[1:]:
            if np.linalg.norm(a - axes[0]) > 1e-9:
                raise ConfigurationError(
                    "absolute coordinates need parallel revolute axes with the same direction"
                )
        C -= np.eye(self.nv, k=-1)
        return C

    def _build_plan(self) -> None:
        desc = self.description
        # breadth-first order from the root
        order = [desc.root]
        for link in order:
            for jn in desc.child_joints[link]:
                order.append(desc.joints[jn].child)
        self._order = tuple(order)
        self._frame_id = {
            link: self.model.getFrameId(link, pin.FrameType.BODY) for link in desc.links
        }
        # elastic coordinates
        flex_plans: dict[str, _FlexPlan] = {}
        node_dofs = PLANAR_NODE_DOFS if self.planar else tuple(range(6))
        if self.planar:
            self._check_planar()
        offset = 0
        layout = []
        for link in order:
            if link in desc.flexible:
                spec = desc.flexible[link]
                n = spec.elements
                cols = offset + np.arange(n * len(node_dofs))
                layout.append((link, spec, cols))
                offset += cols.size
        self.nx = offset
        self.ndof = self.nx + self.nv
        for link, spec, cols in layout:
            flex_plans[link] = self._flex_plan(spec, cols, node_dofs)
        self._flex = flex_plans
        # node-dof rows kept in the assembly: the in-plane ones in planar mode (out-of-plane
        # rows vanish there, and the beam decouples in- and out-of-plane motion)
        self._assembly_arrays = {
            link: {
                "sel": p.sel[p.rows],
                "root": p.root[p.rows],
                "jac": p.jac[p.rows],
                "mass": p.mass[np.ix_(p.rows, p.rows)],
                "stiffness": p.stiffness[np.ix_(p.rows, p.rows)],
            }
            for link, p in flex_plans.items()
        }
        self.x_names = tuple(
            f"{link}.n{k + 1}.{'u' if d < 3 else 'r'}{'xyz'[d % 3]}"
            for link, spec, _ in layout
            for k in range(spec.elements)
            for d in node_dofs
        )
        # joints: attachments of child links
        vidx = {self.model.names[j]: self.model.joints[j].idx_v for j in range(1, self.model.njoints)}
        joints = []
        for link in order[1:]:
            jd = desc.joints[desc.parent_joint[link]]
            kind = {"continuous": "revolute"}.get(jd.type, jd.type)
            proj = np.eye(6)
            if kind == "revolute":
                proj[3:, 3:] -= np.outer(jd.axis, jd.axis)
            elif kind == "prismatic":
                proj[:3, :3] -= np.outer(jd.axis, jd.axis)
            joints.append(
                _ChildJoint(
                    name=jd.name,
                    parent=jd.parent,
                    child=link,
                    kind=kind,
                    user_col=vidx.get(jd.name, -1),
                    R_o=jd.rotation,
                    xyz=jd.xyz,
                    axis=jd.axis,
                    attach=self._attachment(jd.parent, jd.xyz),
                    proj=proj,
                )
            )
        self._joints = tuple(joints)
        # mass carriers
        self._inertias = {
            link: inertia.spatial_matrix()
            for link, inertia in desc.inertias.items()
            if link not in desc.flexible and inertia.mass > 0.0
        }
        self._point_masses = tuple(
            (p.name, p.link, p.xyz, self._attachment(p.link, p.xyz)) for p in desc.point_masses
        )
        carriers = set(self._flex) | set(self._inertias) | {p[1] for p in self._point_masses}
        self._carriers = tuple(link for link in order if link in carriers)

    def _flex_plan(self, spec: FlexibleLink, cols: np.ndarray, node_dofs) -> _FlexPlan:
        n = spec.elements
        le = spec.length_m / n
        sec = spec.section
        ke = beam.element_stiffness(le, spec.E * sec.A, spec.G * sec.J, spec.E * sec.Iy,
                                    spec.E * sec.Iz)
        me = beam.element_mass(le, spec.rhoA, spec.rhoIp)
        K = beam.assemble_line(np.broadcast_to(ke, (n, 12, 12)))
        M = beam.assemble_line(np.broadcast_to(me, (n, 12, 12)))
        rb = spec.rotation
        nodes = np.linspace(0.0, 1.0, n + 1)[:, None] * spec.tip[None, :]
        sel = np.zeros((6 * (n + 1), self.nx))
        k = 0
        for node in range(1, n + 1):
            for d in node_dofs:
                sel[6 * node + d, cols[k]] = 1.0
                k += 1
        root = np.zeros((6 * (n + 1), 6))
        root[:6] = rotate_twist(rb.T)
        jac = np.concatenate([rotate_twist(rb.T) @ translate_twist(p) for p in nodes])
        rows = (6 * np.arange(n + 1)[:, None] + np.asarray(node_dofs)[None, :]).ravel()
        return _FlexPlan(spec.link, spec, cols, sel, root, jac, M, K, nodes, rows)

    def _attachment(self, link: str, point: np.ndarray) -> _Attachment:
        """Elastic twist of a point given in the frame of ``link`` (in link axes)."""
        plan = self._flex.get(link)
        if plan is None:
            return _Attachment(np.zeros((6, self.nx)), translate_twist(point))
        spec = plan.spec
        L, n = spec.length_m, spec.elements
        xdir = spec.tip / L
        s = float(np.clip(point @ xdir, 0.0, L))
        le = L / n
        e = min(int(s / le), n - 1)
        xi = s / le - e
        offset = point - s * xdir
        shape = beam.shape_matrix(le, np.array([xi]))[0]
        to_link = translate_twist(offset) @ rotate_twist(plan.spec.rotation)
        rows = slice(6 * e, 6 * e + 12)
        const = to_link @ shape @ plan.sel[rows]
        lin = to_link @ shape @ plan.root[rows] if e == 0 else None
        return _Attachment(const, lin)

    def _check_planar(self) -> None:
        desc, model = self.description, self.model
        data = model.createData()
        pin.framesForwardKinematics(model, data, pin.neutral(model))
        normal = None
        for name in self.joint_names:
            jd = desc.joints[name]
            if jd.type == "prismatic":
                continue
            jid = model.getJointId(name)
            a = data.oMi[jid].rotation @ jd.axis
            if normal is None:
                normal = a
            elif np.linalg.norm(np.cross(a, normal)) > 1e-9:
                raise PlanarModelError(
                    f"planar mode needs parallel revolute axes; joint '{name}' has axis "
                    f"{np.round(a, 6).tolist()} in the world, the first one {normal.tolist()}"
                )
        for link, spec in desc.flexible.items():
            R = data.oMf[self.model.getFrameId(link, pin.FrameType.BODY)].rotation @ spec.rotation
            if normal is None:
                normal = R[:, 2]
            if np.linalg.norm(np.cross(R[:, 2], normal)) > 1e-9:
                raise PlanarModelError(
                    f"planar mode needs the beam normal of '{link}' along the plane normal "
                    f"{np.round(normal, 6).tolist()}; set normal=\"...\" on <pinflex:flexible>"
                )
        for name in self.joint_names:
            jd = desc.joints[name]
            if jd.type == "prismatic" and normal is not None:
                a = data.oMi[model.getJointId(name)].rotation @ jd.axis
                if abs(a @ normal) > 1e-9:
                    raise PlanarModelError(f"prismatic joint '{name}' leaves the plane")
        self.plane_normal = normal

    # ------------------------------------------------------------------ coordinates
    def check_q(self, q) -> np.ndarray:
        """Validate joint coordinates (nv,) or (n, nv) and return them as an array."""
        q = np.asarray(q, dtype=float)
        if q.shape[-1:] != (self.nv,) or q.ndim not in (1, 2):
            raise ConfigurationError(
                f"expected {self.nv} joint values ({', '.join(self.joint_names)}) per pose, "
                f"got an array of shape {q.shape}"
            )
        if not np.all(np.isfinite(q)):
            raise ConfigurationError("joint values must be finite")
        return q

    def check_y(self, y, *, bounds: bool = True) -> np.ndarray:
        """Validate design values (ny,) or per-pose (n, ny); ``None`` gives the nominal ones."""
        if y is None:
            return self.y0
        if isinstance(y, dict):
            unknown = set(y) - set(self.design_names)
            if unknown:
                raise DesignVariableNotFound(sorted(unknown)[0], self.design_names)
            y = [y.get(d.name, d.nominal) for d in self.design]
        y = np.asarray(y, dtype=float)
        if y.shape[-1:] != (self.ny,) or y.ndim not in (1, 2):
            raise ConfigurationError(
                f"expected {self.ny} design values ({', '.join(self.design_names)}), "
                f"got shape {y.shape}"
            )
        if not np.all(np.isfinite(y)):
            raise ConfigurationError("design values must be finite")
        if bounds:
            for d, v in zip(self.design, np.atleast_2d(y).T):
                bad = (v < d.lower - 1e-12) | (v > d.upper + 1e-12)
                if np.any(bad):
                    raise DesignVariableOutOfBounds(d.name, float(v[bad][0]), d.lower, d.upper)
        return y

    def joint_index(self, name: str) -> int:
        """Index of a moving joint in the coordinate vector."""
        if name not in self.joint_names:
            from pinflex.exceptions import JointNotFound

            raise JointNotFound(name, self.joint_names)
        return self.joint_names.index(name)

    def pin_q(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio joint values (nv,) of user coordinates (relative angles)."""
        return self.coord_map @ q

    def pin_configuration(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio configuration vector (nq,) of user coordinates."""
        qv = self.pin_q(np.asarray(q, dtype=float))
        out = np.zeros(self.model.nq)
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            v = qv[jm.idx_v]
            if jm.nq == 2:
                out[jm.idx_q : jm.idx_q + 2] = np.cos(v), np.sin(v)
            else:
                out[jm.idx_q] = v
        return out

    # ------------------------------------------------------------------ assembly
    def pose_terms(self, Q: np.ndarray) -> _PoseTerms:
        """Pinocchio Jacobians and joint rotations at poses Q (n, nv)."""
        model, data = self.model, self.data
        n = Q.shape[0]
        jac = {link: np.zeros((n, 6, self.nv)) for link in self._carriers}
        fids = [(link, self._frame_id[link]) for link in self._carriers]
        for i in range(n if self.nv else 0):
            qp = self.pin_configuration(Q[i])
            pin.computeJointJacobians(model, data, qp)
            for link, fid in fids:
                jac[link][i] = pin.getFrameJacobian(model, data, fid, pin.LOCAL).reshape(6, -1)
        for link in jac:
            jac[link] = jac[link] @ self.coord_map
        qrel = Q @ self.coord_map.T
        rot, slide = {}, {}
        for j in self._joints:
            if j.kind == "revolute":
                rot[j.name] = j.R_o @ axis_rotation(j.axis, qrel[:, j.user_col])
            elif j.kind == "prismatic":
                slide[j.name] = (j.R_o @ j.axis)[None, :] * qrel[:, j.user_col, None]
        return _PoseTerms(jac, rot, slide)

    def assemble(self, terms: _PoseTerms, alg) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Assemble M without design masses, M per unit design mass, and K.

        Works on any algebra ``alg`` (poses or Taylor coefficients on the leading axis).

        Returns:
            ``M0`` (b, nd, nd), ``Mdesign`` (ny, b, nd, nd), ``K`` (b, nd, nd).
        """
        nd, nx = self.ndof, self.nx
        twist = self._root_twists(terms, alg)
        M = None
        K = None
        for link, plan in self._flex.items():
            e = twist[link]
            a = self._assembly_arrays[link]
            bx = alg.const(a["sel"]) if e is None else alg.const(a["sel"]) + a["root"] @ e
            w = np.concatenate([bx, a["jac"] @ terms.jac[link]], axis=-1)
            m = alg.mm(np.swapaxes(w, -1, -2), a["mass"] @ w)
            k = alg.mm(np.swapaxes(bx, -1, -2), a["stiffness"] @ bx)
            M = m if M is None else M + m
            K = k if K is None else K + k
        for link, inertia in self._inertias.items():
            e = twist[link]
            jl = terms.jac[link]
            g = np.concatenate([_zeros_like(jl, nx) if e is None else e, jl], axis=-1)
            m = alg.mm(np.swapaxes(g, -1, -2), inertia @ g)
            M = m if M is None else M + m
        design_index = {d.name: i for i, d in enumerate(self.design)}
        shape_b = terms.jac[self._carriers[0]].shape[:1] if self._carriers else (1,)
        Mdesign = np.zeros((self.ny,) + shape_b + (nd, nd))
        for name, link, xyz, att in self._point_masses:
            jl = terms.jac[link]
            tau = self._twist_at(alg, att, twist[link])
            g = np.concatenate(
                [_zeros_like(jl, nx) if tau is None else tau, translate_twist(xyz) @ jl], axis=-1
            )[..., :3, :]
            m = alg.mm(np.swapaxes(g, -1, -2), g)
            if name in design_index:
                Mdesign[design_index[name]] = m
            else:
                M = M + self._pm_values[name] * m if M is not None else self._pm_values[name] * m
        if M is None:
            M = np.zeros(shape_b + (nd, nd))
        Kfull = np.zeros(M.shape)
        if K is not None:
            Kfull[..., :nx, :nx] = K
        return M, Mdesign, Kfull

    def _root_twists(self, terms: _PoseTerms, alg) -> dict:
        """Elastic twist of every link root in link axes, (b, 6, nx), or None when zero."""
        twist = {self._order[0]: None}
        for j in self._joints:
            tau = self._twist_at(alg, j.attach, twist[j.parent])
            if tau is None:
                twist[j.child] = None
                continue
            if j.kind == "prismatic":
                # move to the child origin, offset R_o a d from the guide's mount point
                tau = tau + alg.mm(_offset_block(terms.slide[j.name]), tau)
                R = alg.const(j.R_o)
            elif j.kind == "revolute":
                R = terms.rot[j.name]
            else:
                R = alg.const(j.R_o)
            twist[j.child] = j.proj @ alg.mm(_rot6(np.swapaxes(R, -1, -2)), tau)
        return twist

    @staticmethod
    def _twist_at(alg, att: _Attachment, root_twist):
        has_const = np.any(att.const)
        if root_twist is None or att.lin is None:
            return alg.const(att.const) if has_const else None
        out = att.lin @ root_twist
        return out + alg.const(att.const) if has_const else out

    def matrices(self, Q, y=None, *, check_bounds: bool = True):
        """Mass and stiffness matrices at one pose (nv,) or many (n, nv).

        Args:
            Q: Joint coordinates (user convention) [rad or m].
            y: Design values [kg] (default: nominal).
            check_bounds: Raise when a design value leaves its bounds.

        Returns:
            ``(M, K)``, each (ndof, ndof) for one pose or (n, ndof, ndof).
        """
        Q = self.check_q(Q)
        y = self.check_y(y, bounds=check_bounds)
        single = Q.ndim == 1
        Qb = Q[None] if single else Q
        if y.ndim == 2 and y.shape[0] != Qb.shape[0]:
            raise ConfigurationError(
                f"got {y.shape[0]} design vectors for {Qb.shape[0]} poses; give one or one per pose"
            )
        M0, Md, K = self.assemble(self.pose_terms(Qb), BatchAlgebra(Qb.shape[0]))
        if self.ny:
            M = M0 + (np.tensordot(y, Md, axes=(0, 0)) if y.ndim == 1
                      else np.einsum("nj,jnab->nab", y, Md))
        else:
            M = M0
        return (M[0], K[0]) if single else (M, K)

    # ------------------------------------------------------------------ modal analysis
    def _reduced(self, M: np.ndarray, K: np.ndarray):
        """Elastic mass with the rigid coordinates condensed out, and Kxx."""
        nx = self.nx
        Mxx, Mxq, Mqq = M[..., :nx, :nx], M[..., :nx, nx:], M[..., nx:, nx:]
        if self.nv:
            try:
                Lq = np.linalg.cholesky(Mqq)
            except np.linalg.LinAlgError as exc:
                raise EigenSolverError(
                    "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
                    "add inertia to the links it drives"
                ) from exc
            Z = np.linalg.inv(Lq) @ np.swapaxes(Mxq, -1, -2)
            Mred = Mxx - np.swapaxes(Z, -1, -2) @ Z
        else:
            Mred = Mxx
        return Mred, K[..., :nx, :nx]

    def frequencies(self, Q, y=None, *, n_modes: int | None = None, check_bounds=True):
        """Non-rigid eigenfrequencies [Hz] at one or many poses, ascending.

        Batched: all poses are assembled and solved together.

        Returns:
            (k,) for one pose or (n, k).
        """
        M, K = self.matrices(Q, y, check_bounds=check_bounds)
        lam = self.eigvals_from(M, K)
        if n_modes is not None:
            lam = lam[..., :n_modes]
        return np.sqrt(lam) / (2.0 * np.pi)

    def eigvals_from(self, M: np.ndarray, K: np.ndarray) -> np.ndarray:
        """Non-rigid eigenvalues λ [rad²/s²] of stacked matrix pairs (..., ndof, ndof)."""
        if self.nx == 0:
            return np.zeros(M.shape[:-2] + (0,))
        Mred, Kxx = self._reduced(M, K)
        try:
            L = np.linalg.cholesky(Mred)
        except np.linalg.LinAlgError as exc:
            raise EigenSolverError("the reduced elastic mass matrix is not positive") from exc
        Li = np.linalg.inv(L)
        A = Li @ Kxx @ np.swapaxes(Li, -1, -2)
        lam = np.linalg.eigvalsh(A)
        if np.any(lam <= 0.0):
            raise EigenSolverError(
                "a non-positive elastic eigenvalue appeared: the structure is not restrained "
                "(check that every flexible link is attached to the ground through joints)"
            )
        return lam

    def modes(self, q, y=None, *, n_modes: int | None = None, check_bounds=True) -> ModalResult:
        """Eigenfrequencies, mass-normalised mode shapes and nodal motion at one pose."""
        import scipy.linalg

        q = self.check_q(q)
        if q.ndim != 1:
            raise ConfigurationError("modes() takes one pose; use frequencies() for many")
        y = self.check_y(y, bounds=check_bounds)
        M, K = self.matrices(q, y, check_bounds=check_bounds)
        nx = self.nx
        Mred, Kxx = self._reduced(M, K)
        k = nx if n_modes is None else min(int(n_modes), nx)
        lam, phix = scipy.linalg.eigh(Kxx, Mred, subset_by_index=[0, k - 1] if k else None)
        if self.nv:
            phiq = -np.linalg.solve(M[nx:, nx:], M[nx:, :nx] @ phix)
        else:
            phiq = np.zeros((0, k))
        shapes = np.vstack([phix, phiq])
        # sign: largest elastic component positive
        idx = np.argmax(np.abs(phix), axis=0)
        shapes *= np.sign(phix[idx, np.arange(k)])[None, :]
        positions, motion, elastic = self._node_fields(q, shapes)
        return ModalResult(
            q=q, y=y, ndof=self.ndof, rigid_modes=self.nv, eigvals=lam, shapes=shapes,
            node_positions=positions, node_motion=motion, node_elastic=elastic,
        )

    def _node_fields(self, q: np.ndarray, shapes: np.ndarray):
        terms = self.pose_terms(q[None])
        twist = self._root_twists(terms, BatchAlgebra(1))
        pin.framesForwardKinematics(self.model, self.data, self.pin_configuration(q))
        positions, motion, elastic = {}, {}, {}
        nx = self.nx
        for link, plan in self._flex.items():
            oMf = self.data.oMf[self._frame_id[link]]
            e = twist[link]
            bx = plan.sel if e is None else plan.sel + plan.root @ e[0]
            jn = plan.jac @ terms.jac[link][0]
            Rw = rotate_twist(oMf.rotation @ plan.spec.rotation)
            n1 = plan.nodes.shape[0]
            el = (bx @ shapes[:nx]).T.reshape(-1, n1, 6)
            tot = el + (jn @ shapes[nx:]).T.reshape(-1, n1, 6)
            positions[link] = plan.nodes @ oMf.rotation.T + oMf.translation
            motion[link] = np.einsum("ij,knj->kni", Rw, tot)
            elastic[link] = np.einsum("ij,knj->kni", Rw, el)
        return positions, motion, elastic


def _rot6(R: np.ndarray) -> np.ndarray:
    out = np.zeros(R.shape[:-2] + (6, 6))
    out[..., :3, :3] = R
    out[..., 3:, 3:] = R
    return out


def _offset_block(p: np.ndarray) -> np.ndarray:
    """The part of ``translate_twist(p) - I`` (linear in ``p``), batched."""
    out = np.zeros(p.shape[:-1] + (6, 6))
    out[..., :3, 3:] = -skew(p)
    return out


def _zeros_like(jac: np.ndarray, nx: int) -> np.ndarray:
    return np.zeros(jac.shape[:-1] + (nx,))
