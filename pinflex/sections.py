"""Section and material formulas, written once for numbers, arrays and jets.

A flexible link's beam properties (axial, torsional and bending rigidities, mass and rotary
inertia per length) follow from its section dimensions and material. The formulas use only
``+ − * / **``, so they run on floats (the description), on NumPy arrays (one design per
pose) and on :class:`pinflex.jets.scalar.Scalar` jets (exact Taylor coefficients in design
parameters):

* solid circle (``diameter`` d): A = π d²/4, Iy = Iz = π d⁴/64, J = 2 Iy;
* hollow circle (``outer_diameter`` D with ``inner_diameter`` d or ``wall`` t, d = D − 2t):
  A = π (D² − d²)/4, Iy = Iz = π (D⁴ − d⁴)/64, J = 2 Iy;
* rectangle (``width`` b along the section's y, ``height`` h along z): A = b h,
  Iy = b h³/12, Iz = h b³/12, J = a c³ (1/3 − 0.21 (c/a)(1 − (c/a)⁴/12)) with a = max(b, h),
  c = min(b, h) (Saint-Venant series, about 0.5 %); the branch of max/min is taken at the
  value, so a Taylor expansion holds on one side of b = h;
* explicit ``A Iy Iz J``.

Material: ``E``, ``G`` (default E / (2 (1 + poisson))), ``density`` ρ (ρA = ρ A, ρIp = ρ (Iy +
Iz)) or ``linear_density`` μ (ρA = μ, ρIp = μ (Iy + Iz) / A).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pinflex.exceptions import InvalidBeamProperty

SHAPES = {
    "solid_circle": ("diameter",),
    "hollow_circle": ("outer_diameter", "inner_diameter", "wall"),
    "rectangle": ("width", "height"),
    None: ("A", "Iy", "Iz", "J"),
}
#: Beam property channels: (name, matrix it scales). Stiffness channels scale unit element
#: stiffness matrices, mass channels unit element mass matrices.
CHANNELS = (("EA", "K"), ("GJ", "K"), ("EIy", "K"), ("EIz", "K"), ("rhoA", "M"),
            ("rhoIp", "M"))


@dataclass(frozen=True)
class PropertyInputs:
    """What a flexible link's properties are computed from.

    Every entry is a number, or the name of a design parameter (a string) when the attribute
    references one.

    Attributes:
        shape: 'solid_circle', 'hollow_circle', 'rectangle' or None (explicit A, Iy, Iz, J).
        section: Section attributes given (dimensions [m] or properties [m², m⁴]).
        material: ``E`` [Pa] and ``G`` [Pa] or ``poisson``, and ``density`` [kg/m³] or
            ``linear_density`` [kg/m].
    """

    shape: str | None
    section: dict[str, float | str] = field(default_factory=dict)
    material: dict[str, float | str] = field(default_factory=dict)

    def parameters(self) -> tuple[str, ...]:
        """Names of the design parameters the properties depend on, sorted."""
        vals = list(self.section.values()) + list(self.material.values())
        return tuple(sorted({v for v in vals if isinstance(v, str)}))


def section_properties(shape: str | None, dims: dict) -> tuple:
    """``(A, Iy, Iz, J)`` of a section from its dimensions (numbers, arrays or jets)."""
    if shape is None:
        return dims["A"], dims["Iy"], dims["Iz"], dims["J"]
    if shape == "solid_circle":
        d = dims["diameter"]
        i = math.pi / 64.0 * d**4
        return math.pi / 4.0 * d**2, i, i, 2.0 * i
    if shape == "hollow_circle":
        outer = dims["outer_diameter"]
        if "wall" in dims:
            inner = outer - 2.0 * dims["wall"]
        else:
            inner = dims.get("inner_diameter", 0.0)
        i = math.pi / 64.0 * (outer**4 - inner**4)
        return math.pi / 4.0 * (outer**2 - inner**2), i, i, 2.0 * i
    if shape == "rectangle":
        b, h = dims["width"], dims["height"]
        long_, short = (b, h) if _value(b) >= _value(h) else (h, b)
        r = short / long_
        j = long_ * short**3 * (1.0 / 3.0 - 0.21 * r * (1.0 - r**4 / 12.0))
        return b * h, b * h**3 / 12.0, h * b**3 / 12.0, j
    raise InvalidBeamProperty(
        f"unknown shape '{shape}'; use solid_circle, hollow_circle, rectangle or explicit "
        "A, Iy, Iz, J"
    )


def section_limits(inputs: PropertyInputs, get) -> dict:
    """Quantities that must be positive for the section to exist (besides A, I, J > 0).

    A hollow circle needs ``outer − inner > 0`` and ``inner ≥ 0`` (``inner = outer − 2 wall``):
    the area formula alone stays positive for a negative inner diameter, which is no tube.
    """
    if inputs.shape != "hollow_circle":
        return {}

    def val(entry):
        return get(entry) if isinstance(entry, str) else entry

    outer = val(inputs.section["outer_diameter"])
    if "wall" in inputs.section:
        inner = outer - 2.0 * val(inputs.section["wall"])
    else:
        inner = val(inputs.section.get("inner_diameter", 0.0))
    # a solid rod (inner = 0) is a valid limit; round-off below it is tolerated
    return {"outer - inner diameter": outer - inner, "inner diameter": inner + 1e-9 * outer}


def _value(x):
    from pinflex.jets.scalar import value_of  # jets load only with a rectangle section

    try:
        return value_of(x)
    except TypeError:  # an array of values: the branch is decided by the first entry
        import numpy as np

        return float(np.ravel(x)[0])


def beam_properties(inputs: PropertyInputs, get) -> dict:
    """Rigidities and inertias per length of a link, plus ``A, Iy, Iz, J``.

    Args:
        inputs: The link's inputs.
        get: Maps a design-parameter name to its value (a number, array or jet).

    Returns:
        ``{"EA", "GJ", "EIy", "EIz", "rhoA", "rhoIp", "A", "Iy", "Iz", "J"}``.
    """

    def val(entry):
        return get(entry) if isinstance(entry, str) else entry

    dims = {k: val(v) for k, v in inputs.section.items()}
    mat = {k: val(v) for k, v in inputs.material.items()}
    A, Iy, Iz, J = section_properties(inputs.shape, dims)
    E = mat["E"]
    G = mat["G"] if "G" in mat else E / (2.0 * (1.0 + mat.get("poisson", 0.3)))
    if "density" in mat:
        rhoA, rhoIp = mat["density"] * A, mat["density"] * (Iy + Iz)
    else:
        mu = mat["linear_density"]
        rhoA, rhoIp = mu, mu * (Iy + Iz) / A
    return {"EA": E * A, "GJ": G * J, "EIy": E * Iy, "EIz": E * Iz, "rhoA": rhoA,
            "rhoIp": rhoIp, "A": A, "Iy": Iy, "Iz": Iz, "J": J}
