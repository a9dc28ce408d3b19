"""Element matrices against textbook closed forms."""

import numpy as np
import pytest

from pinflex import beam
from pinflex.exceptions import InvalidBeamProperty


def test_bending_stiffness_matches_closed_form():
    """The x–y bending block equals EI/L³ [[12, 6L, -12, 6L], ...]."""
    L, EI = 0.37, 2.3
    K = beam.element_stiffness(L, 1.0, 1.0, 5.0, EI)
    idx = [1, 5, 7, 11]
    ref = EI / L**3 * np.array(
        [[12, 6 * L, -12, 6 * L], [6 * L, 4 * L**2, -6 * L, 2 * L**2],
         [-12, -6 * L, 12, -6 * L], [6 * L, 2 * L**2, -6 * L, 4 * L**2]]
    )
    np.testing.assert_allclose(K[np.ix_(idx, idx)], ref, rtol=1e-13, atol=1e-12)


def test_consistent_mass_matches_closed_form():
    """The x–y bending mass block equals ρAL/420 [[156, 22L, 54, -13L], ...]."""
    L, m = 0.37, 1.9
    M = beam.element_mass(L, m, 0.0)
    idx = [1, 5, 7, 11]
    ref = m * L / 420 * np.array(
        [[156, 22 * L, 54, -13 * L], [22 * L, 4 * L**2, 13 * L, -3 * L**2],
         [54, 13 * L, 156, -22 * L], [-13 * L, -3 * L**2, -22 * L, 4 * L**2]]
    )
    np.testing.assert_allclose(M[np.ix_(idx, idx)], ref, rtol=1e-13, atol=1e-15)
    np.testing.assert_allclose(M[np.ix_([0, 6], [0, 6])], m * L / 6 * np.array([[2, 1], [1, 2]]))


def test_rigid_motions_have_no_strain_energy_and_exact_kinetic_energy():
    """A rigid rotation about z has zero strain energy and kinetic energy m L³/3 ω²/2."""
    L, m = 0.8, 2.0
    K = beam.element_stiffness(L, 3.0, 2.0, 5.0, 7.0)
    M = beam.element_mass(L, m, 0.0)
    u = np.zeros(12)
    u[5] = u[11] = 1.0  # θz at both nodes
    u[7] = L  # v at node b
    assert abs(u @ K @ u) < 1e-10
    assert u @ M @ u == pytest.approx(m * L**3 / 3, rel=1e-13)


def test_sections_derive_properties():
    """Named sections give the textbook area and second moments."""
    s = beam.solid_circle(0.03)
    assert s.A == pytest.approx(7.0686e-4, rel=1e-4)
    assert s.Iz == pytest.approx(3.976e-8, rel=1e-3)
    t = beam.hollow_circle(0.09, 0.08)
    assert t.Iy == pytest.approx(np.pi / 64 * (0.09**4 - 0.08**4))
    r = beam.rectangle(0.02, 0.01)
    assert r.Iy == pytest.approx(0.02 * 0.01**3 / 12) and r.Iz == pytest.approx(0.01 * 0.02**3 / 12)


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan")])
def test_sections_reject_non_positive(bad):
    """Non-positive or non-finite section sizes raise InvalidBeamProperty."""
    with pytest.raises(InvalidBeamProperty):
        beam.solid_circle(bad)
