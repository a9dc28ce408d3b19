"""A flexible robot drawn in meshcat: URDF visuals, deformed beams, joints, masses and bodies.

* URDF visual geometry is loaded by Pinocchio (``pin.buildGeomFromUrdfString``, meshes found
  through ``package://`` URIs in the description's folder and in example-robot-data) and put
  in the scene by Pinocchio's ``MeshcatVisualizer``. Visuals of rigid links move with their
  link; visuals of flexible links stay at the undeformed pose as translucent ghosts, so that
  the deformed beam drawn over them shows the deflection.
* Every flexible link is a chain of cylinders through stations of its centreline
  (:func:`pinflex.visualization.shapes.centrelines`).
* Links without visual geometry get simple shapes: a sphere at the link origin and a cylinder
  to each child joint. Moving joints get a sphere; point masses a sphere whose volume grows
  with the mass (zero masses are not drawn).
* Rigid bodies (``<pinflex:body>`` and the URDF inertia a beam link keeps, e.g. its motor) are
  cubes at their centre of mass, of the volume of a sphere of the same mass, turning with
  their link frame. On a beam a body sits at the drawn centreline at the axial station of its
  centre of mass plus its offset from the axis (turned with the link frame, without the
  section's elastic rotation), as the model carries it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin

from pinflex.checks import check_q, check_y
from pinflex.erls import FlexibleModel, ModalResult
from pinflex.exceptions import InvalidDescription, PinflexWarning
from pinflex.visualization import shapes
from pinflex.visualization.scene import (
    BEAM_COLOUR,
    BODY_COLOUR,
    GHOST_RGBA,
    JOINT_COLOUR,
    LINK_COLOUR,
    MASS_COLOUR,
    SceneWriter,
    rgb_int,
    segment_matrix,
    translation,
)

#: Density used to size point-mass spheres [kg/m^3] (a display choice, not a material).
MASS_SPHERE_DENSITY = 2000.0


def load_visual_model(model: FlexibleModel) -> pin.GeometryModel | None:
    """Visual geometry of the URDF, or ``None`` (with a warning) when it cannot be loaded.

    Raises:
        UnsafePath: A mesh lies outside the description's folder and the package roots
            (allowed by loading it with ``allow_paths=True``).
    """
    desc = model.description
    dirs = [str(desc.base_dir)] if desc.base_dir is not None else []
    try:
        from pinflex.description import robot_data_dir

        dirs.append(str(robot_data_dir().parent.parent))
    except InvalidDescription:
        pass
    from pinflex.description.crosscheck import native_stderr
    from pinflex.description.source import check_mesh_paths

    check_mesh_paths(desc.urdf_xml, desc.base_dir, dirs, allow=desc.allow_paths)
    try:
        with native_stderr():  # urdfdom and assimp messages stay off the terminal
            return pin.buildGeomFromUrdfString(
                model.model, desc.urdf_xml, pin.GeometryType.VISUAL, package_dirs=dirs
            )
    except (RuntimeError, ValueError) as exc:
        warnings.warn(
            f"the URDF's visual geometry could not be loaded ({exc}); drawing simple shapes",
            PinflexWarning,
            stacklevel=3,
        )
        return None


def mesh_geometry(geometry_object) -> Any | None:
    """A mesh visual as one binary triangle buffer, or ``None`` if it is not a loaded mesh.

    The vertices Pinocchio loaded (already scaled by the URDF's ``scale``) go in as float32
    [m], the triangles as 16-bit indices when there are fewer than 65,536 vertices (32-bit
    otherwise); the viewer computes the normals. A COLLADA file of the UR5's upper arm is
    2.0 MB of text; its buffer is 0.35 MB before compression.
    """
    import meshcat.geometry as mg
    import umsgpack

    mesh = geometry_object.geometry
    n_tris = int(getattr(mesh, "num_tris", 0) or 0)
    if n_tris == 0 or not hasattr(mesh, "tri_indices") or not hasattr(mesh, "vertices"):
        return None
    vertices = np.ascontiguousarray(np.asarray(mesh.vertices(), dtype=np.float32))
    faces = np.empty((n_tris, 3), dtype=np.uint32)
    for k in range(n_tris):
        t = mesh.tri_indices(k)
        faces[k] = (t[0], t[1], t[2])
    small = len(vertices) < 65536
    index: np.ndarray = faces.astype(np.uint16) if small else faces
    code, kind = (0x14, "Uint16Array") if small else (0x16, "Uint32Array")

    class _Buffer(mg.Geometry):
        def lower(self, object_data):
            return {
                "uuid": self.uuid,
                "type": "BufferGeometry",
                "data": {
                    "attributes": {"position": {
                        "itemSize": 3, "type": "Float32Array", "normalized": False,
                        "array": umsgpack.Ext(0x17, vertices.tobytes())}},
                    "index": {"itemSize": 3, "type": kind, "normalized": False,
                              "array": umsgpack.Ext(code, index.tobytes())},
                },
            }

    return _Buffer()


@dataclass(frozen=True)
class RobotState:
    """What moves in a frame: link placements and beam station positions.

    Attributes:
        links: World placement of every link frame.
        beams: World positions of the drawing stations of every flexible link, (n_st, 3) [m].
    """

    links: dict[str, pin.SE3]
    beams: dict[str, np.ndarray]


class RobotDrawing:
    """The meshcat objects of a flexible robot at a rest pose, and how to move them.

    Args:
        writer: Scene writer of the preview.
        model: The flexible model.
        q: Rest pose (user coordinates).
        y: Design values [kg] (sizes of the point-mass spheres); default nominal.
        stations_per_element: Drawing stations per beam element.
        ghosts: Draw the visuals of flexible links as translucent ghosts at the rest pose
            (off for trajectories, where the rest pose is only the first sample).
    """

    def __init__(self, writer: SceneWriter, model: FlexibleModel, q: np.ndarray, y=None,
                 stations_per_element: int = 8, ghosts: bool = True):
        self.writer = writer
        self.model = model
        self.q = check_q(model, q)
        self.y = check_y(model, y)
        self.spe = int(stations_per_element)
        self.ghosts = bool(ghosts)
        self.rest = pose_state(model, self.q, self.spe)
        self.size_m = characteristic_length(self.rest)
        radii = [shapes.beam_radius_m(model, link) for link in model.plan.beams]
        self.joint_radius_m = max(1.25 * max(radii, default=0.0), 0.015 * self.size_m)
        self.beam_radius_m = {
            link: max(r, 0.4 * self.joint_radius_m) for link, r in zip(model.plan.beams, radii)
        }
        self.visual_model = load_visual_model(model)
        self._geoms: list[tuple[str, str, pin.SE3]] = []
        self._load()

    # ------------------------------------------------------------------ states
    def pose_state(self, q: np.ndarray) -> RobotState:
        """Rigid robot at pose ``q``: straight beams."""
        return pose_state(self.model, q, self.spe)

    def mode_states(self, result: ModalResult, mode: int, scales: np.ndarray) -> list[RobotState]:
        """The robot moved by one mode at each scale (see :func:`mode_states`)."""
        return mode_states(self.model, result, mode, scales, self.spe)

    # ------------------------------------------------------------------ objects
    def _load(self) -> None:
        import meshcat.geometry as mg

        model, writer, rest = self.model, self.writer, self.rest
        with_visual = set()
        if self.visual_model is not None and self.visual_model.ngeoms:
            with_visual = self._load_visuals(self.visual_model)
        joint_mat = mg.MeshPhongMaterial(color=JOINT_COLOUR)
        link_mat = mg.MeshPhongMaterial(color=LINK_COLOUR)
        desc = model.description
        self._markers: list[tuple[str, list[tuple[str, np.ndarray]]]] = []
        for link in desc.links:
            if link in with_visual or link in model.plan.beams:
                continue
            M = rest.links[link]
            writer.add(f"markers/{link}", mg.Sphere(0.8 * self.joint_radius_m), link_mat,
                       M.homogeneous)
            offsets = []
            for jn in desc.child_joints.get(link, ()):
                xyz = desc.joints[jn].xyz
                if np.linalg.norm(xyz) > 1e-9:
                    T, sc = segment_matrix(np.zeros(3), xyz)
                    writer.add(f"offsets/{link}/{jn}", mg.Cylinder(1.0, 0.5 * self.joint_radius_m),
                               link_mat, M.homogeneous @ T, sc)
                    offsets.append((jn, T))
            self._markers.append((link, offsets))
        rigid_visual = with_visual - set(model.plan.beams)
        self._joints = [
            name for name in model.joint_names
            if desc.joints[name].child not in rigid_visual
            and desc.joints[name].parent not in rigid_visual
        ]
        for name in self._joints:
            child = desc.joints[name].child
            writer.add(f"joints/{name}", mg.Sphere(self.joint_radius_m), joint_mat,
                       rest.links[child].homogeneous)
        for link, st in rest.beams.items():
            mat = mg.MeshPhongMaterial(color=BEAM_COLOUR)
            for i in range(st.shape[0] - 1):
                T, sc = segment_matrix(st[i], st[i + 1])
                writer.add(f"beams/{link}/{i}", mg.Cylinder(1.0, self.beam_radius_m[link]), mat,
                           T, sc)
        self._masses = []
        values = dict(model.point_mass_values)
        values.update({d.name: float(v) for d, v in zip(model.design, self.y)})
        for pm in desc.point_masses:
            mass = values[pm.name]
            if mass <= 0.0:
                continue
            r = (3.0 * mass / (4.0 * np.pi * MASS_SPHERE_DENSITY)) ** (1.0 / 3.0)
            path = f"masses/{pm.name}"
            writer.add(path, mg.Sphere(r), mg.MeshPhongMaterial(color=MASS_COLOUR),
                       translation(self.mass_position(rest, pm.link, pm.xyz)))
            self._masses.append((path, pm.link, pm.xyz))
        self._bodies = []
        body_mat = mg.MeshPhongMaterial(color=BODY_COLOUR)
        for b in desc.bodies:
            if b.mass <= 0.0:
                continue
            side = body_side_m(b.mass)
            path = f"bodies/{b.name}"
            writer.add(path, mg.Box([side, side, side]), body_mat,
                       self.body_placement(rest, b.link, b.com))
            self._bodies.append((path, b.link, np.asarray(b.com, dtype=float)))

    def _load_visuals(self, visual_model: pin.GeometryModel) -> set[str]:
        """Put the URDF visuals in the scene; returns the links that have some.

        Meshes go in as binary triangle buffers (:func:`mesh_geometry`: the vertices and
        triangles Pinocchio loaded, not the mesh files, which are text for COLLADA and several
        times larger); primitives through Pinocchio's loader. Visuals of rigid links move with
        their link; those of flexible links are translucent ghosts that stay at the rest pose.
        """
        import meshcat.geometry as mg
        from pinocchio.visualize import MeshcatVisualizer
        from pinocchio.visualize.meshcat_visualizer import hasMeshFileInfo

        model, writer, rest = self.model, self.writer, self.rest
        frames = model.model.frames
        viz = MeshcatVisualizer(model.model, None, visual_model)
        readers = {".dae": mg.DaeMeshGeometry, ".stl": mg.StlMeshGeometry,
                   ".obj": mg.ObjMeshGeometry}
        ghost = mg.MeshPhongMaterial(color=rgb_int(GHOST_RGBA[:3]), opacity=GHOST_RGBA[3],
                                     transparent=True, depthWrite=False)
        links = set()
        for g in visual_model.geometryObjects:
            frame = frames[g.parentFrame]
            link = frame.name
            links.add(link)
            is_ghost = link in model.plan.beams
            if is_ghost and not self.ghosts:
                continue
            scale = None
            geometry = mesh_geometry(g)
            if geometry is None and hasMeshFileInfo(g):
                geometry = readers[Path(g.meshPath).suffix.lower()].from_file(g.meshPath)
                scale = np.asarray(g.meshScale, dtype=float)
            elif geometry is None:
                geometry = viz.loadPrimitive(g)
            if geometry is None:
                continue
            lMg = frame.placement.actInv(g.placement)
            if is_ghost:
                writer.add(f"ghosts/{g.name}", geometry, ghost,
                           (rest.links[link] * lMg).homogeneous, scale)
                continue
            rgba = np.asarray(g.meshColor, dtype=float)
            material = mg.MeshPhongMaterial(color=rgb_int(rgba[:3]))
            if rgba[3] < 1.0:
                material.transparent, material.opacity = True, float(rgba[3])
            path = f"robot/visuals/{g.name}"
            writer.add(path, geometry, material, (rest.links[link] * lMg).homogeneous, scale)
            self._geoms.append((path, link, lMg))
        return links

    def mass_position(self, state: RobotState, link: str, xyz: np.ndarray) -> np.ndarray:
        """World position of a point of a link: on the drawn beam for a flexible link."""
        if link not in self.model.plan.beams:
            return state.links[link].act(np.asarray(xyz, dtype=float))
        spec = self.model.plan.beams[link].spec
        axial = stations_local(self.model, link, self.spe) @ (spec.tip / spec.length_m)
        s = float(np.clip(xyz @ spec.tip / spec.length_m, 0.0, spec.length_m))
        st = state.beams[link]
        return np.array([np.interp(s, axial, st[:, c]) for c in range(3)])

    def body_placement(self, state: RobotState, link: str, com: np.ndarray) -> np.ndarray:
        """World placement (4×4) of a body drawn at ``com`` (link frame) of a link.

        Rigid link: the link frame moves it. Beam: the drawn centreline at the axial station
        of ``com`` plus the offset from the axis turned with the link frame.
        """
        R = state.links[link].rotation
        T = np.eye(4)
        T[:3, :3] = R
        if link not in self.model.plan.beams:
            T[:3, 3] = state.links[link].act(np.asarray(com, dtype=float))
            return T
        spec = self.model.plan.beams[link].spec
        axis = spec.tip / spec.length_m
        s = float(np.clip(com @ axis, 0.0, spec.length_m))
        T[:3, 3] = self.mass_position(state, link, com) + R @ (com - s * axis)
        return T

    # ------------------------------------------------------------------ keyframes
    def key(self, frame: int, state: RobotState, beam_rgb: np.ndarray | None = None) -> None:
        """Record a keyframe of every moving object."""
        writer, model = self.writer, self.model
        for path, link, lMg in self._geoms:
            writer.key(frame, path, (state.links[link] * lMg).homogeneous)
        for link, offsets in self._markers:
            M = state.links[link].homogeneous
            writer.key(frame, f"markers/{link}", M)
            for jn, T in offsets:
                writer.key(frame, f"offsets/{link}/{jn}", M @ T)
        for name in self._joints:
            child = model.description.joints[name].child
            writer.key(frame, f"joints/{name}", state.links[child].homogeneous)
        for link, st in state.beams.items():
            for i in range(st.shape[0] - 1):
                T, sc = segment_matrix(st[i], st[i + 1])
                writer.key(frame, f"beams/{link}/{i}", T, sc, beam_rgb)
        for path, link, xyz in self._masses:
            writer.key(frame, path, translation(self.mass_position(state, link, xyz)))
        for path, link, com in self._bodies:
            writer.key(frame, path, self.body_placement(state, link, com))


def body_side_m(mass: float) -> float:
    """Edge [m] of the cube drawn for a body: the volume of a point-mass sphere of that mass."""
    return float((mass / MASS_SPHERE_DENSITY) ** (1.0 / 3.0))


def stations_local(model: FlexibleModel, link: str, stations_per_element: int) -> np.ndarray:
    """Drawing stations of a flexible link in its link frame, (n_st, 3) [m]."""
    spec = model.plan.beams[link].spec
    n_el = spec.elements
    xi = np.linspace(0.0, 1.0, int(stations_per_element) + 1)[:-1]
    s = np.append((np.arange(n_el)[:, None] + xi[None, :]).ravel(), n_el) / n_el
    return s[:, None] * spec.tip[None, :]


def pose_state(model: FlexibleModel, q: np.ndarray, stations_per_element: int = 8) -> RobotState:
    """The rigid robot at pose ``q`` (user coordinates): link placements and straight beams."""
    links = shapes.link_placements(model, q)
    beams = {}
    for link in model.plan.beams:
        M = links[link]
        st = stations_local(model, link, stations_per_element)
        beams[link] = st @ M.rotation.T + M.translation
    return RobotState(links, beams)


def mode_states(model: FlexibleModel, result: ModalResult, mode: int, scales,
                stations_per_element: int = 8) -> list[RobotState]:
    """The robot moved by one mode at each scale ``s``.

    Beams follow :func:`shapes.centrelines` (``p₀ + s·d``); links are displaced by ``s`` times
    their twist (:func:`shapes.link_twists`) through the exponential map.
    """
    lines = shapes.centrelines(model, result, mode, stations_per_element)
    twists = shapes.link_twists(model, result.q, result.shapes[:, mode - 1 : mode])
    rest = shapes.link_placements(model, result.q)
    out = []
    for s in np.asarray(scales, dtype=float):
        links = {k: shapes.displaced(M, twists[k][0], s) for k, M in rest.items()}
        beams = {k: c.at(s) for k, c in lines.items()}
        out.append(RobotState(links, beams))
    return out


def characteristic_length(state: RobotState) -> float:
    """Size of the drawn robot [m]: the diagonal of the box around link origins and beams."""
    pts = scene_points(state)
    return max(float(np.linalg.norm(pts.max(axis=0) - pts.min(axis=0))), 1e-3)


def scene_points(state: RobotState) -> np.ndarray:
    """Link origins and beam stations of a state, (n, 3) [m]."""
    pts = [M.translation for M in state.links.values()]
    pts += [p for st in state.beams.values() for p in st]
    return np.array(pts)
