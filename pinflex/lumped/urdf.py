"""URDF export of lumped arms and spring chains, and the loader that reads them back.

The export is two files:

* ``NAME.urdf``: a plain URDF of the rigid segments and the arm's links (one URDF link per
  Pinocchio body; the joints of a hinge station in series through massless links named
  ``<body>__<axis>``). Joint ``<dynamics damping>`` carries the damping. Every sprung joint
  also has a ``<pinflex:joint name=... stiffness=...>`` annotation (namespace
  ``urn:pinflex:urdf:1``), which Pinocchio's parser ignores and
  ``pinflex.FlexibleModel(path, joints="annotated")`` reads as joint springs: the file is
  then a rigid arm with spring joints, whose modes are the lumped arm's.
* ``NAME.springs.json``: the spring data, for any Pinocchio-based tool::

      {"format": "pinflex-springs/1",
       "joints": {"<joint>": {"stiffness": k, "springref": q0, "damping": d,
                               "armature": a}, ...},
       "pose": {"<joint>": value, ...}}

  ``stiffness`` [N m/rad or N/m], ``springref`` the spring's rest value [rad or m] (0 for
  hinges: the straight beam), ``damping`` [N m s/rad], ``armature`` [kg m^2] (the rotor
  inertia to add to ``model.armature``), ``pose`` the export pose. Joints not listed have no
  spring. The passive joint torque is ``-k (q - springref) - d q̇``.

:func:`load_lumped_urdf` reads both into a ``pin.Model`` (armature set) with the stiffness
matrix, rest configuration, damping and pose, and checks that the two files agree.
"""

from __future__ import annotations

import json
import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np
import pinocchio as pin
import scipy.linalg as sla

from pinflex.exceptions import InvalidDescription
from pinflex.lumped.layout import AXIS_VECTORS, SLIDE_AXES
from pinflex.lumped.mjcf import num, vec, welded_placement
from pinflex.lumped.model import LumpedArm
from pinflex.lumped.visuals import Visual

SPRINGS_FORMAT = "pinflex-springs/1"
NAMESPACE = "urn:pinflex:urdf:1"


@dataclass(frozen=True)
class UrdfJoint:
    """One joint of an exported URDF.

    Attributes:
        name: Joint name.
        type: 'revolute', 'continuous', 'prismatic' or 'fixed'.
        axis: Axis in the joint frame (3,).
        stiffness: Spring stiffness (0: none).
        springref: Spring rest value.
        damping: Joint damping.
        armature: Armature.
        limits: (lower, upper) or None (hinges get +-pi, unbounded prismatics +-1 m).
    """

    name: str
    type: str
    axis: np.ndarray
    stiffness: float = 0.0
    springref: float = 0.0
    damping: float = 0.0
    armature: float = 0.0
    limits: tuple[float, float] | None = None


def _rpy(rotation: np.ndarray) -> np.ndarray:
    return pin.rpy.matrixToRpy(np.asarray(rotation, dtype=float))


def _origin(placement: pin.SE3) -> str:
    return f'<origin xyz="{vec(placement.translation)}" rpy="{vec(_rpy(placement.rotation))}"/>'


def _inertial(inertia: pin.Inertia) -> list[str]:
    if inertia.mass <= 0.0:
        return []
    rot = 0.5 * (inertia.inertia + inertia.inertia.T)
    return ["    <inertial>",
            f'      <origin xyz="{vec(inertia.lever)}" rpy="0 0 0"/>',
            f'      <mass value="{num(inertia.mass)}"/>',
            f'      <inertia ixx="{num(rot[0, 0])}" ixy="{num(rot[0, 1])}" '
            f'ixz="{num(rot[0, 2])}" iyy="{num(rot[1, 1])}" iyz="{num(rot[1, 2])}" '
            f'izz="{num(rot[2, 2])}"/>',
            "    </inertial>"]


def _visual(kind: str, placement: pin.SE3, size, mesh: str = "", scale=(1, 1, 1)) -> list[str]:
    if kind == "mesh":
        geo = f'<mesh filename={quoteattr(mesh)} scale="{vec(scale)}"/>'
    elif kind == "box":
        geo = f'<box size="{vec(2 * np.asarray(size))}"/>'
    elif kind in ("cylinder", "capsule"):
        geo = f'<cylinder radius="{num(size[0])}" length="{num(2 * size[1])}"/>'
    else:
        geo = f'<sphere radius="{num(size[0])}"/>'
    return ["    <visual>", f"      {_origin(placement)}", f"      <geometry>{geo}</geometry>",
            "    </visual>"]


def tree_urdf(model: pin.Model, bodies: Sequence[tuple[str, tuple[int, ...], Sequence[UrdfJoint]]],
              *, name: str, root: str, visuals: Mapping[int, list[tuple]] | None = None,
              placements: Mapping[int, pin.SE3] | None = None) -> str:
    """URDF text of a Pinocchio tree grouped into bodies.

    Args:
        model: The Pinocchio model.
        bodies: ``(link name, joint ids in series, URDF joints)`` per body; the URDF joints are
            one per joint id (type 'fixed' for a welded one).
        name: Robot name.
        root: Name of the root link (the world-fixed body, joint id 0).
        visuals: ``{joint id: [(kind, placement in the joint frame, size, mesh, scale)]}``.
        placements: Joint placements replacing ``model.jointPlacements`` (welded joints at
            their value), by joint id.
    """
    visuals = visuals or {}
    placements = placements or {}
    link_of = {0: root}
    for link, ids, _ in bodies:
        link_of[ids[-1]] = link
    lines = ['<?xml version="1.0"?>',
             f"<robot name={quoteattr(name)} xmlns:pinflex=\"{NAMESPACE}\">",
             f"  <link name={quoteattr(root)}>"]
    for item in visuals.get(0, []):
        lines += _visual(*item)
    lines.append("  </link>")
    springs = []
    for link, ids, joints in bodies:
        for pos, (jid, joint) in enumerate(zip(ids, joints)):
            last = pos == len(ids) - 1
            child = link if last else f"{link}__{joint.name}"
            parent = link_of[model.parents[jid]] if pos == 0 else f"{link}__{joints[pos - 1].name}"
            lines.append(f"  <link name={quoteattr(child)}>")
            if last:
                lines += _inertial(model.inertias[jid])
                for item in visuals.get(jid, []):
                    lines += _visual(*item)
            lines.append("  </link>")
            lines += [f"  <joint name={quoteattr(joint.name)} type=\"{joint.type}\">",
                      f"    <parent link={quoteattr(parent)}/>",
                      f"    <child link={quoteattr(child)}/>",
                      f"    {_origin(placements.get(jid, model.jointPlacements[jid]))}"]
            if joint.type != "fixed":
                lines.append(f'    <axis xyz="{vec(joint.axis)}"/>')
                if joint.type != "continuous":
                    lo, hi = joint.limits if joint.limits is not None else (
                        (-1.0, 1.0) if joint.type == "prismatic" else (-math.pi, math.pi))
                    lines.append(f'    <limit lower="{num(lo)}" upper="{num(hi)}" '
                                 'effort="1e9" velocity="1e3"/>')
                lines.append(f'    <dynamics damping="{num(joint.damping)}" friction="0"/>')
                if joint.stiffness:
                    springs.append(f"  <pinflex:joint name={quoteattr(joint.name)} "
                                   f'stiffness="{num(joint.stiffness)}"/>')
            lines.append("  </joint>")
    lines += springs + ["</robot>", ""]
    return "\n".join(lines)


def springs_json(joints: Sequence[UrdfJoint], pose: Mapping[str, float]) -> str:
    """The spring data file (see the module docstring)."""
    data = {"format": SPRINGS_FORMAT,
            "joints": {j.name: {"stiffness": j.stiffness, "springref": j.springref,
                                "damping": j.damping, "armature": j.armature}
                       for j in joints if j.type != "fixed"},
            "pose": {k: float(v) for k, v in pose.items()}}
    return json.dumps(data, indent=2) + "\n"


def lumped_urdf(lumped: LumpedArm, q, *, damping: np.ndarray | None = None,
                visuals: Sequence[Visual] = (), mesh_names: Mapping[str, str] | None = None
                ) -> tuple[str, str]:
    """URDF and spring-data texts of a lumped arm at rest in arm pose ``q``.

    Args:
        lumped: The lumped arm.
        q: Arm pose (user convention): the ``pose`` of the spring data and the rest value
            (``springref``) of the arm's spring joints.
        damping: Joint damping (nv,) (default ``lumped.damping``).
        visuals: Rigid links' visual shapes.
        mesh_names: ``{mesh path: path as written}`` when meshes are copied.

    Returns:
        ``(urdf_text, springs_json_text)``.
    """
    from pinflex.lumped.fit import check_limits

    layout, model = lumped.layout, lumped.model
    damping = np.asarray(lumped.damping if damping is None else damping, dtype=float)
    check_limits(layout, np.atleast_2d(np.asarray(q, dtype=float)))
    qc = lumped.configuration(q)
    arm_by_name = {j.name: j for j in layout.arm_joints}
    child_of = {jd.name: jd.child for jd in layout.joints.values()}
    bodies = []
    placements: dict[int, pin.SE3] = {}
    in_station: set[int] = set()
    all_joints = []
    for (link, h), ids in sorted(lumped.hinge_ids.items()):
        joints = []
        for jid in ids:
            jname = model.names[jid]
            axis = jname.rsplit("_", 1)[1]
            v = model.joints[jid].idx_v
            joints.append(UrdfJoint(jname, "prismatic" if axis in SLIDE_AXES else "revolute",
                                    AXIS_VECTORS[axis], float(lumped.stiffness[v]), 0.0,
                                    float(damping[v])))
        in_station.update(ids)
        bodies.append((f"{link}_s{h}", tuple(ids), joints))
        all_joints += joints
    for jid in range(1, model.njoints):
        if jid in in_station:
            continue
        jname = model.names[jid]
        arm = arm_by_name[jname]
        jd = layout.joints[child_of[jname]]
        v = model.joints[jid].idx_v
        if arm.condition == "locked":
            joint = UrdfJoint(jname, "fixed", jd.axis)
            placements[jid] = welded_placement(model, jid, arm.kind, jd.axis, qc[v])
        else:
            kind = "prismatic" if arm.kind == "prismatic" else (
                "continuous" if arm.continuous else "revolute")
            limits = (arm.lower, arm.upper) if np.isfinite(arm.lower) and np.isfinite(
                arm.upper) else None
            joint = UrdfJoint(jname, kind, jd.axis, float(lumped.stiffness[v]), float(qc[v]),
                              float(damping[v]), float(lumped.armature[v]), limits)
        bodies.append((child_of[jname], (jid,), [joint]))
        all_joints.append(joint)
    bodies.sort(key=lambda b: b[1][0])
    vis: dict[int, list[tuple]] = {}
    for v_ in visuals:
        jid, frame = lumped.frames[v_.link]
        mesh = (mesh_names or {}).get(v_.mesh, v_.mesh)
        vis.setdefault(jid, []).append((v_.kind, frame * v_.placement, v_.size, mesh, v_.scale))
    along_z_to_x = pin.SE3(pin.rpy.rpyToMatrix(0.0, math.pi / 2, 0.0), np.zeros(3))
    for link, seg in lumped.segments.items():
        beam = layout.beams[link]
        b = seg.bounds_m
        for j in range(seg.n_segments):
            jid = lumped.segment_ids[(link, j)]
            length = b[j + 1] - b[j]
            frame = (lumped.frames[link][1] * pin.SE3(beam.rotation, np.zeros(3))
                     if j == 0 else pin.SE3.Identity())
            place = frame * pin.SE3(np.eye(3), np.array([0.5 * length, 0, 0])) * along_z_to_x
            vis.setdefault(jid, []).append(("cylinder", place, (beam.radius_m, 0.5 * length),
                                            "", (1, 1, 1)))
    pose = {model.names[j]: float(qc[model.joints[j].idx_v]) for j in range(1, model.njoints)
            if model.names[j] not in {jn.name for jn in all_joints if jn.type == "fixed"}}
    text = tree_urdf(model, bodies, name=layout.name, root=layout.links[0], visuals=vis,
                     placements=placements)
    return text, springs_json(all_joints, pose)


# ----------------------------------------------------------------------------- loader
@dataclass(frozen=True)
class LoadedLumped:
    """A lumped URDF read back for Pinocchio.

    Attributes:
        model: The Pinocchio model (``model.armature`` set from the spring data).
        stiffness: Joint stiffness matrix (nv, nv), diagonal [N m/rad or N/m].
        springref: Configuration (nq,) at which every spring is at rest.
        damping: Joint damping (nv,) [N m s/rad or N s/m].
        pose: The export pose as a configuration (nq,).
    """

    model: pin.Model
    stiffness: np.ndarray
    springref: np.ndarray
    damping: np.ndarray
    pose: np.ndarray

    def frequencies(self, qpos: np.ndarray | None = None) -> np.ndarray:
        """Non-rigid frequencies [Hz] at configuration ``qpos`` (default: the pose).

        Joints without stiffness are free: their coordinates are condensed out.
        """
        q = self.pose if qpos is None else np.asarray(qpos, dtype=float)
        data = self.model.createData()
        M = pin.crba(self.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        M[np.diag_indices_from(M)] += self.model.armature
        k = np.diag(self.stiffness)
        e, r = k > 0.0, k == 0.0
        Mc = M[np.ix_(e, e)]
        if r.any():
            Mc = Mc - M[np.ix_(e, r)] @ np.linalg.solve(M[np.ix_(r, r)], M[np.ix_(r, e)])
        lam = sla.eigh(np.diag(k[e]), 0.5 * (Mc + Mc.T), eigvals_only=True)
        return np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)


def _config_of(model: pin.Model, values: Mapping[str, float], what: str) -> np.ndarray:
    q = pin.neutral(model)
    for j in range(1, model.njoints):
        jm = model.joints[j]
        v = float(values.get(model.names[j], 0.0))
        if jm.nq == 2:
            q[jm.idx_q:jm.idx_q + 2] = math.cos(v), math.sin(v)
        elif jm.nq == 1:
            q[jm.idx_q] = v
    return q


def load_lumped_urdf(path: str | Path, springs: str | Path | None = None) -> LoadedLumped:
    """Read an exported lumped URDF and its spring data into Pinocchio terms.

    Args:
        path: The ``.urdf`` file.
        springs: The spring data file (default: ``<stem>.springs.json`` beside it; when absent,
            the URDF's ``<pinflex:joint stiffness>`` annotations with rest values 0).

    Returns:
        The :class:`LoadedLumped`.

    Raises:
        InvalidDescription: Unreadable files, an unknown format, a spring on a joint the URDF
            does not have, or stiffnesses that differ between the two files.
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        model = pin.buildModelFromXML(text)
        root = ET.fromstring(text)
    except (OSError, RuntimeError, ValueError, ET.ParseError) as exc:
        raise InvalidDescription(f"cannot read lumped URDF '{path}': {exc}") from exc
    annotated = {e.get("name"): float(e.get("stiffness", "0"))
                 for e in root.iter(f"{{{NAMESPACE}}}joint")}
    spath = Path(springs) if springs is not None else path.with_name(
        path.name[:-len(path.suffix)] + ".springs.json")
    if spath.is_file():
        try:
            data = json.loads(spath.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InvalidDescription(f"cannot read spring data '{spath}': {exc}") from exc
        if data.get("format") != SPRINGS_FORMAT:
            raise InvalidDescription(f"'{spath}' is not spring data of format {SPRINGS_FORMAT}")
        joints = data.get("joints", {})
        pose = data.get("pose", {})
    elif springs is not None:
        raise InvalidDescription(f"spring data file '{spath}' not found")
    else:
        joints = {n: {"stiffness": k} for n, k in annotated.items()}
        pose = {}
    names = list(model.names)
    nv = model.nv
    k = np.zeros(nv)
    damping = np.zeros(nv)
    armature = np.zeros(nv)
    ref = {}
    for name, spec in joints.items():
        if name not in names:
            raise InvalidDescription(f"spring data names joint '{name}', which '{path}' lacks")
        jm = model.joints[model.getJointId(name)]
        stiff = float(spec.get("stiffness", 0.0))
        if name in annotated and not math.isclose(annotated[name], stiff, rel_tol=1e-12):
            raise InvalidDescription(
                f"joint '{name}': stiffness {stiff:g} in '{spath}' but {annotated[name]:g} in "
                f"'{path}'")
        k[jm.idx_v] = stiff
        damping[jm.idx_v] = float(spec.get("damping", 0.0))
        armature[jm.idx_v] = float(spec.get("armature", 0.0))
        ref[name] = float(spec.get("springref", 0.0))
    for name in annotated:
        if name not in joints:
            raise InvalidDescription(f"joint '{name}' has a spring in '{path}' but none in "
                                     f"'{spath}'")
    model.armature = armature
    return LoadedLumped(model, np.diag(k), _config_of(model, ref, "springref"), damping,
                        _config_of(model, pose, "pose"))
