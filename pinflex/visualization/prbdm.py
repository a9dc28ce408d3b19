"""Preview of a pseudo-rigid-body chain over its beam planform (paper 001).

The planform is drawn as a flat extruded polygon of thickness ``t`` (translucent, at rest).
Each rigid link of the chain carries its own piece of the planform (the stretch of beam it
stands for) and moves with the chain; hinge pins across the width mark the revolute joints.
The chain oscillates in one of its modes about a pose ``θ₀``:
``θ(t) = θ₀ + s sin(2π t / period) φ``, ``φ`` solving ``K φ = ω² M(θ₀) φ``.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.linalg as sla

from pinflex.exceptions import ConfigurationError
from pinflex.visualization import shapes
from pinflex.visualization.offline import offline_visualizer
from pinflex.visualization.previews import Preview
from pinflex.visualization.scene import (
    GHOST_RGBA,
    JOINT_COLOUR,
    SceneWriter,
    describe_window,
    rgb_int,
    segment_matrix,
)

#: Colours of alternate chain links.
LINK_COLOURS = (0xD9622B, 0xE9A23B)


def planform_piece(planform, start_m: float, end_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Triangle mesh of the planform between two abscissae, extruded to its thickness.

    Args:
        planform: A :class:`~pinflex.prbdm.beams.Planform`.
        start_m: Start of the piece along the beam [m].
        end_m: End of the piece [m], > ``start_m``.

    Returns:
        ``(vertices, faces)``: vertices (n, 3) in beam axes with x measured from ``start_m``
        [m], and triangles (m, 3). The outline has a vertex at every planform vertex inside
        the piece.
    """
    if not end_m > start_m:
        raise ConfigurationError(f"a planform piece needs start < end, got {start_m}, {end_m}")
    inner = planform.x_m[(planform.x_m > start_m) & (planform.x_m < end_m)]
    x = np.concatenate([[start_m], inner, [end_m]])
    w = np.interp(x, planform.x_m, planform.half_width_m)
    h = 0.5 * planform.thickness_m
    n = x.size
    xs = x - start_m
    # corners: (side sy, face sz) for each station, in the order (-,-), (+,-), (+,+), (-,+)
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    verts = np.array([[xs[i], sy * w[i], sz * h] for i in range(n) for sy, sz in corners])
    faces = []  # counter-clockwise seen from outside (outward normals)
    for i in range(n - 1):
        a, b = 4 * i, 4 * (i + 1)
        for c in range(4):  # four walls between consecutive stations
            c1 = (c + 1) % 4
            faces += [[a + c, b + c1, b + c], [a + c, a + c1, b + c1]]
    faces += [[0, 2, 1], [0, 3, 2]]  # root cap, facing -x
    e = 4 * (n - 1)
    faces += [[e, e + 1, e + 2], [e, e + 2, e + 3]]  # end cap, facing +x
    return verts, np.array(faces)


def chain_mode(chain, theta: np.ndarray, mode: int) -> tuple[float, np.ndarray]:
    """Frequency [Hz] and mass-normalised joint-space shape of one chain mode at ``theta``."""
    from pinflex.prbdm.chain import mass_matrix

    n = chain.n_joints
    if int(mode) != mode or not 1 <= mode <= n:
        raise ConfigurationError(f"mode {mode!r}: a {n}R chain has modes 1..{n}")
    lam, phi = sla.eigh(chain.stiffness_matrix, mass_matrix(chain, theta))
    shape = phi[:, int(mode) - 1]
    shape = shape * np.sign(shape[np.argmax(np.abs(shape))])
    return float(np.sqrt(lam[int(mode) - 1]) / (2.0 * np.pi)), shape


def chain_frames(chain, theta: np.ndarray) -> list[pin.SE3]:
    """World placement of links 1..n (their joint frames) at joint angles ``theta``."""
    data = chain.model.createData()
    pin.forwardKinematics(chain.model, data, np.asarray(theta, dtype=float))
    return [data.oMi[j].copy() for j in range(1, chain.model.njoints)]


def tip_positions(chain, theta: np.ndarray) -> np.ndarray:
    """World tip position (3,) [m] at joint angles ``theta``."""
    data = chain.model.createData()
    pin.framesForwardKinematics(chain.model, data, np.asarray(theta, dtype=float))
    return data.oMf[chain.tip_frame_id].translation.copy()


def as_chain(planform, chain_or_fit):
    """A :class:`~pinflex.prbdm.chain.PrbdmChain` from a chain or a ``PrbdmFit``."""
    from pinflex.prbdm.chain import PrbdmChain, build_chain

    if isinstance(chain_or_fit, PrbdmChain):
        return chain_or_fit
    fractions = getattr(chain_or_fit, "link_fractions", None)
    stiffness = getattr(chain_or_fit, "stiffness", None)
    if fractions is None or stiffness is None:
        raise ConfigurationError(
            f"expected a PrbdmChain or a PrbdmFit, got {type(chain_or_fit).__name__}"
        )
    return build_chain(planform, np.asarray(fractions), np.asarray(stiffness))


def prbdm_preview(
    planform,
    chain,
    *,
    theta=None,
    mode: int = 1,
    amplitude_m: float | None = None,
    truth_hz=None,
    viewer: Any = None,
    frames: int = 32,
    period_s: float = 2.0,
) -> Preview:
    """Animate a PRBDM chain mode over its beam planform.

    Args:
        planform: The beam (:class:`~pinflex.prbdm.beams.Planform`).
        chain: Its chain (:class:`~pinflex.prbdm.chain.PrbdmChain` or a ``PrbdmFit``).
        theta: Pose θ₀ of the oscillation [rad], (n,); default straight.
        mode: Chain mode to animate (1 = lowest).
        amplitude_m: Peak tip displacement drawn [m]; default 10 % of the beam length.
        truth_hz: Beam frequencies [Hz] to quote next to the chain's.
        viewer: A ``meshcat.Visualizer``; default a new offline one.
        frames: Keyframes per oscillation.
        period_s: Animation time of one oscillation [s].

    Returns:
        The preview; ``info`` holds ``freq_hz``, ``scale`` [rad] and ``amplitude_m``.
    """
    import meshcat.geometry as mg

    from pinflex.prbdm.chain import tip_jacobian

    chain = as_chain(planform, chain)
    n = chain.n_joints
    theta0 = np.zeros(n) if theta is None else np.asarray(theta, dtype=float).reshape(-1)
    if theta0.shape != (n,):
        raise ConfigurationError(f"theta must hold {n} joint angles [rad], got {theta!r}")
    length = planform.length_m
    amplitude_m = 0.1 * length if amplitude_m is None else float(amplitude_m)
    if not np.isfinite(amplitude_m) or amplitude_m <= 0.0:
        raise ConfigurationError(f"amplitude = {amplitude_m!r} must be a positive length [m]")
    freq, shape = chain_mode(chain, theta0, mode)
    # tip displacement per unit modal coordinate, from the tip Jacobian
    slope = float(np.linalg.norm(tip_jacobian(chain, theta0) @ shape))
    scale = amplitude_m / max(slope, 1e-12)
    scales = scale * np.sin(2.0 * np.pi * np.arange(int(frames) + 1) / int(frames))
    half = float(planform.half_width_m.max())
    corners = np.array([[0.0, -half, 0.0], [length, half, 0.0]])
    tips = np.array([tip_positions(chain, theta0 + s * shape) for s in (-scale, scale)])
    view = shapes.frame_points(np.vstack([corners, tips]), np.array([0.25, -1.0, 0.4]))
    vis = offline_visualizer() if viewer is None else viewer
    writer = SceneWriter(vis, view, int(frames) / float(period_s))
    ghost = mg.MeshPhongMaterial(color=rgb_int(GHOST_RGBA[:3]), opacity=GHOST_RGBA[3],
                                 transparent=True, depthWrite=False)
    v, f = planform_piece(planform, 0.0, length)
    writer.add("planform", mg.TriangularMeshGeometry(v, f), ghost, np.eye(4))
    lengths = np.asarray(chain.link_lengths_m)
    starts = np.concatenate([[0.0], np.cumsum(lengths)[:-1]])
    rod_radius = max(0.6 * planform.thickness_m, 0.006 * length)
    placements = chain_frames(chain, theta0)
    dark = mg.MeshPhongMaterial(color=JOINT_COLOUR)
    for j in range(n + 1):
        v, f = planform_piece(planform, starts[j], starts[j] + lengths[j])
        # the link's node moves; its parts sit in the link frame
        writer.place(f"links/{j}", np.eye(4) if j == 0 else placements[j - 1].homogeneous)
        writer.add(f"links/{j}/piece", mg.TriangularMeshGeometry(v, f),
                   mg.MeshPhongMaterial(color=LINK_COLOURS[j % 2]), np.eye(4))
        T, sc = segment_matrix(np.zeros(3), np.array([lengths[j], 0.0, 0.0]))
        writer.add(f"links/{j}/rod", mg.Cylinder(1.0, rod_radius), dark, T, sc)
        if j:
            width = 2.0 * float(np.interp(starts[j], planform.x_m, planform.half_width_m))
            writer.add(f"links/{j}/pin", mg.Cylinder(width + 2 * rod_radius, 0.5 * rod_radius),
                       dark, np.eye(4))
            writer.add(f"links/{j}/joint", mg.Sphere(1.8 * rod_radius), dark, np.eye(4))
    for k, s in enumerate(scales):
        for j, M in enumerate(chain_frames(chain, theta0 + s * shape), start=1):
            writer.key(k, f"links/{j}", M.homogeneous)
    writer.finish()
    quoted = ""
    if truth_hz is not None and len(truth_hz) >= mode:
        quoted = f" (beam: {float(truth_hz[mode - 1]):.2f} Hz)"
    caption = (
        f"{planform.name or 'beam'}: {n}R PRBDM, chain mode {mode} at {freq:.2f} Hz{quoted}; "
        f"peak tip displacement drawn {1000 * amplitude_m:.0f} mm, one oscillation per "
        f"{period_s:g} s"
    )
    describe_window(vis, title=f"pinflex: {n}R PRBDM", caption=caption)
    info = {"freq_hz": freq, "scale": float(scale), "amplitude_m": amplitude_m,
            "mode": int(mode), "shape": shape}
    return Preview(vis, view, writer.fps, float(period_s), caption, info)


def prbdm_preview_html(planform, chain, path: str | Path, **kwargs) -> Path:
    """Write :func:`prbdm_preview` as a static HTML page; returns the path.

    Args:
        planform: The beam.
        chain: A :class:`~pinflex.prbdm.chain.PrbdmChain` or a ``PrbdmFit`` (rebuilt with
            :func:`~pinflex.prbdm.chain.build_chain` from its fractions and stiffness).
        path: HTML file to write.
        **kwargs: Passed to :func:`prbdm_preview` (``theta``, ``mode``, ``amplitude_m``,
            ``truth_hz``, ...).
    """
    if "truth_hz" not in kwargs and hasattr(chain, "truth_hz"):
        kwargs["truth_hz"] = chain.truth_hz
    return prbdm_preview(planform, chain, **kwargs).write_html(path)
