"""Lumped pseudo-rigid models of whole flexible arms, and their MuJoCo and URDF exports.

Each flexible link becomes rigid segments joined by spring hinges (:mod:`.model`), fitted to
the arm's own ERLS modes with exact Jacobians (:mod:`.fit`, :mod:`.sensitivity`), exported
as MJCF (:mod:`.mjcf`) or URDF plus spring data with a loader (:mod:`.urdf`); damping mapped
to joint damping (:mod:`.damping`); the fewest segments meeting a tolerance
(:mod:`.fidelity`). MuJoCo itself is needed only to run the exported files, not to write
them.
"""

from pinflex.lumped.damping import DampingMap, map_damping
from pinflex.lumped.fit import LumpedFit, fit_lumped
from pinflex.lumped.layout import ArmLayout, layout_of
from pinflex.lumped.mjcf import MjcfDocument, lumped_mjcf
from pinflex.lumped.model import LinkSegments, LumpedArm, build, equal_lumped
from pinflex.lumped.urdf import LoadedLumped, load_lumped_urdf, lumped_urdf

__all__ = [
    "ArmLayout",
    "DampingMap",
    "LinkSegments",
    "LoadedLumped",
    "LumpedArm",
    "LumpedFit",
    "MjcfDocument",
    "build",
    "equal_lumped",
    "fit_lumped",
    "layout_of",
    "load_lumped_urdf",
    "lumped_mjcf",
    "lumped_urdf",
    "map_damping",
]
