"""Beam sections and 12-dof Euler–Bernoulli element matrices.

Conventions (used throughout pinflex):

* A beam has its own frame: ``x`` along the axis (root to tip), ``y`` and ``z`` the principal
  axes of the section. ``Iy`` is the second moment about ``y`` (bending in the x–z plane,
  deflection ``w`` along ``z``), ``Iz`` the one about ``z`` (bending in the x–y plane,
  deflection ``v`` along ``y``).
* Node dofs are ``(ux, uy, uz, θx, θy, θz)``: a small translation and a small rotation vector,
  both in beam axes, so that an element has 12 dofs ``(node a, node b)``.
* Kinematics: ``θz = dv/dx`` and ``θy = −dw/dx``; axial and torsional fields are linear,
  bending fields cubic Hermite. Consistent mass with translational line mass ``ρA`` and
  torsional rotary inertia ``ρIp`` (rotary inertia of bending is neglected, as in the
  Euler–Bernoulli model).

Element matrices are computed by Gauss–Legendre quadrature of the shape functions, which
is exact (to round-off) for these polynomial integrands.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex.exceptions import InvalidBeamProperty

# 5-point Gauss-Legendre rule on [-1, 1] in closed form (numpy.polynomial costs start-up time)
_GAUSS_X = np.array([-np.sqrt(5.0 + 2.0 * np.sqrt(10.0 / 7.0)) / 3.0,
                     -np.sqrt(5.0 - 2.0 * np.sqrt(10.0 / 7.0)) / 3.0, 0.0,
                     np.sqrt(5.0 - 2.0 * np.sqrt(10.0 / 7.0)) / 3.0,
                     np.sqrt(5.0 + 2.0 * np.sqrt(10.0 / 7.0)) / 3.0])
_GAUSS_W = np.array([(322.0 - 13.0 * np.sqrt(70.0)) / 900.0,
                     (322.0 + 13.0 * np.sqrt(70.0)) / 900.0, 128.0 / 225.0,
                     (322.0 + 13.0 * np.sqrt(70.0)) / 900.0,
                     (322.0 - 13.0 * np.sqrt(70.0)) / 900.0])
_GAUSS_XI = 0.5 * (_GAUSS_X + 1.0)
_GAUSS_WXI = 0.5 * _GAUSS_W


@dataclass(frozen=True)
class Section:
    """Cross-section properties of a straight beam.

    Attributes:
        A: Area [m^2].
        Iy: Second moment of area about the section's y axis [m^4].
        Iz: Second moment of area about the section's z axis [m^4].
        J: Torsion constant [m^4].
    """

    A: float
    Iy: float
    Iz: float
    J: float

    def __post_init__(self):
        for name in ("A", "Iy", "Iz", "J"):
            value = getattr(self, name)
            if not np.isfinite(value) or value <= 0.0:
                raise InvalidBeamProperty(
                    f"section property {name} = {value!r} must be a positive finite number [SI]"
                )

    @property
    def Ip(self) -> float:
        """Polar moment of area Iy + Iz [m^4] (rotary inertia of torsion)."""
        return self.Iy + self.Iz


def solid_circle(diameter_m: float) -> Section:
    """Section of a solid circular rod of the given diameter [m] (:mod:`pinflex.sections`)."""
    _positive("diameter", diameter_m)
    return _section("solid_circle", {"diameter": diameter_m})


def hollow_circle(outer_diameter_m: float, inner_diameter_m: float) -> Section:
    """Section of a circular tube [m]; the inner diameter must be below the outer one."""
    _positive("outer_diameter", outer_diameter_m)
    if not 0.0 <= inner_diameter_m < outer_diameter_m:
        raise InvalidBeamProperty(
            f"inner_diameter = {inner_diameter_m!r} must satisfy 0 <= inner < outer = "
            f"{outer_diameter_m!r} [m]"
        )
    return _section("hollow_circle", {"outer_diameter": outer_diameter_m,
                                      "inner_diameter": inner_diameter_m})


def rectangle(width_m: float, height_m: float) -> Section:
    """Solid rectangle: ``width`` along the section's y axis, ``height`` along z [m].

    The torsion constant uses the classical series approximation of Saint-Venant torsion
    (accurate to about 0.5 %).
    """
    _positive("width", width_m)
    _positive("height", height_m)
    return _section("rectangle", {"width": width_m, "height": height_m})


def _section(shape: str, dims: dict) -> Section:
    """The :class:`Section` of a shape, by the one set of formulas in :mod:`pinflex.sections`."""
    from pinflex.sections import section_properties

    A, Iy, Iz, J = section_properties(shape, dims)
    return Section(A=float(A), Iy=float(Iy), Iz=float(Iz), J=float(J))


def _positive(name: str, value: float) -> None:
    if not np.isfinite(value) or value <= 0.0:
        raise InvalidBeamProperty(f"{name} = {value!r} must be a positive finite number [m]")


def hermite_shapes(xi: np.ndarray, length_m) -> tuple[np.ndarray, np.ndarray]:
    """Cubic Hermite shape functions of one bending plane and their second derivatives.

    Element dofs are ``(w_a, w'_a, w_b, w'_b)`` with ``w' = dw/dx``; ``xi`` and ``length_m``
    broadcast against each other (e.g. ``xi`` of shape (1, k) with lengths (n, 1) for ``n``
    elements of different lengths).

    Args:
        xi: Points along the element, ``x / L`` in [0, 1].
        length_m: Element length(s) L [m].

    Returns:
        ``(N, B)``, each of shape ``broadcast(xi, length_m).shape + (4,)``: the values [1, m]
        and the second derivatives ``d²N/dx²`` [1/m², 1/m].
    """
    xi, h = np.broadcast_arrays(np.asarray(xi, dtype=float), np.asarray(length_m, dtype=float))
    n = np.stack([1.0 - 3.0 * xi**2 + 2.0 * xi**3, h * (xi - 2.0 * xi**2 + xi**3),
                  3.0 * xi**2 - 2.0 * xi**3, h * (-(xi**2) + xi**3)], axis=-1)
    b = np.stack([(-6.0 + 12.0 * xi) / h**2, (-4.0 + 6.0 * xi) / h,
                  (6.0 - 12.0 * xi) / h**2, (-2.0 + 6.0 * xi) / h], axis=-1)
    return n, b


def shape_matrix(length_m: float, xi: np.ndarray) -> np.ndarray:
    """Interpolation of the 12 element dofs to the displacement and rotation on the axis.

    Args:
        length_m: Element length L [m].
        xi: Points along the element, ``x / L`` in [0, 1], shape (k,).

    Returns:
        Array (k, 6, 12): rows ``(ux, uy, uz, θx, θy, θz)`` at each point, in beam axes.
    """
    xi = np.atleast_1d(np.asarray(xi, dtype=float))
    L = float(length_m)
    n1, n2 = 1.0 - xi, xi
    h1, h2, h3, h4 = np.moveaxis(hermite_shapes(xi, L)[0], -1, 0)
    d1 = (-6.0 * xi + 6.0 * xi**2) / L
    d2 = 1.0 - 4.0 * xi + 3.0 * xi**2
    d3 = (6.0 * xi - 6.0 * xi**2) / L
    d4 = -2.0 * xi + 3.0 * xi**2
    N = np.zeros((xi.size, 6, 12))
    N[:, 0, 0], N[:, 0, 6] = n1, n2  # axial
    N[:, 3, 3], N[:, 3, 9] = n1, n2  # torsion
    # x-y plane: v with θz = dv/dx
    N[:, 1, 1], N[:, 1, 5], N[:, 1, 7], N[:, 1, 11] = h1, h2, h3, h4
    N[:, 5, 1], N[:, 5, 5], N[:, 5, 7], N[:, 5, 11] = d1, d2, d3, d4
    # x-z plane: w with θy = -dw/dx
    N[:, 2, 2], N[:, 2, 4], N[:, 2, 8], N[:, 2, 10] = h1, -h2, h3, -h4
    N[:, 4, 2], N[:, 4, 4], N[:, 4, 8], N[:, 4, 10] = -d1, d2, -d3, d4
    return N


def _strain_matrix(length_m: float, xi: np.ndarray) -> np.ndarray:
    """Generalised strains (ε, κx, κy, κz) per element dof, shape (k, 4, 12)."""
    L = float(length_m)
    B = np.zeros((xi.size, 4, 12))
    B[:, 0, 0], B[:, 0, 6] = -1.0 / L, 1.0 / L  # axial strain du/dx
    B[:, 1, 3], B[:, 1, 9] = -1.0 / L, 1.0 / L  # twist rate dθx/dx
    c1, c2, c3, c4 = np.moveaxis(hermite_shapes(xi, L)[1], -1, 0)
    # curvature about z: d2v/dx2 ; curvature about y: d2w/dx2 (sign irrelevant in energy)
    B[:, 3, 1], B[:, 3, 5], B[:, 3, 7], B[:, 3, 11] = c1, c2, c3, c4
    B[:, 2, 2], B[:, 2, 4], B[:, 2, 8], B[:, 2, 10] = c1, -c2, c3, -c4
    return B


def element_stiffness(
    length_m: float, EA: float, GJ: float, EIy: float, EIz: float
) -> np.ndarray:
    """Stiffness matrix (12, 12) of a spatial Euler–Bernoulli element in beam axes.

    Args:
        length_m: Element length [m].
        EA: Axial rigidity [N].
        GJ: Torsional rigidity [N m^2].
        EIy: Bending rigidity about y (x–z plane) [N m^2].
        EIz: Bending rigidity about z (x–y plane) [N m^2].
    """
    B = _strain_matrix(length_m, _GAUSS_XI)
    D = np.diag([EA, GJ, EIy, EIz])
    w = _GAUSS_WXI * length_m
    return np.einsum("k,kai,ab,kbj->ij", w, B, D, B)


def element_mass(length_m: float, rhoA: float, rhoIp: float) -> np.ndarray:
    """Consistent mass matrix (12, 12) of a spatial Euler–Bernoulli element in beam axes.

    Args:
        length_m: Element length [m].
        rhoA: Mass per unit length [kg/m].
        rhoIp: Torsional rotary inertia per unit length [kg m].
    """
    N = shape_matrix(length_m, _GAUSS_XI)
    w = _GAUSS_WXI * length_m
    Nt = N[:, :3, :]
    Nr = N[:, 3, :]
    return rhoA * np.einsum("k,kai,kaj->ij", w, Nt, Nt) + rhoIp * np.einsum(
        "k,ki,kj->ij", w, Nr, Nr
    )


def assemble_line(blocks: np.ndarray) -> np.ndarray:
    """Assemble element matrices of a straight chain of elements.

    Args:
        blocks: Element matrices (ne, 12, 12), element e joining nodes e and e+1.

    Returns:
        The (6 (ne+1), 6 (ne+1)) matrix over all node dofs.
    """
    ne = blocks.shape[0]
    n = 6 * (ne + 1)
    rows = (6 * np.arange(ne))[:, None] + np.arange(12)[None, :]
    out = np.zeros((n, n))
    np.add.at(out, (rows[:, :, None], rows[:, None, :]), blocks)
    return out


#: Points ``x / L`` of the element quadrature (5-point Gauss–Legendre) at which
#: :func:`element_geometric_stiffness` takes a varying axial force.
GEOMETRIC_POINTS = _GAUSS_XI.copy()
GEOMETRIC_POINTS.flags.writeable = False


def element_geometric_stiffness(length_m: float, axial_force_n) -> np.ndarray:
    """Geometric stiffness (12, 12) of an element under an axial force, in beam axes.

    The second-order strain energy of a beam prestressed by the axial force ``N(x)``
    (tension positive) is ``½ ∫ N (v'² + w'²) dx``, with the slopes of the cubic Hermite
    bending fields (``v' = θz``, ``w' = −θy``). Axial, torsional and shear prestress
    terms are left out.

    Args:
        length_m: Element length L [m].
        axial_force_n: Axial force [N]: one number (constant along the element), or its
            values at :data:`GEOMETRIC_POINTS` (shape (..., 5); exact for a force polynomial
            of degree up to 3 along the element), giving matrices (..., 12, 12).

    Returns:
        ``K_G`` (12, 12) or (..., 12, 12) [N/m, N, N m]; for a constant force ``N`` its bending
        blocks are the classical ``N / (30 L) [[36, 3L, −36, 3L], [3L, 4L², −3L, −L²], ...]``.
    """
    slopes = shape_matrix(length_m, _GAUSS_XI)[:, 4:6, :]  # (5, 2, 12): θy, θz
    unit = np.einsum("kai,kaj->kij", slopes, slopes)  # (5, 12, 12)
    force = np.asarray(axial_force_n, dtype=float)
    w = _GAUSS_WXI * float(length_m)
    if force.ndim == 0:
        return float(force) * np.einsum("k,kij->ij", w, unit)
    if force.shape[-1] != _GAUSS_XI.size:
        raise InvalidBeamProperty(
            f"axial_force_n has shape {force.shape}: give one number or the values at the "
            f"{_GAUSS_XI.size} points GEOMETRIC_POINTS"
        )
    return np.einsum("...k,k,kij->...ij", force, w, unit)
