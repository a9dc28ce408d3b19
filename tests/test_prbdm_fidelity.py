"""Fewest PRBDM links for a tolerance: the estimate against closed-form beam solutions."""

import json

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import ellipe, ellipeinc, ellipk, ellipkinc

from pinflex.cli import main
from pinflex.exceptions import ConfigurationError
from pinflex.prbdm.beams import uniform_beam
from pinflex.prbdm.chain import chain_frequencies, solve_tip_statics
from pinflex.prbdm.fidelity import links_for_tolerance
from pinflex.prbdm.problem import compute_truth

BETA_L = np.array([1.8751040687119611, 4.6940911329741745])


def _elliptic_tip(alpha):
    """Tip (x/L, w/L) of a uniform cantilever under a transverse dead load (elliptic form)."""

    def phi1(m):
        return np.arcsin(1.0 / np.sqrt(2.0 * m))

    m = brentq(lambda m: ellipk(m) - ellipkinc(phi1(m), m) - np.sqrt(alpha),
               0.5 + 1e-15, 1.0 - 1e-16, xtol=1e-16, rtol=1e-15)
    x = np.sqrt(2.0 * (2.0 * m - 1.0) / alpha)
    w = 1.0 - 2.0 * (ellipe(m) - ellipeinc(phi1(m), m)) / np.sqrt(alpha)
    return np.array([x, -w])


@pytest.fixture(scope="module")
def uniform_choice():
    """Fewest links for 1e-3 on paper 001's uniform beam, two modes judged."""
    beam = uniform_beam()
    truth = compute_truth(beam, 2)
    return beam, links_for_tolerance(beam, 1e-3, n_modes=2, max_links=6, n_starts=4,
                                     truth=truth)


def test_estimate_equals_the_error_against_closed_forms(uniform_choice):
    """The chosen chain's estimate is its error against the beta-L roots and the elastica."""
    beam, choice = uniform_choice
    e = beam.material.youngs_modulus_pa
    ei = e * float(beam.area_moment_m4(0.0))
    rho_a = beam.material.density_kg_m3 * float(beam.area_m2(0.0))
    length = beam.length_m
    exact_hz = BETA_L**2 * np.sqrt(ei / (rho_a * length**4)) / (2.0 * np.pi)
    chain = choice.fit.chain(beam)
    hz = chain_frequencies(chain)[:2]
    eig = np.sqrt(np.mean((hz / exact_hz - 1.0) ** 2))
    misses = []
    for alpha in choice.fit.alphas:
        exact_tip = _elliptic_tip(alpha) * length
        force = np.array([0.0, -alpha * ei / length**2])
        tip = solve_tip_statics(chain, force, load_steps=4).tip_m
        misses.append(np.linalg.norm(tip - exact_tip)
                      / np.linalg.norm(exact_tip - np.array([length, 0.0])))
    defl = np.sqrt(np.mean(np.square(misses)))
    measured = np.hypot(eig, defl)
    assert choice.estimate == pytest.approx(measured, rel=1e-6)
    assert choice.truth_error < 1e-6 * choice.estimate


def test_the_smallest_chain_meeting_the_tolerance_is_chosen(uniform_choice):
    """Every chain fitted before the choice misses the tolerance; the choice meets it."""
    _, choice = uniform_choice
    assert choice.estimate <= 1e-3
    assert choice.levels[0][0] == 2 and choice.levels[-1][0] == choice.n_joints
    assert all(level[1] > 1e-3 for level in choice.levels[:-1])
    assert len(choice.levels) >= 2            # the tolerance is not met by the first chain


def test_unreachable_tolerance_names_the_best_estimate():
    """No chain meeting tol is a named error with the best estimate; bad tol is refused."""
    beam = uniform_beam()
    with pytest.raises(ConfigurationError, match="best is 2R"):
        links_for_tolerance(beam, 1e-9, n_modes=1, max_links=2, n_starts=2)
    with pytest.raises(ConfigurationError, match="positive"):
        links_for_tolerance(beam, -1.0)


def test_cli_tol_reports_the_choice_and_its_estimate(capsys, uniform_choice):
    """`pinflex prbdm --tol` fits the same chain as the Python call and reports the estimate."""
    _, choice = uniform_choice
    status = main(["prbdm", "--tol", "1e-3", "--modes", "2", "--links", "6", "--starts", "4",
                   "--json", "--no-progress"])
    assert status == 0
    data = json.loads(capsys.readouterr().out)
    assert data["n_joints"] == data["fidelity"]["n_joints"] == choice.n_joints
    assert data["fidelity"]["estimate"] == pytest.approx(choice.estimate, rel=1e-9)
    assert data["combined_error"] == pytest.approx(choice.estimate, rel=1e-12)
