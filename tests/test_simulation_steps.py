"""The fixed-step integrator of prescribed motions: order, Richardson estimate, ``tol``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from pinflex import FlexibleModel
from pinflex.dynamics import ErlsDynamics, simulate_prescribed, vibration_report
from pinflex.dynamics.simulate import fixed_step, richardson_fixed
from pinflex.exceptions import ConfigurationError
from pinflex.trajectory import Trajectory

URDF = Path(__file__).resolve().parents[1] / "urdf"


def _oscillator(omega=2 * np.pi * 7.0, zeta=0.02, big=2 * np.pi * 900.0, w_f=2 * np.pi * 3.0):
    """Two uncoupled oscillators (one stiff) under f = [1, 1] sin(w_f t), zero start.

    Returns the batched coefficient function and the closed-form displacement x(t).
    """
    w = np.array([omega, big])
    z = np.array([zeta, 0.0])

    def coeffs(ts):
        n = ts.size
        M = np.broadcast_to(np.eye(2), (n, 2, 2)).copy()
        C = np.broadcast_to(np.diag(2 * z * w), (n, 2, 2)).copy()
        K = np.broadcast_to(np.diag(w**2), (n, 2, 2)).copy()
        f = np.sin(w_f * ts)[:, None] * np.ones((n, 2))
        return M, C, K, f

    def exact(t):
        # particular solution A sin + B cos, plus the damped homogeneous part fitting x(0) = 0,
        # x'(0) = 0
        out = np.empty((t.size, 2))
        for i in range(2):
            den = (w[i] ** 2 - w_f**2) ** 2 + (2 * z[i] * w[i] * w_f) ** 2
            A = (w[i] ** 2 - w_f**2) / den
            B = -2 * z[i] * w[i] * w_f / den
            wd = w[i] * np.sqrt(1 - z[i] ** 2)
            c1 = -B
            c2 = (-A * w_f + z[i] * w[i] * c1) / wd
            out[:, i] = (A * np.sin(w_f * t) + B * np.cos(w_f * t)
                         + np.exp(-z[i] * w[i] * t) * (c1 * np.cos(wd * t) + c2 * np.sin(wd * t)))
        return out

    return coeffs, exact


def test_trapezoidal_steps_are_second_order_and_the_estimate_is_their_error():
    """Against a closed form: error ∝ h², Richardson estimate = the finer run's error."""
    coeffs, exact = _oscillator()
    errs = {}
    for n in (400, 800, 1600):
        t, X, _, _ = fixed_step(coeffs, 0.0, 1.0, n, np.zeros(2), np.zeros(2))
        errs[n] = np.abs(X[:, 0] - exact(t)[:, 0]).max()
    assert errs[400] / errs[800] == pytest.approx(4.0, rel=0.05)
    assert errs[800] / errs[1600] == pytest.approx(4.0, rel=0.05)
    run = richardson_fixed(coeffs, 0.0, 1.0, np.zeros(2), np.zeros(2), n_steps=800)
    scale = np.abs(exact(run.t)).max()
    # the estimate is the error of the 1600-step run (relative to the largest |x|) ...
    assert run.error_estimate == pytest.approx(errs[1600] / scale, rel=0.1)
    # ... and the extrapolated result returned is far better than it
    true = np.abs(run.x - exact(run.t)).max() / scale
    assert true < 0.05 * run.error_estimate


def test_tol_picks_the_step_and_its_estimate_holds_against_the_converged_run():
    """Benchmark A arm, a fast move: the tol ladder meets tol; the estimate bounds the error."""
    arm = FlexibleModel(URDF / "two_link.urdf", planar=True)
    t = np.linspace(0.0, 0.12, 25)
    s = t / 0.12
    h = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.array([1.7, 5.1])[None] + h[:, None] * np.array([0.2, 0.2])[None]
    traj = Trajectory(t, q, ("q1", "q2"))
    dyn = ErlsDynamics(arm, y=[0.1, 0.05])
    conv = simulate_prescribed(dyn, traj, after_s=0.02, sample_hz=4000.0, tol=1e-6)
    loose = simulate_prescribed(dyn, traj, after_s=0.02, sample_hz=4000.0, steps=30)
    picked = simulate_prescribed(dyn, traj, after_s=0.02, sample_hz=4000.0, steps=30, tol=1e-3)
    during = conv.times_s <= conv.stop_s
    scale = np.abs(conv.x[during]).max()

    def err(sim):
        return np.abs(sim.x[during] - conv.x[during]).max() / scale

    assert loose.error_estimate > 1e-3  # 30 steps do not meet 1e-3 ...
    assert picked.error_estimate <= 1e-3  # ... the ladder doubled until the estimate did
    assert picked.steps - int((~during).sum()) > 60
    assert 1.6 < picked.observed_order < 2.4
    assert err(picked) <= picked.error_estimate  # the extrapolated result is within it
    assert err(picked) < 0.1 * err(loose)
    # the default (no tol) and the adaptive generalized-alpha agree with the converged run
    rep_c = vibration_report(dyn, conv)
    for kw in ({}, {"method": "newmark", "rtol": 1e-6}):
        rep = vibration_report(dyn, simulate_prescribed(dyn, traj, after_s=0.02,
                                                        sample_hz=4000.0, **kw))
        peak = np.abs(rep_c.deflection_m).max()
        assert np.abs(rep.deflection_m - rep_c.deflection_m).max() <= 2e-3 * peak


def test_bad_step_settings_are_refused():
    """tol, steps and the grid are checked; tol and steps belong to the fixed integrator."""
    arm = FlexibleModel(URDF / "two_link.urdf", planar=True)
    dyn = ErlsDynamics(arm, y=[0.1, 0.05])
    traj = Trajectory(np.array([0.0, 0.1]), np.array([[1.7, 5.1], [1.8, 5.2]]), ("q1", "q2"))
    for kw in ({"tol": 0.0}, {"tol": float("nan")}, {"steps": 1}, {"grid_per_interval": 0},
               {"method": "newmark", "tol": 1e-3}):
        with pytest.raises(ConfigurationError):
            simulate_prescribed(dyn, traj, after_s=0.01, **kw)


def test_simulate_command_tol_reaches_the_integrator(tmp_path, capsys):
    """`pinflex simulate --tol`: each design's step-error estimate meets it; bad values refused."""
    from pinflex.cli import main

    t = np.linspace(0.0, 0.12, 25)
    s = t / 0.12
    q = np.array([1.7, 5.1])[None] + (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None] * 0.2
    csv = tmp_path / "move.csv"
    csv.write_text("t,q1,q2\n" + "\n".join(f"{a},{b},{c}" for a, (b, c) in zip(t, q)))
    study = tmp_path / "s.toml"
    study.write_text('robot = "builtin:two_link.urdf"\nplanar = true\n'
                     f'[trajectory]\ncsv = "{csv}"\n[[targets]]\nmode = 1\nfreq_hz = 190.0\n'
                     '[simulation]\nafter_s = 0.02\nsample_hz = 4000.0\n')
    assert main(["simulate", str(study), "--json", "--tol", "1e-3"]) == 0
    designs = json.loads(capsys.readouterr().out)["designs"]
    assert len(designs) == 2
    for d in designs:
        assert 0.0 < d["step_error_estimate"] <= 1e-3
    assert main(["simulate", str(study), "--json"]) == 0  # one pair: a coarser estimate
    loose = json.loads(capsys.readouterr().out)["designs"]
    assert all(a["step_error_estimate"] > b["step_error_estimate"]
               for a, b in zip(loose, designs))
    assert main(["simulate", str(study), "--json", "--tol", "0"]) == 2
    assert "tol" in capsys.readouterr().err
