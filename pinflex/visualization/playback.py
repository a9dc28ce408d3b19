"""Playback of a simulated motion with the deformed arm (exaggerated elastic motion)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from pinflex.erls.joints import joint_transform
from pinflex.erls.modal import ModalResult, node_fields
from pinflex.exceptions import ConfigurationError
from pinflex.visualization import shapes
from pinflex.visualization.offline import offline_visualizer
from pinflex.visualization.previews import Preview, view_direction
from pinflex.visualization.robot import (
    RobotDrawing,
    mode_states,
    pose_state,
    scene_points,
)
from pinflex.visualization.scene import SceneWriter, describe_window


def simulation_playback(
    dyn,
    sim,
    *,
    exaggeration: float = 200.0,
    viewer: Any = None,
    slowdown: float = 4.0,
    fps: float = 30.0,
    stations_per_element: int = 4,
    title: str | None = None,
) -> Preview:
    """Play a :class:`~pinflex.dynamics.Simulation` back on the robot.

    The arm is drawn at the motor (physical) joint angles with the elastic motion ``[x; A x]``
    (beam deformation and the elastic joint offsets) multiplied by ``exaggeration``.

    Args:
        dyn: The equations of motion the simulation ran on (model and design).
        sim: The simulation.
        exaggeration: Factor on the elastic motion in the drawing.
        viewer: A ``meshcat.Visualizer``; default a new offline one.
        slowdown: Animation time per simulated second.
        fps: Keyframes per second of animation time.
        stations_per_element: Drawing stations per beam element.
        title: Page title.
    """
    if not (np.isfinite(exaggeration) and exaggeration > 0):
        raise ConfigurationError(f"exaggeration = {exaggeration!r} must be positive")
    model = dyn.model
    t = sim.times_s
    frame_of = np.round((t - t[0]) * slowdown * fps).astype(int)
    keep = np.flatnonzero(np.concatenate([[True], np.diff(frame_of) > 0]))
    states = []
    for i in keep:
        q = sim.q_physical[i]
        A = dyn.joint_offsets(q)[0]
        sh = np.concatenate([sim.x[i], A @ sim.x[i]])[:, None]
        if sh.shape[0] != model.ndof:  # locked joints: to the solver coordinates [x; q_kept]
            sh = np.linalg.lstsq(joint_transform(model, q), sh, rcond=None)[0]
        pos, motion, elastic = node_fields(model, q, sh)
        res = ModalResult(q=q, y=dyn.y, ndof=model.ndof, rigid_modes=model.nv,
                          eigvals=np.ones(1), shapes=sh, node_positions=pos,
                          node_motion=motion, node_elastic=elastic)
        states.append(mode_states(model, res, 1, [exaggeration], stations_per_element)[0])
    vis = offline_visualizer() if viewer is None else viewer
    pts = np.vstack([scene_points(s) for s in states]
                    + [scene_points(pose_state(model, sim.q_physical[0], 1))])
    view = shapes.frame_points(pts, view_direction(model))
    writer = SceneWriter(vis, view, fps)
    drawing = RobotDrawing(writer, model, sim.q_physical[0], dyn.y,
                           stations_per_element=stations_per_element, ghosts=False)
    for i, state in zip(keep, states):
        drawing.key(int(frame_of[i]), state)
    writer.finish()
    labels = [f"t = {t[i]:.3f} s{' (held)' if t[i] > sim.stop_s else ''}; elastic motion x"
              f"{exaggeration:g}" for i in keep]
    timeline = {"times": (frame_of[keep] / fps).tolist(), "labels": labels}
    caption = (f"{model.description.name}: simulated {sim.drive} drive, elastic motion drawn "
               f"{exaggeration:g} x, {slowdown:g} s of animation per simulated second")
    describe_window(vis, title=title or f"pinflex: {model.description.name} simulation",
                    caption=caption, timeline=timeline)
    return Preview(vis, view, fps, float(frame_of[-1] / fps), caption,
                   {"exaggeration": float(exaggeration), "frames": int(keep.size)})


def simulation_playback_html(dyn, sim, path: str | Path, **kwargs) -> Path:
    """Write :func:`simulation_playback` as a static HTML page; returns the path."""
    return simulation_playback(dyn, sim, **kwargs).write_html(path)
