"""One isotropic material for every beam model: ERLS links and PRBDM planforms.

A :class:`Material` is what ``<pinflex:material>`` says in XML: Young's modulus, the shear
modulus (or Poisson's ratio) and a mass density, volumetric or per unit length. ERLS beams
(:class:`pinflex.Beam`) take either density; a PRBDM planform (its mass follows its varying
width) needs the volumetric one. The PRBDM code reads the same fields under its unit-suffixed
names, :attr:`Material.youngs_modulus_pa` and :attr:`Material.density_kg_m3`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from numbers import Real

from pinflex.exceptions import InvalidBeamProperty

__all__ = ["ALUMINIUM", "STEEL", "Material"]


def _positive(value, label: str) -> None:
    if isinstance(value, bool) or not isinstance(value, Real) or not math.isfinite(value) \
            or value <= 0.0:
        raise InvalidBeamProperty(
            f"Material {label} = {value!r} must be a finite positive number "
            "(steel: E = 210e9 Pa, G = 81e9 Pa, density = 7850 kg/m^3)")


@dataclass(frozen=True)
class Material:
    """Isotropic linear elastic material.

    Args:
        E: Young's modulus [Pa].
        G: Shear modulus [Pa]; default ``E / (2 (1 + poisson))``.
        poisson: Poisson's ratio, used only when ``G`` is not given, in (-1, 0.5).
        density: Volumetric mass density [kg/m^3]; give it or ``linear_density``.
        linear_density: Mass per unit length [kg/m]; give it or ``density``.
        name: Label used in reports.

    Raises:
        InvalidBeamProperty: a value is not a finite positive number, ``poisson`` is outside
            (-1, 0.5), or not exactly one of ``density`` and ``linear_density`` is given.
    """

    E: float
    G: float | None = None
    poisson: float = 0.3
    density: float | None = None
    linear_density: float | None = None
    name: str = ""

    def __post_init__(self) -> None:
        _positive(self.E, "E [Pa]")
        if self.G is not None:
            _positive(self.G, "G [Pa]")
        elif isinstance(self.poisson, bool) or not isinstance(self.poisson, Real) \
                or not -1.0 < self.poisson < 0.5:
            raise InvalidBeamProperty(
                f"Material poisson = {self.poisson!r} must be a number in (-1, 0.5)")
        if (self.density is None) == (self.linear_density is None):
            raise InvalidBeamProperty(
                "Material: give exactly one of density [kg/m^3] or linear_density [kg/m]")
        if self.density is not None:
            _positive(self.density, "density [kg/m^3]")
        else:
            _positive(self.linear_density, "linear_density [kg/m]")

    @property
    def shear_modulus(self) -> float:
        """G [Pa]: as given, else ``E / (2 (1 + poisson))``."""
        return float(self.G) if self.G is not None else self.E / (2.0 * (1.0 + self.poisson))

    @property
    def youngs_modulus_pa(self) -> float:
        """E [Pa] (the name the PRBDM code reads)."""
        return self.E

    @property
    def density_kg_m3(self) -> float:
        """Volumetric density [kg/m^3] (the name the PRBDM code reads).

        Raises:
            InvalidBeamProperty: the material gives a linear density only.
        """
        if self.density is None:
            label = f"Material '{self.name}'" if self.name else "Material"
            raise InvalidBeamProperty(f"{label}: a planform needs a volumetric density "
                                      "[kg/m^3]; this one gives linear_density [kg/m] only")
        return self.density

    def attributes(self) -> dict[str, str]:
        """The ``<pinflex:material>`` attributes (numbers as the shortest exact text)."""
        out = {"E": repr(float(self.E))}
        if self.G is not None:
            out["G"] = repr(float(self.G))
        else:
            out["poisson"] = repr(float(self.poisson))
        if self.density is not None:
            out["density"] = repr(float(self.density))
        else:
            out["linear_density"] = repr(float(self.linear_density))  # type: ignore[arg-type]
        return out


ALUMINIUM = Material(E=70e9, G=26.3e9, density=2700.0, name="aluminium")
"""A typical aluminium alloy (E = 70 GPa, G = 26.3 GPa, 2700 kg/m^3)."""

STEEL = Material(E=210e9, G=81e9, density=7850.0, name="steel")
"""A typical structural steel (E = 210 GPa, G = 81 GPa, 7850 kg/m^3)."""
