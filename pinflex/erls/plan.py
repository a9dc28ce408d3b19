"""Set-up of an ERLS model: coordinates, elastic layout, attachments, planar checks."""

from __future__ import annotations

from collections.abc import Mapping
from types import MappingProxyType

import numpy as np
import pinocchio as pin

from pinflex import beam
from pinflex.description import FlexibleLink
from pinflex.erls.terms import (
    PLANAR_NODE_DOFS,
    Attachment,
    BeamPlan,
    BodyPlan,
    JointPlan,
    ModelPlan,
    PointMassPlan,
    joint_kind,
)
from pinflex.exceptions import ConfigurationError, PlanarModelError
from pinflex.linalg import rotate_twist, translate_twist


def coordinate_map(model, absolute: bool) -> np.ndarray:
    """Map C from user coordinates to Pinocchio joint values (q_pin = C q_user)."""
    C = np.eye(model.nv)
    if not absolute:
        return C
    pmodel = model.model
    data = pmodel.createData()
    pin.forwardKinematics(pmodel, data, pin.neutral(pmodel))
    axes = []
    for j in range(1, pmodel.njoints):
        if pmodel.parents[j] != j - 1:
            raise ConfigurationError(
                "absolute coordinates need a serial chain; joint "
                f"'{pmodel.names[j]}' does not follow joint '{pmodel.names[j - 1]}'"
            )
        jdesc = model.description.joints[pmodel.names[j]]
        if not joint_kind(jdesc.type).rotates:
            raise ConfigurationError("absolute coordinates need revolute joints only")
        axes.append(data.oMi[j].rotation @ jdesc.axis)
    for a in axes[1:]:
        if np.linalg.norm(a - axes[0]) > 1e-9:
            raise ConfigurationError(
                "absolute coordinates need parallel revolute axes with the same direction"
            )
    C -= np.eye(model.nv, k=-1)
    return C


def _frozen(values, dtype=float) -> np.ndarray:
    array = np.array(values, dtype=dtype)
    array.setflags(write=False)
    return array


def build_plan(model) -> ModelPlan:
    """Lay out elastic coordinates, beam plans, joint attachments and mass carriers.

    Args:
        model: A :class:`~pinflex.erls.FlexibleModel` whose description, Pinocchio model,
            ``planar`` flag and ``nv`` are set.

    Returns:
        The model's read-only :class:`~pinflex.erls.terms.ModelPlan`.

    Raises:
        PlanarModelError: A planar model whose axes or beams leave the plane.
    """
    desc = model.description
    # breadth-first order from the root
    order = [desc.root]
    for link in order:
        for jn in desc.child_joints[link]:
            order.append(desc.joints[jn].child)
    frame_ids = {link: model.model.getFrameId(link, pin.FrameType.BODY) for link in desc.links}
    # elastic coordinates
    node_dofs = PLANAR_NODE_DOFS if model.planar else tuple(range(6))
    normal = check_planar(model) if model.planar else None
    offset = 0
    layout = []
    for link in order:
        if link in desc.flexible:
            spec = desc.flexible[link]
            n = spec.elements
            cols = offset + np.arange(n * len(node_dofs))
            layout.append((link, spec, cols))
            offset += cols.size
    nx = offset
    # node-dof rows kept in the assembly: the in-plane ones in planar mode (out-of-plane
    # rows vanish there, and the beam decouples in- and out-of-plane motion)
    beams = {link: flex_plan(nx, spec, cols, node_dofs) for link, spec, cols in layout}
    x_names = tuple(
        f"{link}.n{k + 1}.{'u' if d < 3 else 'r'}{'xyz'[d % 3]}"
        for link, spec, _ in layout
        for k in range(spec.elements)
        for d in node_dofs
    )
    # joints: attachments of child links
    pm = model.model
    vidx = {pm.names[j]: pm.joints[j].idx_v for j in range(1, pm.njoints)}
    joints = []
    for link in order[1:]:
        jd = desc.joints[desc.parent_joint[link]]
        kind = joint_kind(jd.type)
        joints.append(
            JointPlan(
                name=jd.name,
                parent=jd.parent,
                child=link,
                kind=kind.name,
                user_col=vidx.get(jd.name, -1),
                R_o=_frozen(jd.rotation),
                xyz=_frozen(jd.xyz),
                axis=_frozen(jd.axis),
                attach=attachment(beams, jd.parent, jd.xyz),
                proj=_frozen(kind.projection(jd.axis)),
            )
        )
    # mass carriers; bodies on rigid links join their link's inertia (at the link origin)
    inertias = {
        link: inertia.spatial_matrix()
        for link, inertia in desc.inertias.items()
        if link not in desc.flexible and inertia.mass > 0.0
    }
    bodies = []
    for body in desc.bodies:
        at_com = body.spatial_matrix()
        if body.link in beams:
            bodies.append(BodyPlan(body.name, body.link, _frozen(body.com),
                                   attachment(beams, body.link, body.com), _frozen(at_com)))
        else:
            X = translate_twist(body.com)  # twist at the body from the link-origin twist
            inertias[body.link] = inertias.get(body.link, 0.0) + X.T @ at_com @ X
    inertias = {link: _frozen(v) for link, v in inertias.items()}
    point_masses = tuple(
        PointMassPlan(p.name, p.link, _frozen(p.xyz), attachment(beams, p.link, p.xyz))
        for p in desc.point_masses
    )
    carriers = set(beams) | set(inertias) | {p.link for p in point_masses} | {
        b.link for b in bodies}
    return ModelPlan(
        links=tuple(order),
        beams=MappingProxyType(beams),
        joints=tuple(joints),
        inertias=MappingProxyType(inertias),
        point_masses=point_masses,
        carriers=tuple(link for link in order if link in carriers),
        frame_ids=MappingProxyType(frame_ids),
        nx=nx,
        x_names=x_names,
        plane_normal=None if normal is None else _frozen(normal),
        bodies=tuple(bodies),
    )


def flex_plan(nx: int, spec: FlexibleLink, cols: np.ndarray, node_dofs) -> BeamPlan:
    """Constant matrices of one flexible link: element assembly, selections, node Jacobians.

    Args:
        nx: Number of elastic coordinates of the whole model.
        spec: The link's beam annotation.
        cols: Columns of ``x`` owned by nodes 1..N of this beam.
        node_dofs: Node dofs kept per node (all six, or the in-plane ones).
    """
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
    sel = np.zeros((6 * (n + 1), nx))
    k = 0
    for node in range(1, n + 1):
        for d in node_dofs:
            sel[6 * node + d, cols[k]] = 1.0
            k += 1
    root = np.zeros((6 * (n + 1), 6))
    root[:6] = rotate_twist(rb.T)
    jac = np.concatenate([rotate_twist(rb.T) @ translate_twist(p) for p in nodes])
    rows = (6 * np.arange(n + 1)[:, None] + np.asarray(node_dofs)[None, :]).ravel()
    return BeamPlan(spec.link, spec, _frozen(cols, int), _frozen(sel), _frozen(root),
                    _frozen(jac), _frozen(M), _frozen(K), _frozen(nodes), _frozen(rows, int))


def attachment(beams: Mapping[str, BeamPlan], link: str, point: np.ndarray) -> Attachment:
    """Elastic twist of a point given in the frame of ``link`` (in link axes).

    Args:
        beams: Plans of the flexible links.
        link: Link carrying the point.
        point: (3,) position in the link frame [m].
    """
    plan = beams.get(link)
    if plan is None:
        return Attachment(None, _frozen(translate_twist(point)))
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
    return Attachment(_frozen(const) if np.any(const) else None,
                      None if lin is None else _frozen(lin))


def check_planar(model) -> np.ndarray | None:
    """Check that the arm moves in one plane with beams normal to it.

    Returns:
        The world normal (3,) of the plane, or None for an arm without revolute joints or beams.
    """
    desc, pmodel = model.description, model.model
    data = pmodel.createData()
    pin.framesForwardKinematics(pmodel, data, pin.neutral(pmodel))
    normal = None
    for name in model.joint_names:
        jd = desc.joints[name]
        if not joint_kind(jd.type).rotates:
            continue
        jid = pmodel.getJointId(name)
        a = data.oMi[jid].rotation @ jd.axis
        if normal is None:
            normal = a
        elif np.linalg.norm(np.cross(a, normal)) > 1e-9:
            raise PlanarModelError(
                f"planar mode needs parallel revolute axes; joint '{name}' has axis "
                f"{np.round(a, 6).tolist()} in the world, the first one {normal.tolist()}"
            )
    for link, spec in desc.flexible.items():
        R = data.oMf[pmodel.getFrameId(link, pin.FrameType.BODY)].rotation @ spec.rotation
        if normal is None:
            normal = R[:, 2]
        if np.linalg.norm(np.cross(R[:, 2], normal)) > 1e-9:
            raise PlanarModelError(
                f"planar mode needs the beam normal of '{link}' along the plane normal "
                f"{np.round(normal, 6).tolist()}; set normal=\"...\" on <pinflex:flexible>"
            )
    for name in model.joint_names:
        jd = desc.joints[name]
        if not joint_kind(jd.type).rotates and normal is not None:
            a = data.oMi[pmodel.getJointId(name)].rotation @ jd.axis
            if abs(a @ normal) > 1e-9:
                raise PlanarModelError(f"prismatic joint '{name}' leaves the plane")
    return normal
