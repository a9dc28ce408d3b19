"""Eigenfrequency assignment on benchmark A, checked against independent solutions."""

import json
import warnings

import numpy as np
import pytest
from conftest import TWO_LINK
from scipy.optimize import lsq_linear

from pinflex.assignment import (
    Target,
    assign_frequencies,
    build_assignment,
    exact_cost,
    solve_assignment_qp,
    solve_assignment_qp_scipy,
)
from pinflex.assignment.study import user_trajectory
from pinflex.erls import FlexibleModel
from pinflex.exceptions import AssignmentInfeasible, AssignmentWarning, TrajectoryWarning
from pinflex.trajectory import Trajectory

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def setup():
    """Benchmark A model and its 152-sample trajectory in absolute coordinates."""
    model = FlexibleModel(TWO_LINK, planar=True)
    return model, user_trajectory(model, "benchmark_a")


def test_benchmark_a_assignment_reproduces_the_paper(setup):
    """Mode 1 → 190 Hz: m2 = 0, m1 near the paper's 0.2254 kg, 8.3 % → about 1.5 % (exact)."""
    model, traj = setup
    r = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, report_modes=(2, 3, 4))
    assert r.found
    assert r.design["m2"] == pytest.approx(0.0, abs=1e-9)
    # the design is the bounded weighted least-squares optimum of the same polynomial, solved
    # independently of the QP (SciPy lsq_linear on the residuals)
    l0, L = r.taylor.linear_parts(traj.q, quantity="freq_hz")
    w = np.sqrt(traj.trapezoid_weights())
    lo = np.array([d.lower for d in model.design]) - r.taylor.y0
    hi = np.array([d.upper for d in model.design]) - r.taylor.y0
    ref = lsq_linear(w[:, None] * L[:, 0, :], -w * (l0[:, 0] - 190.0), bounds=(lo, hi),
                     tol=1e-14, max_iter=1000)
    np.testing.assert_allclose(r.y, r.taylor.y0 + ref.x, atol=1e-7)
    assert abs(r.design["m1"] - 0.2254) < 0.015  # near the paper's value (0.2370 here)
    assert r.max_error_before == pytest.approx(0.0831, abs=0.0005)
    assert 0.013 < r.max_error_after < 0.017
    # the reported "after" is the exact model's: recompute it independently
    f = model.frequencies(traj.q, r.y)[:, 0]
    assert r.max_error_after == pytest.approx(np.max(np.abs(f / 190 - 1)), rel=1e-12)
    assert r.freq_after_hz.shape == (152, 4)


def test_proxqp_answer_matches_scipy_on_the_same_qp(setup):
    """ProxQP and an independent SciPy solution of the same QP agree to 1e-6."""
    model, traj = setup
    problem, _ = build_assignment(model, traj, [Target(1, 190.0)], q0=Q0)
    a = solve_assignment_qp(problem)
    b = solve_assignment_qp_scipy(problem)
    np.testing.assert_allclose(a.dy, b.dy, atol=1e-6)


def test_qp_cost_is_the_trapezoidal_integral_of_the_polynomial_mismatch(setup):
    """The QP's cost at a design equals ½∫(λ̂ − λ_d)² dt computed directly from the polynomial."""
    model, traj = setup
    problem, tm = build_assignment(model, traj, [Target(1, 190.0)], q0=Q0)
    dy = np.array([0.05, -0.1])
    pred = tm.evaluate(traj.q, tm.y0 + dy, quantity="freq_hz", linear_in_design=True)[:, 0]
    direct = 0.5 * np.sum(traj.trapezoid_weights() * (pred - 190.0) ** 2)
    assert problem.cost(dy) == pytest.approx(direct, rel=1e-10)


def test_mass_budget_binds(setup):
    """With a 0.15 kg budget below the unconstrained m1 ≈ 0.237 kg, the answer sits on it."""
    model, traj = setup
    r = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, mass_budget_kg=0.15)
    assert sum(r.design.values()) == pytest.approx(0.15, abs=1e-7)
    free = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0)
    assert r.max_error_after > free.max_error_after


def test_a_floor_only_the_first_polynomial_binds_is_re_expanded_and_confirmed(setup):
    """A mode-2 floor the polynomial at y0 binds (it is 7 % off at its answer) but the exact
    model clears: the answer is re-expanded until the exact model confirms it (0.5 %)."""
    model, traj = setup
    free = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, report_modes=(2,))
    # halfway between the predicted lowest mode-2 value of the unconstrained answer and that of
    # the bare arm (y = 0), so the floor is feasible for the polynomial at y0 and binds there
    from pinflex.parametric import expand

    tm = expand(model, Q0, model.y0, modes=(1, 2))
    pred = tm.evaluate(traj.q, free.y, quantity="freq_hz", linear_in_design=True,
                       warn=False)[:, 1].min()
    pred_bare = tm.evaluate(traj.q, np.zeros(2), quantity="freq_hz",
                            linear_in_design=True, warn=False)[:, 1].min()
    floor = float(pred + 0.5 * (pred_bare - pred))
    r = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, report_modes=(2,),
                           floors=[(2, floor)])
    first = r.iterations[0]
    assert first["gap"] > 0.05  # the first answer's mode 2 was predicted 7 % off
    assert r.refinements >= 1 and r.confirmed and r.status == "met"
    exact = model.frequencies(traj.q, r.y, n_modes=2)
    assert np.max(np.abs(r.predicted_hz[:, :2] / exact - 1)) == pytest.approx(r.prediction_gap,
                                                                               rel=1e-6)
    assert r.prediction_gap <= 5e-3
    assert exact[:, 1].min() > floor  # the floor holds on the exact model (with room)


def test_frequency_floor_on_mode_2_binds_on_the_exact_model(setup):
    """A mode-2 floor between the bare arm's and the unconstrained answer's exact values holds
    on the exact model, binds (to 1e-6) and moves the design."""
    model, traj = setup
    free = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, report_modes=(2,))
    f2_free = free.freq_after_hz[:, 1].min()
    floor = f2_free + 3.0
    r = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, report_modes=(2,),
                           floors=[(2, floor)])
    exact = model.frequencies(traj.q, r.y, n_modes=2)[:, 1]
    assert r.status == "met" and r.confirmed
    assert exact.min() >= floor * (1 - 1e-6)
    assert exact.min() == pytest.approx(floor, rel=1e-5)  # active on the exact model
    assert r.floor_margin_hz == pytest.approx(exact.min() - floor, abs=1e-6)
    assert r.y[0] < free.y[0] - 1e-3  # less mass on link 1 keeps mode 2 up


def test_multi_mode_targets_weigh_both_modes(setup):
    """Targeting modes 1 and 2 changes the design; the cost is the sum of single-mode costs."""
    model, traj = setup
    targets = [Target(1, 190.0), Target(2, 400.0, weight=0.5)]
    p_both, _ = build_assignment(model, traj, targets, q0=Q0)
    p1, _ = build_assignment(model, traj, targets[:1], q0=Q0)
    p2, _ = build_assignment(model, traj, [Target(2, 400.0)], q0=Q0)
    dy = np.array([0.03, -0.02])
    assert p_both.cost(dy) == pytest.approx(p1.cost(dy) + 0.5 * p2.cost(dy), rel=1e-10)
    r = assign_frequencies(model, traj, targets, q0=Q0)
    assert r.freq_after_hz.shape[1] == 2
    r1 = assign_frequencies(model, traj, targets[:1], q0=Q0)
    assert np.max(np.abs(r.y - r1.y)) > 1e-3


def test_infeasible_constraints_raise(setup):
    """A floor no design can meet together with the bounds raises AssignmentInfeasible."""
    model, traj = setup
    with pytest.raises(AssignmentInfeasible, match="floor"):
        assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, floors=[(1, 260.0)])


def test_unreachable_target_warns(setup):
    """A 120 Hz target needs far more mass than the bounds allow: a warning says so."""
    model, traj = setup
    with pytest.warns(AssignmentWarning, match="out of reach"):
        assign_frequencies(model, traj, [Target(1, 120.0)], q0=Q0)


def test_trajectory_outside_joint_limits_warns(setup):
    """Samples beyond the URDF joint limits give a TrajectoryWarning naming the joint."""
    model, traj = setup
    q = traj.q.copy()
    q[:, 0] += 8.0  # base angle beyond its ±6.2832 rad limit
    q[:, 1] += 8.0  # keep the relative elbow angle
    bad = Trajectory(traj.times_s, q, traj.joint_names)
    with pytest.warns(TrajectoryWarning, match="q1 = "):
        assign_frequencies(model, bad, [Target(1, 190.0)], q0=q[76])


def test_exact_cost_prefers_the_qp_design_over_the_original(setup):
    """Independent exact cost: the QP's design costs far less than the original one."""
    model, traj = setup
    r = assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0)
    costs, errs = exact_cost(model, traj, [Target(1, 190.0)], np.array([r.y, [0.0, 0.0]]))
    assert costs[0] < 0.1 * costs[1]
    assert errs[0] == pytest.approx(r.max_error_after, rel=1e-10)


def test_cli_assign_json(tmp_path, capsys):
    """`pinflex assign CONFIG --json --out DIR` prints the design and errors and writes charts."""
    from pinflex.cli import main

    cfg = tmp_path / "study.toml"
    cfg.write_text(
        f'robot = "{TWO_LINK.as_posix()}"\nplanar = true\n[trajectory]\nbuiltin = "benchmark_a"\n'
        '[expansion]\nq0 = [1.817, 5.312]\n[[targets]]\nmode = 1\nfreq_hz = 190.0\n'
        '[options]\nbaseline = { m1 = 0.0, m2 = 0.0 }\n'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert main(["assign", str(cfg), "--json", "--out", str(tmp_path / "charts")]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["design"]) == {"m1", "m2"}
    assert out["max_error_before"] == pytest.approx(0.0832, abs=5e-4)
    assert out["max_error_after"] < 0.017
    for key in ("qp_iterations", "qp_time_s", "total_time_s"):
        assert key in out
    assert (tmp_path / "charts" / "mode1_assignment.png").stat().st_size > 10_000
    assert (tmp_path / "charts" / "other_modes.png").is_file()
    # per-sample frequencies and the constraint report come with the summary
    assert out["modes"][0]["mode"] == 1 and len(out["modes"][0]["after_hz"]) == 152
    assert out["active_constraints"] == [] or isinstance(out["active_constraints"], list)
    assert (tmp_path / "charts" / "assignment.csv").is_file()


def test_trajectory_limit_check_names_a_wrong_joint_count():
    """Samples with the wrong number of columns: a named error, not a NumPy shape error."""
    from pinflex.assignment import check_trajectory_limits
    from pinflex.exceptions import InvalidTrajectory

    model = FlexibleModel(TWO_LINK, planar=True)
    bad = Trajectory(np.array([0.0, 1.0]), np.zeros((2, 3)), ("a", "b", "c"))
    with pytest.raises(InvalidTrajectory, match="column .a. names no joint"):
        check_trajectory_limits(model, bad)
    check_trajectory_limits(model, Trajectory(np.array([0.0, 1.0]),
                                              np.array([[1.7, 5.1], [1.8, 5.2]]), ("q1", "q2")))
