"""Python specifications of flexible links and point masses.

These objects say in Python what the ``<pinflex:flexible>`` and ``<pinflex:point_mass>``
annotations say in XML (see docs/overlays.md). They are turned into exactly those annotations
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

from pinflex.beam import Section
from pinflex.description.types import NAMESPACE
from pinflex.exceptions import InvalidBeamProperty, InvalidDescription
from pinflex.materials import Material

_NS = "{" + NAMESPACE + "}"


def _num(value: float) -> str:
    """Shortest text that parses back to the same float."""
    return repr(float(value))


def _vec(values: Sequence[float], what: str) -> str:
    try:
        vals = [float(v) for v in values]
    except (TypeError, ValueError) as exc:
        raise InvalidDescription(f"{what}: expected three numbers, got {values!r}") from exc
    if len(vals) != 3:
        raise InvalidDescription(f"{what}: expected three numbers, got {values!r}")
    return " ".join(_num(v) for v in vals)


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
        el = ET.Element(_NS + "flexible", {"link": link, "elements": str(int(self.elements))})
        if int(self.elements) != self.elements:
            raise InvalidBeamProperty(f"Beam.elements must be an integer, got {self.elements!r}")
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
            "mass": _num(self.mass),
        }
        if self.design:
            attrs.update(design="true", lower=_num(self.lower), upper=_num(self.upper))
        return ET.Element(_NS + "point_mass", attrs)


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
        if not isinstance(mass, Mass):
            raise InvalidDescription(
                f"masses['{name}'] must be a pinflex.Mass, got {type(mass).__name__}"
            )
        out.append(mass.element(name))
    if coordinates is not None:
        out.append(ET.Element(_NS + "coordinates", {"convention": coordinates}))
    return out
