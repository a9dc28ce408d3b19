"""Previews of a flexible robot: an animated mode shape and a trajectory playback.

Each preview builds a meshcat scene (on an offline window by default, see
:mod:`pinflex.visualization.offline`) and returns a :class:`Preview`; ``preview.html()`` is
the self-contained page, ``preview.write_html(path)`` writes it.

Animations are slowed down to be watchable: a mode shape oscillates once per ``period_s``
seconds of animation time whatever its frequency, and a trajectory plays ``slowdown`` times
slower than real time. The caption states the real numbers.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pinflex.checks import check_q
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.progress import ProgressBar
from pinflex.visualization import shapes
from pinflex.visualization.offline import offline_visualizer
from pinflex.visualization.robot import (
    RobotDrawing,
    characteristic_length,
    mode_states,
    pose_state,
    scene_points,
)
from pinflex.visualization.scene import SceneWriter, describe_window


@dataclass(frozen=True)
class Preview:
    """A preview scene in a meshcat visualizer.

    Attributes:
        viewer: The ``meshcat.Visualizer`` holding the scene.
        camera: Camera view (scene centre and eye position).
        fps: Keyframes per second of animation time.
        duration_s: Length of the animation clip [s of animation time].
        caption: Text shown under the scene.
        info: Numbers shown in the preview (frequencies [Hz], mode scale, ...).
    """

    viewer: Any
    camera: shapes.CameraView
    fps: float
    duration_s: float
    caption: str
    info: dict = field(default_factory=dict)

    def html(self) -> str:
        """The scene as one HTML page (meshcat's ``Visualizer.static_html``)."""
        return self.viewer.static_html()

    def write_html(self, path: str | Path) -> Path:
        """Write :meth:`html` to ``path`` atomically (folders are created); return the path.

        Args:
            path: HTML file to write.

        Returns:
            ``Path(path)``.

        Raises:
            OutputError: ``path`` is a folder or cannot be written.
        """
        from pinflex.outputs import write_text

        return write_text(path, self.html(), "HTML preview")


def view_direction(model: FlexibleModel) -> np.ndarray:
    """Direction from the scene to the camera: nearly along a planar robot's normal."""
    normal = model.plane_normal
    if model.planar and normal is not None:
        n = np.asarray(normal, dtype=float) / np.linalg.norm(normal)
        for v in ([0.0, -1.0, 0.0], [-1.0, 0.0, 0.0]):
            down = np.asarray(v) - (np.asarray(v) @ n) * n
            if np.linalg.norm(down) > 1e-6:
                break
        return n + 0.15 * down / np.linalg.norm(down)
    return np.array([1.0, -1.4, 0.9])


def mode_preview(
    model: FlexibleModel,
    q=None,
    mode: int = 1,
    *,
    y=None,
    amplitude_m: float | None = None,
    viewer: Any = None,
    frames: int = 32,
    period_s: float = 2.0,
    stations_per_element: int = 8,
) -> Preview:
    """Animate one mode shape on the robot.

    Args:
        model: The flexible model.
        q: Pose (user coordinates); default zeros.
        mode: Mode number, 1 for the lowest non-rigid mode.
        y: Design values [kg]; default nominal.
        amplitude_m: Peak nodal translation of the drawn mode [m]; default 8 % of the
            robot's size.
        viewer: A ``meshcat.Visualizer`` to draw in; default a new offline one.
        frames: Keyframes per oscillation.
        period_s: Animation time of one oscillation [s].
        stations_per_element: Drawing stations per beam element.

    Returns:
        The preview; ``info`` holds ``freq_hz``, ``scale`` (the factor on the mass-normalised
        mode) and ``amplitude_m``.
    """
    q = np.zeros(model.nv) if q is None else check_q(model, q)
    if int(mode) != mode or not 1 <= mode <= model.n_elastic:
        raise ConfigurationError(
            f"mode {mode!r} does not exist: the model has elastic modes 1..{model.n_elastic}"
        )
    if int(frames) < 4:
        raise ConfigurationError(f"frames = {frames!r}: an oscillation needs at least 4 frames")
    result = model.modes(q, y, n_modes=int(mode))
    rest = pose_state(model, q, stations_per_element)
    if amplitude_m is None:
        amplitude_m = 0.08 * characteristic_length(rest)
    scale = shapes.mode_scale(result, mode, amplitude_m)
    vis = offline_visualizer() if viewer is None else viewer
    phases = 2.0 * np.pi * np.arange(int(frames) + 1) / int(frames)
    scales = scale * np.sin(phases)
    extremes = mode_states(model, result, mode, [-scale, scale], stations_per_element)
    pts = np.vstack([scene_points(rest)] + [scene_points(s) for s in extremes])
    view = shapes.frame_points(pts, view_direction(model))
    fps = int(frames) / float(period_s)
    writer = SceneWriter(vis, view, fps)
    drawing = RobotDrawing(writer, model, q, y, stations_per_element)
    for j, state in enumerate(drawing.mode_states(result, mode, scales)):
        drawing.key(j, state)
    writer.finish()
    freq = float(result.freq_hz[int(mode) - 1])
    qtext = ", ".join(f"{v:.4g}" for v in q)
    caption = (
        f"{model.description.name}: mode {mode} at {freq:.2f} Hz, q = [{qtext}] "
        f"({model.coordinates}), joints {model.joint_switch}; peak displacement drawn "
        f"{1000 * amplitude_m:.0f} mm, "
        f"one oscillation per {period_s:g} s"
    )
    describe_window(vis, title=f"pinflex: {model.description.name} mode {mode}",
                    caption=caption)
    info = {"freq_hz": freq, "scale": scale, "amplitude_m": float(amplitude_m),
            "mode": int(mode), "q": q.copy()}
    return Preview(vis, view, fps, float(period_s), caption, info)


def trajectory_preview(
    model: FlexibleModel,
    times_s,
    Q,
    *,
    y=None,
    mode: int = 1,
    freq_hz=None,
    labels: list[str] | None = None,
    viewer: Any = None,
    slowdown: float = 4.0,
    fps: float = 60.0,
    title: str | None = None,
    progress: bool = False,
) -> Preview:
    """Play a trajectory back with the beams coloured by one mode's frequency.

    Args:
        model: The flexible model.
        times_s: Sample times, increasing, (n,) [s].
        Q: Poses (user coordinates), (n, nv).
        y: Design values [kg]; default nominal.
        mode: Mode whose frequency colours the beams.
        freq_hz: That mode's frequency at each sample, (n,) [Hz]; default computed with
            :meth:`FlexibleModel.frequencies`.
        labels: Caption text per sample; default time and frequency.
        viewer: A ``meshcat.Visualizer``; default a new offline one.
        slowdown: Animation time per real second.
        fps: Keyframe rate of the animation [1/s of animation time].
        title: Page title.
        progress: Show a progress bar on stderr (poses, then keyframes).

    Returns:
        The preview; ``info`` holds ``freq_hz`` (n,), ``low_hz`` and ``high_hz``.
    """
    times = np.asarray(times_s, dtype=float).ravel()
    Q = check_q(model, Q)
    if Q.ndim != 2 or Q.shape[0] != times.size or times.size < 2:
        raise ConfigurationError(
            f"a trajectory needs n >= 2 times and (n, {model.nv}) poses; got {times.size} times "
            f"and poses of shape {Q.shape}"
        )
    if np.any(np.diff(times) <= 0.0):
        raise ConfigurationError("trajectory times must increase")
    if freq_hz is None:
        freq_hz = model.frequencies(Q, y, n_modes=int(mode))[:, int(mode) - 1]
    freq = np.asarray(freq_hz, dtype=float).ravel()
    if freq.size != times.size:
        raise ConfigurationError(f"freq_hz has {freq.size} values for {times.size} samples")
    frame_of = np.round((times - times[0]) * slowdown * fps).astype(int)
    keep = np.concatenate([[True], np.diff(frame_of) > 0])
    vis = offline_visualizer() if viewer is None else viewer
    bar = ProgressBar(len(Q) + int(keep.sum()), "playback", progress)
    states = []
    for q in Q:
        states.append(pose_state(model, q, 1))
        bar.update()
    view = shapes.frame_points(np.vstack([scene_points(s) for s in states]),
                               view_direction(model))
    writer = SceneWriter(vis, view, fps)
    drawing = RobotDrawing(writer, model, Q[0], y, stations_per_element=1, ghosts=False)
    low, high = float(freq.min()), float(freq.max())
    colours = shapes.colormap(freq, low, high)
    for i in np.flatnonzero(keep):
        drawing.key(int(frame_of[i]), states[i], colours[i])
        bar.update()
    bar.close()
    writer.finish()
    if labels is None:
        labels = [f"t = {t:.3f} s, mode {mode}: {f:.2f} Hz (joints {model.joint_switch})"
                  for t, f in zip(times, freq)]
    timeline = {"times": (frame_of[keep] / fps).tolist(),
                "labels": [labels[i] for i in np.flatnonzero(keep)]}
    legend = {"label": f"mode {mode} frequency [Hz], joints {model.joint_switch}", "low": low,
              "high": high, "css": shapes.colormap_css()}
    caption = labels[0]
    describe_window(vis, title=title or f"pinflex: {model.description.name} trajectory",
                    caption=caption, timeline=timeline, legend=legend)
    info = {"freq_hz": freq, "low_hz": low, "high_hz": high, "mode": int(mode)}
    return Preview(vis, view, fps, float(frame_of[-1] / fps), caption, info)


def mode_preview_html(model: FlexibleModel, q, path: str | Path, mode: int = 1,
                      **kwargs) -> Path:
    """Write :func:`mode_preview` as a static HTML page; returns the path.

    Args:
        model: The flexible model.
        q: Pose (nv,) in user coordinates [rad or m].
        path: HTML file to write.
        mode: Mode number, 1 for the lowest non-rigid mode.
        **kwargs: ``y``, ``amplitude_m``, ``frames``, ... as for :func:`mode_preview`.

    Returns:
        ``Path(path)``.

    Raises:
        ConfigurationError: Invalid pose, a mode that does not exist, or fewer than 4 frames.
        MissingDependency: meshcat is not installed.
        OutputError: ``path`` is a folder or cannot be written.
    """
    return mode_preview(model, q, mode, **kwargs).write_html(path)


def assignment_preview_html(model: FlexibleModel, traj, result, path: str | Path) -> Path:
    """Trajectory playback of an assigned design, coloured by the first target's mode.

    Args:
        model: The flexible model of the study.
        traj: The trajectory (``times_s`` [s] and ``q`` (n, nv) in user coordinates).
        result: An :class:`~pinflex.assignment.AssignmentResult`.
        path: HTML file to write.

    Returns:
        The path written.
    """
    mode = int(result.modes[0])
    after = np.asarray(result.freq_after_hz)[:, 0]
    before = np.asarray(result.freq_before_hz)[:, 0]
    target = np.asarray(result.targets_hz)[0]
    labels = [
        f"t = {t:.3f} s, mode {mode}: {fa:.2f} Hz (target {ft:.2f} Hz; before assignment "
        f"{fb:.2f} Hz)"
        for t, fa, fb, ft in zip(traj.times_s, after, before, target)
    ]
    design = ", ".join(f"{k} = {v:.4g} kg" for k, v in result.design.items())
    design += f"; joints {model.joint_switch}"
    preview = trajectory_preview(
        model, traj.times_s, traj.q, y=result.y, mode=mode, freq_hz=after, labels=labels,
        title=f"pinflex: assigned design {design}",
    )
    return preview.write_html(path)
