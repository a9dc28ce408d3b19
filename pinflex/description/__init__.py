"""Robot description: a URDF file plus pinflex annotations in the same file.

Annotations live in the XML namespace :data:`NAMESPACE` as direct children of ``<robot>``;
URDF parsers (Pinocchio's included) ignore them, so the file still loads unchanged. Example::

    <robot name="arm" xmlns:pinflex="urn:pinflex:urdf:1">
      ...
      <pinflex:flexible link="link1" elements="4" normal="0 0 1">
        <pinflex:material E="69e9" G="26e9" linear_density="1.9"/>
        <pinflex:section A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"/>
      </pinflex:flexible>
      <pinflex:point_mass name="m1" link="link1" xyz="0.6 0 0" mass="0.125"
                          design="true" lower="0" upper="0.25"/>
      <pinflex:coordinates convention="absolute"/>
    </robot>

``<pinflex:flexible>`` attributes: ``link`` (required), ``elements`` (required, >= 1),
``tip`` (beam end in the link frame [m]; default: the origin of the link's only child joint),
``normal`` (a vector in the link frame fixing the beam's z axis; default: the parent joint's
axis if it is normal to the beam, else the link axis least aligned with the beam).
The beam replaces the link's URDF inertial (its mass comes from the section and density);
everything attached to the link (child joints, point masses) rides on the beam at its axial
station, with a rigid offset from the axis.
``<pinflex:material>``: ``E`` [Pa] (required), ``G`` [Pa] (default ``E / (2 (1 + poisson))``,
``poisson`` default 0.3), and ``density`` [kg/m^3] or ``linear_density`` [kg/m].
``<pinflex:section>``: explicit ``A Iy Iz J`` [m^2, m^4], or ``shape`` = ``solid_circle``
(``diameter``), ``hollow_circle`` (``outer_diameter``, ``inner_diameter``) or ``rectangle``
(``width`` along the beam's y, ``height`` along z).

``<pinflex:point_mass>``: ``name``, ``link``, ``xyz`` in the link frame [m], ``mass`` [kg];
with ``design="true"`` it is a design variable with ``lower``/``upper`` bounds [kg].

``<pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.05" design="true"/>``
declares a named number; any numeric attribute of a pinflex element may read ``"{d1}"``
instead (see :mod:`pinflex.description.params`). ``design="true"`` makes it a design variable
(section dimensions and properties, E, G, density, linear_density, point-mass values, joint
stiffness); ``FlexibleModel(..., values={"d1": 0.04})`` and ``--set d1=0.04`` set it. The
hollow circle also takes ``wall`` (thickness [m]) instead of ``inner_diameter``.

``<pinflex:joint name="..." stiffness="..."/>`` puts a spring on a moving joint's physical
relative motion [N m/rad revolute, N/m prismatic]; ``locked="true"`` holds it rigidly. These
conditions apply by default when a model is built (``joints="free"`` or ``"locked"``
override them, see :class:`pinflex.erls.FlexibleModel`).

``<pinflex:coordinates convention="absolute"/>`` declares that the user-facing coordinates of a
planar serial arm are absolute link angles (paper 000's convention) instead of Pinocchio's
relative joint angles; see :class:`pinflex.erls.FlexibleModel`.
"""

from pinflex.description.overlay import (
    ROBOT_DATA_PREFIX,
    apply_overlay,
    resolve_base,
    robot_data_dir,
)
from pinflex.description.parse import load, parse, rpy_matrix
from pinflex.description.types import (
    MOVING_JOINTS,
    NAMESPACE,
    SUPPORTED_JOINTS,
    FlexibleLink,
    Joint,
    JointAnnotation,
    PointMass,
    RigidBody,
    RigidInertia,
    RobotDescription,
)

__all__ = [
    "MOVING_JOINTS",
    "NAMESPACE",
    "ROBOT_DATA_PREFIX",
    "SUPPORTED_JOINTS",
    "FlexibleLink",
    "Joint",
    "JointAnnotation",
    "PointMass",
    "RigidBody",
    "RigidInertia",
    "RobotDescription",
    "apply_overlay",
    "load",
    "parse",
    "resolve_base",
    "robot_data_dir",
    "rpy_matrix",
]
