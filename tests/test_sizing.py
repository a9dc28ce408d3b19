"""Section design variables in assignment: least added mass under floors, budgets, targets."""

import numpy as np
import pytest
from arms import two_link
from scipy.optimize import minimize

from pinflex.assignment import Target, assign_frequencies
from pinflex.assignment.sizing import size_for_floors
from pinflex.assignment.study import user_trajectory
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.erls.design import design_mass
from pinflex.trajectory import Trajectory

RODS = two_link(
    'shape="solid_circle" diameter="{d1}"', 'shape="solid_circle" diameter="{d2}"',
    params='<pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.06" design="true"/>'
    '<pinflex:parameter name="d2" value="0.03" lower="0.02" upper="0.06" design="true"/>',
    extra='<pinflex:point_mass name="m1" link="link1" xyz="0.6 0 0" mass="0.125"/>'
    '<pinflex:point_mass name="m2" link="link2" xyz="0.45 0 0" mass="0.125"/>',
)


@pytest.fixture(scope="module")
def rods():
    """Benchmark A with solid-rod diameters as design variables, 10 trajectory samples."""
    model = FlexibleModel(parse(RODS), planar=True)
    full = user_trajectory(model, "benchmark_a")
    idx = np.linspace(0, len(full.times_s) - 1, 10).round().astype(int)
    return model, Trajectory(full.times_s[idx], full.q[idx], model.joint_names)


def test_design_mass_counts_link_beams_and_masses(rods):
    """ρ A(d) L of both rods plus nothing else designed; gradient ρ π d L / 2."""
    model, _ = rods
    m, g = design_mass(model, [0.04, 0.03], order=1)
    rho = 2687.0
    expected = rho * np.pi / 4 * (0.04**2 * 0.6 + 0.03**2 * 0.45)
    assert m == pytest.approx(expected, rel=1e-13)
    np.testing.assert_allclose(g, rho * np.pi / 2 * np.array([0.04 * 0.6, 0.03 * 0.45]),
                               rtol=1e-13)


def test_least_mass_under_a_floor_matches_exact_optimisation(rods):
    """Least rod mass with mode 1 15 % above today: the optimum of SLSQP on the exact model.

    Floors hold on the exact model at every sample.
    """
    model, traj = rods
    f_today = model.frequencies(traj.q, n_modes=1)[:, 0]
    floor = 1.15 * f_today.min()
    res = size_for_floors(model, traj, [(1, floor)])
    assert res.feasible and res.margin_hz >= -1e-6
    exact = model.frequencies(traj.q, res.y, n_modes=1)[:, 0]
    assert exact.min() >= floor - 1e-6
    # SLSQP on a scaled problem (diameters in cm, the floor as a relative margin): unscaled,
    # its finite-difference line search stops short with "Positive directional derivative"
    cm = 100.0
    ref = minimize(lambda x: design_mass(model, x / cm), model.y0 * cm, method="SLSQP",
                   bounds=[(2.0, 6.0)] * 2, options={"ftol": 1e-12, "maxiter": 200},
                   constraints=[{"type": "ineq", "fun": lambda x: model.frequencies(
                       traj.q, x / cm, n_modes=1)[:, 0] / floor - 1.0}])
    assert ref.success
    assert res.mass_kg <= ref.fun * (1 + 1e-4)
    np.testing.assert_allclose(res.y, ref.x / cm, rtol=2e-3)
    assert res.expansions >= 2  # it re-expanded as the design moved away from y0
    assert res.joints == {"q1": "free", "q2": "free"}


def test_assignment_raises_a_frequency_with_diameters_under_a_link_mass_budget(rods):
    """A target above today's value through the QP, with a budget that counts rod mass."""
    model, traj = rods
    f_today = model.frequencies(traj.q, n_modes=1)[:, 0]
    target = 1.1 * f_today.max()
    budget = design_mass(model, model.y0) * 1.3
    res = assign_frequencies(model, traj, [Target(1, target)], mass_budget_kg=budget,
                             refine=True)
    after = model.frequencies(traj.q, res.y, n_modes=1)[:, 0]
    np.testing.assert_allclose(res.freq_after_hz[:, 0], after, rtol=1e-12)
    assert res.max_error_after < res.max_error_before
    assert after.mean() > f_today.mean()
    # the linearised budget holds on the exact mass up to its curvature (ρ π L δd² / 4)
    assert design_mass(model, res.y) <= budget * (1 + 1e-2)


def test_assignment_floor_along_the_motion_with_diameters(rods):
    """A floor on mode 1 at every sample, section variables, held on the exact model."""
    model, traj = rods
    f_today = model.frequencies(traj.q, n_modes=1)[:, 0]
    floor = 1.08 * f_today.min()
    res = assign_frequencies(model, traj, [Target(1, floor)], floors=[(1, floor)], refine=True)
    after = model.frequencies(traj.q, res.y, n_modes=1)[:, 0]
    assert after.min() >= floor - 1e-6 * floor
    assert res.floor_margin_hz is not None and res.floor_margin_hz >= -1e-6 * floor
    assert res.joints == {"q1": "free", "q2": "free"}
