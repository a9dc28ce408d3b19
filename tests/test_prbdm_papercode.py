"""Paper 001 under its code's definitions, against a chain written here, and its global optimum.

The reference below shares no code with pinflex: the links' mass, centre of mass and rotational
inertia come from Gauss quadrature of the planform's piecewise-linear width, the mass matrix
from the links' centre-of-mass and angular Jacobians of the planar chain, the eigenvalues from
scipy's symmetric-definite solver.
"""

import json
import warnings
from dataclasses import replace

import numpy as np
import pytest
from scipy.linalg import eigh
from scipy.optimize import differential_evolution, minimize, minimize_scalar

import pinflex.prbdm.posedfit as posedfit
from pinflex.cases.paper001 import CODE_POSE_COUNTS
from pinflex.cli import main
from pinflex.exceptions import OptimumNotConfirmedWarning
from pinflex.prbdm.beams import random_beam
from pinflex.prbdm.chain import build_chain, solve_tip_statics
from pinflex.prbdm.paper import PAPER_CODE, PAPER_TEXT, code_tip_force
from pinflex.prbdm.paperfit import paper_losses_of, posed_problem
from pinflex.prbdm.perpose import deflection_errors, eigen_terms, link_arrays, reference_springs
from pinflex.prbdm.posedfit import (
    best_factors,
    fit_posed,
    objective_values,
    project_fractions,
)
from pinflex.prbdm.problem import compute_truth
from pinflex.prbdm.truth import elastica_tip

GAUSS_X, GAUSS_W = np.polynomial.legendre.leggauss(4)


def _links(beam, gamma):
    """Mass, centre of mass (absolute) and inertia about it of links 1..n, by quadrature."""
    x_v, half = beam.x_m, beam.half_width_m
    t, rho = beam.thickness_m, beam.material.density_kg_m3
    ends = np.cumsum(gamma) * beam.length_m
    starts = np.concatenate([[0.0], ends[:-1]])
    out = []
    for a, b in zip(starts[1:], ends[1:]):
        cuts = np.unique(np.concatenate([[a, b], x_v[(x_v > a) & (x_v < b)]]))
        m0 = m1 = m2 = 0.0
        for lo, hi in zip(cuts[:-1], cuts[1:]):
            s = 0.5 * (lo + hi) + 0.5 * (hi - lo) * GAUSS_X
            dm = rho * t * 2.0 * np.interp(s, x_v, half) * 0.5 * (hi - lo) * GAUSS_W
            m0, m1, m2 = m0 + dm.sum(), m1 + (dm * s).sum(), m2 + (dm * s * s).sum()
        com = m1 / m0
        out.append((m0, com, m2 - m0 * com**2 + m0 * t**2 / 12.0))
    return np.array(out), starts, ends


def _mass_matrix(gamma, links, starts, poses):
    """M(theta) of the planar chain from its links' Jacobians, for poses (P, n): (P, n, n)."""
    poses = np.atleast_2d(poses)
    n = poses.shape[1]
    q = np.cumsum(poses, axis=1)
    du = np.stack([-np.sin(q), np.cos(q)], axis=1)            # d u(q_a) / d q_a, (P, 2, n)
    lengths = np.diff(np.concatenate([[0.0], np.cumsum(gamma)]))[1:]
    m = np.zeros((poses.shape[0], n, n))
    for j in range(n):
        mass, com, inertia = links[j]
        jv = np.zeros((poses.shape[0], 2, n))
        for i in range(j + 1):
            for a in range(i, j):
                jv[:, :, i] += lengths[a] * du[:, :, a]
            jv[:, :, i] += (com - starts[j + 1]) * du[:, :, j]
        jw = (np.arange(n) <= j).astype(float)
        m += mass * np.einsum("pki,pkj->pij", jv, jv) + inertia * np.outer(jw, jw)
    return m


def _code_pose_losses(beam, gamma, f_truth, poses, factor_min=True):
    """Per pose: min over k of ||eig(M^-1 k K) - omega^2|| / ||omega^2||, and the best k."""
    links, starts, _ = _links(beam, gamma)
    k_ref = np.sqrt(beam.material.youngs_modulus_pa * links[:, 2] / links[:, 0])
    w = (2.0 * np.pi * f_truth) ** 2
    losses, factors = [], []
    for m_pose in _mass_matrix(gamma, links, starts, poses):
        lam = eigh(np.diag(k_ref), m_pose, eigvals_only=True)[: w.size]
        res = minimize_scalar(lambda k, lam=lam: np.linalg.norm(k * lam - w),
                              bounds=(1e-3, 1e4), method="bounded",
                              options={"xatol": 1e-12})
        losses.append(res.fun / np.linalg.norm(w))
        factors.append(res.x)
    return np.array(losses), np.array(factors)


@pytest.fixture(scope="module")
def small():
    """A four-section random beam with its first three frequencies."""
    beam = random_beam(4, n_sections=4)
    return beam, compute_truth(beam, 3, alphas=())


def test_code_pose_sweep():
    """0.1 : 0.01 : pi/(2n), every joint alike: 43 / 30 / 22 poses for 3R / 4R / 5R."""
    for n, count in CODE_POSE_COUNTS.items():
        poses = PAPER_CODE.poses(n)
        assert poses.shape == (count, n)
        assert np.all(poses == poses[:, :1])
        assert poses[0, 0] == pytest.approx(0.1) and np.diff(poses[:, 0]) == pytest.approx(0.01)
        assert poses[-1, 0] <= np.pi / (2 * n) < poses[-1, 0] + 0.01


def test_code_frequency_loss_against_the_reference_chain(small):
    """Omega^2 compared, best factor per pose, mean over poses: the reference to 1e-8."""
    beam, truth = small
    problem = posed_problem(beam, 3, 3, truth, PAPER_CODE, code_force_n=1e5)
    poses = problem.poses[::7]
    problem = type(problem)(beam, 3, 3, PAPER_CODE, poses, problem.truth_hz)
    for gamma in ([0.3, 0.2, 0.25, 0.25], [0.55, 0.05, 0.15, 0.25]):
        gamma = np.array(gamma)
        ref_loss, ref_k = _code_pose_losses(beam, gamma, truth.modes.freq_hz[:3], poses)
        per_pose, k, _ = eigen_terms(problem, gamma[None])
        np.testing.assert_allclose(per_pose[0], ref_loss, rtol=1e-7)
        np.testing.assert_allclose(k[0], ref_k, rtol=1e-6)
        assert PAPER_CODE.combine(per_pose[0]) == pytest.approx(ref_loss.mean(), rel=1e-7)


def test_eq14_scale_depends_on_the_width_under_the_code_only(small):
    """Mass-moment eq. 14 changes with the planform's width profile; the area-moment one not.

    (A uniform scaling of the width leaves both unchanged: inertia and mass scale alike.)
    """
    beam, _ = small
    gamma = np.array([[0.2, 0.3, 0.3, 0.2]])
    wide = type(beam)(beam.x_m, beam.half_width_m * (1.0 + 2.0 * beam.x_m), beam.thickness_m,
                      beam.material)
    for definitions, changes in ((PAPER_CODE, True), (PAPER_TEXT, False)):
        springs = [reference_springs(b, definitions.inertia, *np.array(
            link_arrays(b, gamma))[[2, 4, 5]])[0] for b in (beam, wide)]
        ratio = springs[1] / springs[0]
        assert (np.max(np.abs(ratio - 1.0)) > 1e-3) == changes
        if not changes:
            np.testing.assert_allclose(ratio, 1.0, rtol=1e-12)


def test_code_deflection_case(small):
    """The code's case deflects the tip by 0.1437 L; its error is the tip-position error."""
    beam, truth = small
    force = code_tip_force(beam)
    tip = elastica_tip(beam, np.array([0.0, -force])).tip_m
    assert tip[1] == pytest.approx(-0.1437 * beam.length_m, rel=1e-9)
    problem = posed_problem(beam, 3, 3, truth, PAPER_CODE)
    gamma = np.array([0.25, 0.3, 0.25, 0.2])
    _, _, mass, _, iyy, mean_i = link_arrays(beam, gamma[None])
    k_ref = reference_springs(beam, "mass", mass, iyy, mean_i)[0]
    for factor in (20.0, 60.0):
        chain = build_chain(beam, gamma, factor * k_ref)
        model = solve_tip_statics(chain, problem.forces_n[0], load_steps=8).tip_m
        expected = np.linalg.norm(model - tip) / np.linalg.norm(tip)
        got = deflection_errors(problem, gamma[None], np.array([[factor]]))[0, 0]
        assert got == pytest.approx(expected, rel=1e-8)


def test_combined_factors_are_stationary(small):
    """Eq. 27 at the factors found is not lowered by moving any of them."""
    beam, truth = small
    problem = posed_problem(beam, 3, 3, truth, PAPER_CODE, epsilon=0.08)
    gamma = np.array([[0.3, 0.25, 0.25, 0.2]])
    found = best_factors(problem, gamma, "combined")
    _, _, v = eigen_terms(problem, gamma)
    w = problem.target

    def value(factors):
        e = np.linalg.norm(factors[:, None] * v[0] - w, axis=1) / np.linalg.norm(w)
        d = deflection_errors(problem, gamma, factors[None])[0]
        return np.hypot(e.mean(), d.mean())

    base = value(found.factors[0])
    assert base == pytest.approx(found.value[0], rel=1e-12)
    rng = np.random.default_rng(1)
    for _ in range(12):
        trial = found.factors[0] * np.exp(1e-3 * rng.normal(size=found.factors.shape[1]))
        assert value(trial) >= base * (1.0 - 1e-9)


@pytest.mark.parametrize("seed", [1, 3])
def test_global_search_reaches_an_independent_differential_evolution(seed):
    """The fit's optimum is at least as good as scipy's differential evolution on the reference.

    Reference: the loss above (factors solved per pose), 3R on a four-section random beam, at
    every third pose of the code's sweep, minimised over the three free fractions by
    differential evolution and its own polish. (On beam 1 the evolution stops at 0.121 %
    and the fit reaches 0.103 %: the landscape has narrow basins.)
    """
    beam = random_beam(seed, n_sections=4)
    truth = compute_truth(beam, 3, alphas=())
    problem = posed_problem(beam, 3, 3, truth, PAPER_CODE, code_force_n=1e5)
    poses = problem.poses[::3]
    problem = type(problem)(beam, 3, 3, PAPER_CODE, poses, problem.truth_hz)
    f_truth = truth.modes.freq_hz[:3]
    w = (2.0 * np.pi * f_truth) ** 2

    def reference(z):
        gamma = np.concatenate([z, [1.0 - z.sum()]])
        if gamma[-1] < 0.02:
            return 1.0 + (0.02 - gamma[-1])
        links, starts, _ = _links(beam, gamma)
        k_ref = np.sqrt(205e9 * links[:, 2] / links[:, 0])
        scale = 1.0 / np.sqrt(k_ref)
        lam = 1.0 / np.linalg.eigvalsh(scale[:, None] * _mass_matrix(gamma, links, starts, poses)
                                       * scale[None, :])[:, ::-1]
        cos = lam @ w / (np.linalg.norm(lam, axis=1) * np.linalg.norm(w))
        return float(np.mean(np.sqrt(np.clip(1.0 - cos**2, 0.0, None))))

    de = differential_evolution(reference, [(0.02, 0.94)] * 3, popsize=15, maxiter=80,
                                tol=1e-12, seed=0, polish=True)
    fit = fit_posed(problem, "eigen", n_samples=8192, n_starts=12, seed=0)
    ours = reference(fit.gamma[:3])
    assert ours == pytest.approx(fit.value, rel=1e-7)
    assert ours <= de.fun * (1.0 + 1e-6)
    assert fit.within(1e-6) >= 1 and fit.start_values[0] == pytest.approx(fit.value)


@pytest.mark.slow
@pytest.mark.parametrize("seed", [1, 3])
def test_combined_fit_reaches_an_independent_differential_evolution(seed):
    """The default combined (eq. 27) search is at least as good as differential evolution.

    The reference minimises the public loss (``objective_values``: eq. 27 at each design's
    best factors per pose) over the three free fractions of a 3R chain by scipy's
    differential evolution, then Nelder-Mead from its result (the loss is accurate to about
    1e-5 relative, so no derivative-based polish). The fit, with its default search, must
    reach that value within 1e-3 relative, and report that its best was reached by two
    starts or more.
    """
    beam = random_beam(seed, n_sections=4)
    truth = compute_truth(beam, 3, alphas=())
    problem = posed_problem(beam, 3, 3, truth, PAPER_CODE)
    problem = replace(problem, poses=problem.poses[::3])

    def reference(zs):
        zs = np.atleast_2d(zs)
        last = 1.0 - zs.sum(axis=1)
        out = 1.0 + (0.02 - last)                       # outside: above any loss here
        ok = last >= 0.02
        if ok.any():
            out[ok] = objective_values(problem, np.column_stack([zs[ok], last[ok]]),
                                       "combined")
        return out

    de = differential_evolution(lambda z: reference(z.T), [(0.02, 0.94)] * 3, popsize=20,
                                maxiter=100, tol=1e-8, seed=0, polish=False,
                                vectorized=True, updating="deferred")
    nm = minimize(lambda z: float(reference(z)[0]), de.x, method="Nelder-Mead",
                  options={"xatol": 1e-7, "fatol": 1e-9, "maxiter": 300})
    target = min(de.fun, nm.fun)
    with warnings.catch_warnings():
        warnings.simplefilter("error", OptimumNotConfirmedWarning)
        fit = fit_posed(problem, "combined", seed=0)
    assert fit.value == pytest.approx(float(reference(fit.gamma[:3])[0]), rel=1e-9)
    assert fit.value <= target * (1.0 + 1e-3)
    assert fit.starts_at_best >= 2


def test_unconfirmed_optimum_warns():
    """One polished start cannot confirm its optimum: the fit says so and reports 1."""
    beam = random_beam(3, n_sections=4)
    truth = compute_truth(beam, 3, alphas=())
    problem = posed_problem(beam, 3, 3, truth, PAPER_CODE, code_force_n=1e5)
    with pytest.warns(OptimumNotConfirmedWarning, match="one of 1 polished"):
        fit = fit_posed(problem, "eigen", n_samples=64, n_starts=1, seed=0)
    assert fit.starts_at_best == 1 and fit.n_starts == 1


def test_projection_onto_the_feasible_fractions():
    """project_fractions is the nearest feasible point (checked by SLSQP), identity inside."""
    rng = np.random.default_rng(3)
    points = rng.uniform(-0.5, 1.2, size=(20, 3))
    ours = project_fractions(points)
    for p, q in zip(points, ours):
        ref = minimize(lambda z, p=p: np.sum((z - p) ** 2), np.full(3, 0.25),
                       jac=lambda z, p=p: 2 * (z - p), method="SLSQP",
                       bounds=[(0.02, None)] * 3,
                       constraints=[{"type": "ineq", "fun": lambda z: 0.98 - z.sum()}],
                       options={"ftol": 1e-15, "maxiter": 200}).x
        assert q == pytest.approx(ref, abs=1e-7)
    inside = np.array([[0.1, 0.2, 0.3], [0.02, 0.02, 0.94]])
    assert project_fractions(inside) == pytest.approx(inside, abs=0.0)


def test_polish_evaluates_only_feasible_designs(monkeypatch):
    """The fractions' polish never asks for a design with a link shorter than 0.02 L.

    SLSQP's line search leaves the simplex: on this beam (text reading, 3R) an earlier polish
    evaluated a last fraction of -0.81, whose link has no mass matrix, and the eigensolver
    failed. Outside the set the polish now evaluates the projection plus a penalty.
    """
    beam = random_beam(0)
    truth = compute_truth(beam, 3, alphas=(0.5,))
    problem = posed_problem(beam, 3, 3, truth, PAPER_TEXT)
    smallest = [1.0]
    original = posedfit.objective_values

    def watched(problem, gammas, objective):
        smallest[0] = min(smallest[0], float(np.min(gammas)))
        return original(problem, gammas, objective)

    monkeypatch.setattr(posedfit, "objective_values", watched)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", OptimumNotConfirmedWarning)   # 16 starts: may be
        fit = fit_posed(problem, "eigen", n_samples=512, n_starts=16, seed=0)
    assert smallest[0] >= 0.02 * (1.0 - 1e-12)
    assert np.all(fit.gamma >= 0.02 * (1.0 - 1e-12)) and fit.gamma.sum() == pytest.approx(1.0)


def test_unsolved_loads_in_a_reported_loss_are_named():
    """A reported deflection loss that counts an unsolved load as 100 % says so.

    On random beam 0 the text reading's eigen-only optimum, with its mean factor (eq. 25), is
    so soft that the statics at alpha = 5 find no equilibrium: eq. 19 is then a penalty.
    """
    from pinflex.exceptions import UnsolvedLoadWarning

    beam = random_beam(0)
    truth = compute_truth(beam, 3)
    problem = posed_problem(beam, 3, 3, truth, PAPER_TEXT)
    with pytest.warns(OptimumNotConfirmedWarning):
        posed = fit_posed(problem, "eigen", n_samples=64, n_starts=1, seed=0)
    soft = replace(posed, gamma=np.array([0.59603533, 0.068577, 0.24642448, 0.08896319]),
                   factors=np.array([402.168, 405.141, 410.784, 418.598, 428.031]))
    with pytest.warns(UnsolvedLoadWarning, match="1 of 4 tip statics"):
        losses = paper_losses_of(problem, soft)
    assert 0.5 < losses["eq19_rms"] < 1.0


def test_cli_paper_code(capsys):
    """``--definitions paper-code`` prints the code's losses, per-mode errors and stability."""
    status = main(["prbdm", "--beam", "random", "--sections", "4", "--links", "3",
                   "--definitions", "paper-code", "--objective", "eigen", "--samples", "2048",
                   "--starts", "4", "--json", "--no-progress"])
    out = json.loads(capsys.readouterr().out)
    assert status == 0 and out["definitions"] == "paper-code" and out["n_poses"] == 43
    assert set(out["losses"]) == {"frequency", "deflection", "combined"}
    assert len(out["mode_errors"]) == 3 and len(out["start_values"]) == 4
    assert out["start_values"][0] == pytest.approx(out["losses"]["frequency"])
