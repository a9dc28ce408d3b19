"""More load cases: tip moments, inclined and combined end loads, fixed-guided beams.

References written here, with no pinflex code: the circular arc of a pure end moment; an
independent shooting solver of the elastica (root curvature shot forward with scipy's
solve_ivp and a secant root finder, continued in the load); linear beam theory; Mattiasson's
table (via the fixed-guided beam's antisymmetry); Howell and Midha's table of the 1R
characteristic radius (gamma, Theta_max).
"""

import json
import math

import numpy as np
import pytest
from scipy.integrate import quad, solve_ivp
from scipy.optimize import brentq, newton

from pinflex.exceptions import (
    ConfigurationError,
    InvalidChain,
    NewtonDivergence,
    TruthNotConverged,
)
from pinflex.prbdm.beams import random_beam, uniform_beam
from pinflex.prbdm.chain import build_chain, solve_tip_statics, tip_position
from pinflex.prbdm.elastica import end_load_equilibrium
from pinflex.prbdm.loads import EXTENDED_CASES, LoadCase, case_truth, force_cases
from pinflex.prbdm.mapping import fit_prbdm
from pinflex.prbdm.problem import compute_truth

E_STEEL = 205e9


def _ei_function(beam):
    """EI(s) of the planform from its vertex data [N m^2] (width linear between vertices)."""
    t3 = beam.thickness_m**3 / 12.0

    def ei(s):
        return E_STEEL * 2.0 * np.interp(s, beam.x_m, beam.half_width_m) * t3
    return ei


def _reference(beam, force, moment=0.0, guided=False, steps=10):
    """Independent elastica: shoot the root bending moment forward, secant on the end condition.

    theta' = m / EI(s), m' = Fx sin(theta) + Fz cos(theta) (theta turns +X towards -Z), with
    theta(0) = 0 and m(L) = M (free end) or theta(L) = 0 (guided end). Returns (tip x, tip z,
    end rotation, end moment).
    """
    ei = _ei_function(beam)
    fx, fz = force

    def shoot(m0, frac):
        def rhs(s, y):
            c, sn = math.cos(y[2]), math.sin(y[2])
            return [c, -sn, y[3] / ei(s), frac * (fx * sn + fz * c)]
        y = np.array([0.0, 0.0, 0.0, m0])
        for a, b in zip(beam.x_m[:-1], beam.x_m[1:]):
            y = solve_ivp(rhs, (a, b), y, method="DOP853", rtol=1e-13, atol=1e-15).y[:, -1]
        return y

    scale = max(abs(moment), math.hypot(fx, fz) * beam.length_m)
    m0 = 0.0
    for i in range(1, steps + 1):
        frac = i / steps

        def residual(m, frac=frac):
            y = shoot(m * scale, frac)
            return y[2] if guided else (y[3] - frac * moment) / scale
        m0 = newton(residual, m0 + (1e-3 if i == 1 else 0.0), tol=1e-15, maxiter=200)
    return shoot(m0 * scale, 1.0)


# -- truth: pure end moment ----------------------------------------------------------------

@pytest.mark.parametrize("beta", [0.5, 2.0, math.pi, 6.0])
def test_tip_moment_is_a_circular_arc(beta):
    """Under an end moment the uniform beam is an arc of curvature M/EI, to round-off."""
    beam = uniform_beam()
    sol = case_truth(beam, LoadCase(beta=beta))
    length = beam.length_m
    kappa = beta / length
    exact = np.array([math.sin(kappa * length) / kappa, -(1.0 - math.cos(kappa * length)) / kappa])
    assert np.max(np.abs(sol.tip_m - exact)) < 1e-12 * length
    assert sol.tip_rotation_rad == pytest.approx(beta, abs=1e-12)
    assert sol.end_moment_nm == pytest.approx(sol.root_moment_nm, rel=1e-13)


def test_tip_moment_rotation_on_random_beam():
    """Non-uniform beam: the end rotation is M times the integral of 1/EI, to 1e-10."""
    beam = random_beam(3)
    moment = 2.0e5
    sol = end_load_equilibrium(beam, np.zeros(2), moment)
    ei = _ei_function(beam)
    compliance = sum(quad(lambda s: 1.0 / ei(s), a, b, epsabs=0, epsrel=1e-13)[0]
                     for a, b in zip(beam.x_m[:-1], beam.x_m[1:]))
    assert sol.tip_rotation_rad == pytest.approx(moment * compliance, rel=1e-10)


# -- truth: inclined and combined end loads -------------------------------------------------

CASES = [(2.0, 30.0, 0.0), (10.0, 60.0, 0.0), (10.0, 120.0, 0.0), (10.0, 135.0, 0.0),
         (5.0, 150.0, 0.0), (2.0, 90.0, 1.0), (5.0, 135.0, 1.0), (10.0, 45.0, -1.0),
         (10.0, 90.0, 3.0), (5.0, -60.0, 2.0), (5.0, 160.0, 0.0), (10.0, 170.0, 0.0)]


@pytest.mark.parametrize("alpha, angle, beta", CASES)
def test_inclined_and_combined_loads_match_independent_shooting(alpha, angle, beta):
    """Uniform cantilever, alpha up to 10, force angles 30-150 deg, with and without moment."""
    beam = uniform_beam()
    case = LoadCase(alpha=alpha, angle_deg=angle, beta=beta)
    sol = case_truth(beam, case)
    ref = _reference(beam, case.force_n(beam), case.moment_nm(beam))
    assert np.max(np.abs(sol.tip_m - ref[:2])) < 1e-8 * beam.length_m
    assert sol.tip_rotation_rad == pytest.approx(ref[2], abs=1e-8)


@pytest.mark.parametrize("angle, beta", [(120.0, 1.0)])
def test_inclined_loads_on_random_beam_match_independent_shooting(angle, beta):
    """A non-uniform planform (EI from its vertices in the reference), alpha = 5."""
    beam = random_beam(3)
    case = LoadCase(alpha=5.0, angle_deg=angle, beta=beta)
    sol = case_truth(beam, case)
    ref = _reference(beam, case.force_n(beam), case.moment_nm(beam))
    assert np.max(np.abs(sol.tip_m - ref[:2])) < 1e-8 * beam.length_m
    assert sol.tip_rotation_rad == pytest.approx(ref[2], abs=1e-8)


def test_snap_through_of_the_load_path_is_refused():
    """A fold of the proportional load path raises TruthNotConverged.

    alpha = 10 at 90 deg with beta = 10: three equilibria at 0.64 of the load, one at 0.66
    (counted by sign changes of the clamp residual over the end rotation; docs/prbdm.md), so
    the equilibrium snaps; the truth refuses by name instead of returning either side.
    """
    beam = uniform_beam()
    with pytest.raises(TruthNotConverged, match="stalled"):
        case_truth(beam, LoadCase(alpha=10.0, angle_deg=90.0, beta=10.0))


# -- truth: fixed-guided beam ---------------------------------------------------------------

def test_fixed_guided_small_load_is_linear_theory():
    """Small load: deflection P L^3 / (12 EI) and a guide moment of P L / 2 (uniform beam)."""
    beam = uniform_beam()
    ei = E_STEEL * beam.width_m(0.0) * beam.thickness_m**3 / 12.0
    force = 1e-4 * ei / beam.length_m**2
    sol = end_load_equilibrium(beam, np.array([0.0, -force]), 0.0, "fixed-guided")
    assert -sol.tip_m[1] == pytest.approx(force * beam.length_m**3 / (12.0 * ei), rel=1e-7)
    assert abs(sol.end_moment_nm) == pytest.approx(0.5 * force * beam.length_m, rel=1e-7)
    assert sol.tip_rotation_rad == 0.0


@pytest.mark.parametrize("beam, alpha", [(uniform_beam(), 2.0), (uniform_beam(), 10.0),
                                         (random_beam(3), 10.0)])
def test_fixed_guided_matches_independent_shooting(beam, alpha):
    """Large transverse loads on the guided end, uniform and random beams."""
    case = LoadCase(alpha=alpha, boundary="fixed-guided")
    sol = case_truth(beam, case)
    ref = _reference(beam, case.force_n(beam), guided=True)
    assert np.max(np.abs(sol.tip_m - ref[:2])) < 1e-8 * beam.length_m
    assert sol.end_moment_nm == pytest.approx(ref[3], rel=1e-7)


# Mattiasson (1981), Table 1: cantilever under a transverse tip force, w/L and u/L at alpha.
MATTIASSON = [(1.0, 0.30172, 0.05643), (2.0, 0.49346, 0.16064), (5.0, 0.71379, 0.38763)]


@pytest.mark.parametrize("alpha, w_ref, u_ref", MATTIASSON)
def test_fixed_guided_is_two_cantilevers_of_mattiasson(alpha, w_ref, u_ref):
    """A guided beam at 4 alpha moves its end by Mattiasson's (u, w) at alpha.

    Antisymmetry: a guided beam under P is two cantilevers of length L/2 under P; the
    printed digits are matched.
    """
    beam = uniform_beam()
    force = LoadCase(alpha=alpha).force_n(beam) * 4.0
    sol = end_load_equilibrium(beam, force, 0.0, "fixed-guided")
    assert round(-sol.tip_m[1], 5) == pytest.approx(w_ref, abs=1e-12)
    assert round(1.0 - sol.tip_m[0], 5) == pytest.approx(u_ref, abs=1e-12)


# -- published: Howell's 1R characteristic radius ------------------------------------------

# Howell and Midha, J. Mech. Des. 117(1), 1995, 156-165 (also Howell, Compliant Mechanisms,
# 2001, Table 5.1): load factor n (horizontal component -nP beside the transverse P),
# characteristic radius factor gamma and the largest pseudo-rigid-body angle Theta_max [deg]
# for which the 1R tip path stays within 0.5 % of the deflection.
HOWELL_TABLE = [(0.0, 0.8517, 64.3), (0.5, 0.8430, 81.8), (1.0, 0.8360, 94.8)]


def _path_error(beam, gamma, tip):
    """The 1R model's angle Theta for an elastica tip, and its tip error over the deflection.

    The 1R chain (pivot at (1 - gamma) L) set to the beam's Theta, its tip by the chain's own
    kinematics.
    """
    length = beam.length_m
    chain = build_chain(beam, np.array([1.0 - gamma, gamma]), np.array([1.0]))
    theta = math.atan2(-tip[1], tip[0] - (1.0 - gamma) * length)
    prb = tip_position(chain, np.array([theta]))
    return math.degrees(theta), np.linalg.norm(prb - tip) / np.linalg.norm(tip - [length, 0.0])


@pytest.mark.parametrize("n, gamma, theta_max", HOWELL_TABLE)
def test_howell_1r_path_error_band(n, gamma, theta_max):
    """The 1R tip path error reaches 0.5 % of the deflection at Howell's Theta_max (0.1 deg)."""
    beam = uniform_beam()
    angle = math.degrees(math.atan2(1.0, -n))

    def error(alpha):
        tip = case_truth(beam, LoadCase(alpha=alpha, angle_deg=angle)).tip_m
        return _path_error(beam, gamma, tip)

    limit = brentq(lambda a: error(a)[1] - 0.005, 6.0, 8.5, xtol=1e-7)
    assert error(limit)[0] == pytest.approx(theta_max, abs=0.1)
    below = [error(a)[1] for a in np.linspace(0.5, limit, 8)[:-1]]
    assert max(below) < 0.005
    assert error(min(limit + 0.5, 10.0))[1] > 0.005


def test_howell_fixed_guided_band_by_antisymmetry():
    """Howell's fixed-guided model's path error reaches 0.5 % at 64.3 deg.

    The model (pivots (1 - gamma) L / 2 from each end, K = 2 gamma K_Theta EI / L) is two 1R
    half-cantilevers.
    """
    beam = uniform_beam()
    gamma = 0.8517
    length = beam.length_m
    chain = build_chain(beam, np.array([(1 - gamma) / 2, gamma, (1 - gamma) / 2]),
                        np.array([1.0, 1.0]))

    def error(alpha):
        tip = end_load_equilibrium(beam, LoadCase(alpha=1.0).force_n(beam) * alpha, 0.0,
                                   "fixed-guided").tip_m
        shift = (1.0 - gamma) / 2 * length
        theta = math.atan2(-tip[1], tip[0] - (1.0 - gamma) * length)
        prb = tip_position(chain, np.array([theta, -theta]))
        assert prb[0] == pytest.approx(2 * shift + gamma * length * math.cos(theta), abs=1e-14)
        return math.degrees(theta), np.linalg.norm(prb - tip) / np.linalg.norm(tip - [length, 0])

    limit = brentq(lambda a: error(a)[1] - 0.005, 4 * 6.5, 4 * 7.8, xtol=1e-6)
    assert error(limit)[0] == pytest.approx(64.3, abs=0.1)


# -- chain statics under the new loads ------------------------------------------------------

def test_chain_under_end_moment_is_linear():
    """A pure end moment: K theta = M 1 exactly (each spring carries M)."""
    beam = uniform_beam()
    k = np.array([3.0e6, 2.0e6, 1.5e6])
    chain = build_chain(beam, np.array([0.1, 0.35, 0.4, 0.15]), k)
    moment = 2.5e6
    res = solve_tip_statics(chain, np.zeros(2), moment_nm=moment)
    assert np.allclose(res.theta, moment / k, rtol=1e-12, atol=0.0)
    q = np.cumsum(moment / k)
    lengths = chain.link_lengths_m
    tip = np.array([lengths[0] + np.sum(lengths[1:] * np.cos(q)),
                    -np.sum(lengths[1:] * np.sin(q))])
    assert np.allclose(res.tip_m, tip, rtol=0.0, atol=1e-14)


@pytest.mark.parametrize("alpha, beta", [(2.0, 0.0), (10.0, 0.0), (2.0, 1.0)])
def test_howell_1r_statics_closed_form(alpha, beta):
    """1R (gamma = 0.85, K_Theta = 2.65): K Theta = P gamma L cos(Theta) + M (vertical P)."""
    beam = uniform_beam()
    ei = E_STEEL * beam.width_m(0.0) * beam.thickness_m**3 / 12.0
    length, gamma = beam.length_m, 0.85
    k = gamma * 2.65 * ei / length
    chain = build_chain(beam, np.array([1 - gamma, gamma]), np.array([k]))
    p, m = alpha * ei / length**2, beta * ei / length
    res = solve_tip_statics(chain, np.array([0.0, -p]), load_steps=4, moment_nm=m)
    theta = res.theta[0]
    assert k * theta == pytest.approx(p * gamma * length * math.cos(theta) + m, rel=1e-10)


@pytest.mark.parametrize("alpha", [2.0, 10.0])
def test_howell_fixed_guided_statics_closed_form(alpha):
    """Guided 2R: theta_2 = -theta_1, 2 K Theta = P gamma L cos(Theta).

    The guide's moment is -K Theta - P (1 - gamma) L / 2 (joint 2's balance, its arm the
    horizontal end link).
    """
    beam = uniform_beam()
    ei = E_STEEL * beam.width_m(0.0) * beam.thickness_m**3 / 12.0
    length, gamma = beam.length_m, 0.85
    k = 2.0 * gamma * 2.65 * ei / length
    chain = build_chain(beam, np.array([(1 - gamma) / 2, gamma, (1 - gamma) / 2]),
                        np.array([k, k]))
    p = alpha * ei / length**2
    res = solve_tip_statics(chain, np.array([0.0, -p]), load_steps=4, boundary="fixed-guided")
    theta = res.theta[0]
    assert res.theta[1] == pytest.approx(-theta, rel=1e-12)
    assert 2.0 * k * theta == pytest.approx(p * gamma * length * math.cos(theta), rel=1e-9)
    assert res.end_moment_nm == pytest.approx(-k * theta - p * (1 - gamma) * length / 2,
                                              rel=1e-9)


def test_force_with_moment_never_silently_leaves_the_continuation_branch():
    """Under a force with a moment 4 load steps raise or give the 200-step answer.

    There is no branch check for these loads; random 1R-5R chains, moments up to 10 against
    and with the force, forces up to 170 deg.
    """
    beam = uniform_beam()
    ei = E_STEEL * beam.width_m(0.0) * beam.thickness_m**3 / 12.0
    rng = np.random.default_rng(1)
    cases = [LoadCase(10, 90, 3), LoadCase(10, 90, -3), LoadCase(10, 45, -5),
             LoadCase(10, 135, 5), LoadCase(5, 170, 2), LoadCase(2, 90, 10)]
    compared = 0
    for _ in range(12):
        n = int(rng.integers(1, 6))
        gamma = 0.02 + (1 - 0.02 * (n + 1)) * rng.dirichlet(np.ones(n + 1))
        chain = build_chain(beam, gamma, ei * n * rng.uniform(1.5, 5.0, n))
        for case in cases:
            load = (case.force_n(beam), case.moment_nm(beam))
            try:
                coarse = solve_tip_statics(chain, load[0], load_steps=4, moment_nm=load[1])
            except NewtonDivergence:
                continue
            fine = solve_tip_statics(chain, load[0], load_steps=200, moment_nm=load[1])
            assert np.allclose(coarse.tip_m, fine.tip_m, rtol=0.0, atol=1e-9)
            compared += 1
    assert compared >= 60


def test_chain_statics_refuse_bad_end_conditions():
    """A guided end needs 2 joints and takes no moment; unknown boundaries are named."""
    beam = uniform_beam()
    one = build_chain(beam, np.array([0.15, 0.85]), np.array([1e6]))
    two = build_chain(beam, np.array([0.2, 0.4, 0.4]), np.array([1e6, 1e6]))
    with pytest.raises(ConfigurationError, match="at least 2 joints"):
        solve_tip_statics(one, np.array([0.0, -1e5]), boundary="fixed-guided")
    with pytest.raises(ConfigurationError, match="no applied moment"):
        solve_tip_statics(two, np.array([0.0, -1e5]), moment_nm=1.0, boundary="fixed-guided")
    with pytest.raises(ConfigurationError, match="boundary"):
        solve_tip_statics(two, np.array([0.0, -1e5]), boundary="pinned")


@pytest.mark.parametrize("kwargs, match", [
    ({"alpha": 11.0}, "alpha"), ({"alpha": 1.0, "angle_deg": 180.0}, "compression"),
    ({"beta": 1.0, "boundary": "fixed-guided"}, "no applied moment"),
    ({"alpha": 1.0, "boundary": "free"}, "boundary"), ({}, "needs a force"),
    ({"alpha": float("nan")}, "finite"), ({"beta": -10.5}, "beta"),
])
def test_load_case_validation(kwargs, match):
    """Out-of-range or contradictory load cases are refused by name."""
    with pytest.raises(InvalidChain, match=match):
        LoadCase(**kwargs)


# -- fits on the new cases -------------------------------------------------------------------

def test_default_truth_unchanged_by_load_cases():
    """The paper's loads through LoadCase give the same truth as the default path, exactly."""
    beam = random_beam(2)
    default = compute_truth(beam, 2)
    cases = compute_truth(beam, 2, loads=force_cases((0.5, 1.0, 2.0, 5.0)))
    assert np.array_equal(default.forces_n, cases.forces_n)
    assert np.array_equal(default.tips_m, cases.tips_m)


def test_fit_reports_per_case_errors_of_the_chain_statics():
    """A 3R fit's reported per-case errors are its chain's own statics against the elastica.

    Cases: a moment, an inclined and a combined load, a guided end; recomputed here.
    """
    beam = uniform_beam()
    cases = (LoadCase(beta=1.5), LoadCase(alpha=10.0, angle_deg=45.0),
             LoadCase(alpha=2.0, angle_deg=90.0, beta=1.0),
             LoadCase(alpha=10.0, boundary="fixed-guided"))
    fit = fit_prbdm(beam, 3, loads=cases, n_starts=2)
    assert fit.load_labels == tuple(c.label for c in cases)
    chain = fit.chain(beam)
    undeformed = np.array([beam.length_m, 0.0])
    for case, reported in zip(cases, fit.load_errors):
        truth = case_truth(beam, case).tip_m
        tip = solve_tip_statics(chain, case.force_n(beam), load_steps=4,
                                moment_nm=case.moment_nm(beam), boundary=case.boundary).tip_m
        error = np.linalg.norm(tip - truth) / np.linalg.norm(truth - undeformed)
        assert reported == pytest.approx(error, rel=1e-8)
    assert fit.deflection_error == pytest.approx(np.sqrt(np.mean(np.square(fit.load_errors))))
    assert fit.deflection_error < 0.05


def test_fit_refuses_loads_it_cannot_use():
    """Guided loads on a 1R chain and load cases with the paper's definitions are refused."""
    beam = uniform_beam()
    with pytest.raises(InvalidChain, match="1R chain cannot"):
        fit_prbdm(beam, 1, loads=(LoadCase(alpha=2.0, boundary="fixed-guided"),), n_starts=1)
    with pytest.raises(InvalidChain, match="definitions"):
        fit_prbdm(beam, 3, loads=(LoadCase(beta=1.0),), definitions="paper-code")


def test_extended_cases_cover_the_bullet():
    """The extended set has moments, inclined, combined and guided loads up to level 10."""
    assert any(c.beta and not c.alpha for c in EXTENDED_CASES)
    assert any(c.alpha and c.angle_deg not in (90.0,) for c in EXTENDED_CASES)
    assert any(c.alpha and c.beta for c in EXTENDED_CASES)
    assert any(c.boundary == "fixed-guided" for c in EXTENDED_CASES)
    assert max(c.alpha for c in EXTENDED_CASES) == 10.0


def test_cli_fits_on_the_extended_cases(capsys):
    """`pinflex prbdm --loads extended` fits on those cases and names each case's error."""
    from pinflex.cli import main

    status = main(["prbdm", "--beam", "uniform", "--links", "2", "--starts", "1",
                   "--loads", "extended", "--json", "--no-progress"])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["load_labels"] == [c.label for c in EXTENDED_CASES]
    assert len(data["load_errors"]) == len(EXTENDED_CASES)
    assert all(0.0 <= e < 1.0 for e in data["load_errors"])
    status = main(["prbdm", "--loads", "extended", "--definitions", "paper-code",
                   "--no-progress"])
    assert status == 2
    assert "--loads extended" in capsys.readouterr().err
