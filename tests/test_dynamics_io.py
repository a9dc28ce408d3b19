"""Dynamics: study tables, joint offsets and springs, frequency responses, energy."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import reference_fe as ref

from pinflex import FlexibleModel
from pinflex.dynamics import ErlsDynamics
from pinflex.dynamics.frf import frf, frf_direct, linear_pose
from pinflex.dynamics.simulate import Damping, energy, simulate_torque
from pinflex.dynamics.study import InvalidSimulationTable, parse_simulation_table
from pinflex.exceptions import ConfigurationError, PinflexError

URDF = Path(__file__).resolve().parents[1] / "urdf"


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(URDF / "two_link.urdf", planar=True)


def test_simulation_table_lists_every_problem():
    """Unknown keys, wrong types and ranges come back in one named error."""
    with pytest.raises(InvalidSimulationTable) as err:
        parse_simulation_table({"drive": "fly", "after_s": -1, "gravity": [0, 1], "foo": 3,
                                "damping": {"kind": "modal"}, "rtol": "x"})
    assert isinstance(err.value, PinflexError)
    assert len(err.value.problems) == 6
    s = parse_simulation_table({"damping": {"kind": "rayleigh", "beta": 1e-5},
                                "gravity": [0, -9.81, 0], "frame": "link2"})
    assert s.damping == Damping("rayleigh", 0.0, 1e-5)
    assert s.gravity == (0.0, -9.81, 0.0) and s.frame == "link2"
    assert parse_simulation_table(None).drive == "prescribed"


def test_joint_offsets_match_the_relative_motion_rows():
    """A (the elastic offset of the ERLS joint coordinates) against the joint layer's G."""
    for name, planar in (("two_link.urdf", True), ("ur5_flexible.xml", False)):
        fm = FlexibleModel(URDF / name, planar=planar)
        dyn = ErlsDynamics(fm)
        q = np.random.default_rng(1).uniform(-1, 1, fm.nv)
        A = dyn.joint_offsets(q)[0]
        G = fm.relative_motion_rows(q)
        assert np.allclose(fm.coord_map @ A, -G[:, : fm.nx], rtol=0, atol=1e-13)
        assert np.any(A)


def test_joint_springs_enter_the_stiffness():
    """With joint springs K(q) still equals the assembly's."""
    fm = FlexibleModel(URDF / "two_link.urdf", planar=True, joints={"q1": 2e4, "q2": 5e3})
    dyn = ErlsDynamics(fm)
    q = np.array([1.8, 5.3])
    assert np.allclose(dyn.linear_terms(q)[2], fm.matrices(q)[1], rtol=0,
                       atol=1e-9 * np.abs(fm.matrices(q)[1]).max())
    # locked joints are constraints of the drive (tests/test_dynamics_locked.py), not of eq. (1)
    locked = ErlsDynamics(FlexibleModel(URDF / "two_link.urdf", planar=True, joints="locked"))
    assert locked.locked == (("q1", 0), ("q2", 1)) and locked.ndof == fm.nx + 2


def test_frf_from_modes_equals_the_direct_solve(arm, tmp_path):
    """Modal receptance = (K − ω²M + iωC)⁻¹ at sampled ω, free and locked joints."""
    dyn = ErlsDynamics(arm, y=[0.1, 0.05])
    q = np.array([1.8, 5.3])
    tip = ("displacement", "tool", (0, 0, 0), (0, 1, 0))
    freqs = np.array([3.0, 50.0, 190.0, 333.0, 1500.0])
    for joints, inputs, damping in (
            ("free", [("torque", "q1"), ("force", "tool", (0, 0, 0), (1, 1, 0))],
             Damping("modal", ratios=(0.02, 0.01))),
            ("locked", [("force", "link2", (0.2, 0, 0), (0, 1, 0))],
             Damping("rayleigh", alpha=0.5, beta=2e-5))):
        lp = linear_pose(dyn, q, inputs, [tip], damping=damping, joints=joints)
        Hm, Hd = frf(lp, freqs), frf_direct(lp, freqs)
        assert np.abs(Hm - Hd).max() <= 1e-9 * np.abs(Hd).max()
    from pinflex.dynamics.charts import bode_chart

    png = bode_chart(freqs, Hm[:, 0, :].T, ["force"], tmp_path / "bode.png", title="tip")
    assert png.stat().st_size > 1000
    with pytest.raises(ConfigurationError):
        linear_pose(dyn, q, [("torque", "q1")], [tip], joints="locked")


def test_locked_static_receptance_equals_global_fe_compliance(arm):
    """At ω → 0 the locked receptance tip/tip is the clamped frame's static compliance."""
    y = np.array([0.1, 0.05])
    q = np.array([1.8, 5.3])
    dyn = ErlsDynamics(arm, y=y)
    tip_y = ("displacement", "tool", (0, 0, 0), (0, 1, 0))
    lp = linear_pose(dyn, q, [("force", "tool", (0, 0, 0), (0, 1, 0))], [tip_y],
                     joints="locked")
    h0 = frf(lp, [1e-6])[0, 0, 0].real
    K, M = ref.planar_two_link_matrices(q, *y)
    n = K.shape[0]
    keep = [i for i in range(n) if i not in (0, 13)]
    T = np.zeros((n, n - 2))
    for col, i in enumerate(keep):
        T[i, col] = 1.0
    T[13, keep.index(12)] = 1.0
    f = np.zeros(n)
    f[21] = 1.0  # unit force along world y at the tip node
    u = T @ np.linalg.solve(T.T @ K @ T, T.T @ f)
    assert h0 == pytest.approx(u[21], rel=1e-9)


def test_free_vibration_conserves_energy_to_the_tolerance(arm):
    """No damping, no torque, free joints: T + V stays within a few rtol over 1.5 periods."""
    y = [0.1, 0.05]
    dyn = ErlsDynamics(arm, y=y)
    q0 = np.array([1.8, 5.3])
    mode = arm.modes(q0, y, n_modes=1)
    nx = arm.nx
    sh = mode.shapes[:, 0] * 1e-4 / np.abs(mode.shapes[:nx, 0]).max()
    period = 1.0 / mode.freq_hz[0]
    energies = {}
    for rtol in (1e-3, 1e-4):
        sim = simulate_torque(dyn, q0=q0 + sh[nx:], x0=sh[:nx], duration_s=1.5 * period,
                              rho_inf=1.0, sample_hz=12 / period, rtol=rtol)
        E = np.array([energy(dyn, np.r_[sim.x[i], sim.q[i]], np.r_[sim.xd[i], sim.qd[i]])
                      for i in range(sim.times_s.size)])
        energies[rtol] = (E.max() - E.min()) / E[0]
        assert sim.joint_condition == "free"
    assert energies[1e-4] <= 10 * 1e-4
    assert energies[1e-4] < energies[1e-3]
    assert math.isfinite(energies[1e-3])


def test_playback_page_of_a_simulation(arm, tmp_path):
    """The meshcat playback of a short simulation writes an offline page."""
    pytest.importorskip("meshcat")
    from pinflex.dynamics import simulate_prescribed
    from pinflex.trajectory import Trajectory
    from pinflex.visualization.playback import simulation_playback_html

    dyn = ErlsDynamics(arm, y=[0.1, 0.05])
    t = np.linspace(0, 0.05, 6)
    s = t / 0.05
    q = np.array([1.7, 5.1]) + (10 * s**3 - 15 * s**4 + 6 * s**5)[:, None] * 0.05
    sim = simulate_prescribed(dyn, Trajectory(t, q), after_s=0.02, sample_hz=1000.0)
    page = simulation_playback_html(dyn, sim, tmp_path / "play.html", exaggeration=100)
    text = page.read_text()
    assert "elastic motion drawn 100 x" in text
    with pytest.raises(ConfigurationError):
        simulation_playback_html(dyn, sim, tmp_path / "bad.html", exaggeration=0)


def test_simulate_command_rejects_a_bad_table(tmp_path, capsys):
    """`pinflex simulate` exits with status 2 and one line naming every problem."""
    from pinflex.cli import main

    study = tmp_path / "s.toml"
    study.write_text('robot = "builtin:two_link.urdf"\nplanar = true\n[[targets]]\nmode = 1\n'
                     'freq_hz = 190.0\n[simulation]\ndrive = "fly"\nfoo = 1\n')
    assert main(["simulate", str(study), "--json"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "foo" in err[0] and "fly" in err[0]


def test_reduced_basis_of_one_pose_is_detected(arm):
    """Modes of the final pose alone miss the static response of a folding move: warned."""
    from pinflex.dynamics.motion import JointMotion
    from pinflex.dynamics.simulate import PrescribedSystem, _ReducedSystem
    from pinflex.exceptions import PinflexWarning
    from pinflex.trajectory import Trajectory

    dyn = ErlsDynamics(arm, y=[0.0, 0.0])
    t = np.linspace(0.0, 0.3, 31)
    s = t / 0.3
    h = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.array([1.8, 5.15]) + h[:, None] * np.array([0.3, 0.7])  # the elbow folds 0.4 rad
    full = PrescribedSystem(dyn, JointMotion(Trajectory(t, q)))
    with pytest.warns(PinflexWarning):
        one = _ReducedSystem(full, 4, n_poses=1)
    three = _ReducedSystem(full, 4, n_poses=3)
    assert one.static_error > 0.5
    assert three.static_error < 0.05
    assert three.nx == 12


def test_prbdm_responses_against_closed_forms_and_the_linear_chain():
    """Beam FE static tip compliance = L³/3EI; chain ABA step response = its linear modes."""
    from pinflex.dynamics import prbdm as pd
    from pinflex.prbdm import build_chain, uniform_beam

    pl = uniform_beam()
    E, L, w, t = 205e9, 1.0, 0.3624, 0.040532
    EI = E * w * t**3 / 12.0
    beam = pd.beam_linear(pl, 0.02)
    assert abs(pd.receptance(beam, [0.0])[0]) == pytest.approx(L**3 / (3 * EI), rel=1e-9)
    # Su's 3R PRBM (K_i = k_i EI / L)
    chain = build_chain(pl, np.array([0.10, 0.35, 0.40, 0.15]),
                        np.array([3.51, 2.99, 2.58]) * EI / L)
    lin = pd.chain_linear(chain, 0.02)
    f1 = np.sqrt(np.linalg.eigvals(np.linalg.solve(lin.M, lin.K)).real.min()) / (2 * np.pi)
    times = np.linspace(0.0, 3.0 / f1, 400)
    force = 0.001 / abs(pd.receptance(lin, [0.0])[0])  # 1 mm static: linear range
    z_aba = pd.chain_step_response(chain, 0.02, force, times)
    z_lin = pd.beam_step_response(lin, force, times)  # exact modal sum of the linear chain
    assert np.abs(z_aba - z_lin).max() <= 2e-3 * np.abs(z_lin).max()
    report = pd.compare(pl, chain, xi=0.02, periods=2.0)
    assert len(report["peak_error"]) == 3 and report["static_error"] == pytest.approx(
        abs(pd.receptance(lin, [0.0])[0]) * 3 * EI / L**3 - 1.0, rel=1e-9)


def test_slow_tip_force_gives_the_static_compliance(arm):
    """A tip force ramped slowly on the held arm settles at the global FE's static deflection."""
    from pinflex.dynamics import simulate_prescribed, vibration_report
    from pinflex.trajectory import Trajectory

    y = np.array([0.1, 0.05])
    q = np.array([1.8, 5.3])
    dyn = ErlsDynamics(arm, y=y)
    T = 1.0

    def force(t):
        s = min(max(t / T, 0.0), 1.0)
        return np.array([0.0, 2.0, 0.0]) * (10 * s**3 - 15 * s**4 + 6 * s**5)

    traj = Trajectory(np.linspace(0.0, T, 11), np.tile(q, (11, 1)))
    sim = simulate_prescribed(dyn, traj, after_s=0.2, sample_hz=500.0,
                              damping=Damping("modal", ratios=(0.05,)),
                              forces=[("tool", (0, 0, 0), force)])
    rep = vibration_report(dyn, sim, frame="tool")
    K, M = ref.planar_two_link_matrices(q, *y)
    n = K.shape[0]
    keep = [i for i in range(n) if i not in (0, 13)]
    Tm = np.zeros((n, n - 2))
    for col, i in enumerate(keep):
        Tm[i, col] = 1.0
    Tm[13, keep.index(12)] = 1.0
    f = np.zeros(n)
    f[21] = 2.0
    u = Tm @ np.linalg.solve(Tm.T @ K @ Tm, Tm.T @ f)
    assert rep.deflection_m[-1, :2] == pytest.approx(u[[20, 21]], rel=1e-3,
                                                     abs=1e-3 * abs(u[21]))


@pytest.mark.parametrize("setting, named", [("nosuch=1", "nosuch"), ("m1=0.3", "m1")])
def test_simulate_command_takes_set_and_checks_it(tmp_path, capsys, setting, named):
    """`pinflex simulate --set` reaches the model: unknown names and out-of-bounds values fail."""
    from pinflex.cli import main

    study = tmp_path / "s.toml"
    study.write_text('robot = "builtin:two_link.urdf"\nplanar = true\n[[targets]]\nmode = 1\n'
                     'freq_hz = 190.0\n[simulation]\ndrive = "prescribed"\n')
    assert main(["simulate", str(study), "--json", "--set", setting]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and named in err[0]
