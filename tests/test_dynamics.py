"""Time simulation of eq. (1): terms, prescribed motion, checks against independent references."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import reference_fe as ref
import scipy.linalg
from arms import locked_global_fe as _locked_global_fe
from arms import move as _move

from pinflex import FlexibleModel
from pinflex.dynamics import (
    ErlsDynamics,
    dominant_frequency,
    simulate_prescribed,
    vibration_report,
)

URDF = Path(__file__).resolve().parents[1] / "urdf"


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(URDF / "two_link.urdf", planar=True)


def test_mass_and_stiffness_equal_the_erls_assembly():
    """The material-point sums of eq. (1) give the assembly's M and K to round-off."""
    for name, planar in (("two_link.urdf", True), ("ur5_flexible.xml", False)):
        fm = FlexibleModel(URDF / name, planar=planar)
        dyn = ErlsDynamics(fm)
        rng = np.random.default_rng(3)
        q = rng.uniform(-1.0, 1.0, fm.nv)
        M0, K0 = fm.matrices(q)
        M, Ck, K, F = dyn.linear_terms(q)
        assert np.abs(M - M0).max() <= 1e-13 * np.abs(M0).max()
        assert np.abs(K - K0).max() <= 1e-13 * np.abs(K0).max()
        assert not np.any(F)  # no gravity by default


def _world_points(fm, q, link, c):
    """World positions of points c (n, 3) on a link, straight from Pinocchio's kinematics."""
    data = fm.model.createData()
    pin.framesForwardKinematics(fm.model, data, fm.pin_configuration(q))
    oMf = data.oMf[fm.model.getFrameId(link, pin.FrameType.BODY)]
    return c @ oMf.rotation.T + oMf.translation


def test_erls_acceleration_and_root_rate_match_finite_differences():
    """Ṡ q̇ (Pinocchio's Jacobian time variation) and Ė against central differences."""
    fm = FlexibleModel(URDF / "ur5_flexible.xml")
    dyn = ErlsDynamics(fm)
    rng = np.random.default_rng(7)
    q0, v, a = rng.uniform(-1, 1, fm.nv), rng.uniform(-1, 1, fm.nv), rng.uniform(-1, 1, fm.nv)
    maps = dyn.point_maps(q0)
    h = 1e-4

    def q_at(t):
        return q0 + v * t + 0.5 * a * t * t

    for link, (W, Sdk, R, c) in maps.items():
        P = [_world_points(fm, q_at(s * h), link, c) for s in (-1, 0, 1)]
        acc_fd = (P[0] - 2 * P[1] + P[2]) / h**2
        S = W[:, :, fm.nx:]
        acc = (S @ a + np.einsum("k,knaj,j->na", v, Sdk, v)) @ R.T
        assert np.abs(acc - acc_fd).max() <= 2e-5 * max(1.0, np.abs(acc_fd).max()), link
        # rate of the elastic map (root copy turning with the joints)
        E = [dyn.point_maps(q_at(s * h))[link][0][:, :, : fm.nx] for s in (-1, 1)]
        Ed_fd = (E[1] - E[0]) / (2 * h)
        J, Jd, Rr, e, ed = dyn._kinematics(q0)
        p = next(g for g in dyn._points if g.link == link)
        Ed = 0 * Ed_fd if ed.get(link) is None else np.einsum("nab,kbx,k->nax", p.D, ed[link], v)
        assert np.abs(Ed - Ed_fd).max() <= 1e-6 * max(1.0, np.abs(Ed_fd).max()), link


def test_residual_vibration_has_the_locked_joint_frequency(arm):
    """After a prescribed move the tip rings at the locked-joint eigenfrequency (global FE).

    Holding the ERLS coordinates instead of the physical joint angle would give a frequency
    tens of percent away: that one is checked to be far.
    """
    y = np.array([0.1, 0.05])
    q_end = np.array([1.9, 5.3])
    traj = _move([1.7, 5.1], q_end, 0.12, n=25)
    dyn = ErlsDynamics(arm, y=y)
    sim = simulate_prescribed(dyn, traj, after_s=0.25, sample_hz=4000.0)
    rep = vibration_report(dyn, sim, frame="tool")
    Kl, Ml, _ = _locked_global_fe(q_end, *y)
    f_fe = np.sqrt(scipy.linalg.eigh(Kl, Ml, eigvals_only=True)[0]) / (2 * math.pi)
    assert rep.joint_condition == "locked"
    assert rep.reference_hz[0] == pytest.approx(f_fe, rel=1e-9)
    assert rep.dominant_frequency_hz == pytest.approx(f_fe, rel=2e-4)
    M, K = arm.matrices(q_end, y)
    nx = arm.nx
    f_wrong = np.sqrt(scipy.linalg.eigh(K[:nx, :nx], M[:nx, :nx], eigvals_only=True)[0]) / (
        2 * math.pi)
    assert abs(f_wrong / f_fe - 1.0) > 0.1
    assert rep.residual_amplitude_m > 1e-6


def test_slow_motion_under_gravity_is_quasi_static(arm):
    """A slow small move under gravity: the tip deflection follows the static one (global FE)."""
    y = np.array([0.05, 0.1])
    g = np.array([0.0, -9.81, 0.0])
    traj = _move([1.7, 5.1], [1.75, 5.15], 2.0, n=21)
    dyn = ErlsDynamics(arm, y=y, gravity=g)
    sim = simulate_prescribed(dyn, traj, after_s=0.01, sample_hz=200.0)
    rep = vibration_report(dyn, sim, frame="tool")
    for t_check in (0.0, 1.0, 2.0):
        i = int(np.argmin(np.abs(sim.times_s - t_check)))
        _, _, keep = _locked_global_fe(sim.q_physical[i], *y)
        # consistent gravity load: M times the rigid translation field along g
        K, M = ref.planar_two_link_matrices(sim.q_physical[i], *y)
        r = np.zeros(K.shape[0])
        dofs = ref.planar_chain_dofs([4, 3])
        for table in dofs:
            for row in table:
                if row[0] >= 0:
                    r[row[0]], r[row[1]] = g[0], g[1]
        f = M @ r
        T = np.zeros((K.shape[0], len(keep)))
        for col, k in enumerate(keep):
            T[k, col] = 1.0
        T[13, keep.index(12)] = 1.0
        u = T @ np.linalg.solve(T.T @ K @ T, T.T @ f)
        tip = u[[20, 21]]
        assert np.linalg.norm(tip) > 1e-5
        assert rep.deflection_m[i, :2] == pytest.approx(tip, rel=2e-3, abs=1e-3 * np.linalg.norm(
            tip))
        assert abs(rep.deflection_m[i, 2]) < 1e-12


def test_stiff_arm_torques_equal_rigid_inverse_dynamics(tmp_path):
    """With E x 1e6 the motor torques of a prescribed move equal Pinocchio's RNEA."""
    text = (URDF / "two_link.urdf").read_text().replace('E="69e9"', 'E="69e15"')
    path = tmp_path / "stiff.urdf"
    path.write_text(text)
    fm = FlexibleModel(path, planar=True)
    y = np.array([0.1, 0.05])
    traj = _move([1.7, 5.1], [2.2, 5.4], 0.3, n=31)
    sim = simulate_prescribed(ErlsDynamics(fm, y=y), traj, after_s=0.01, sample_hz=1000.0)
    # rigid model: each link a 1.9 kg/m line mass (inertia m L²/12 about its middle, no
    # rotary inertia in the plane), plus the point masses
    model = pin.buildModelFromUrdf(str(path))
    for jid, L, mass in ((1, 0.6, y[0]), (2, 0.45, y[1])):
        m = 1.9 * L
        rod = pin.Inertia(m, np.array([L / 2, 0, 0]), np.diag([0.0, m * L**2 / 12, m * L**2 / 12]))
        tip = pin.Inertia.FromSphere(mass, 0.0).se3Action(pin.SE3(np.eye(3), np.array([L, 0, 0])))
        model.inertias[jid] = rod + tip
    data = model.createData()
    from pinflex.dynamics.motion import JointMotion

    motion = JointMotion(traj)
    C = fm.coord_map
    worst = 0.0
    scale = 0.0
    along = sim.torque_times_s <= sim.stop_s  # after the stop the stiff arm rings (kHz)
    for t, tau in zip(sim.torque_times_s[along], sim.torques[along]):
        q, qd, qdd = motion(t)
        qp = C @ q
        rigid = pin.rnea(model, data, np.array([qp[0], qp[1]]), C @ qd, C @ qdd)
        worst = max(worst, float(np.abs(tau - rigid).max()))
        scale = max(scale, float(np.abs(rigid).max()))
    assert scale > 0.1
    assert worst <= 1e-6 * scale


def test_dominant_frequency_of_a_damped_sinusoid():
    """The spectral peak refined by a fit recovers a damped sinusoid's frequency."""
    t = np.arange(0, 0.4, 1 / 3000)
    s = np.exp(-2.0 * t) * np.sin(2 * np.pi * 123.4 * t + 0.3) + 0.05 * np.sin(2 * np.pi * 410 * t)
    assert dominant_frequency(t, s) == pytest.approx(123.4, rel=1e-4)
