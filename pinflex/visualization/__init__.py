"""meshcat previews of flexible robots and PRBDM chains (SPEC §8).

* :func:`modes_preview`: every computed mode of a pose on one page, selectable, with its
  frequency, a framed camera and a floor grid (also into a user's meshcat viewer);
* :func:`mode_preview`: a mode shape animated on the robot (deformed beams drawn with the
  element shape functions, URDF visuals through Pinocchio's ``MeshcatVisualizer``);
* :func:`trajectory_preview`: a trajectory played back with the beams coloured by one mode's
  frequency, the value shown in the caption;
* :func:`prbdm_preview`: a PRBDM chain oscillating over its beam planform;
* ``*_html`` helpers write a static page that opens offline (meshcat's viewer is inlined).

meshcat is imported only when a preview is built (``import pinflex`` never imports it);
importing this package without meshcat installed raises
:class:`~pinflex.exceptions.MissingDependency` (an ``ImportError``) with the ``pip install``
command. Nothing here
opens a browser or waits for one; a served viewer is made only on request
(:func:`served_visualizer`).
"""

from __future__ import annotations

import importlib.util

from pinflex.exceptions import MissingDependency

if importlib.util.find_spec("meshcat") is None:  # checked without importing meshcat
    raise MissingDependency("meshcat", "pinflex previews")

from pinflex.visualization.modes_page import ModesPreview, modes_preview
from pinflex.visualization.offline import OfflineWindow, offline_visualizer, require_meshcat
from pinflex.visualization.prbdm import prbdm_preview, prbdm_preview_html
from pinflex.visualization.previews import (
    Preview,
    assignment_preview_html,
    mode_preview,
    mode_preview_html,
    trajectory_preview,
)
from pinflex.visualization.server import MeshcatServer, served_visualizer
from pinflex.visualization.shapes import CameraView, Centreline, centrelines, mode_scale

__all__ = [
    "CameraView",
    "Centreline",
    "ModesPreview",
    "MeshcatServer",
    "OfflineWindow",
    "Preview",
    "assignment_preview_html",
    "centrelines",
    "mode_preview",
    "mode_preview_html",
    "mode_scale",
    "modes_preview",
    "offline_visualizer",
    "prbdm_preview",
    "prbdm_preview_html",
    "require_meshcat",
    "served_visualizer",
    "trajectory_preview",
]
