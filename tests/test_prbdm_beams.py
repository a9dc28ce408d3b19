"""Tests of pinflex.prbdm.beams: planforms, segment properties, input validation."""

import numpy as np
import pytest

from pinflex.exceptions import InvalidBeam, InvalidBeamProperty
from pinflex.prbdm.beams import (
    STEEL,
    Planform,
    chain_segments,
    equivalent_bending_stiffness,
    random_beam,
    segment_properties,
    uniform_beam,
)


def test_uniform_segment_matches_rectangle_formulas():
    """A rectangular segment has m = rho b t l, CoM at its middle and Iyy = m (l^2 + t^2) / 12."""
    beam = uniform_beam()
    b, t = 0.3624, 0.040532
    seg = segment_properties(beam, 0.2, 0.7)
    mass = 7850.0 * b * t * 0.5
    assert seg.mass_kg == pytest.approx(mass, rel=1e-13)
    assert seg.com_m == pytest.approx(0.45, rel=1e-13)
    assert seg.inertia_com_kg_m2[1] == pytest.approx(mass * (0.5**2 + t**2) / 12, rel=1e-12)
    assert seg.inertia_com_kg_m2[0] == pytest.approx(mass * (b**2 + t**2) / 12, rel=1e-12)
    ei = 205e9 * b * t**3 / 12
    assert seg.compliance_1_n_m == pytest.approx(0.5 / ei, rel=1e-13)


def test_trapezoid_segment_matches_closed_forms():
    """A linearly tapered planform has the trapezoid's mass, centroid and log-mean compliance."""
    beam = Planform(np.array([0.0, 2.0]), np.array([0.3, 0.1]), 0.01, STEEL)
    seg = segment_properties(beam, 0.0, 2.0)
    w0, w1, length = 0.6, 0.2, 2.0
    assert seg.mass_kg == pytest.approx(7850 * 0.01 * length * (w0 + w1) / 2, rel=1e-13)
    assert seg.com_m == pytest.approx(length * (w0 + 2 * w1) / (3 * (w0 + w1)), rel=1e-13)
    i0, i1 = w0 * 1e-6 / 12, w1 * 1e-6 / 12
    compliance = length * np.log(i0 / i1) / (i0 - i1) / 205e9
    assert seg.compliance_1_n_m == pytest.approx(compliance, rel=1e-12)


def test_chain_segments_add_up_to_whole_beam():
    """Masses and first moments of consecutive segments sum to the whole random planform's."""
    beam = random_beam(3)
    whole = segment_properties(beam, 0.0, beam.length_m)
    parts = chain_segments(beam, np.array([0.0, 0.13, 0.4, 0.41, 0.77, 1.0]))
    assert sum(p.mass_kg for p in parts) == pytest.approx(whole.mass_kg, rel=1e-13)
    assert sum(p.mass_kg * p.com_m for p in parts) == pytest.approx(
        whole.mass_kg * whole.com_m, rel=1e-13)
    assert sum(p.compliance_1_n_m for p in parts) == pytest.approx(whole.compliance_1_n_m,
                                                                   rel=1e-12)


def test_equivalent_stiffness_of_uniform_beam_is_ei():
    """The tip-compliance-equivalent EI of a uniform beam is its own EI."""
    beam = uniform_beam()
    assert equivalent_bending_stiffness(beam) == pytest.approx(
        205e9 * 0.3624 * 0.040532**3 / 12, rel=1e-13)


def test_equivalent_stiffness_matches_quadrature_on_random_beam():
    """The closed-form tip compliance of a random planform matches dense Gauss quadrature."""
    beam = random_beam(5)
    x, w = np.polynomial.legendre.leggauss(200)
    total = 0.0
    for a, b in zip(beam.x_m[:-1], beam.x_m[1:]):
        s = 0.5 * (a + b) + 0.5 * (b - a) * x
        total += np.sum(0.5 * (b - a) * w * (1.0 - s) ** 2 / (205e9 * beam.area_moment_m4(s)))
    assert equivalent_bending_stiffness(beam) == pytest.approx(1.0 / (3.0 * total), rel=1e-10)


def test_random_beam_is_seeded_and_follows_section_2_1():
    """Same seed, same planform; p + 2 sorted vertices from 0 to L, half-widths in (0, 0.5) m."""
    a, b = random_beam(11), random_beam(11)
    assert np.array_equal(a.x_m, b.x_m) and np.array_equal(a.half_width_m, b.half_width_m)
    assert a.x_m.size == 12 and a.x_m[0] == 0.0 and a.x_m[-1] == 1.0
    assert np.all(np.diff(a.x_m) > 0.0)
    assert np.all((a.half_width_m > 0.0) & (a.half_width_m < 0.5))
    assert not np.array_equal(random_beam(12).half_width_m, a.half_width_m)


def test_outline_is_closed_and_symmetric():
    """The planform polygon closes on itself and is symmetric about the beam axis."""
    outline = random_beam(2).outline_m()
    assert np.array_equal(outline[0], outline[-1])
    assert sorted(outline[:-1, 1]) == pytest.approx(sorted(-outline[:-1, 1]))


def test_negative_thickness_raises():
    """A non-positive thickness raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="thickness"):
        uniform_beam(thickness_m=-0.01)


def test_zero_width_raises():
    """A zero half-width (a true hinge) raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="half-widths must be positive"):
        Planform(np.array([0.0, 0.5, 1.0]), np.array([0.1, 0.0, 0.1]), 0.01)


def test_repeated_vertex_raises():
    """Repeated vertex abscissae (a zero-length section) raise InvalidBeam."""
    with pytest.raises(InvalidBeam, match="strictly increasing"):
        Planform(np.array([0.0, 0.5, 0.5, 1.0]), np.full(4, 0.1), 0.01)


def test_zero_length_beam_raises():
    """A beam of zero length raises InvalidBeam (an InvalidBeamProperty)."""
    with pytest.raises(InvalidBeamProperty):
        uniform_beam(length_m=0.0)


def test_root_not_at_origin_raises():
    """A first vertex away from x = 0 raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="root"):
        Planform(np.array([0.1, 1.0]), np.full(2, 0.1), 0.01)


def test_mismatched_arrays_raise():
    """Different numbers of abscissae and half-widths raise InvalidBeam."""
    with pytest.raises(InvalidBeam, match="same length"):
        Planform(np.array([0.0, 0.5, 1.0]), np.full(2, 0.1), 0.01)


def test_non_finite_width_raises():
    """A NaN half-width raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="finite"):
        Planform(np.array([0.0, 1.0]), np.array([0.1, np.nan]), 0.01)


def test_negative_section_count_raises():
    """A negative number of random sections raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="n_sections"):
        random_beam(0, n_sections=-1)


def test_segment_outside_beam_raises():
    """A segment leaving the beam raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="segment"):
        segment_properties(uniform_beam(), 0.5, 1.5)
