r"""Beam planforms for pseudo-rigid-body dynamic models (paper 001, Sec. 2.1).

A planform is a polygon symmetric about the beam axis X, extruded to a uniform thickness
``t`` along Z. The beam bends out of plane (about the width axis Y), so the bending second
moment of area of a cross-section is :math:`I(x) = w(x) t^3 / 12` and its area
:math:`A(x) = w(x) t`, with :math:`w(x)` the full width, piecewise linear between vertices.

Modelling choice (recorded here because the paper leaves it open): the planform is treated as
a 1D Euler-Bernoulli beam. Random planforms can be nearly as wide as they are long and can pinch
to a near-hinge; plate effects (anticlastic curvature, the plate modulus
:math:`E/(1-\nu^2)`), shear deformation and torsion are not modelled. Symmetry about X means
bending does not couple to torsion.

Random planforms follow Sec. 2.1: ``p`` sorted uniform abscissae in (0, 1) with 0 and 1
appended, ``p + 2`` uniform half-widths in (0, 1) scaled by ``max_half_width_m``, the curve
reflected about X. The paper's "endpoint (0, 1)" is read as (1, 0): the root half-width is
``Y[0]`` and the tip half-width ``Y[p + 1]``. The default ``max_half_width_m = 0.5`` keeps the
width below the paper's 1 m panel limit.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from pinflex.linalg import readonly as _readonly
from pinflex.materials import Material

from ..exceptions import InvalidBeam

_GAUSS3_X, _GAUSS3_W = np.polynomial.legendre.leggauss(3)
_GAUSS3_UNIT = 0.5 * (_GAUSS3_X + 1.0)      # nodes on [0, 1]
_GAUSS3_HALF_W = 0.5 * _GAUSS3_W            # weights on [0, 1]


STEEL = Material(E=205e9, density=7850.0, name="steel")
"""Paper 001's steel (E = 205 GPa, 7850 kg/m^3): the PRBDM default; its G is not used (the
planform bends out of plane only)."""



@dataclass(frozen=True)
class Planform:
    """A symmetric beam planform of uniform thickness, clamped at x = 0.

    Attributes:
        x_m: Vertex abscissae along the beam, shape (p + 2,), strictly increasing from 0 [m].
        half_width_m: Half-width at each vertex, shape (p + 2,), positive [m].
        thickness_m: Uniform thickness t along Z [m].
        material: Beam material.
        name: Label used in reports.
        thickness_profile_m: Optional thickness at each vertex, linear in between (a depth
            taper) [m]; ``thickness_m`` is then the root thickness. None: uniform.

    Tapers to zero: the tip vertex (only) may have zero half-width or zero thickness (a wedge
    or a pointed planform). The reference solutions of :mod:`pinflex.prbdm.truth` accept
    such beams and depth tapers; the nR chains (:func:`chain_segments`) need a uniform
    thickness and a positive width and refuse the rest.
    """

    x_m: np.ndarray
    half_width_m: np.ndarray
    thickness_m: float
    material: Material = STEEL
    name: str = ""
    thickness_profile_m: np.ndarray | None = None

    def __post_init__(self) -> None:
        x = np.asarray(self.x_m, dtype=float)
        y = np.asarray(self.half_width_m, dtype=float)
        _validate_planform(x, y, self.thickness_m)
        if not isinstance(self.material, Material) or self.material.density is None:
            raise InvalidBeam(
                "material must be a pinflex.Material with a volumetric density [kg/m^3] (the "
                f"planform's mass follows its width), got {self.material!r}")
        object.__setattr__(self, "x_m", _readonly(x))
        object.__setattr__(self, "half_width_m", _readonly(y))
        if self.thickness_profile_m is not None:
            t = np.asarray(self.thickness_profile_m, dtype=float)
            if t.shape != x.shape or not np.all(np.isfinite(t)) or np.any(t[:-1] <= 0.0) \
                    or t[-1] < 0.0:
                raise InvalidBeam(
                    "thickness_profile_m needs one finite thickness per vertex, positive "
                    f"except possibly zero at the tip; got {np.round(t, 6).tolist()}")
            if abs(t[0] - self.thickness_m) > 1e-12 * self.thickness_m:
                raise InvalidBeam(f"thickness_m = {self.thickness_m!r} must equal the root "
                                  f"thickness of the profile, {t[0]!r}")
            object.__setattr__(self, "thickness_profile_m", _readonly(t))

    @property
    def uniform_thickness(self) -> bool:
        """Whether the thickness is the same everywhere."""
        t = self.thickness_profile_m
        return t is None or bool(np.all(t == t[0]))

    def _require_chain_ready(self) -> None:
        if not self.uniform_thickness or self.half_width_m[-1] <= 0.0:
            raise InvalidBeam(
                "nR chains need a planform of uniform thickness and positive width; this beam "
                "(a depth taper or a zero tip width) is supported by the reference solutions "
                "only")

    @cached_property
    def _cumulative_integrals(self) -> np.ndarray:
        """Integrals from 0 to each vertex of (w, w x, w x^2, w^3, 1/I), shape (p + 2, 5)."""
        a, b = self.x_m[:-1, None], self.x_m[1:, None]
        q = 0.5 * (a + b) + 0.5 * (b - a) * _GAUSS3_X
        w = self.width_m(q)
        gw = 0.5 * (b - a) * _GAUSS3_W
        moments = self.area_moment_m4(self.x_m)
        pieces = np.column_stack([
            (gw * w).sum(1), (gw * w * q).sum(1), (gw * w * q * q).sum(1), (gw * w**3).sum(1),
            np.diff(self.x_m) * _log_mean_inverse(moments[:-1], moments[1:]),
        ])
        table = np.vstack([np.zeros((1, 5)), np.cumsum(pieces, axis=0)])
        table.setflags(write=False)
        return table

    @cached_property
    def _pieces(self) -> np.ndarray:
        """Per planform piece: left abscissa, full width there and width slope, (p + 1, 3)."""
        x, w = self.x_m, 2.0 * self.half_width_m
        table = np.column_stack([x[:-1], w[:-1], (w[1:] - w[:-1]) / (x[1:] - x[:-1])])
        table.setflags(write=False)
        return table

    @property
    def length_m(self) -> float:
        """Beam length L [m]."""
        return float(self.x_m[-1])

    @property
    def n_sections(self) -> int:
        """Number of interior vertices p (the paper's section count)."""
        return int(self.x_m.size - 2)

    def width_m(self, s: np.ndarray | float) -> np.ndarray:
        """Full width w(s) at abscissae s [m].

        Args:
            s: Abscissae along the beam axis from the root, a number or an array of any shape [m];
                linear interpolation between vertices.

        Returns:
            Width [m], the shape of ``s``.
        """
        return 2.0 * np.interp(s, self.x_m, self.half_width_m)

    def thickness_at(self, s: np.ndarray | float) -> np.ndarray:
        """Thickness t(s) at abscissae s [m].

        Args:
            s: Abscissae along the beam axis from the root, a number or an array of any shape [m];
                linear interpolation between vertices.

        Returns:
            Thickness [m], the shape of ``s`` (constant without a thickness profile).
        """
        if self.thickness_profile_m is None:
            return np.full(np.shape(s), float(self.thickness_m))
        return np.interp(s, self.x_m, self.thickness_profile_m)

    def area_m2(self, s: np.ndarray | float) -> np.ndarray:
        """Cross-section area A(s) = w(s) t(s) [m^2].

        Args:
            s: Abscissae along the beam axis from the root, a number or an array of any shape [m];
                linear interpolation between vertices.

        Returns:
            Area [m^2], the shape of ``s``.
        """
        if self.thickness_profile_m is None:
            return self.width_m(s) * self.thickness_m
        return self.width_m(s) * self.thickness_at(s)

    def area_moment_m4(self, s: np.ndarray | float) -> np.ndarray:
        """Out-of-plane bending second moment of area I(s) = w(s) t(s)^3 / 12 [m^4].

        Args:
            s: Abscissae along the beam axis from the root, a number or an array of any shape [m];
                linear interpolation between vertices.

        Returns:
            Second moment of area [m^4], the shape of ``s``.
        """
        if self.thickness_profile_m is None:
            return self.width_m(s) * self.thickness_m**3 / 12.0
        return self.width_m(s) * self.thickness_at(s) ** 3 / 12.0

    def outline_m(self) -> np.ndarray:
        """Closed planform polygon, shape (2 (p + 2) + 1, 2), counter-clockwise [m]."""
        lower = np.column_stack([self.x_m, -self.half_width_m])
        upper = np.column_stack([self.x_m[::-1], self.half_width_m[::-1]])
        return np.vstack([lower, upper, lower[:1]])


def _validate_planform(x: np.ndarray, y: np.ndarray, thickness_m: float) -> None:
    if x.ndim != 1 or y.ndim != 1 or x.shape != y.shape:
        raise InvalidBeam(
            f"x_m has shape {x.shape} and half_width_m has shape {y.shape}; both must be 1D "
            "arrays of the same length (one half-width per vertex)"
        )
    if x.size < 2:
        raise InvalidBeam(f"a planform needs at least 2 vertices (root and tip), got {x.size}")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise InvalidBeam("planform vertices and half-widths must be finite numbers")
    if x[0] != 0.0:
        raise InvalidBeam(f"the first vertex must be the clamped root at x = 0, got {x[0]:g} m")
    steps = np.diff(x)
    if np.any(steps <= 0.0):
        bad = int(np.argmin(steps))
        raise InvalidBeam(
            f"vertex abscissae must be strictly increasing; x[{bad}] = {x[bad]:g} m and "
            f"x[{bad + 1}] = {x[bad + 1]:g} m (a zero-length beam or section); "
            "remove or merge repeated vertices"
        )
    if np.any(y[:-1] <= 0.0) or y[-1] < 0.0:
        bad = int(np.argmin(y))
        raise InvalidBeam(
            f"half-widths must be positive (zero is allowed at the tip only); "
            f"half_width_m[{bad}] = {y[bad]:g} m; a zero width inside the beam is a hinge that "
            "a beam model cannot represent"
        )
    if not np.isfinite(thickness_m) or thickness_m <= 0.0:
        raise InvalidBeam(f"thickness_m = {thickness_m!r} must be a finite positive number [m]")


def uniform_beam(length_m: float = 1.0, width_m: float = 0.3624, thickness_m: float = 0.040532,
                 material: Material = STEEL) -> Planform:
    """Rectangular planform; the defaults are paper 001's uniform steel test beam.

    Args:
        length_m: Beam length L [m].
        width_m: Full width [m].
        thickness_m: Thickness t [m].
        material: Beam material.

    Returns:
        The planform, with two vertices.

    Raises:
        InvalidBeam: If a dimension is not a finite positive number.
    """
    for label, value in (("length_m", length_m), ("width_m", width_m)):
        if not np.isfinite(value) or value <= 0.0:
            raise InvalidBeam(f"{label} = {value!r} must be a finite positive number [m]")
    return Planform(np.array([0.0, length_m]), np.full(2, 0.5 * width_m), thickness_m,
                    material, name="uniform")


def random_beam(seed: int, n_sections: int = 10, length_m: float = 1.0,
                max_half_width_m: float = 0.5, thickness_m: float = 0.040532,
                material: Material = STEEL) -> Planform:
    """Seeded random planform of paper 001, Sec. 2.1.

    Args:
        seed: Seed of ``numpy.random.default_rng``.
        n_sections: Number p of random interior vertices (the paper uses p = 10).
        length_m: Beam length L [m]; the unit abscissae are scaled by it.
        max_half_width_m: Scale of the unit half-widths [m].
        thickness_m: Thickness t [m].
        material: Beam material.

    Returns:
        The planform with p + 2 vertices.

    Raises:
        InvalidBeam: If p is negative or a dimension is not a finite positive number.
    """
    if int(n_sections) != n_sections or n_sections < 0:
        raise InvalidBeam(f"n_sections = {n_sections!r} must be a non-negative integer")
    for label, value in (("length_m", length_m), ("max_half_width_m", max_half_width_m)):
        if not np.isfinite(value) or value <= 0.0:
            raise InvalidBeam(f"{label} = {value!r} must be a finite positive number [m]")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or seed < 0:
        raise InvalidBeam(f"seed = {seed!r} must be a non-negative integer")
    rng = np.random.default_rng(seed)
    interior = np.sort(rng.uniform(0.0, 1.0, int(n_sections)))
    x = np.concatenate([[0.0], interior, [1.0]]) * length_m
    y = rng.uniform(0.0, 1.0, int(n_sections) + 2) * max_half_width_m
    return Planform(x, y, thickness_m, material, name=f"random(seed={seed}, p={n_sections})")


@dataclass(frozen=True)
class SegmentProperties:
    """Rigid-body and bending properties of the beam between two abscissae.

    Attributes:
        start_m: Segment start along the beam [m].
        end_m: Segment end along the beam [m].
        mass_kg: Mass [kg].
        com_m: Centre of mass abscissa along the beam (absolute) [m].
        inertia_com_kg_m2: Principal rotational inertias about the centre of mass,
            (Ixx, Iyy, Izz) with x along the beam and y the bending axis [kg m^2].
        mean_area_moment_m4: Length-averaged bending second moment of area [m^4].
        compliance_1_n_m: Series bending compliance int dx / (E I(x)) [1/(N m)].
    """

    start_m: float
    end_m: float
    mass_kg: float
    com_m: float
    inertia_com_kg_m2: tuple[float, float, float]
    mean_area_moment_m4: float
    compliance_1_n_m: float


def _log_mean_inverse(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Mean of 1/v over a segment where v varies linearly from a to b."""
    ratio = b / a
    close = np.abs(ratio - 1.0) < 1e-6
    if not close.any():
        return np.log(ratio) / (b - a)
    safe = np.where(close, 2.0, ratio)
    exact = np.log(safe) / np.where(close, 1.0, b - a)
    u = ratio - 1.0
    series = (1.0 - u / 2.0 + u * u / 3.0) / a
    return np.where(close, series, exact)


def _partial_integrals(planform: Planform, s_m: np.ndarray) -> np.ndarray:
    """Integrals from 0 to each s of (w, w x, w x^2, w^3, 1/I), shape (len(s), 5).

    Whole planform pieces come from a cumulative table; the last partial piece is integrated
    exactly (3-point Gauss for the polynomials, the logarithmic mean for 1/I). The width is
    linear on the piece, so it is evaluated from the piece's end values directly.
    """
    return partial_integrals_and_widths(planform, s_m)[0]


def partial_integrals_and_widths(planform: Planform,
                                  s_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`_partial_integrals` and the full widths w(s) [m] found on the way."""
    x = planform.x_m
    # s = L belongs to the last piece.
    piece = np.minimum(np.maximum(x.searchsorted(s_m, "right") - 1, 0), x.size - 2)
    table = planform._cumulative_integrals
    left, w_left, slope = planform._pieces[piece].T
    span = s_m - left
    offset = span[:, None] * _GAUSS3_UNIT
    q = left[:, None] + offset
    w = w_left[:, None] + slope[:, None] * offset
    gww = (span[:, None] * _GAUSS3_HALF_W) * w
    cubed = planform.thickness_m**3 / 12.0
    w_end = w_left + slope * span
    if planform.thickness_profile_m is None:
        i_left, i_right = w_left * cubed, w_end * cubed
    else:
        i_left, i_right = planform.area_moment_m4(left), planform.area_moment_m4(s_m)
    out = np.empty((s_m.size, 5))
    gwq = gww * q
    out[:, 0] = gww.sum(1)
    out[:, 1] = gwq.sum(1)
    out[:, 2] = (gwq * q).sum(1)
    out[:, 3] = (gww * w * w).sum(1)
    out[:, 4] = span * _log_mean_inverse(i_left, i_right)
    return table[piece] + out, w_end


def compliance_between(planform: Planform, bounds_m: np.ndarray) -> np.ndarray:
    """Bending compliances int dx / EI of consecutive segments of trusted bounds [1/(N m)]."""
    x = planform.x_m
    s_m = np.asarray(bounds_m, dtype=float)
    piece = np.minimum(np.maximum(x.searchsorted(s_m, "right") - 1, 0), x.size - 2)
    left, w_left, slope = planform._pieces[piece].T
    span = s_m - left
    if planform.thickness_profile_m is None:
        cubed = planform.thickness_m**3 / 12.0
        i_left, i_right = w_left * cubed, (w_left + slope * span) * cubed
    else:
        i_left, i_right = planform.area_moment_m4(left), planform.area_moment_m4(s_m)
    inv = planform._cumulative_integrals[piece, 4] + span * _log_mean_inverse(i_left, i_right)
    return (inv[1:] - inv[:-1]) / planform.material.youngs_modulus_pa


def chain_segments(planform: Planform, bounds_m: np.ndarray) -> list[SegmentProperties]:
    """Properties of consecutive segments [b0, b1], [b1, b2], ... in one vectorised pass.

    Integrals are exact: the width is linear between vertices, so the mass moments are
    piecewise polynomials (3-point Gauss on each piece) and the compliance uses the exact
    logarithmic mean of 1/I; segment values are differences of cumulative integrals.

    Args:
        planform: The beam.
        bounds_m: Increasing segment boundaries inside [0, L], shape (k + 1,) [m].

    Returns:
        One :class:`SegmentProperties` per segment.

    Raises:
        InvalidBeam: If the boundaries are not increasing or leave the beam.
    """
    planform._require_chain_ready()
    bounds = np.asarray(bounds_m, dtype=float)
    length = planform.length_m
    if bounds.ndim != 1 or bounds.size < 2 or np.any(np.diff(bounds) <= 0.0) \
            or bounds[0] < 0.0 or bounds[-1] > length * (1.0 + 1e-12):
        raise InvalidBeam(f"segment bounds {np.round(bounds, 9).tolist()} must increase "
                          f"strictly inside [0, L = {length:g}] m")
    bounds = np.minimum(bounds, length)
    arrays = segment_arrays(planform, bounds)
    mass, com, ixx, iyy, izz, mean_i, comp = arrays
    return [SegmentProperties(float(bounds[k]), float(bounds[k + 1]), float(mass[k]),
                              float(com[k]), (float(ixx[k]), float(iyy[k]), float(izz[k])),
                              float(mean_i[k]), float(comp[k]))
            for k in range(bounds.size - 1)]


def segment_arrays(planform: Planform, bounds_m: np.ndarray) -> tuple[np.ndarray, ...]:
    """Array form of :func:`chain_segments` for trusted, increasing bounds (no checks).

    ``bounds_m`` may carry leading dimensions (several designs at once, shape (..., k + 1)).

    Returns:
        (mass, com, ixx, iyy, izz, mean_area_moment, compliance), each shape (..., k).
    """
    bounds = np.asarray(bounds_m, dtype=float)
    cumulative = _partial_integrals(planform, bounds.ravel()).reshape(bounds.shape + (5,))
    m0, m1, m2, w3, inv_i = np.moveaxis(cumulative[..., 1:, :] - cumulative[..., :-1, :], -1, 0)
    t = planform.thickness_m
    rho_t = planform.material.density_kg_m3 * t
    mass = rho_t * m0
    com = m1 / m0
    bending = rho_t * (m2 - com * m1)
    ixx = rho_t * (w3 + t**2 * m0) / 12.0
    iyy = bending + mass * t**2 / 12.0
    izz = bending + rho_t * w3 / 12.0
    mean_i = m0 * t**3 / 12.0 / np.diff(bounds, axis=-1)
    comp = inv_i / planform.material.youngs_modulus_pa
    return mass, com, ixx, iyy, izz, mean_i, comp


def segment_properties(planform: Planform, start_m: float, end_m: float) -> SegmentProperties:
    """Mass, centre of mass, rotational inertia and bending compliance of one beam segment.

    Args:
        planform: The beam.
        start_m: Segment start [m], 0 <= start < end.
        end_m: Segment end [m], end <= L.

    Returns:
        The segment's properties (see :func:`chain_segments`).

    Raises:
        InvalidBeam: If the segment is empty or leaves the beam.
    """
    return chain_segments(planform, np.array([start_m, end_m]))[0]


def equivalent_bending_stiffness(planform: Planform) -> float:
    r"""Uniform EI with the same linear tip compliance under a transverse tip force [N m^2].

    :math:`EI_{eq} = L^3 / (3 \int_0^L (L - x)^2 / EI(x)\, dx)`; equal to EI for a uniform beam.
    It scales tip loads of non-uniform beams: :math:`\alpha = P L^2 / EI_{eq}`.
    """
    length = planform.length_m
    x1, x2 = planform.x_m[:-1], planform.x_m[1:]
    i1, i2 = planform.area_moment_m4(x1), planform.area_moment_m4(x2)
    h = x2 - x1
    k = (i2 - i1) / h
    near = np.abs(i2 / i1 - 1.0) < 0.05
    k_safe = np.where(near, 1.0, k)
    d = (length - x1) * k_safe + i1
    exact = (d**2 * np.log(i2 / i1) - 2.0 * d * (i2 - i1) + 0.5 * (i2**2 - i1**2)) / k_safe**3
    x_gauss, w_gauss = np.polynomial.legendre.leggauss(12)
    s = 0.5 * (x1 + x2)[:, None] + 0.5 * h[:, None] * x_gauss
    gauss = np.sum(0.5 * h[:, None] * w_gauss * (length - s) ** 2
                   / planform.area_moment_m4(s), axis=1)
    integral = np.sum(np.where(near, gauss, exact)) / planform.material.youngs_modulus_pa
    return float(length**3 / (3.0 * integral))
