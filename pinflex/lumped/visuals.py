"""Visual geometry of an arm's rigid links, read from its URDF for the exports.

Pinocchio loads the URDF's ``<visual>`` elements (meshes found through ``package://`` URIs in
the file's folder and in example-robot-data). MuJoCo reads STL, OBJ and MSH meshes only: a
visual mesh in another format (COLLADA ``.dae`` in example-robot-data's arms) is replaced by
the link's collision mesh when that one is readable, and otherwise left out; what was replaced
or left out is listed in ``skipped``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin

#: Mesh formats MuJoCo reads.
MUJOCO_MESHES = (".stl", ".obj", ".msh")


@dataclass(frozen=True)
class Visual:
    """One visual shape of a link.

    Attributes:
        link: Link carrying it.
        placement: Its placement in the link frame.
        kind: 'mesh', 'box', 'cylinder', 'sphere' or 'capsule'.
        size: Box half sizes (3,), cylinder/capsule (radius, half length), sphere (radius,) [m].
        mesh: Mesh file path (kind 'mesh').
        scale: Mesh scale (3,).
        rgba: Colour.
    """

    link: str
    placement: pin.SE3
    kind: str
    size: tuple[float, ...] = ()
    mesh: str = ""
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    rgba: tuple[float, float, float, float] = (0.7, 0.7, 0.7, 1.0)


@dataclass(frozen=True)
class Visuals:
    """Visual shapes by link, and what could not be carried over.

    Attributes:
        shapes: Visuals of the links.
        skipped: Notes on meshes replaced by collision meshes or left out.
    """

    shapes: tuple[Visual, ...] = ()
    skipped: tuple[str, ...] = field(default_factory=tuple)


def _package_dirs(desc) -> list[str]:
    dirs = [str(desc.base_dir)] if desc.base_dir is not None else []
    try:
        from pinflex.description import robot_data_dir

        dirs.append(str(robot_data_dir().parent.parent))
    except Exception:  # example-robot-data absent: local meshes only
        pass
    return dirs


def _geometry(arm, kind) -> pin.GeometryModel | None:
    desc = arm.description
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            return pin.buildGeomFromUrdfString(arm.model, desc.urdf_xml, kind,
                                               package_dirs=_package_dirs(desc))
    except (RuntimeError, ValueError):
        return None


def _shape(link: str, placement: pin.SE3, g) -> Visual | None:
    geom = g.geometry
    colour = np.asarray(g.meshColor, dtype=float).ravel()
    rgba = ((float(colour[0]), float(colour[1]), float(colour[2]), float(colour[3]))
            if colour.size >= 4 else (0.7, 0.7, 0.7, 1.0))
    path = str(getattr(g, "meshPath", "") or "")
    name = type(geom).__name__
    if path and Path(path).suffix:
        s = np.asarray(g.meshScale, dtype=float).ravel()
        scale = (float(s[0]), float(s[1]), float(s[2]))
        return Visual(link, placement, "mesh", mesh=path, scale=scale, rgba=rgba)
    if name == "Box":
        return Visual(link, placement, "box", tuple(float(v) for v in geom.halfSide), rgba=rgba)
    if name == "Cylinder":
        return Visual(link, placement, "cylinder", (float(geom.radius), float(geom.halfLength)),
                      rgba=rgba)
    if name == "Capsule":
        return Visual(link, placement, "capsule", (float(geom.radius), float(geom.halfLength)),
                      rgba=rgba)
    if name == "Sphere":
        return Visual(link, placement, "sphere", (float(geom.radius),), rgba=rgba)
    return None


def _by_link(arm, gmodel) -> dict[str, list]:
    out: dict[str, list] = {}
    if gmodel is None:
        return out
    model = arm.model
    for g in gmodel.geometryObjects:
        frame = model.frames[g.parentFrame]
        placement = frame.placement.inverse() * g.placement
        out.setdefault(frame.name, []).append((placement, g))
    return out


def arm_visuals(arm, skip_links=()) -> Visuals:
    """Visual shapes of the arm's links (flexible links in ``skip_links`` left out).

    Args:
        arm: The :class:`~pinflex.erls.FlexibleModel`.
        skip_links: Links whose URDF visuals are not wanted (the flexible ones, drawn as
            segments instead).

    Returns:
        The shapes MuJoCo can read, and notes on the others.
    """
    visual = _by_link(arm, _geometry(arm, pin.GeometryType.VISUAL))
    collision: dict[str, list] | None = None
    shapes, skipped = [], []
    for link, items in visual.items():
        if link in skip_links:
            continue
        for placement, g in items:
            shape = _shape(link, placement, g)
            if shape is None:
                skipped.append(f"{link}: {type(g.geometry).__name__} shape left out")
                continue
            if shape.kind == "mesh" and Path(shape.mesh).suffix.lower() not in MUJOCO_MESHES:
                if collision is None:
                    collision = _by_link(arm, _geometry(arm, pin.GeometryType.COLLISION))
                found = [_shape(link, p, c) for p, c in collision.get(link, [])]
                subs = [s for s in found if s is not None and (
                    s.kind != "mesh" or Path(s.mesh).suffix.lower() in MUJOCO_MESHES)]
                if subs:
                    shapes.extend(subs)
                    skipped.append(f"{link}: {Path(shape.mesh).name} (not readable by MuJoCo) "
                                   "replaced by the link's collision geometry")
                else:
                    skipped.append(f"{link}: {Path(shape.mesh).name} left out (MuJoCo reads "
                                   f"{', '.join(MUJOCO_MESHES)})")
                continue
            shapes.append(shape)
    return Visuals(tuple(shapes), tuple(skipped))
