"""pinflex: flexible-link robots on Pinocchio.

ERLS modal analysis of URDF arms with finite-element links, exact Taylor models of their
eigenfrequencies in pose and design, eigenfrequency assignment by quadratic programming, and
pseudo-rigid-body dynamic models of compliant beams.
"""

from pinflex.assignment import (
    AssignmentResult,
    Target,
    assign_frequencies,
    brute_force,
    build_assignment,
)
from pinflex.description import RobotDescription, load
from pinflex.erls import FlexibleModel, ModalResult
from pinflex.exceptions import PinflexError, PinflexWarning
from pinflex.native.robots import example_robot
from pinflex.native.spec import Beam, Mass, Material
from pinflex.parametric import TaylorModel, expand, matrix_jets
from pinflex.trajectory import Trajectory

__version__ = "0.1.0"

__all__ = [
    "AssignmentResult",
    "Beam",
    "FlexibleModel",
    "Mass",
    "Material",
    "ModalResult",
    "PinflexError",
    "PinflexWarning",
    "RobotDescription",
    "Target",
    "TaylorModel",
    "Trajectory",
    "__version__",
    "assign_frequencies",
    "brute_force",
    "build_assignment",
    "example_robot",
    "expand",
    "load",
    "matrix_jets",
]
