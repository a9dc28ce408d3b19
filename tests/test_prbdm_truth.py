"""Tests of pinflex.prbdm.truth: converged beam frequencies and the elastica."""

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from pinflex.exceptions import InvalidBeam, TruthNotConverged
from pinflex.prbdm.beams import equivalent_bending_stiffness, random_beam, uniform_beam
from pinflex.prbdm.truth import beam_frequencies, beam_mesh, elastica_tip, fe_eigenvalues

BETA_L = np.array([1.875104, 4.694091, 7.854757, 10.995541, 14.137168])
MATTIASSON = [(1.0, 0.30172, 0.05643), (2.0, 0.49346, 0.16064), (5.0, 0.71379, 0.38763),
              (10.0, 0.81061, 0.55500)]


def _uniform_reference_hz():
    beam = uniform_beam()
    ei = 205e9 * float(beam.area_moment_m4(0.0))
    rho_a = 7850.0 * float(beam.area_m2(0.0))
    return beam, ei, BETA_L**2 * np.sqrt(ei / rho_a) / (2.0 * np.pi)


def _shooting_hz(beam, guesses_hz):
    """Independent reference: shoot the ODE (EI w'')'' = omega^2 rho A w, clamped-free."""
    e, rho = beam.material.youngs_modulus_pa, beam.material.density_kg_m3
    ei0 = e * float(beam.area_moment_m4(0.0))

    def det(omega):
        def rhs(s, y):
            y = y.reshape(4, 2)
            return np.concatenate([y[1], y[2] / (e * beam.area_moment_m4(s)), y[3],
                                   omega**2 * rho * beam.area_m2(s) * y[0]])

        y = np.array([0, 0, 0, 0, ei0, 0, 0, ei0], dtype=float)
        for a, b in zip(beam.x_m[:-1], beam.x_m[1:]):
            y = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-12, atol=1e-14).y[:, -1]
        y = y.reshape(4, 2)
        return y[2, 0] * y[3, 1] - y[2, 1] * y[3, 0]

    return np.array([brentq(det, 2 * np.pi * f * (1 - 2e-3), 2 * np.pi * f * (1 + 2e-3),
                            xtol=1e-12 * f) / (2 * np.pi) for f in guesses_hz])


def test_uniform_frequencies_match_beta_l_roots():
    """Converged FE frequencies of the uniform beam are within 1e-6 of the beta-L closed form."""
    beam, _, exact = _uniform_reference_hz()
    modes = beam_frequencies(beam, 5)
    assert np.max(np.abs(modes.freq_hz / exact - 1.0)) < 1e-6


def test_hermite_eigenvalues_converge_at_fourth_order():
    """Halving the elements divides the eigenvalue error by about 16 (observed order 4)."""
    modes = beam_frequencies(uniform_beam(), 5)
    assert modes.observed_order[1:] == pytest.approx(4.0, abs=0.05)


def test_direct_formulation_loses_digits_as_mesh_grows():
    """K phi = lambda M phi loses accuracy on refinement; relative coordinates do not."""
    beam, _, exact = _uniform_reference_hz()

    def err(n_el, form):
        lam = fe_eigenvalues(beam, np.linspace(0.0, 1.0, n_el + 1), 1, form)[0]
        return abs(np.sqrt(lam) / (2 * np.pi) / exact[0] - 1.0)

    assert err(50, "stiffness") < 2e-7
    assert err(800, "stiffness") > 1e-4
    assert err(800, "stiffness") > 100 * err(50, "stiffness")
    assert err(800, "relative") < 2e-7


def test_round_off_dominated_mesh_is_detected():
    """A fine mesh with the direct formulation fails the extrapolation check with a named error."""
    with pytest.raises(TruthNotConverged, match="not converged"):
        beam_frequencies(uniform_beam(), 5, max_element_m=1 / 200, formulation="stiffness")


def test_graded_mesh_keeps_vertices_and_bounds_stiffness_ratio():
    """Mesh nodes include every vertex, and EI varies by at most the allowed ratio per element."""
    beam = random_beam(0)
    nodes = beam_mesh(beam, 1 / 32, max_stiffness_ratio=1.5)
    assert np.all(np.isin(beam.x_m, nodes))
    inertia = beam.area_moment_m4(nodes)
    ratio = np.maximum(inertia[1:] / inertia[:-1], inertia[:-1] / inertia[1:])
    assert ratio.max() <= 1.5 + 1e-9
    assert np.diff(nodes).max() <= 1 / 32 + 1e-12


def test_random_beam_frequencies_match_ode_shooting():
    """On a random planform, FE frequencies agree with an independent ODE shooting solution."""
    beam = random_beam(7)
    modes = beam_frequencies(beam, 3)
    assert modes.rel_error_estimate.max() < 1e-7
    reference = _shooting_hz(beam, modes.freq_hz)
    assert np.max(np.abs(modes.freq_hz / reference - 1.0)) < 1e-8


def test_pinched_random_beam_converges_at_fourth_order():
    """Graded meshes keep fourth-order convergence on a planform that pinches to a near-hinge."""
    beam = random_beam(0)
    assert beam.half_width_m.min() < 0.002
    modes = beam_frequencies(beam, 5)
    assert modes.observed_order == pytest.approx(4.0, abs=0.1)


@pytest.mark.parametrize("alpha, w_ref, u_ref", MATTIASSON)
def test_elastica_matches_mattiasson_table(alpha, w_ref, u_ref):
    """Elastica tip deflection and shortening equal Mattiasson's table to its printed digits."""
    beam, ei, _ = _uniform_reference_hz()
    sol = elastica_tip(beam, np.array([0.0, -alpha * ei]))
    assert round(-sol.tip_m[1], 5) == pytest.approx(w_ref, abs=1e-12)
    assert round(1.0 - sol.tip_m[0], 5) == pytest.approx(u_ref, abs=1e-12)


def test_elastica_tip_rotation_at_alpha_one():
    """The tip rotation at alpha = 1 is 0.46135 rad."""
    beam, ei, _ = _uniform_reference_hz()
    assert round(elastica_tip(beam, np.array([0.0, -ei])).tip_rotation_rad, 5) == 0.46135


def test_elastica_small_load_matches_linear_theory_on_random_beam():
    """For a tiny load the elastica tip deflection equals P L^3 / (3 EI_eq)."""
    beam = random_beam(4)
    force = 1e-5 * equivalent_bending_stiffness(beam)
    sol = elastica_tip(beam, np.array([0.0, -force]))
    linear = force / (3.0 * equivalent_bending_stiffness(beam))
    assert -sol.tip_m[1] == pytest.approx(linear, rel=1e-4)


def test_elastica_rejects_bad_force():
    """A force that is not a finite 2-vector raises InvalidBeam."""
    with pytest.raises(InvalidBeam, match="force_n"):
        elastica_tip(uniform_beam(), np.array([0.0, np.inf]))


def _elliptic_cantilever(alpha):
    """Closed-form elastica of a uniform cantilever under a transverse dead tip load.

    With k^2 = (1 + sin phi_L)/2 and sin phi_1 = 1/(k sqrt 2), the load satisfies
    sqrt(alpha) = K(k) - F(phi_1, k); the tip sits at x/L = sqrt(2 sin phi_L / alpha) and
    w/L = 1 - 2 (E(k) - E(phi_1, k)) / sqrt(alpha) (scipy's parameter m = k^2).
    """
    from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

    def phi1(m):
        return np.arcsin(1.0 / np.sqrt(2.0 * m))

    def load(m):
        return ellipk(m) - ellipkinc(phi1(m), m) - np.sqrt(alpha)

    m = brentq(load, 0.5 + 1e-15, 1.0 - 1e-16, xtol=1e-16, rtol=1e-15)
    sin_tip = 2.0 * m - 1.0
    x = np.sqrt(2.0 * sin_tip / alpha)
    w = 1.0 - 2.0 * (ellipe(m) - ellipeinc(phi1(m), m)) / np.sqrt(alpha)
    return x, w, np.arcsin(sin_tip)


@pytest.mark.parametrize("alpha", [40.0, 100.0, 200.0])
def test_elastica_follows_stable_branch_to_alpha_200(alpha):
    """At large loads the elastica stays on the stable branch of the elliptic closed form."""
    beam, ei, _ = _uniform_reference_hz()
    sol = elastica_tip(beam, np.array([0.0, -alpha * ei]))
    x, w, phi = _elliptic_cantilever(alpha)
    assert sol.tip_m[0] == pytest.approx(x, abs=1e-9)
    assert -sol.tip_m[1] == pytest.approx(w, abs=1e-9)
    assert sol.tip_rotation_rad == pytest.approx(phi, abs=1e-9)
    # Root moment of the dead load P about the clamp is P times the tip's axial position.
    assert sol.root_moment_nm == pytest.approx(alpha * ei * x, rel=1e-9)


def test_elastica_refuses_unstable_straight_column():
    """An axial compression above the Euler load has no stable answer on the loading path."""
    beam, ei, _ = _uniform_reference_hz()
    with pytest.raises(TruthNotConverged):
        elastica_tip(beam, np.array([-4.0 * ei, 0.0]))


def _tapered(width_tip, thickness_tip):
    """A 1 m steel cantilever whose width and/or thickness fall linearly to the tip values."""
    from pinflex.prbdm.beams import Planform

    return Planform(np.array([0.0, 1.0]), np.array([0.15, 0.5 * width_tip]), 0.04,
                    thickness_profile_m=np.array([0.04, thickness_tip]))


def _omega(beam, freq_hz):
    """Frequency parameter omega L^2 sqrt(rho A_root / EI_root)."""
    ei0 = 205e9 * float(beam.area_moment_m4(0.0))
    return 2 * np.pi * np.asarray(freq_hz) * np.sqrt(7850.0 * float(beam.area_m2(0.0)) / ei0)


def test_depth_taper_to_zero_is_kirchhoffs_wedge():
    """A wedge (depth linear to zero, constant width) has Kirchhoff's frequencies.

    With xi = 1 - x/L the modes solve (xi^3 w'')'' = Omega^2 xi w; the solutions regular at the
    sharp tip are z^-1 J1(z), z^-1 I1(z) with z = 2 sqrt(Omega xi), and the clamp gives
    J1(z) I2(z) + I1(z) J2(z) = 0 (Omega_1 = 5.3151).
    """
    from scipy.special import iv, jv

    def clamp(z):
        return jv(1, z) * iv(2, z) + iv(1, z) * jv(2, z)

    grid = np.arange(0.5, 20.0, 0.25)
    roots = [brentq(clamp, a, a + 0.25, xtol=1e-15) for a in grid if clamp(a) * clamp(a + 0.25) < 0]
    exact = np.array(roots[:3]) ** 2 / 4.0
    assert exact[0] == pytest.approx(5.3151, abs=1e-4)
    beam = _tapered(0.3, 0.0)
    np.testing.assert_allclose(_omega(beam, beam_frequencies(beam, 3).freq_hz), exact, rtol=1e-8)


def test_width_taper_to_zero_matches_power_series():
    """A pointed planform (width linear to zero, constant depth) against its power series.

    (xi w'')'' = Omega^2 xi w has the solutions regular at the free tip
    w = sum a_k xi^k with a_2 = a_3 = 0 and a_{j+3} (j+3)(j+2)^2(j+1) = Omega^2 a_{j-1};
    the clamp at xi = 1 is a 2 x 2 determinant in (a_0, a_1).
    """
    def clamp(omega):
        def series(a0, a1):
            a = np.zeros(80)
            a[0], a[1] = a0, a1
            for j in range(1, 77):
                a[j + 3] = omega**2 * a[j - 1] / ((j + 3) * (j + 2) ** 2 * (j + 1))
            k = np.arange(80)
            return a.sum(), (k * a).sum()

        (w0, d0), (w1, d1) = series(1.0, 0.0), series(0.0, 1.0)
        return w0 * d1 - w1 * d0

    grid = np.arange(1.0, 80.0, 0.5)
    exact = np.array([brentq(clamp, a, a + 0.5, xtol=1e-14) for a in grid
                      if clamp(a) * clamp(a + 0.5) < 0][:3])
    beam = _tapered(0.0, 0.04)
    np.testing.assert_allclose(_omega(beam, beam_frequencies(beam, 3).freq_hz), exact, rtol=1e-8)


def test_chains_refuse_tapered_thickness_and_zero_tip_width():
    """Beams only the reference solutions support are refused by the chain, with a reason."""
    from pinflex.prbdm.beams import chain_segments

    for beam in (_tapered(0.3, 0.02), _tapered(0.0, 0.04)):
        with pytest.raises(InvalidBeam, match="reference solutions only"):
            chain_segments(beam, np.array([0.0, 0.5, 1.0]))
