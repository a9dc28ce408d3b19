"""ERLS (equivalent rigid-link system) model of a flexible-link arm on Pinocchio.

:class:`FlexibleModel` (``model.py``) loads an annotated URDF and assembles ``M(q, y)`` and
``K(q, y)``; ``plan.py`` sets up the elastic layout and attachments, ``terms.py`` holds the data
the assembly runs on, and ``modal.py`` solves the modal problem.
"""

from pinflex.erls.modal import ModalResult
from pinflex.erls.model import FlexibleModel
from pinflex.erls.terms import (
    PLANAR_NODE_DOFS,
    BatchAlgebra,
    DesignVariable,
    _PoseTerms,  # noqa: F401  (used by the Taylor model)
)

__all__ = ["BatchAlgebra", "DesignVariable", "FlexibleModel", "ModalResult", "PLANAR_NODE_DOFS"]
