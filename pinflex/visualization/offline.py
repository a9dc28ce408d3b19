"""meshcat without a server: record the scene in-process and export it as static HTML.

meshcat's :class:`meshcat.Visualizer` talks to a ``ViewerWindow`` that forwards each command to
a zmq server; the server keeps the scene tree and, asked for ``get_scene``, packs it into one
HTML page with the viewer's JavaScript inlined (what :meth:`meshcat.Visualizer.static_html`
returns). :class:`OfflineWindow` is a drop-in window that keeps the same scene tree in the
Python process instead, so a preview can be built and exported with no server, no port and no
browser: ``meshcat.Visualizer(window=OfflineWindow()).static_html()``.

Two differences with the server's export, both for robustness offline:

* Commands are decoded and applied synchronously, in order (the server emits one asynchronous
  ``fetch`` of a data URL per command, which does not guarantee the order).
* The animation is applied last, after every object exists (the server emits the root node's
  animation first, so an animation could bind to placeholder nodes replaced later).

The page honours a URL fragment ``#t=SECONDS``: the animation is paused and shown at that time,
which makes screenshots of given instants reproducible.
"""

from __future__ import annotations

import base64
import gzip
import importlib
import json
from pathlib import Path
from typing import Any

from pinflex.exceptions import MissingDependency

#: Template of the exported page; ``{viewer_js}`` is meshcat's bundled viewer, inlined.
HTML_TEMPLATE = """<!DOCTYPE html>
<html>
<head><meta charset="utf-8"><title>{title}</title>
<style>
body {{ margin: 0; }}
#meshcat-pane {{ width: 100vw; height: 100vh; overflow: hidden; }}
.pinflex-box {{ position: absolute; left: 12px; font: 14px sans-serif; color: #222;
  background: rgba(255, 255, 255, 0.85); padding: 4px 8px; border-radius: 4px; }}
#pinflex-caption {{ bottom: 10px; }}
#pinflex-legend {{ top: 10px; }}
#pinflex-legend .bar {{ width: 220px; height: 12px; margin: 4px 0 2px 0; }}
#pinflex-legend .ends {{ display: flex; justify-content: space-between; font-size: 12px; }}
</style>
</head>
<body>
<div id="meshcat-pane"></div>
<div id="pinflex-caption" class="pinflex-box">{caption}</div>
{legend}
<script>
{viewer_js}
</script>
<script>
// Scene data: one base64 string of a gzip stream of length-prefixed msgpack commands.
function pinflexUnpack(b64) {{
  var raw = atob(b64);
  var bytes = new Uint8Array(raw.length);
  for (var j = 0; j < raw.length; j++) {{ bytes[j] = raw.charCodeAt(j); }}
  var stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("gzip"));
  return new Response(stream).arrayBuffer().then(function (buf) {{
    var out = [], view = new DataView(buf), pos = 0;
    while (pos + 4 <= buf.byteLength) {{
      var n = view.getUint32(pos, true);
      pos += 4;
      out.push(new Uint8Array(buf.slice(pos, pos + n)));
      pos += n;
    }}
    return out;
  }});
}}
var viewer = new MeshCat.Viewer(document.getElementById("meshcat-pane"));
var pinflexReady = pinflexUnpack("{commands}").then(function (commands) {{
  for (var i = 0; i < commands.length; i++) {{
    try {{
      viewer.handle_command_bytearray(commands[i]);
    }} catch (err) {{
      console.warn("pinflex: a scene command failed:", err);
    }}
  }}
  requestAnimationFrame(function () {{
    requestAnimationFrame(function () {{
      console.info("pinflex: scene drawn " + Math.round(performance.now()) +
                   " ms after the page started");
    }});
  }});
  var match = /[#&]t=([0-9.eE+-]+)/.exec(window.location.hash);
  if (match) {{
    viewer.animator.pause();
    viewer.animator.seek(parseFloat(match[1]));
    // a paused scene stops drawing; keep drawing so that a screenshot finds a fresh frame
    var redraw = function () {{ viewer.set_dirty(); requestAnimationFrame(redraw); }};
    redraw();
  }}
  if (/[#&]gui=0/.test(window.location.hash)) {{
    viewer.gui.domElement.style.display = "none";
  }}
  var timeline = {timeline};
  if (timeline) {{
    var caption = document.getElementById("pinflex-caption");
    var update = function () {{
      var actions = viewer.animator.actions;
      var t = actions.length ? actions[0].time : 0.0;
      var i = 0;
      while (i + 1 < timeline.times.length && timeline.times[i + 1] <= t + 1e-9) {{ i++; }}
      caption.textContent = timeline.labels[i];
      requestAnimationFrame(update);
    }};
    update();
  }}
}});
</script>
</body>
</html>
"""


def require_meshcat(purpose: str = "previews") -> Any:
    """Import meshcat, or raise :class:`MissingDependency` with the install command.

    Args:
        purpose: What needs meshcat, for the error message.

    Returns:
        The ``meshcat`` module.

    Raises:
        MissingDependency: If meshcat (or one of its own dependencies) cannot be imported.
    """
    try:
        return importlib.import_module("meshcat")
    except ImportError as exc:
        raise MissingDependency("meshcat", purpose) from exc


def viewer_js_path() -> Path:
    """Path of meshcat's bundled viewer (``main.min.js``)."""
    meshcat = require_meshcat()
    return Path(meshcat.__file__).parent / "viewer" / "dist" / "main.min.js"


class OfflineWindow:
    """A meshcat window that records the scene instead of sending it to a server.

    It keeps the scene as meshcat's server does (one node per path with its object,
    properties and transform, and one animation) and renders it as a self-contained HTML page.
    """

    def __init__(self) -> None:
        from meshcat.servers.tree import SceneTree

        self._new_tree = SceneTree
        self.tree = SceneTree()
        self.animation: bytes | None = None
        self.web_url = None
        self.title = "pinflex preview"
        self.caption = ""
        self.timeline: dict | None = None
        self.legend: dict | None = None

    def send(self, command) -> None:
        """Apply a meshcat command (``SetObject``, ``SetTransform``, ...) to the scene tree.

        Args:
            command: A ``meshcat.commands`` object with a ``lower()`` method; a
                ``set_animation`` command replaces the recorded animation, ``delete`` removes
                a node (the whole scene for the root path).
        """
        import umsgpack
        from meshcat.servers.tree import find_node

        data = command.lower()
        kind = data["type"]
        packed = umsgpack.packb(data)
        path = [p for p in data.get("path", "").split("/") if p]
        if kind == "set_animation":
            self.animation = packed
            return
        if kind == "delete":
            if path:
                parent = find_node(self.tree, path[:-1])
                parent.pop(path[-1], None)
            else:
                self.tree = self._new_tree()
            return
        node = find_node(self.tree, path)
        if kind == "set_object":
            node.object = packed
            node.properties = []
        elif kind == "set_transform":
            node.transform = packed
        elif kind == "set_property":
            node.properties.append(packed)
        else:
            raise ValueError(f"meshcat command '{kind}' cannot be recorded offline")

    def commands(self) -> list[bytes]:
        """The recorded scene as msgpack commands, objects first and the animation last.

        The animation is as recorded (float64); the page carries it compacted
        (:func:`compact_animation`).
        """
        from meshcat.servers.tree import walk

        out = []
        for node in walk(self.tree):
            if node.object is not None:
                out.append(node.object)
            out.extend(node.properties)
            if node.transform is not None:
                out.append(node.transform)
        if self.animation is not None:
            out.append(self.animation)
        return out

    def get_scene(self) -> str:
        """The scene as one HTML page with meshcat's viewer inlined (no network needed)."""
        js = viewer_js_path().read_text(encoding="utf-8")
        return HTML_TEMPLATE.format(
            title=_escape(self.title), caption=_escape(self.caption), viewer_js=js,
            commands=pack_chunks(self._page_commands()),
            timeline=json.dumps(self.timeline).replace("</", "<\\/"),
            legend=self._legend_html(),
        )

    def _page_commands(self) -> list[bytes]:
        out = self.commands()
        if self.animation is not None:
            out[-1] = compact_animation(self.animation)
        return out

    def _legend_html(self) -> str:
        if not self.legend:
            return ""
        lg = self.legend
        return (
            '<div id="pinflex-legend" class="pinflex-box">'
            f'{_escape(lg["label"])}<div class="bar" style="background: {lg["css"]}"></div>'
            f'<div class="ends"><span>{lg["low"]:.1f}</span><span>{lg["high"]:.1f}</span></div>'
            "</div>"
        )

    def get_image(self):  # pragma: no cover - needs a browser
        """Not available offline: open the exported HTML in a browser instead."""
        raise NotImplementedError("an offline meshcat window has no browser to capture from")


def pack_chunks(chunks) -> str:
    """Byte strings as one base64 string of a gzip stream of length-prefixed records.

    The page's ``pinflexUnpack`` reads it back (the browser's ``DecompressionStream``); scene
    commands compress about threefold, which keeps previews of meshed arms small.
    """
    raw = b"".join(len(c).to_bytes(4, "little") + bytes(c) for c in chunks)
    return base64.b64encode(gzip.compress(raw, compresslevel=9, mtime=0)).decode("ascii")


def unpack_chunks(text: str) -> list[bytes]:
    """The byte strings of :func:`pack_chunks`."""
    raw = gzip.decompress(base64.b64decode(text))
    out, pos = [], 0
    while pos + 4 <= len(raw):
        n = int.from_bytes(raw[pos:pos + 4], "little")
        out.append(raw[pos + 4:pos + 4 + n])
        pos += 4 + n
    return out


def compact_animation(command: bytes) -> bytes:
    """A packed ``set_animation`` command made small for a page: numbers as float32.

    A track whose keyframes all hold the same value keeps its first keyframe only (the object
    stays where that value puts it). Display precision: float32 keeps 7 digits, 0.1 µm on a
    1 m arm.
    """
    import umsgpack

    data = umsgpack.unpackb(command)
    for entry in data.get("animations", []):
        for track in entry.get("clip", {}).get("tracks", []):
            keys = track.get("keys", [])
            if len(keys) > 1 and all(k["value"] == keys[0]["value"] for k in keys[1:]):
                track["keys"] = keys[:1]
    return umsgpack.packb(data, force_float_precision="single")


def _escape(text: str) -> str:
    return (text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;"))


def offline_visualizer():
    """A ``meshcat.Visualizer`` on an :class:`OfflineWindow` (no server is started)."""
    meshcat = require_meshcat()
    return meshcat.Visualizer(window=OfflineWindow())
