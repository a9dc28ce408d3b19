"""Geometry of previews, without meshcat: deformed beams, link motions, camera, colours.

A mode of the ERLS model (see :mod:`pinflex.erls`) gives, per flexible link, the world-axes
translation and rotation of every beam node (rigid ERLS motion plus elastic motion). Between
nodes the beam is drawn with the element's own shape functions
(:func:`pinflex.beam.shape_matrix`: linear axial and torsion fields, cubic Hermite bending),
so the drawn centreline is the finite-element displacement field, not straight segments between
nodes. Cubic Hermite functions reproduce rigid motions exactly, so the total motion can be
interpolated as it is.

Drawn positions are linear in the mode's scale ``s``: ``p(s) = p₀ + s·d``, where ``d`` is the
interpolated mode displacement. Rigid bodies follow the small twist ``ν`` of their link
(Pinocchio's LOCAL frame Jacobian times the joint part of the mode plus the elastic twist of
the link root) through the exponential map, ``oMl · exp6(s ν)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pinflex import beam
from pinflex.checks import check_q
from pinflex.erls import BatchAlgebra, FlexibleModel, ModalResult, kinematics
from pinflex.erls.joints import full_shapes
from pinflex.exceptions import ConfigurationError


@dataclass(frozen=True)
class Centreline:
    """Stations along one flexible link and their mode displacement.

    Attributes:
        link: Link name.
        positions_m: World positions of the stations at rest, (n_st, 3) [m].
        displacement_m: World displacement of the stations per unit mode scale, (n_st, 3) [m].
        node_index: Indices of the FE nodes among the stations, (N+1,).
        radius_m: Radius used to draw the beam [m].
    """

    link: str
    positions_m: np.ndarray
    displacement_m: np.ndarray
    node_index: np.ndarray
    radius_m: float

    def at(self, scale: float) -> np.ndarray:
        """Station positions (n_st, 3) [m] with the mode drawn at ``scale``.

        Args:
            scale: Factor on :attr:`displacement_m` (0 gives the rest positions).

        Returns:
            World positions (n_st, 3) [m].
        """
        return self.positions_m + scale * self.displacement_m


def beam_rotations(model: FlexibleModel, q: np.ndarray) -> dict[str, np.ndarray]:
    """World rotation of each flexible link's beam axes at pose ``q``, (3, 3) per link."""
    return {link: p.rotation for link, p in model.node_placements(q).items()}


def beam_radius_m(model: FlexibleModel, link: str) -> float:
    """Drawing radius of a beam: the solid circle with the section's largest bending moment."""
    sec = model.plan.beams[link].spec.section
    return float((4.0 * max(sec.Iy, sec.Iz) / np.pi) ** 0.25)


def centrelines(
    model: FlexibleModel,
    result: ModalResult,
    mode: int,
    stations_per_element: int = 8,
) -> dict[str, Centreline]:
    """Deformed centreline of every flexible link for one mode.

    Args:
        model: The flexible model.
        result: Modal analysis at one pose (from :meth:`FlexibleModel.modes`).
        mode: Mode number, 1 for the lowest non-rigid mode.
        stations_per_element: Drawing stations per element (>= 1); nodes are always stations.

    Returns:
        One :class:`Centreline` per flexible link; ``at(s)`` at the node indices equals
        ``node_positions + s · node_motion[mode - 1, :, :3]``.

    Raises:
        ConfigurationError: If the mode was not computed or the station count is below 1.
    """
    k = _mode_index(result, mode)
    if int(stations_per_element) < 1:
        raise ConfigurationError(
            f"stations_per_element = {stations_per_element!r} must be at least 1"
        )
    xi = np.linspace(0.0, 1.0, int(stations_per_element) + 1)[:-1]
    rot = beam_rotations(model, result.q)
    out = {}
    for link, plan in model.plan.beams.items():
        n_el = plan.spec.elements
        le = plan.spec.length_m / n_el
        R = rot[link]
        motion = result.node_motion[link][k]  # (N+1, 6) world axes
        beam_dofs = np.concatenate([motion[:, :3] @ R, motion[:, 3:] @ R], axis=1)
        elem = np.concatenate([beam_dofs[:-1], beam_dofs[1:]], axis=1)  # (n_el, 12)
        N = beam.shape_matrix(le, xi)[:, :3, :]  # (n_xi, 3, 12) translations
        disp = np.einsum("xij,ej->exi", N, elem).reshape(-1, 3)
        disp = np.vstack([disp, beam_dofs[-1:, :3]]) @ R.T
        nodes = result.node_positions[link]
        s = (np.arange(n_el)[:, None] + xi[None, :]).ravel()
        axial = np.append(s, n_el) * le
        rest = nodes[0] + axial[:, None] * R[:, 0][None, :]
        idx = np.arange(n_el + 1) * xi.size
        out[link] = Centreline(link, rest, disp, idx, beam_radius_m(model, link))
    return out


def mode_scale(result: ModalResult, mode: int, amplitude_m: float) -> float:
    """Scale of a mass-normalised mode whose largest nodal translation is ``amplitude_m``.

    Args:
        result: Modal analysis at one pose.
        mode: Mode number (1-based).
        amplitude_m: Wanted peak translation of the drawn mode [m], > 0.

    Returns:
        The factor ``s`` multiplying the mass-normalised mode [m per unit modal coordinate].
    """
    if not np.isfinite(amplitude_m) or amplitude_m <= 0.0:
        raise ConfigurationError(f"amplitude = {amplitude_m!r} must be a positive length [m]")
    k = _mode_index(result, mode)
    peak = max(
        float(np.max(np.linalg.norm(m[k, :, :3], axis=1))) for m in result.node_motion.values()
    )
    if peak == 0.0:
        raise ConfigurationError(f"mode {mode} moves no beam node; nothing to draw")
    return amplitude_m / peak


def link_twists(model: FlexibleModel, q: np.ndarray, shapes: np.ndarray) -> dict[str, np.ndarray]:
    """Small motion of every link frame for each mode, in link axes.

    Args:
        model: The flexible model.
        q: Pose (user coordinates).
        shapes: Mode shapes over the model's modal coordinates ``[x; q_kept]``, (ndof, k).

    Returns:
        Per link a (k, 6) array ``(δp, θ)``: translation of the link origin and rotation of the
        link, both in link axes (Pinocchio's LOCAL convention).
    """
    q = check_q(model, q)
    nx = model.nx
    shapes = full_shapes(model, q, shapes)  # locked joints' coordinates back in
    terms = kinematics.pose_terms(model, q[None])
    roots = kinematics.root_twists(model, terms, BatchAlgebra(1))
    data = model.model.createData()
    pin.computeJointJacobians(model.model, data, model.pin_configuration(q))
    pin.updateFramePlacements(model.model, data)
    out = {}
    for link in model.description.links:
        fid = model.model.getFrameId(link, pin.FrameType.BODY)
        jac = pin.getFrameJacobian(model.model, data, fid, pin.LOCAL).reshape(6, -1)
        jac = jac @ model.coord_map  # (6, nv); Pinocchio returns (6,) when nv = 1
        nu = jac @ shapes[nx:]
        root = roots.get(link)
        if root is not None:
            nu = nu + root[0] @ shapes[:nx]
        out[link] = nu.T
    return out


def link_placements(model: FlexibleModel, q: np.ndarray) -> dict[str, pin.SE3]:
    """World placement of every link frame at pose ``q`` (user coordinates)."""
    data = model.model.createData()
    pin.framesForwardKinematics(model.model, data, model.pin_configuration(q))
    return {
        link: data.oMf[model.model.getFrameId(link, pin.FrameType.BODY)].copy()
        for link in model.description.links
    }


def displaced(placement: pin.SE3, twist: np.ndarray, scale: float) -> pin.SE3:
    """A link placement moved by ``scale`` times a small LOCAL twist (δp, θ)."""
    return placement * pin.exp6(pin.Motion(scale * twist[:3], scale * twist[3:]))


@dataclass(frozen=True)
class CameraView:
    """A perspective view of a scene whose content is centred on the origin.

    Attributes:
        centre_m: World point moved to the origin of the drawing [m], (3,).
        eye_m: Camera position relative to the centre, world axes (z up) [m], (3,).
        fov_deg: Vertical field of view [deg] (meshcat's default camera: 75).
    """

    centre_m: np.ndarray
    eye_m: np.ndarray
    fov_deg: float = 75.0

    def project(self, points_m: np.ndarray, width: int, height: int) -> np.ndarray:
        """Pixel coordinates (column, row) of world points in a ``width × height`` image.

        Args:
            points_m: World points (n, 3) or one point (3,) [m].
            width: Image width [px].
            height: Image height [px] (the field of view is vertical).

        Returns:
            Pixel coordinates (n, 2) [px], column from the left, row from the top.
        """
        p = np.atleast_2d(points_m) - self.centre_m
        fwd = -self.eye_m / np.linalg.norm(self.eye_m)
        right = np.cross(fwd, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        up = np.cross(right, fwd)
        rel = p - self.eye_m
        depth = rel @ fwd
        f = 0.5 * height / np.tan(np.radians(self.fov_deg) / 2.0)
        col = 0.5 * width + f * (rel @ right) / depth
        row = 0.5 * height - f * (rel @ up) / depth
        return np.column_stack([col, row])

    def meshcat_position(self) -> list[float]:
        """Camera position in meshcat's rotated (y-up) camera frame."""
        x, y, z = (float(v) for v in self.eye_m)
        return [x, z, -y]


def frame_points(points_m: np.ndarray, direction: np.ndarray, *, fov_deg: float = 75.0,
                 aspect: float = 4.0 / 3.0, fill: float = 0.75) -> CameraView:
    """A view from ``direction`` (world, towards the camera) that fits all points.

    The camera looks at the centre of the points' bounding box from the nearest distance at
    which every point projects inside ``fill`` times the half-width and half-height of an
    image of the given aspect ratio.

    Args:
        points_m: Points to keep in view, (n, 3) [m].
        direction: Direction from the scene centre to the camera (world axes).
        fov_deg: Vertical field of view [deg].
        aspect: Image width over height (wider images only add margin at the sides).
        fill: Fraction of the half-image the points may use, in (0, 1].
    """
    pts = np.atleast_2d(points_m)
    centre = 0.5 * (pts.min(axis=0) + pts.max(axis=0))
    d = np.asarray(direction, dtype=float)
    d /= np.linalg.norm(d)
    right = np.cross(-d, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    up = np.cross(right, -d)
    rel = pts - centre
    tan_v = fill * np.tan(np.radians(fov_deg) / 2.0)
    tan_h = tan_v * aspect
    size = max(float(np.max(np.linalg.norm(rel, axis=1))), 1e-3)
    distance = max(
        float(np.max(rel @ d + np.abs(rel @ right) / tan_h)),
        float(np.max(rel @ d + np.abs(rel @ up) / tan_v)),
        1.5 * size,
    )
    return CameraView(centre, distance * d, fov_deg)


# Perceptually uniform colour map (matplotlib's "viridis" at 9 stops), RGB in [0, 1].
_VIRIDIS = np.array([
    [0.267, 0.005, 0.329], [0.283, 0.141, 0.458], [0.254, 0.265, 0.530],
    [0.207, 0.372, 0.553], [0.164, 0.471, 0.558], [0.128, 0.567, 0.551],
    [0.135, 0.659, 0.518], [0.267, 0.749, 0.441], [0.478, 0.821, 0.318],
    [0.741, 0.873, 0.150], [0.993, 0.906, 0.144],
])


def colormap(values: np.ndarray, low: float, high: float) -> np.ndarray:
    """RGB colours (n, 3) of values on a viridis scale from ``low`` to ``high``."""
    v = np.asarray(values, dtype=float)
    span = high - low
    t = np.clip((v - low) / span, 0.0, 1.0) if span > 0 else np.full(v.shape, 0.5)
    grid = np.linspace(0.0, 1.0, _VIRIDIS.shape[0])
    return np.column_stack([np.interp(t, grid, _VIRIDIS[:, c]) for c in range(3)])


def colormap_css(stops: int = 11) -> str:
    """CSS ``linear-gradient`` of the colour map, low to high from left to right."""
    rgb = colormap(np.linspace(0.0, 1.0, stops), 0.0, 1.0)
    parts = ", ".join(f"rgb({int(r * 255)}, {int(g * 255)}, {int(b * 255)})" for r, g, b in rgb)
    return f"linear-gradient(to right, {parts})"


def _mode_index(result: ModalResult, mode: int) -> int:
    k = int(mode) - 1
    if int(mode) != mode or not 0 <= k < result.eigvals.size:
        raise ConfigurationError(
            f"mode {mode!r} is not available: the modal result holds modes 1..{result.eigvals.size}"
            " (ask modes() for more with n_modes)"
        )
    return k
