"""MJCF (MuJoCo) export of lumped arms and spring chains.

The Pinocchio model's joints become MJCF bodies (the joints of one hinge station share one
body, in series in their order, as MuJoCo applies a body's joints); each body carries the
Pinocchio body inertia of its last joint as ``<inertial>`` (``fullinertia``, compiler
``inertiafromgeom="false"`` so geoms add no mass). Joints carry ``stiffness``, ``springref``,
``damping``, ``armature`` and ``range``: MuJoCo's passive spring ``-k (q - springref)`` and
damper ``-d q̇`` are exactly the lumped model's diagonal K and joint damping. Visual geoms
have ``contype = conaffinity = 0``.

MuJoCo refuses moving bodies without mass; such a body (a massless URDF link between two
joints) gets ``MASSLESS_MASS`` kg and ``MASSLESS_INERTIA`` kg m² and is listed in the export's
notes.
"""

from __future__ import annotations

import shutil
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pinocchio as pin

from pinflex.lumped.layout import AXIS_VECTORS, SLIDE_AXES
from pinflex.lumped.model import LumpedArm
from pinflex.lumped.visuals import Visual

MASSLESS_MASS = 1e-9
MASSLESS_INERTIA = 1e-12


def num(value: float) -> str:
    """Shortest round-trip text of a number."""
    return repr(float(value))


def vec(values) -> str:
    """Space-separated round-trip numbers."""
    return " ".join(num(v) for v in np.asarray(values, dtype=float).ravel())


@dataclass(frozen=True)
class MjcfJoint:
    """One MJCF joint.

    Attributes:
        name: Joint name.
        type: 'hinge' or 'slide'.
        axis: Axis in the body frame (3,).
        stiffness: Spring stiffness [N m/rad or N/m].
        springref: Spring rest position [rad or m].
        damping: Damping [N m s/rad or N s/m].
        armature: Armature [kg m^2 or kg].
        range: Limits (lower, upper) or None.
    """

    name: str
    type: str
    axis: np.ndarray
    stiffness: float = 0.0
    springref: float = 0.0
    damping: float = 0.0
    armature: float = 0.0
    range: tuple[float, float] | None = None

    def xml(self) -> str:
        """The ``<joint>`` element."""
        attrs = [f'name={quoteattr(self.name)}', f'type="{self.type}"',
                 f'axis="{vec(self.axis)}"']
        if self.stiffness:
            attrs += [f'stiffness="{num(self.stiffness)}"', f'springref="{num(self.springref)}"']
        if self.damping:
            attrs.append(f'damping="{num(self.damping)}"')
        if self.armature:
            attrs.append(f'armature="{num(self.armature)}"')
        if self.range is not None:
            attrs.append(f'range="{num(self.range[0])} {num(self.range[1])}" limited="true"')
        return "<joint " + " ".join(attrs) + "/>"


@dataclass
class MjcfBody:
    """An MJCF body made of one or more Pinocchio joints (the last one carries the inertia).

    Attributes:
        name: Body name.
        joint_ids: Pinocchio joint ids, in series (identity placements after the first).
        joints: MJCF joints of the body (empty: welded to its parent).
        geoms: ``<geom>`` elements in the frame of the last joint.
    """

    name: str
    joint_ids: tuple[int, ...]
    joints: list[MjcfJoint] = field(default_factory=list)
    geoms: list[str] = field(default_factory=list)


def _inertial(inertia: pin.Inertia, name: str, notes: list[str]) -> str:
    mass = float(inertia.mass)
    com = inertia.lever
    rot = 0.5 * (inertia.inertia + inertia.inertia.T)
    if mass <= 0.0:
        notes.append(f"body '{name}' has no mass; given {MASSLESS_MASS:g} kg and "
                     f"{MASSLESS_INERTIA:g} kg m^2 (MuJoCo refuses massless moving bodies)")
        mass, rot = MASSLESS_MASS, MASSLESS_INERTIA * np.eye(3)
    full = [rot[0, 0], rot[1, 1], rot[2, 2], rot[0, 1], rot[0, 2], rot[1, 2]]
    return (f'<inertial pos="{vec(com)}" mass="{num(mass)}" fullinertia="{vec(full)}"/>')


def _quat(rotation: np.ndarray) -> np.ndarray:
    q = pin.Quaternion(np.asarray(rotation, dtype=float))
    q.normalize()
    return np.array([q.w, q.x, q.y, q.z])


def _pose_attrs(placement: pin.SE3) -> str:
    out = f'pos="{vec(placement.translation)}"'
    if not np.allclose(placement.rotation, np.eye(3), rtol=0.0, atol=1e-15):
        out += f' quat="{vec(_quat(placement.rotation))}"'
    return out


def geom_xml(visual: Visual, placement: pin.SE3, mesh_name: str | None = None) -> str:
    """``<geom>`` of a visual shape at ``placement`` in its body frame (no contacts, no mass)."""
    common = (f'{_pose_attrs(placement)} contype="0" conaffinity="0" group="1" '
              f'rgba="{vec(visual.rgba)}"')
    if visual.kind == "mesh":
        return f'<geom type="mesh" mesh={quoteattr(mesh_name or "")} {common}/>'
    if visual.kind == "box":
        return f'<geom type="box" size="{vec(visual.size)}" {common}/>'
    if visual.kind in ("cylinder", "capsule"):
        return f'<geom type="{visual.kind}" size="{vec(visual.size)}" {common}/>'
    return f'<geom type="sphere" size="{vec(visual.size)}" {common}/>'


def segment_geom(start: np.ndarray, end: np.ndarray, radius: float,
                 rgba=(0.55, 0.65, 0.8, 1.0)) -> str:
    """A visual cylinder between two points of a body frame."""
    return (f'<geom type="cylinder" fromto="{vec(start)} {vec(end)}" size="{num(radius)}" '
            f'contype="0" conaffinity="0" group="1" rgba="{vec(rgba)}"/>')


@dataclass(frozen=True)
class MjcfDocument:
    """An MJCF text and what goes with it.

    Attributes:
        text: The XML.
        qpos: Keyframe configuration in MuJoCo's qpos order, by joint name.
        meshes: ``(asset name, source path)`` of the mesh files it references.
        notes: What the export changed or left out.
    """

    text: str
    qpos: dict[str, float]
    meshes: tuple[tuple[str, str], ...]
    notes: tuple[str, ...]


def mjcf_text(model: pin.Model, bodies: Sequence[MjcfBody], *, name: str,
              world_geoms: Sequence[str] = (), actuators: Sequence[str] = (),
              assets: Sequence[str] = (), qpos: dict[str, float] | None = None,
              timestep: float = 0.002, gravity=(0.0, 0.0, -9.81), comment: str = "",
              notes: list[str] | None = None, meshdir: str | None = None,
              placements: dict[int, pin.SE3] | None = None) -> str:
    """MJCF text of a Pinocchio tree grouped into bodies.

    Args:
        model: The Pinocchio model (bodies' placements and inertias are read from it).
        bodies: Every moving joint of ``model`` in exactly one body.
        name: Model name.
        world_geoms: Geoms fixed to the world.
        actuators: ``<actuator>`` children.
        assets: ``<asset>`` children.
        qpos: Keyframe ``pose`` values by joint name (default none).
        timestep: Simulation time step [s].
        gravity: Gravity (3,) [m/s^2].
        comment: Text of a leading XML comment.
        notes: List to append notes to (massless bodies).
        meshdir: Compiler ``meshdir`` (relative to the file).
        placements: Body placements replacing ``model.jointPlacements`` (welded joints at
            their value), by first joint id.
    """
    notes = [] if notes is None else notes
    placements = placements or {}
    group_of = {}
    for i, body in enumerate(bodies):
        for jid in body.joint_ids:
            group_of[jid] = i
    children: dict[int, list[int]] = {-1: []}
    for i, body in enumerate(bodies):
        parent = model.parents[body.joint_ids[0]]
        children.setdefault(group_of.get(parent, -1) if parent else -1, []).append(i)
    order: list[str] = []
    lines = ['<?xml version="1.0"?>']
    if comment:
        lines.append("<!-- " + comment.replace("--", "- -") + " -->")
    lines.append(f"<mujoco model={quoteattr(name)}>")
    compiler = '<compiler angle="radian" inertiafromgeom="false" autolimits="true"'
    if meshdir:
        compiler += f" meshdir={quoteattr(meshdir)}"
    lines.append("  " + compiler + "/>")
    lines.append(f'  <option timestep="{num(timestep)}" gravity="{vec(gravity)}" '
                 'integrator="implicitfast"/>')
    if assets:
        lines.append("  <asset>")
        lines += ["    " + a for a in assets]
        lines.append("  </asset>")
    lines.append("  <worldbody>")
    lines += ["    " + g for g in world_geoms]

    def emit(i: int, depth: int) -> None:
        body = bodies[i]
        pad = "  " * depth
        first = body.joint_ids[0]
        lines.append(f"{pad}<body name={quoteattr(body.name)} "
                     f"{_pose_attrs(placements.get(first, model.jointPlacements[first]))}>")
        for inner, outer in zip(body.joint_ids[:-1], body.joint_ids[1:]):
            if not model.jointPlacements[outer].isIdentity(1e-14) or \
                    model.inertias[inner].mass != 0.0:
                raise ValueError(f"joints of body '{body.name}' are not in series at its origin")
        for joint in body.joints:
            lines.append(f"{pad}  {joint.xml()}")
            order.append(joint.name)
        inertia = model.inertias[body.joint_ids[-1]]
        lines.append(f"{pad}  {_inertial(inertia, body.name, notes)}")
        lines.extend(f"{pad}  {g}" for g in body.geoms)
        for c in children.get(i, []):
            emit(c, depth + 1)
        lines.append(f"{pad}</body>")

    for i in children[-1]:
        emit(i, 2)
    lines.append("  </worldbody>")
    if actuators:
        lines.append("  <actuator>")
        lines += ["    " + a for a in actuators]
        lines.append("  </actuator>")
    if qpos is not None and order:
        values = " ".join(num(qpos.get(n, 0.0)) for n in order)
        lines += ["  <keyframe>", f'    <key name="pose" qpos="{values}"/>', "  </keyframe>"]
    lines += ["</mujoco>", ""]
    return "\n".join(lines)


def _axis_joint(kind: str, axis) -> str:
    return "slide" if kind == "prismatic" else "hinge"


def welded_placement(model: pin.Model, jid: int, kind: str, axis: np.ndarray,
                     value: float) -> pin.SE3:
    """Placement of a joint's child frame with the joint held at ``value`` [rad or m]."""
    axis = np.asarray(axis, dtype=float)
    if kind == "prismatic":
        motion = pin.SE3(np.eye(3), axis * value)
    else:
        motion = pin.SE3(pin.AngleAxis(value, axis / np.linalg.norm(axis)).matrix(), np.zeros(3))
    return model.jointPlacements[jid] * motion


def suggested_timestep(f_max_hz: float, default: float = 0.002) -> float:
    """A step resolving the highest mode: ``min(default, 1 / (20 f_max))`` [s]."""
    if not np.isfinite(f_max_hz) or f_max_hz <= 0.0:
        return default
    step = 1.0 / (20.0 * f_max_hz)
    return float(min(default, float(f"{step:.2g}")))


def lumped_mjcf(lumped: LumpedArm, q, *, damping: np.ndarray | None = None,
                visuals: Sequence[Visual] = (), actuators: str = "motor",
                kp: float | None = None, kv: float = 0.0, gravity=(0.0, 0.0, -9.81),
                timestep: float | None = None, comment: str = "",
                mesh_names: dict[str, str] | None = None,
                meshdir: str | None = None) -> MjcfDocument:
    """MJCF of a lumped arm at rest in arm pose ``q``.

    Args:
        lumped: The lumped arm.
        q: Arm pose (user convention): the keyframe ``pose``, and the rest position
            (``springref``) of the arm's spring joints (the ERLS springs are unloaded there).
        damping: Joint damping (nv,) (default: ``lumped.damping``).
        visuals: Rigid links' visual shapes (:func:`pinflex.lumped.visuals.arm_visuals`).
        actuators: 'motor' (a torque/force on each free or sprung arm joint), 'position'
            (a servo of gain ``kp`` [N m/rad] and ``kv`` [N m s/rad]) or 'none'.
        kp: Position gain (required for 'position').
        kv: Velocity gain of the position servos.
        gravity: Gravity (3,) [m/s^2].
        timestep: Step [s] (default: :func:`suggested_timestep` of the highest lumped mode).
        comment: Leading comment text.
        mesh_names: ``{mesh path: file name as written}`` when meshes are copied.
        meshdir: Compiler ``meshdir`` for copied meshes.

    Returns:
        The :class:`MjcfDocument`.
    """
    from pinflex.lumped.fit import check_limits

    layout = lumped.layout
    model = lumped.model
    damping = np.asarray(lumped.damping if damping is None else damping, dtype=float)
    qc = lumped.configuration(q)
    check_limits(layout, np.atleast_2d(np.asarray(q, dtype=float)))
    arm_by_name = {j.name: j for j in layout.arm_joints}
    child_of = {jd.name: jd.child for jd in layout.joints.values()}
    bodies: list[MjcfBody] = []
    body_of: dict[int, MjcfBody] = {}
    placements: dict[int, pin.SE3] = {}
    station_ids: set[int] = set()
    for (link, h), ids in sorted(lumped.hinge_ids.items()):
        joints = []
        for jid in ids:
            jname = model.names[jid]
            axis = jname.rsplit("_", 1)[1]
            v = model.joints[jid].idx_v
            joints.append(MjcfJoint(jname, "slide" if axis in SLIDE_AXES else "hinge",
                                    AXIS_VECTORS[axis], stiffness=lumped.stiffness[v],
                                    damping=damping[v]))
        body = MjcfBody(f"{link}_s{h}", tuple(ids), joints)
        station_ids.update(ids)
        bodies.append(body)
        for jid in ids:
            body_of[jid] = body
    for jid in range(1, model.njoints):
        if jid in station_ids:
            continue
        jname = model.names[jid]
        arm = arm_by_name[jname]
        jd = layout.joints[child_of[jname]]
        v = model.joints[jid].idx_v
        joints = []
        if arm.condition == "locked":
            placements[jid] = welded_placement(model, jid, arm.kind, jd.axis, qc[v])
        else:
            limits = None
            if not arm.continuous and np.isfinite(arm.lower) and np.isfinite(arm.upper):
                limits = (arm.lower, arm.upper)
            joints.append(MjcfJoint(jname, _axis_joint(arm.kind, jd.axis), jd.axis,
                                    stiffness=lumped.stiffness[v], springref=qc[v],
                                    damping=damping[v], armature=lumped.armature[v],
                                    range=limits))
        body = MjcfBody(child_of[jname], (jid,), joints)
        bodies.append(body)
        body_of[jid] = body
    bodies.sort(key=lambda b: b.joint_ids[0])
    # visuals of rigid links, at their link frames
    world_geoms: list[str] = []
    assets, meshes = [], []
    mesh_asset: dict[tuple, str] = {}
    for vis in visuals:
        jid, frame = lumped.frames[vis.link]
        mesh_name = None
        if vis.kind == "mesh":
            key = (vis.mesh, vis.scale)
            if key not in mesh_asset:
                mesh_name = f"mesh{len(mesh_asset)}"
                mesh_asset[key] = mesh_name
                file = (mesh_names or {}).get(vis.mesh, vis.mesh)
                assets.append(f'<mesh name="{mesh_name}" file={quoteattr(file)} '
                              f'scale="{vec(vis.scale)}"/>')
                meshes.append((mesh_name, vis.mesh))
            mesh_name = mesh_asset[key]
        text = geom_xml(vis, frame * vis.placement, mesh_name)
        (world_geoms if jid == 0 else body_of[jid].geoms).append(text)
    # segments drawn as cylinders of the section's area
    for link, seg in lumped.segments.items():
        beam = layout.beams[link]
        b = seg.bounds_m
        for j in range(seg.n_segments):
            jid = lumped.segment_ids[(link, j)]
            length = b[j + 1] - b[j]
            if j == 0:
                frame = lumped.frames[link][1] * pin.SE3(beam.rotation, np.zeros(3))
            else:
                frame = pin.SE3.Identity()
            start = frame.translation
            end = frame.act(np.array([length, 0.0, 0.0]))
            text = segment_geom(start, end, beam.radius_m)
            (world_geoms if jid == 0 else body_of[jid].geoms).append(text)
    acts = []
    if actuators not in ("motor", "position", "none"):
        raise ValueError(f"actuators '{actuators}': expected 'motor', 'position' or 'none'")
    for arm in layout.arm_joints:
        if arm.condition == "locked" or actuators == "none":
            continue
        if actuators == "motor":
            acts.append(f'<motor name={quoteattr(arm.name)} joint={quoteattr(arm.name)} '
                        'gear="1"/>')
        else:
            if kp is None or not kp > 0:
                raise ValueError("position actuators need a positive kp")
            acts.append(f'<position name={quoteattr(arm.name)} joint={quoteattr(arm.name)} '
                        f'kp="{num(kp)}" kv="{num(kv)}"/>')
    if timestep is None:
        f_hi = lumped.frequencies(q, "own").max(initial=0.0)
        timestep = suggested_timestep(float(f_hi))
    notes: list[str] = []
    qpos = {model.names[j]: qc[model.joints[j].idx_v] for j in range(1, model.njoints)}
    text = mjcf_text(model, bodies, name=layout.name, world_geoms=world_geoms,
                     actuators=acts, assets=assets, qpos=qpos, timestep=timestep,
                     gravity=gravity, comment=comment, notes=notes, meshdir=meshdir,
                     placements=placements)
    return MjcfDocument(text, qpos, tuple(meshes), tuple(notes))


def copy_meshes(paths: Sequence[str], folder: Path) -> dict[str, str]:
    """Copy mesh files into ``folder``; returns ``{source path: file name in folder}``."""
    folder.mkdir(parents=True, exist_ok=True)
    out = {}
    for i, src in enumerate(dict.fromkeys(paths)):
        target = f"{i:03d}_{Path(src).name}"
        shutil.copyfile(src, folder / target)
        out[src] = target
    return out
