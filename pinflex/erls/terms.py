"""Data carried by the ERLS assembly: plans, attachments, pose terms, batch algebra."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from pinflex.description import FlexibleLink
from pinflex.linalg import skew

PLANAR_NODE_DOFS = (0, 1, 5)  # ux, uy, θz in beam axes (beam z = plane normal)


@dataclass(frozen=True)
class DesignVariable:
    """A design variable: a point mass [kg] or a design parameter [its unit].

    Attributes:
        name: Name of the point mass or parameter.
        lower: Lower bound.
        upper: Upper bound.
        nominal: Value from the description (or ``values=`` / ``--set``).
        kind: 'mass' (a point mass with ``design="true"``) or 'parameter' (a
            ``<pinflex:parameter design="true">``: a section dimension or property, material
            constant, point-mass value or joint stiffness).
    """

    name: str
    lower: float
    upper: float
    nominal: float
    kind: str = "mass"


@dataclass(frozen=True)
class _FlexPlan:
    link: str
    spec: FlexibleLink
    x_cols: np.ndarray  # columns of x owned by nodes 1..N
    sel: np.ndarray  # (6(N+1), nx) constant selection of node dofs from x
    root: np.ndarray  # (6(N+1), 6) places the root twist (link axes) at node 0 in beam axes
    jac: np.ndarray  # (6(N+1), 6) link-origin velocity -> node velocities in beam axes
    mass: np.ndarray  # (6(N+1), 6(N+1)) assembled consistent mass
    stiffness: np.ndarray  # (6(N+1), 6(N+1)) assembled stiffness
    nodes: np.ndarray  # (N+1, 3) node positions in the link frame [m]
    rows: np.ndarray  # node-dof rows used in the assembly (in-plane ones in planar mode)


@dataclass(frozen=True)
class _Attachment:
    """Elastic twist at a point of a link = const + lin @ (twist of the link root)."""

    const: np.ndarray | None  # (6, nx), or None when the point has no own elastic dofs
    lin: np.ndarray | None  # (6, 6) or None when the point does not see the root twist


@dataclass(frozen=True)
class _ChildJoint:
    name: str
    parent: str
    child: str
    kind: str  # 'revolute', 'prismatic' or 'fixed'
    user_col: int  # index of the joint in pin velocity order (-1 when fixed)
    R_o: np.ndarray
    xyz: np.ndarray
    axis: np.ndarray
    attach: _Attachment
    proj: np.ndarray  # (6, 6) removes the motion subspace (in child axes)


@dataclass
class _PoseTerms:
    """Pose-dependent inputs of the assembly (leading axis: poses or Taylor coefficients)."""

    jac: dict[str, np.ndarray]  # link -> (b, 6, nv) LOCAL Jacobian in user coordinates
    rot: dict[str, np.ndarray]  # moving joint -> (b, 3, 3) child-in-parent rotation
    slide: dict[str, np.ndarray] = field(default_factory=dict)  # prismatic joint -> (b, 3)


class BatchAlgebra:
    """Plain arrays with a leading pose axis."""

    def __init__(self, size: int):
        self.size = size

    def const(self, c: np.ndarray) -> np.ndarray:
        """Lift a constant array."""
        return np.broadcast_to(c, (self.size,) + c.shape)

    @staticmethod
    def mm(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Product of two pose-dependent matrices."""
        return a @ b



def _offset_block(p: np.ndarray) -> np.ndarray:
    """The part of ``translate_twist(p) - I`` (linear in ``p``), batched."""
    out = np.zeros(p.shape[:-1] + (6, 6))
    out[..., :3, 3:] = -skew(p)
    return out


def _zeros_like(jac: np.ndarray, nx: int) -> np.ndarray:
    return np.zeros(jac.shape[:-1] + (nx,))
