"""Python specifications of flexible links and point masses.

These objects say in Python what the ``<pinflex:flexible>``, ``<pinflex:point_mass>``,
``<pinflex:body>`` and ``<pinflex:joint>`` annotations say in XML (see docs/overlays.md). They are turned into exactly those annotations
and parsed by the same code, so a model declared in Python and one declared in an overlay file
are the same model.

Example::

    from pinflex import Beam, Material, Mass
    from pinflex.beam import hollow_circle

    alu = Material(E=70e9, G=26.3e9, density=2700.0)
    upper = Beam(hollow_circle(0.09, 0.08), alu, elements=6, tip=(0, 0, 0.425),
                 normal=(0, 1, 0))
    payload = Mass("ee_link", 1.0, design=True, lower=0.0, upper=5.0)
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pinflex.beam import Section
from pinflex.description.types import NAMESPACE
from pinflex.exceptions import InvalidBeamProperty, InvalidDescription
from pinflex.materials import Material
from pinflex.validation import require_bool, require_count, require_number

_NS = "{" + NAMESPACE + "}"


def _num(value: float, what: str = "value") -> str:
    """Shortest text that parses back to the same float; only real numbers (no strings,
    booleans or None: ``float("1_0")`` and ``float(True)`` would be read silently)."""
    return repr(require_number(value, what, error=InvalidDescription))


def _vec(values: Sequence[float], what: str) -> str:
    if isinstance(values, str | bytes) or not isinstance(values, Sequence | np.ndarray) or \
            len(values) != 3:
        raise InvalidDescription(f"{what}: expected three numbers, got {values!r}")
    return " ".join(_num(v, what) for v in values)


@dataclass(frozen=True)
class Beam:
    """A link modelled as a straight Euler–Bernoulli beam.

    The beam starts at the link frame origin and ends at ``tip``. It replaces the link's URDF
    inertial in the modal model (its mass comes from the section and the material); child
    joints and point masses on the link ride on the beam at their axial station.

    Args:
        section: Cross-section (:class:`pinflex.beam.Section`, e.g. from
            :func:`pinflex.beam.hollow_circle`), [m^2, m^4].
        material: :class:`Material`.
        elements: Number of equal finite elements (>= 1).
        tip: Beam end in the link frame [m]; default: the origin of the link's only child
            joint.
        normal: Vector in the link frame fixing the beam's z axis; default: the parent joint's
            axis if it is normal to the beam, else the link axis least aligned with the beam.
    """

    section: Section
    material: Material
    elements: int = 4
    tip: Sequence[float] | None = None
    normal: Sequence[float] | None = None

    def __post_init__(self):
        if not isinstance(self.section, Section):
            raise InvalidBeamProperty(
                f"Beam.section must be a pinflex.beam.Section, got {type(self.section).__name__}"
            )
        if not isinstance(self.material, Material):
            raise InvalidBeamProperty(
                f"Beam.material must be a pinflex.Material, got {type(self.material).__name__}"
            )

    def element(self, link: str) -> ET.Element:
        """The ``<pinflex:flexible>`` element declaring ``link`` as this beam.

        Args:
            link: Name of the link the beam replaces.

        Returns:
            The element, with ``<pinflex:material>`` [Pa, kg/m^3 or kg/m] and
            ``<pinflex:section>`` [m^2, m^4] children.

        Raises:
            InvalidBeamProperty: ``elements`` is not an integer.
            InvalidDescription: ``tip`` or ``normal`` is not three numbers.
        """
        elements = require_count(self.elements, "Beam.elements", error=InvalidBeamProperty)
        el = ET.Element(_NS + "flexible", {"link": link, "elements": str(elements)})
        if self.tip is not None:
            el.set("tip", _vec(self.tip, f"beam on '{link}' tip"))
        if self.normal is not None:
            el.set("normal", _vec(self.normal, f"beam on '{link}' normal"))
        ET.SubElement(el, _NS + "material", self.material.attributes())
        s = self.section
        ET.SubElement(
            el, _NS + "section", {k: _num(getattr(s, k)) for k in ("A", "Iy", "Iz", "J")}
        )
        return el


@dataclass(frozen=True)
class Mass:
    """A point mass on a link, optionally a design variable.

    Args:
        link: Link carrying the mass.
        mass: Nominal mass [kg].
        xyz: Position in the link frame [m].
        design: Whether the mass is a design variable of the assignment.
        lower: Lower bound of the design variable [kg].
        upper: Upper bound of the design variable [kg].
    """

    link: str
    mass: float
    xyz: Sequence[float] = (0.0, 0.0, 0.0)
    design: bool = False
    lower: float = 0.0
    upper: float = math.inf

    def element(self, name: str) -> ET.Element:
        """The ``<pinflex:point_mass>`` element of this mass under ``name``.

        Args:
            name: Name of the point mass (and of its design variable).

        Returns:
            The element with ``mass`` [kg], ``xyz`` [m] and, for a design mass, ``lower`` and
            ``upper`` [kg].

        Raises:
            InvalidDescription: ``xyz`` is not three numbers.
        """
        attrs = {
            "name": name,
            "link": self.link,
            "xyz": _vec(self.xyz, f"point mass '{name}' xyz"),
            "mass": _num(self.mass, f"point mass '{name}' mass"),
        }
        if require_bool(self.design, f"point mass '{name}' design", error=InvalidDescription):
            attrs.update(design="true", lower=_num(self.lower, f"point mass '{name}' lower"))
            if self.upper != math.inf:  # unbounded above: no attribute
                attrs["upper"] = _num(self.upper, f"point mass '{name}' upper")
        return ET.Element(_NS + "point_mass", attrs)


@dataclass(frozen=True)
class Body:
    """A rigid body with mass and rotational inertia on a link (a motor, a flange, a tool).

    What ``<pinflex:body>`` says in XML. On a beam it moves with the cross-section at the axial
    station of its centre of mass, with a rigid offset from the axis.

    Args:
        link: Link carrying the body.
        mass: Mass [kg], > 0.
        xyz: Centre of mass in the link frame [m].
        inertia: Rotational inertia about the centre of mass in link axes [kg m²]: a 3×3
            matrix or ``(ixx, ixy, ixz, iyy, iyz, izz)``; default zero (a point mass).
    """

    link: str
    mass: float
    xyz: Sequence[float] = (0.0, 0.0, 0.0)
    inertia: Sequence = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0)

    def element(self, name: str) -> ET.Element:
        """The ``<pinflex:body>`` element of this body under ``name``.

        Raises:
            InvalidDescription: ``xyz`` is not three numbers or ``inertia`` neither a 3×3
                matrix nor six numbers.
        """
        import numpy as np

        I = np.asarray(self.inertia, dtype=float)
        if I.shape == (3, 3):
            six = (I[0, 0], I[0, 1], I[0, 2], I[1, 1], I[1, 2], I[2, 2])
        elif I.shape == (6,):
            six = tuple(I)
        else:
            raise InvalidDescription(f"body '{name}': inertia must be a 3x3 matrix or (ixx, "
                                     f"ixy, ixz, iyy, iyz, izz) [kg m^2], got shape {I.shape}")
        attrs = {"name": name, "link": self.link, "xyz": _vec(self.xyz, f"body '{name}' xyz"),
                 "mass": _num(self.mass)}
        attrs.update({k: _num(v) for k, v in zip(("ixx", "ixy", "ixz", "iyy", "iyz", "izz"),
                                                  six)})
        return ET.Element(_NS + "body", attrs)


@dataclass(frozen=True)
class JointSpec:
    """How a moving joint is held: what ``<pinflex:joint>`` says in XML.

    Given as ``joints={name: JointSpec(...)}`` to :class:`~pinflex.FlexibleModel`,
    :meth:`~pinflex.FlexibleModel.from_pinocchio` or :func:`pinflex.example_robot`; see
    :func:`servo` for a PD-controlled drive.

    Args:
        stiffness: Spring on the joint's physical relative motion [N m/rad or N/m]; None for
            none (free).
        damping: Damper on the same motion [N m s/rad or N s/m], >= 0.
        armature: Reflected rotor inertia, rotor inertia × gear ratio² [kg m² or kg], >= 0,
            added to M on the same motion (as Pinocchio's ``model.armature``, MuJoCo's
            ``armature``); None keeps the file's.
        locked: Held rigidly (stiffness and damping must then be absent).
    """

    stiffness: float | None = None
    damping: float = 0.0
    armature: float | None = None
    locked: bool = False

    def __post_init__(self):
        if self.locked and (self.stiffness is not None or self.damping):
            raise InvalidDescription("JointSpec: a locked joint takes no stiffness or damping")
        for what, v in (("stiffness", self.stiffness), ("damping", self.damping),
                        ("armature", self.armature)):
            if v is None:
                continue
            if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) \
                    or v < 0 or (what == "stiffness" and v == 0):
                raise InvalidBeamProperty(f"JointSpec.{what} = {v!r} must be a finite number "
                                          + ("> 0" if what == "stiffness" else ">= 0"))

    def element(self, name: str) -> ET.Element:
        """The ``<pinflex:joint>`` element of this specification for joint ``name``."""
        attrs = {"name": name}
        if self.locked:
            attrs["locked"] = "true"
        if self.stiffness is not None:
            attrs["stiffness"] = _num(self.stiffness)
        if self.damping:
            attrs["damping"] = _num(self.damping)
        if self.armature:
            attrs["armature"] = _num(self.armature)
        return ET.Element(_NS + "joint", attrs)


def servo(kp: float, kd: float = 0.0, *, gear_ratio: float = 1.0, rotor_inertia: float = 0.0,
          gains: str = "joint") -> JointSpec:
    """A PD-controlled drive as a joint spring, damper and reflected rotor inertia.

    About an equilibrium, a joint-side PD law ``τ = Kp (q_d − q) − Kd q̇`` is a spring
    ``k = Kp`` and a damper ``c = Kd`` on the joint's relative motion. Gains on the motor side
    (``τ_m = Kp (θ_d − θ) − Kd θ̇`` with ``θ = N q`` and ``τ = N τ_m``) reflect through the
    gear ratio ``N``: ``k = N² Kp``, ``c = N² Kd``. The rotor (inertia ``I_r``) turns ``N``
    times faster than the joint: its kinetic energy ``½ I_r (N q̇)²`` is an armature
    ``N² I_r`` on the joint. Integral action, current-loop bandwidth, friction and gearbox
    compliance are left out (a gearbox's own stiffness in series would lower ``k``).

    Args:
        kp: Proportional gain [N m/rad or N/m; motor side: N m/rad of the motor].
        kd: Derivative gain [N m s/rad or N s/m], >= 0.
        gear_ratio: ``N = θ_motor / q`` (>= 1 for a reducer).
        rotor_inertia: Motor rotor inertia [kg m²], >= 0.
        gains: ``'joint'`` (gains act on the joint angle) or ``'motor'`` (on the motor angle).

    Returns:
        A :class:`JointSpec` with ``stiffness``, ``damping`` and ``armature``.
    """
    from pinflex.exceptions import ConfigurationError

    if gains not in ("joint", "motor"):
        raise ConfigurationError(f"gains='{gains}': expected 'joint' or 'motor'")
    for what, v in (("kp", kp), ("kd", kd), ("gear_ratio", gear_ratio),
                    ("rotor_inertia", rotor_inertia)):
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v) or \
                v < 0 or (what in ("kp", "gear_ratio") and v == 0):
            raise ConfigurationError(f"servo: {what} = {v!r} must be a finite number "
                                     + ("> 0" if what in ("kp", "gear_ratio") else ">= 0"))
    n2 = float(gear_ratio) ** 2
    scale = n2 if gains == "motor" else 1.0
    return JointSpec(stiffness=scale * float(kp), damping=scale * float(kd),
                     armature=n2 * float(rotor_inertia))


def annotation_elements(
    flexible: dict[str, Beam] | None,
    masses: dict[str, Mass] | None,
    coordinates: str | None = None,
) -> list[ET.Element]:
    """The pinflex annotation elements of Python specifications, in declaration order."""
    out = []
    for link, spec in (flexible or {}).items():
        if not isinstance(spec, Beam):
            raise InvalidBeamProperty(
                f"flexible['{link}'] must be a pinflex.Beam, got {type(spec).__name__}"
            )
        out.append(spec.element(link))
    for name, mass in (masses or {}).items():
        if not isinstance(mass, Mass | Body):
            raise InvalidDescription(
                f"masses['{name}'] must be a pinflex.Mass or pinflex.Body, got "
                f"{type(mass).__name__}"
            )
        out.append(mass.element(name))
    if coordinates is not None:
        out.append(ET.Element(_NS + "coordinates", {"convention": coordinates}))
    return out
