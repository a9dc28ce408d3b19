"""ERLS (equivalent rigid-link system) model of a flexible-link arm on Pinocchio.

:class:`FlexibleModel` (``model.py``) loads an annotated URDF and assembles ``M(q, y)`` and
``K(q, y)``; ``plan.py`` builds its read-only :class:`ModelPlan` (``model.plan``: links, beams,
joints, mass carriers, attachments), ``terms.py`` holds the data types the assembly runs on,
and ``modal.py`` solves the modal problem. The model is constant once built; what a
computation writes lives in its workspace, :class:`FlexibleData` (``workspace.py``).
"""

from pinflex.erls.modal import ModalResult
from pinflex.erls.model import FlexibleModel, NodePlacement
from pinflex.erls.terms import (
    PLANAR_NODE_DOFS,
    Algebra,
    Attachment,
    BatchAlgebra,
    BeamPlan,
    DesignVariable,
    JointPlan,
    ModelPlan,
    PointMassPlan,
    PoseTerms,
)
from pinflex.erls.workspace import FlexibleData

__all__ = [
    "PLANAR_NODE_DOFS",
    "Algebra",
    "Attachment",
    "BatchAlgebra",
    "BeamPlan",
    "DesignVariable",
    "FlexibleData",
    "FlexibleModel",
    "JointPlan",
    "ModalResult",
    "ModelPlan",
    "NodePlacement",
    "PointMassPlan",
    "PoseTerms",
]
