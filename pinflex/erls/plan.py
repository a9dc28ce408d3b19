"""Set-up of an ERLS model: coordinates, elastic layout, attachments, planar checks."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from pinflex import beam
from pinflex.description import FlexibleLink
from pinflex.erls.terms import PLANAR_NODE_DOFS, _Attachment, _ChildJoint, _FlexPlan
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
        if jdesc.type not in ("revolute", "continuous"):
            raise ConfigurationError("absolute coordinates need revolute joints only")
        axes.append(data.oMi[j].rotation @ jdesc.axis)
    for a in axes[1:]:
        if np.linalg.norm(a - axes[0]) > 1e-9:
            raise ConfigurationError(
                "absolute coordinates need parallel revolute axes with the same direction"
            )
    C -= np.eye(model.nv, k=-1)
    return C


def build_plan(model) -> None:
    """Lay out elastic coordinates, beam plans, joint attachments and mass carriers."""
    desc = model.description
    # breadth-first order from the root
    order = [desc.root]
    for link in order:
        for jn in desc.child_joints[link]:
            order.append(desc.joints[jn].child)
    model._order = tuple(order)
    model._frame_id = {
        link: model.model.getFrameId(link, pin.FrameType.BODY) for link in desc.links
    }
    # elastic coordinates
    flex_plans: dict[str, _FlexPlan] = {}
    node_dofs = PLANAR_NODE_DOFS if model.planar else tuple(range(6))
    if model.planar:
        check_planar(model)
    offset = 0
    layout = []
    for link in order:
        if link in desc.flexible:
            spec = desc.flexible[link]
            n = spec.elements
            cols = offset + np.arange(n * len(node_dofs))
            layout.append((link, spec, cols))
            offset += cols.size
    model.nx = offset
    model.ndof = model.nx + model.nv
    for link, spec, cols in layout:
        flex_plans[link] = flex_plan(model, spec, cols, node_dofs)
    model._flex = flex_plans
    # node-dof rows kept in the assembly: the in-plane ones in planar mode (out-of-plane
    # rows vanish there, and the beam decouples in- and out-of-plane motion)
    model._assembly_arrays = {
        link: {
            "sel": p.sel[p.rows],
            "root": p.root[p.rows],
            "jac": p.jac[p.rows],
            "mass": p.mass[np.ix_(p.rows, p.rows)],
            "stiffness": p.stiffness[np.ix_(p.rows, p.rows)],
        }
        for link, p in flex_plans.items()
    }
    model.x_names = tuple(
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
                attach=attachment(model, jd.parent, jd.xyz),
                proj=proj,
            )
        )
    model._joints = tuple(joints)
    # mass carriers
    model._inertias = {
        link: inertia.spatial_matrix()
        for link, inertia in desc.inertias.items()
        if link not in desc.flexible and inertia.mass > 0.0
    }
    model._point_masses = tuple(
        (p.name, p.link, p.xyz, attachment(model, p.link, p.xyz)) for p in desc.point_masses
    )
    carriers = set(model._flex) | set(model._inertias) | {p[1] for p in model._point_masses}
    model._carriers = tuple(link for link in order if link in carriers)


def flex_plan(model, spec: FlexibleLink, cols: np.ndarray, node_dofs) -> _FlexPlan:
    """Constant matrices of one flexible link: element assembly, selections, node Jacobians."""
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
    sel = np.zeros((6 * (n + 1), model.nx))
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


def attachment(model, link: str, point: np.ndarray) -> _Attachment:
    """Elastic twist of a point given in the frame of ``link`` (in link axes)."""
    plan = model._flex.get(link)
    if plan is None:
        return _Attachment(None, translate_twist(point))
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
    return _Attachment(const if np.any(const) else None, lin)


def check_planar(model) -> None:
    """Check that the arm moves in one plane with beams normal to it; set plane_normal."""
    desc, pmodel = model.description, model.model
    data = pmodel.createData()
    pin.framesForwardKinematics(pmodel, data, pin.neutral(pmodel))
    normal = None
    for name in model.joint_names:
        jd = desc.joints[name]
        if jd.type == "prismatic":
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
        if jd.type == "prismatic" and normal is not None:
            a = data.oMi[pmodel.getJointId(name)].rotation @ jd.axis
            if abs(a @ normal) > 1e-9:
                raise PlanarModelError(f"prismatic joint '{name}' leaves the plane")
    model.plane_normal = normal
