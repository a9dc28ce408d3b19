"""The robot description's dataclasses: joints, inertias, flexible links, point masses."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pinflex import beam
from pinflex.description.params import Parameter
from pinflex.exceptions import InvalidDescription, JointNotFound, LinkNotFound
from pinflex.linalg import skew as _skew
from pinflex.sections import PropertyInputs

NAMESPACE = "urn:pinflex:urdf:1"
_NS = "{" + NAMESPACE + "}"

MOVING_JOINTS = ("revolute", "continuous", "prismatic")
SUPPORTED_JOINTS = MOVING_JOINTS + ("fixed",)


@dataclass(frozen=True)
class Joint:
    """A URDF joint.

    Attributes:
        name: Joint name.
        type: 'revolute', 'continuous', 'prismatic' or 'fixed'.
        parent: Parent link name.
        child: Child link name.
        xyz: Origin of the joint frame in the parent link frame [m], (3,).
        rotation: Rotation of the joint frame in the parent link frame, (3, 3).
        axis: Unit joint axis in the joint frame, (3,).
        lower: Lower position limit [rad or m] (-inf when absent).
        upper: Upper position limit [rad or m] (+inf when absent).
    """

    name: str
    type: str
    parent: str
    child: str
    xyz: np.ndarray
    rotation: np.ndarray
    axis: np.ndarray
    lower: float = -np.inf
    upper: float = np.inf


@dataclass(frozen=True)
class RigidInertia:
    """URDF inertial of a link, expressed at the link frame origin in link axes.

    Attributes:
        mass: Mass [kg].
        com: Centre of mass [m], (3,).
        inertia: Rotational inertia about the centre of mass in link axes [kg m^2], (3, 3).
    """

    mass: float
    com: np.ndarray
    inertia: np.ndarray

    def spatial_matrix(self) -> np.ndarray:
        """6×6 spatial inertia at the link origin, ordering (linear, angular)."""
        c = self.com
        cx = _skew(c)
        out = np.zeros((6, 6))
        out[:3, :3] = self.mass * np.eye(3)
        out[:3, 3:] = -self.mass * cx
        out[3:, :3] = self.mass * cx
        out[3:, 3:] = self.inertia - self.mass * cx @ cx
        return out


@dataclass(frozen=True)
class FlexibleLink:
    """A link modelled as a straight finite-element beam.

    Attributes:
        link: URDF link name.
        elements: Number of equal beam elements.
        tip: Beam end point in the link frame [m], (3,); the beam starts at the link origin.
        normal: Unit vector in the link frame, the beam's z axis (normal to the beam).
        E: Young's modulus [Pa].
        G: Shear modulus [Pa].
        rhoA: Mass per unit length [kg/m].
        rhoIp: Torsional rotary inertia per unit length [kg m].
        section: Cross-section properties.
        inputs: What the properties are computed from (section dimensions, material), with
            design parameters by name (see :mod:`pinflex.sections`).
        inertia: What the beam keeps of the URDF link's inertia: ``'keep-excess'`` (the part
            beyond the beam's own, default), ``'keep'`` (all) or ``'beam-only'`` (none); see
            :mod:`pinflex.description.link_inertia`.
    """

    link: str
    elements: int
    tip: np.ndarray
    normal: np.ndarray
    E: float
    G: float
    rhoA: float
    rhoIp: float
    section: beam.Section
    inputs: PropertyInputs | None = None
    inertia: str = "keep-excess"

    @property
    def length_m(self) -> float:
        """Beam length [m]."""
        return float(np.linalg.norm(self.tip))

    @property
    def rotation(self) -> np.ndarray:
        """Beam axes in the link frame, columns (x, y, z), (3, 3) (computed once, read-only)."""
        cached = self.__dict__.get("_rotation")
        if cached is None:
            x = self.tip / self.length_m
            z = self.normal
            cached = np.column_stack([x, np.cross(z, x), z])
            cached.setflags(write=False)
            object.__setattr__(self, "_rotation", cached)
        return cached


@dataclass(frozen=True)
class PointMass:
    """A point mass on a link.

    Attributes:
        name: Unique name.
        link: Link carrying the mass.
        xyz: Position in the link frame [m], (3,).
        mass: Nominal mass [kg].
        design: Whether the mass is a design variable.
        lower: Lower bound of the design variable [kg].
        upper: Upper bound of the design variable [kg].
        mass_ref: The design parameter the mass references (``mass="{name}"``), else None.
    """

    name: str
    link: str
    xyz: np.ndarray
    mass: float
    design: bool = False
    lower: float = 0.0
    upper: float = np.inf
    mass_ref: str | None = None


@dataclass(frozen=True)
class RigidBody:
    """A rigid body with mass and rotational inertia carried by a link.

    From a ``<pinflex:body>`` element, or the URDF inertia a beam link keeps (see
    :mod:`pinflex.description.link_inertia`). On a beam it moves with the cross-section at the
    axial station of its centre of mass (with a rigid offset from the axis).

    Attributes:
        name: Unique name (``link.urdf`` for a kept URDF inertia).
        link: Link carrying it.
        com: Centre of mass in the link frame [m], (3,).
        mass: Mass [kg].
        inertia: Rotational inertia about the centre of mass in link axes [kg m²], (3, 3).
        source: ``'body'`` (a ``<pinflex:body>``), ``'urdf'`` or ``'urdf excess'``.
    """

    name: str
    link: str
    com: np.ndarray
    mass: float
    inertia: np.ndarray
    source: str = "body"

    def spatial_matrix(self) -> np.ndarray:
        """6×6 spatial inertia at the centre of mass, ordering (linear, angular)."""
        out = np.zeros((6, 6))
        out[:3, :3] = self.mass * np.eye(3)
        out[3:, 3:] = self.inertia
        return out


@dataclass(frozen=True)
class JointAnnotation:
    """The mechanical condition a ``<pinflex:joint>`` element gives a moving joint.

    Attributes:
        name: Joint name (a revolute, continuous or prismatic URDF joint).
        stiffness: Spring stiffness on the joint's physical relative motion [N m/rad for a
            revolute joint, N/m for a prismatic one], or ``None`` for no spring.
        locked: Whether the joint is held rigidly (the child's root follows the parent's
            deformed attachment).
        stiffness_ref: The design parameter the stiffness references, else None.
        damping: Damper on the same relative motion [N m s/rad or N s/m] (0: none).
        armature: Reflected rotor inertia, rotor inertia × gear ratio² [kg m² or kg], added
            to M on the joint's relative motion (as Pinocchio's ``model.armature``).
    """

    name: str
    stiffness: float | None = None
    locked: bool = False
    stiffness_ref: str | None = None
    damping: float = 0.0
    armature: float = 0.0


@dataclass(frozen=True)
class RobotDescription:
    """Everything pinflex reads from an annotated URDF.

    Attributes:
        name: Robot name.
        urdf_xml: The URDF text that Pinocchio parses.
        base_dir: Folder of the file, for relative mesh paths.
        root: Name of the root link (clamped to the ground).
        links: Link names in file order.
        joints: Joints by name.
        inertias: URDF inertials by link name (links without one are absent).
        flexible: Flexible links by link name.
        point_masses: Point masses in file order.
        absolute_coordinates: Whether user coordinates are absolute link angles.
        joint_annotations: ``<pinflex:joint>`` conditions by joint name (a model's default
            joint conditions, unless built with ``joints="free"`` or ``"locked"``).
        parameters: ``<pinflex:parameter>`` elements by name, with their current values.
        values: The parameter overrides the description was parsed with.
        bodies: Rigid bodies on links: ``<pinflex:body>`` elements and the URDF inertia beam
            links keep (:mod:`pinflex.description.link_inertia`).
        inertia_notes: One line per flexible link saying what it kept of its URDF inertia.
        allow_paths: Whether files named by the description (meshes) may be read from
            outside its folder and the package roots.
    """

    name: str
    urdf_xml: str
    base_dir: Path | None
    root: str
    links: tuple[str, ...]
    joints: dict[str, Joint]
    inertias: dict[str, RigidInertia]
    flexible: dict[str, FlexibleLink]
    point_masses: tuple[PointMass, ...]
    absolute_coordinates: bool = False
    child_joints: dict[str, tuple[str, ...]] = field(default_factory=dict)
    parent_joint: dict[str, str] = field(default_factory=dict)
    joint_annotations: dict[str, JointAnnotation] = field(default_factory=dict)
    parameters: dict[str, Parameter] = field(default_factory=dict)
    values: dict[str, float] = field(default_factory=dict)
    bodies: tuple[RigidBody, ...] = ()
    inertia_notes: tuple[str, ...] = ()
    allow_paths: bool = False
    #: Reads the same text again with other parameter values (set by the parser; keeps this
    #: module free of an import of the parser).
    reparse: Callable[[dict], RobotDescription] | None = field(
        default=None, repr=False, compare=False)

    def with_values(self, values: dict[str, float]) -> RobotDescription:
        """The same description with parameter values overridden (re-read from its text).

        Args:
            values: ``{parameter: value}`` in each parameter's own unit; merged over the
                values this description was read with.

        Returns:
            A new :class:`RobotDescription` parsed from the same URDF text.

        Raises:
            DesignVariableOutOfBounds: A value leaves its parameter's bounds.
            ConfigurationError: ``values`` is not a mapping of names to finite numbers.
            InvalidDescription: The description was not made by pinflex's parser.
        """
        from pinflex.exceptions import ConfigurationError

        if not isinstance(values, dict):
            raise ConfigurationError(f"values must be a dict {{name: number}}, got {values!r}")
        if self.reparse is None:
            raise InvalidDescription("this description was not read by pinflex's parser, so "
                                     "it cannot be re-read with other values")
        return self.reparse({**self.values, **values})

    def require_link(self, name: str) -> None:
        """Raise :class:`LinkNotFound` unless ``name`` is a link.

        Args:
            name: A link name.

        Raises:
            LinkNotFound: ``name`` is not a link of the description.
        """
        if name not in self.links:
            raise LinkNotFound(name, self.links)

    def require_joint(self, name: str) -> None:
        """Raise :class:`JointNotFound` unless ``name`` is a joint.

        Args:
            name: A joint name.

        Raises:
            JointNotFound: ``name`` is not a joint of the description.
        """
        if name not in self.joints:
            raise JointNotFound(name, self.joints)
