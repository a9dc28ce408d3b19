"""One preview page with every computed mode selectable, a framed camera and a floor grid.

:func:`modes_preview` draws the robot once and records one animation per mode (meshcat holds
one animation at a time). The offline page carries them all with a selector listing each mode
and its frequency; choosing one loads its animation and its caption. ``#mode=K`` in the page's
URL selects mode K at load (with ``#t=SECONDS`` the animation is paused there, as in the other
previews). On a served or user-owned viewer, :meth:`ModesPreview.select` sends mode K's
animation to it.

Drawing into an existing viewer: pass ``viewer=`` a ``meshcat.Visualizer`` or a Pinocchio
``MeshcatVisualizer`` (its ``.viewer`` is used); the preview goes under the ``pinflex`` node.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from pinflex.checks import check_q
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.progress import ProgressBar
from pinflex.visualization import shapes
from pinflex.visualization.offline import compact_animation, offline_visualizer, pack_chunks
from pinflex.visualization.previews import view_direction
from pinflex.visualization.robot import (
    RobotDrawing,
    characteristic_length,
    mode_states,
    pose_state,
    scene_points,
)
from pinflex.visualization.scene import REPETITIONS, ROOT, SceneWriter, describe_window

GRID_COLOUR = 0xC8C8C8

_SELECTOR = """
<div id="pinflex-modes" class="pinflex-box" style="top: 36px; left: auto; right: 12px;">
<label for="pinflex-mode-select">mode </label>
<select id="pinflex-mode-select">{options}</select>
</div>
<script>
pinflexReady.then(function () {{
  return pinflexUnpack("{animations}");
}}).then(function (animations) {{
  var captions = {captions};
  var modes = {modes};
  var select = document.getElementById("pinflex-mode-select");
  var caption = document.getElementById("pinflex-caption");
  function show(i) {{
    viewer.handle_command_bytearray(animations[i]);
    var t = /[#&]t=([0-9.eE+-]+)/.exec(window.location.hash);
    if (t) {{ viewer.animator.pause(); viewer.animator.seek(parseFloat(t[1])); }}
    caption.textContent = captions[i];
    select.value = String(i);
    document.title = captions[i];
  }}
  select.addEventListener("change", function () {{ show(parseInt(select.value, 10)); }});
  var m = /[#&]mode=([0-9]+)/.exec(window.location.hash);
  var first = modes.indexOf(m ? parseInt(m[1], 10) : {initial});
  show(first < 0 ? 0 : first);
}});
</script>
"""


def _viewer_of(viewer: Any):
    """A ``meshcat.Visualizer`` from itself or from a Pinocchio ``MeshcatVisualizer``."""
    if viewer is None:
        return offline_visualizer()
    inner = getattr(viewer, "viewer", None)
    if inner is not None and hasattr(inner, "set_animation"):
        return inner
    if hasattr(viewer, "set_animation") and hasattr(viewer, "__getitem__"):
        return viewer
    raise ConfigurationError(
        f"viewer must be a meshcat.Visualizer or a pinocchio MeshcatVisualizer, got "
        f"{type(viewer).__name__}"
    )


def nice_spacing(size_m: float) -> float:
    """A round grid spacing (1, 2 or 5 times a power of ten) near a tenth of ``size_m``."""
    raw = max(float(size_m), 1e-6) / 10.0
    power = 10.0 ** np.floor(np.log10(raw))
    for m in (1.0, 2.0, 5.0, 10.0):
        if m * power >= raw:
            return float(m * power)
    return float(10.0 * power)  # pragma: no cover


def add_grid(writer, points_m: np.ndarray) -> dict:
    """A floor grid under the scene: lines in the x–y plane at the lowest point.

    ``writer`` is a :class:`SceneWriter` or a ``meshcat.Visualizer`` holding a preview (the
    grid goes under its ``pinflex`` node, in world coordinates).

    Returns:
        ``spacing_m`` (a round number), ``z_m`` (height of the grid) and ``extent_m``
        (x and y ranges).
    """
    import meshcat.geometry as mg

    pts = np.atleast_2d(points_m)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    size = float(np.max(hi - lo))
    h = nice_spacing(size)
    x0, x1 = np.floor(lo[0] / h - 1) * h, np.ceil(hi[0] / h + 1) * h
    y0, y1 = np.floor(lo[1] / h - 1) * h, np.ceil(hi[1] / h + 1) * h
    z = float(lo[2])
    segs = []
    for x in np.arange(x0, x1 + 0.5 * h, h):
        segs += [[x, y0, z], [x, y1, z]]
    for y in np.arange(y0, y1 + 0.5 * h, h):
        segs += [[x0, y, z], [x1, y, z]]
    P = np.array(segs, dtype=np.float32).T
    root = writer.root if isinstance(writer, SceneWriter) else writer[ROOT]
    root["grid"].set_object(mg.LineSegments(mg.PointsGeometry(P),
                                                   mg.LineBasicMaterial(color=GRID_COLOUR)))
    return {"spacing_m": h, "z_m": z, "extent_m": [[float(x0), float(x1)], [float(y0), float(y1)]]}


@dataclass(frozen=True)
class ModesPreview:
    """Every computed mode of a pose, selectable.

    Attributes:
        viewer: The ``meshcat.Visualizer`` holding the scene.
        camera: Camera view.
        modes: Mode numbers (1 = lowest non-rigid).
        freq_hz: Their frequencies [Hz].
        captions: Caption of each mode.
        animations: meshcat ``set_animation`` commands (msgpack bytes), one per mode; the
            page carries them compacted (float32).
        info: ``scales`` (factor on each mass-normalised shape), ``amplitude_m``, ``grid``,
            ``clips`` (the ``meshcat.animation.Animation`` of each mode).
    """

    viewer: Any
    camera: shapes.CameraView
    modes: tuple[int, ...]
    freq_hz: np.ndarray
    captions: tuple[str, ...]
    animations: tuple[bytes, ...]
    info: dict = field(default_factory=dict)

    def select(self, mode: int) -> None:
        """Play mode ``mode`` in the viewer (offline, served or a user's viewer).

        Args:
            mode: A mode number of :attr:`modes` (1 = lowest non-rigid).

        Raises:
            ConfigurationError: ``mode`` is not in this preview.
        """
        if mode not in self.modes:
            raise ConfigurationError(f"mode {mode} is not in this preview {list(self.modes)}")
        i = self.modes.index(mode)
        self.viewer.set_animation(self.info["clips"][i], play=True, repetitions=REPETITIONS)
        describe_window(self.viewer, title=f"pinflex: mode {mode}", caption=self.captions[i])

    def html(self, initial: int | None = None) -> str:
        """The offline page with the selector; ``initial`` is the mode shown first.

        Args:
            initial: Mode number shown first (default: the first of :attr:`modes`).

        Returns:
            A self-contained HTML page.
        """
        page = self.viewer.static_html()
        options = "".join(
            f'<option value="{i}">{m}: {f:.2f} Hz</option>'
            for i, (m, f) in enumerate(zip(self.modes, self.freq_hz))
        )
        block = _SELECTOR.format(
            options=options,
            animations=pack_chunks([compact_animation(a) for a in self.animations]),
            captions=json.dumps(list(self.captions)).replace("</", "<\\/"),
            modes=json.dumps(list(self.modes)),
            initial=int(self.modes[0] if initial is None else initial),
        )
        k = page.rfind("</body>")
        return page[:k] + block + page[k:]

    def write_html(self, path: str | Path, initial: int | None = None) -> Path:
        """Write :meth:`html` atomically (folders are created); returns the path.

        Args:
            path: HTML file to write.
            initial: Mode number shown first (default: the first of :attr:`modes`).

        Returns:
            ``Path(path)``.

        Raises:
            OutputError: ``path`` is a folder or cannot be written.
        """
        from pinflex.outputs import write_text

        return write_text(path, self.html(initial), "HTML preview")


def modes_preview(
    model: FlexibleModel,
    q=None,
    modes=None,
    *,
    y=None,
    amplitude_m: float | None = None,
    viewer: Any = None,
    frames: int = 32,
    period_s: float = 2.0,
    stations_per_element: int = 8,
    grid: bool = True,
    fill: float = 0.8,
    progress: bool = False,
) -> ModesPreview:
    """Every requested mode at one pose, one animation each, on one page.

    Args:
        model: The flexible model.
        q: Pose (user coordinates or a Pinocchio configuration); default zeros.
        modes: Mode numbers, an int n (modes 1..n) or ``None`` (the lowest min(nx, 8)).
        y: Design values [kg]; default nominal.
        amplitude_m: Peak nodal translation drawn [m]; default 8 % of the robot's size.
        viewer: A ``meshcat.Visualizer`` or Pinocchio ``MeshcatVisualizer`` to draw into;
            default a new offline one.
        frames: Keyframes per oscillation.
        period_s: Animation time of one oscillation [s].
        stations_per_element: Drawing stations per beam element.
        grid: Draw a floor grid (round spacing, under the lowest point of the scene).
        fill: Fraction of the half-image the scene may use (the camera is as close as that
            allows, see :func:`pinflex.visualization.shapes.frame_points`).
        progress: Show a progress bar on stderr (one step per mode).

    Returns:
        A :class:`ModesPreview` (``write_html`` for the offline page).
    """
    q = np.zeros(model.nv) if q is None else check_q(model, q)
    if modes is None:
        modes = min(model.n_elastic, 8)
    mode_list = list(range(1, int(modes) + 1)) if np.ndim(modes) == 0 else [int(m) for m in modes]
    if not mode_list or min(mode_list) < 1 or max(mode_list) > model.n_elastic:
        raise ConfigurationError(f"modes {mode_list} must lie in 1..{model.n_elastic}")
    if int(frames) < 4:
        raise ConfigurationError(f"frames = {frames!r}: an oscillation needs at least 4 frames")
    import meshcat.animation as ma
    import umsgpack
    from meshcat.commands import SetAnimation

    result = model.modes(q, y, n_modes=max(mode_list))
    rest = pose_state(model, q, stations_per_element)
    if amplitude_m is None:
        amplitude_m = 0.08 * characteristic_length(rest)
    scales = {m: shapes.mode_scale(result, m, amplitude_m) for m in mode_list}
    pts = [scene_points(rest)]
    for m in mode_list:
        for st in mode_states(model, result, m, [-scales[m], scales[m]], stations_per_element):
            pts.append(scene_points(st))
    pts_all = np.vstack(pts)
    view = shapes.frame_points(pts_all, view_direction(model), fill=fill)
    vis = _viewer_of(viewer)
    fps = int(frames) / float(period_s)
    writer = SceneWriter(vis, view, fps)
    grid_info = add_grid(writer, pts_all) if grid else None
    drawing = RobotDrawing(writer, model, q, y, stations_per_element)
    phases = np.sin(2.0 * np.pi * np.arange(int(frames) + 1) / int(frames))
    animations, captions, clips = [], [], []
    qtext = ", ".join(f"{v:.4g}" for v in q)
    bar = ProgressBar(len(mode_list), "modes preview", progress)
    for m in mode_list:
        writer.anim = ma.Animation(default_framerate=fps)
        for j, state in enumerate(drawing.mode_states(result, m, scales[m] * phases)):
            drawing.key(j, state)
        clips.append(writer.anim)
        animations.append(umsgpack.packb(SetAnimation(writer.anim, True, REPETITIONS).lower()))
        freq = float(result.freq_hz[m - 1])
        captions.append(
            f"{model.description.name}: mode {m} at {freq:.2f} Hz, q = [{qtext}] "
            f"({model.coordinates}), joints {model.joint_switch}; peak displacement drawn "
            f"{1000 * amplitude_m:.0f} mm, one "
            f"oscillation per {period_s:g} s"
            + (f"; grid {100 * grid_info['spacing_m']:g} cm" if grid_info else "")
        )
        bar.update()
    # the first mode plays in the viewer itself (offline page, served or user viewer)
    vis.set_animation(clips[0], play=True, repetitions=REPETITIONS)
    describe_window(vis, title=f"pinflex: {model.description.name} modes", caption=captions[0])
    info = {"scales": scales, "amplitude_m": float(amplitude_m), "grid": grid_info,
            "q": q.copy(), "clips": clips}
    return ModesPreview(vis, view, tuple(mode_list), result.freq_hz[[m - 1 for m in mode_list]],
                        tuple(captions), tuple(animations), info)
