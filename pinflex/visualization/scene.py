"""meshcat scene writing: static objects, keyframes and the camera.

:class:`SceneWriter` puts objects under one root node (translated so that the camera's target
is the origin), records keyframes of transforms, scales and colours, and sends them as one
``meshcat.animation.Animation`` at the end. It works on any ``meshcat.Visualizer``: one
served by meshcat's zmq server or one on an :class:`~pinflex.visualization.offline.OfflineWindow`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pinflex.visualization.shapes import CameraView

ROOT = "pinflex"

#: Colours (0xRRGGBB) of the preview elements.
BEAM_COLOUR = 0xD9622B
JOINT_COLOUR = 0x3A3A3A
MASS_COLOUR = 0x2B6CB0
BODY_COLOUR = 0x4A5A8C
GHOST_RGBA = (0.55, 0.55, 0.55, 0.22)
LINK_COLOUR = 0x9A9A9A

#: Loop count of animations in the browser (meshcat plays a clip this many times).
REPETITIONS = 1_000_000


def rgb_int(rgb) -> int:
    """0xRRGGBB of an RGB triple in [0, 1]."""
    r, g, b = (int(round(255 * float(np.clip(c, 0.0, 1.0)))) for c in rgb)
    return (r << 16) + (g << 8) + b


def segment_matrix(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Transform and scale of a unit cylinder (axis y, centred) stretched from ``a`` to ``b``.

    Returns:
        ``(T, scale)``: a rigid 4×4 transform and the scale ``(1, |b - a|, 1)``.
    """
    d = np.asarray(b, dtype=float) - np.asarray(a, dtype=float)
    length = float(np.linalg.norm(d))
    y = d / length if length > 0 else np.array([0.0, 1.0, 0.0])
    helper = np.array([1.0, 0.0, 0.0]) if abs(y[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = np.cross(y, helper)
    x /= np.linalg.norm(x)
    z = np.cross(x, y)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([x, y, z])
    T[:3, 3] = 0.5 * (np.asarray(a) + np.asarray(b))
    return T, np.array([1.0, max(length, 1e-9), 1.0])


def translation(p: np.ndarray) -> np.ndarray:
    """4×4 translation."""
    T = np.eye(4)
    T[:3, 3] = p
    return T


class SceneWriter:
    """Objects and keyframes of one preview in a meshcat visualizer.

    Args:
        vis: A ``meshcat.Visualizer``.
        view: Camera view; its centre is moved to the origin of the drawing.
        fps: Keyframes per second of animation time.
    """

    def __init__(self, vis: Any, view: CameraView, fps: float = 16.0):
        import meshcat.animation as ma

        self.vis = vis
        self.view = view
        self.fps = float(fps)
        self.anim = ma.Animation(default_framerate=self.fps)
        self.root = vis[ROOT]
        self.has_keys = False
        self._setup()

    def _setup(self) -> None:
        vis = self.vis
        vis["/Grid"].set_property("visible", False)
        vis["/Axes"].set_property("visible", False)
        vis["/Background"].set_property("top_color", [1.0, 1.0, 1.0])
        vis["/Background"].set_property("bottom_color", [1.0, 1.0, 1.0])
        vis["/Cameras/default/rotated/<object>"].set_property(
            "position", self.view.meshcat_position()
        )
        vis[ROOT].set_transform(translation(-self.view.centre_m))

    def add(self, path: str, geometry, material, T: np.ndarray,
            scale: np.ndarray | None = None) -> None:
        """Create an object under the root with a rest transform (and scale)."""
        node = self.root[path]
        node.set_object(geometry, material)
        self.place(path, T, scale)

    def place(self, path: str, T: np.ndarray, scale: np.ndarray | None = None) -> None:
        """Set the rest transform of a node under the root."""
        M = np.array(T, dtype=float)
        if scale is not None:
            M = M @ np.diag(np.append(scale, 1.0))
        self.root[path].set_transform(M)

    def key(self, frame: int, path: str, T: np.ndarray | None = None,
            scale: np.ndarray | None = None, colour: np.ndarray | None = None) -> None:
        """Record the transform, scale and/or colour of a node at a keyframe."""
        with self.anim.at_frame(self.vis, int(frame)) as f:
            node = f[ROOT][path]
            if T is not None:
                node.set_transform(np.asarray(T, dtype=float))
            if scale is not None:
                node.set_property("scale", "vector3", [float(v) for v in scale])
            if colour is not None:
                # the mesh itself lives in the node's "<object>" child
                node["<object>"].set_property("material.color", "color",
                                              [float(v) for v in colour])
        self.has_keys = True

    def finish(self, play: bool = True) -> None:
        """Send the recorded animation (looping) to the viewer."""
        if self.has_keys:
            self.vis.set_animation(self.anim, play=play, repetitions=REPETITIONS)


def describe_window(vis: Any, *, title: str, caption: str, timeline=None, legend=None) -> None:
    """Give an offline window its page title, caption, timeline labels and colour legend.

    Ignored for a served viewer (meshcat's page has no caption).
    """
    window = getattr(vis, "window", None)
    if window is not None and hasattr(window, "caption"):
        window.title = title
        window.caption = caption
        window.timeline = timeline
        window.legend = legend
