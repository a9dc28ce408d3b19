"""Tests of pinflex.prbdm.problem and pinflex.prbdm.mapping: losses and fitted models."""

import json

import numpy as np
import pytest

from pinflex.exceptions import InvalidChain
from pinflex.prbdm.beams import chain_segments, random_beam, uniform_beam
from pinflex.prbdm.chain import build_chain, chain_frequencies, solve_tip_statics
from pinflex.prbdm.mapping import fit_prbdm
from pinflex.prbdm.problem import (
    build_problem,
    compute_truth,
    evaluate,
    joint_pieces,
    paper_poses,
    reference_stiffness,
)

EI_UNIFORM = 205e9 * 0.3624 * 0.040532**3 / 12


@pytest.fixture(scope="module")
def uniform_truth():
    """Converged truth of paper 001's uniform beam (5 modes, 4 loads)."""
    return compute_truth(uniform_beam(), 5)


def test_paper_pose_sweep_stops_before_right_angle():
    """Eq. (10)-(11): poses start at xi and the end link never passes pi/2."""
    poses = paper_poses(4, offset_rad=0.05, step_rad=0.1)
    assert poses[0] == pytest.approx(np.full(4, 0.05))
    assert np.all(poses.sum(axis=1) <= np.pi / 2 + 1e-12)
    assert (poses[-1] + 0.1).sum() > np.pi / 2


def test_segment_law_gives_ei_over_piece_length_on_uniform_beam(uniform_truth):
    """On a uniform beam the reference spring of joint j is EI over the length of its piece."""
    problem = build_problem(uniform_beam(), 3, truth=uniform_truth)
    gamma = np.array([0.1, 0.3, 0.4, 0.2])
    pieces = np.diff(joint_pieces(uniform_beam(), gamma))
    assert pieces == pytest.approx([0.25, 0.35, 0.4])
    assert reference_stiffness(problem, gamma) == pytest.approx(EI_UNIFORM / pieces, rel=1e-12)


def test_paper_law_is_eq_14(uniform_truth):
    """The paper law's reference stiffness is sqrt(E I_j / m_j) of link j."""
    beam = uniform_beam()
    problem = build_problem(beam, 2, stiffness_law="paper", poses="paper", truth=uniform_truth)
    gamma = np.array([0.2, 0.5, 0.3])
    links = chain_segments(beam, np.array([0.2, 0.7, 1.0]))
    expected = [np.sqrt(205e9 * s.mean_area_moment_m4 / s.mass_kg) for s in links]
    assert reference_stiffness(problem, gamma) == pytest.approx(expected, rel=1e-12)


def test_losses_of_howell_model_match_direct_computation(uniform_truth):
    """evaluate() reproduces frequency and displacement-normalised tip errors computed by hand."""
    beam = uniform_beam()
    problem = build_problem(beam, 1, truth=uniform_truth)
    gamma = np.array([0.15, 0.85])
    factor = 0.85 * 2.65 * EI_UNIFORM * reference_stiffness(problem, gamma)[0] ** -1
    ev = evaluate(problem, np.concatenate([gamma, [np.log(factor)]]))
    chain = build_chain(beam, gamma, np.array([0.85 * 2.65 * EI_UNIFORM]))
    f1 = chain_frequencies(chain)[0]
    assert ev.eigen_error == pytest.approx(abs(f1 / uniform_truth.modes.freq_hz[0] - 1), rel=1e-9)
    errors = []
    for force, truth in zip(uniform_truth.forces_n, uniform_truth.tips_m):
        tip = solve_tip_statics(chain, force, load_steps=4).tip_m
        errors.append(np.linalg.norm(tip - truth) / np.linalg.norm(truth - [1.0, 0.0]))
    assert ev.load_errors == pytest.approx(errors, rel=1e-8)
    assert ev.deflection_error == pytest.approx(np.sqrt(np.mean(np.square(errors))), rel=1e-8)
    assert ev.combined_error == pytest.approx(np.hypot(ev.eigen_error, ev.deflection_error))


def test_uniform_5r_eigen_mapping_matches_five_modes(uniform_truth):
    """An eigen-only 5R mapping of the uniform beam matches its first five frequencies."""
    fit = fit_prbdm(uniform_beam(), 5, 5, "eigen", n_starts=2, truth=uniform_truth)
    assert np.max(np.abs(np.array(fit.model_hz) / uniform_truth.modes.freq_hz - 1)) < 1e-8
    assert min(fit.link_fractions) >= 0.02 - 1e-12
    assert sum(fit.link_fractions) == pytest.approx(1.0, abs=1e-12)
    chain = fit.chain(uniform_beam())
    assert chain_frequencies(chain) == pytest.approx(fit.model_hz, rel=1e-12)


def test_fit_json_has_report_fields(uniform_truth):
    """PrbdmFit.to_json() is valid JSON with the errors, lengths, stiffness and frequencies."""
    fit = fit_prbdm(uniform_beam(), 2, 2, "eigen", n_starts=1, truth=uniform_truth)
    data = json.loads(fit.to_json())
    for key in ("eigen_error", "deflection_error", "link_lengths", "stiffness", "truth_hz",
                "model_hz"):
        assert key in data
    assert len(data["link_lengths"]) == 3 and len(data["stiffness"]) == 2
    assert data["eigen_error"] == pytest.approx(fit.eigen_error)


def test_combined_mapping_beats_eigen_only_deflection():
    """A combined 2R mapping cuts the eigen-only model's deflection loss by over 10x."""
    beam = random_beam(2)
    truth = compute_truth(beam, 2, alphas=(1.0, 2.0))
    eig = fit_prbdm(beam, 2, 2, "eigen", n_starts=2, truth=truth)
    comb = fit_prbdm(beam, 2, 2, "combined", n_starts=2, truth=truth)
    assert comb.combined_error < 0.1 * eig.deflection_error
    assert comb.combined_error < 0.05


def test_unknown_objective_raises(uniform_truth):
    """An unknown objective raises InvalidChain."""
    with pytest.raises(InvalidChain, match="objective"):
        fit_prbdm(uniform_beam(), 2, objective="speed", truth=uniform_truth)


def test_too_many_modes_raises(uniform_truth):
    """Asking an nR chain for more than n modes raises InvalidChain."""
    with pytest.raises(InvalidChain, match="modes"):
        build_problem(uniform_beam(), 2, n_modes=3, truth=uniform_truth)


@pytest.mark.slow
def test_random_beam_combined_losses_beat_paper():
    """On the seeded random beam, 3R/4R/5R combined losses beat paper 001's Table 5."""
    beam = random_beam(0)
    truth = compute_truth(beam, 5)
    for n, paper in ((3, 0.598), (4, 0.1296), (5, 0.1018)):
        fit = fit_prbdm(beam, n, n, "pareto", n_starts=6, truth=truth)
        assert fit.combined_error < 0.01 * paper
