"""pinflex: flexible-link robots on Pinocchio.

ERLS modal analysis of URDF arms with finite-element links, exact Taylor models of their
eigenfrequencies in pose and design, eigenfrequency assignment by quadratic programming, and
pseudo-rigid-body dynamic models of compliant beams.

The names below are imported when first used (:mod:`pinflex.lazy`), so ``import pinflex`` and
``import pinflex.jets`` load neither Pinocchio nor SciPy.
"""

from typing import TYPE_CHECKING

from pinflex.lazy import lazy_exports

__version__ = "0.1.0"

_EXPORTS = {
    "AssignmentResult": "pinflex.assignment",
    "Beam": "pinflex.native.spec",
    "Body": "pinflex.native.spec",
    "FlexibleData": "pinflex.erls",
    "FlexibleModel": "pinflex.erls",
    "JointSpec": "pinflex.native.spec",
    "Mass": "pinflex.native.spec",
    "Material": "pinflex.materials",
    "ModalResult": "pinflex.erls",
    "PinflexError": "pinflex.exceptions",
    "PinflexWarning": "pinflex.exceptions",
    "PointForce": "pinflex.erls.preload",
    "Preload": "pinflex.erls.preload",
    "RobotDescription": "pinflex.description",
    "Target": "pinflex.assignment",
    "TaylorModel": "pinflex.parametric",
    "Trajectory": "pinflex.trajectory",
    "assign_frequencies": "pinflex.assignment",
    "brute_force": "pinflex.assignment",
    "build_assignment": "pinflex.assignment",
    "example_robot": "pinflex.erls.robots",
    "expand": "pinflex.parametric",
    "load": "pinflex.description",
    "matrix_jets": "pinflex.parametric",
    "servo": "pinflex.native.spec",
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "__version__",
    "AssignmentResult",
    "Beam",
    "Body",
    "FlexibleData",
    "FlexibleModel",
    "JointSpec",
    "Mass",
    "Material",
    "ModalResult",
    "PinflexError",
    "PinflexWarning",
    "PointForce",
    "Preload",
    "RobotDescription",
    "Target",
    "TaylorModel",
    "Trajectory",
    "assign_frequencies",
    "brute_force",
    "build_assignment",
    "example_robot",
    "expand",
    "load",
    "matrix_jets",
    "servo",
]

if TYPE_CHECKING:
    from pinflex.assignment import (
        AssignmentResult,
        Target,
        assign_frequencies,
        brute_force,
        build_assignment,
    )
    from pinflex.description import RobotDescription, load
    from pinflex.erls import FlexibleData, FlexibleModel, ModalResult
    from pinflex.erls.preload import PointForce, Preload
    from pinflex.erls.robots import example_robot
    from pinflex.exceptions import PinflexError, PinflexWarning
    from pinflex.materials import Material
    from pinflex.native.spec import Beam, Body, JointSpec, Mass, servo
    from pinflex.parametric import TaylorModel, expand, matrix_jets
    from pinflex.trajectory import Trajectory
