"""Dynamics of one design and of one-joint arms: the model's own values reach eq. (1)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import reference_fe as ref
import scipy.linalg

from pinflex import FlexibleModel
from pinflex.dynamics import ErlsDynamics, dominant_frequency, simulate_prescribed
from pinflex.dynamics.frf import frf, frf_direct, linear_pose
from pinflex.dynamics.torque import simulate_torque
from pinflex.trajectory import Trajectory

DESIGNED = """<?xml version="1.0"?>
<robot name="designed" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="tool"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-6" upper="6" effort="100" velocity="10"/></joint>
  <joint name="q2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-6" upper="6" effort="100" velocity="10"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="link2"/><child link="tool"/>
    <origin xyz="0.45 0 0"/></joint>
  <pinflex:parameter name="d1" value="0.03" lower="0.02" upper="0.05" design="true"/>
  <pinflex:parameter name="E2" value="69e9" lower="5e10" upper="2.2e11" design="true"/>
  <pinflex:parameter name="k2" value="2e4" lower="1e3" upper="1e6" design="true"/>
  <pinflex:parameter name="mp" value="0.2" lower="0" upper="1" design="true"/>
  <pinflex:flexible link="link1" elements="4" normal="0 0 1">
    <pinflex:material E="69e9" density="2700"/>
    <pinflex:section shape="solid_circle" diameter="{d1}"/>
  </pinflex:flexible>
  <pinflex:flexible link="link2" elements="3" normal="0 0 1">
    <pinflex:material E="{E2}" density="2700"/>
    <pinflex:section shape="solid_circle" diameter="0.03"/>
  </pinflex:flexible>
  <pinflex:point_mass name="tip" link="link2" xyz="0.45 0 0" mass="{mp}"/>
  <pinflex:point_mass name="m1" link="link1" xyz="0.6 0 0" mass="0.1" design="true"
                      lower="0" upper="0.3"/>
  <pinflex:joint name="q2" stiffness="{k2}"/>
</robot>
"""

#: Kane, Ryan and Banerjee's beam on one revolute joint: L = 10 m, EI = 1.4e4 N m², ρA = 1.2
#: kg/m (EA = 1.4e7 N), ten elements.
ONE_LINK = """<?xml version="1.0"?>
<robot name="one_link" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="tool"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <origin xyz="0 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-1000" upper="1000" effort="100" velocity="100"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="link1"/><child link="tool"/>
    <origin xyz="10 0 0"/></joint>
  <pinflex:flexible link="link1" elements="10" normal="0 0 1">
    <pinflex:material E="7e10" linear_density="1.2"/>
    <pinflex:section A="2e-4" Iy="2e-7" Iz="2e-7" J="4e-7"/>
  </pinflex:flexible>
</robot>
"""
KANE = {"EI": 1.4e4, "rhoA": 1.2, "EA": 1.4e7}


def _write(tmp_path, name, text):
    path = tmp_path / name
    path.write_text(text)
    return path


@pytest.fixture(scope="module")
def designed(tmp_path_factory):
    """A two-link arm whose section, material, spring and a point mass are parameters."""
    return _write(tmp_path_factory.mktemp("design"), "designed.urdf", DESIGNED)


@pytest.fixture(scope="module")
def one_link(tmp_path_factory):
    """Kane's beam on one revolute joint, planar."""
    path = _write(tmp_path_factory.mktemp("one"), "one_link.urdf", ONE_LINK)
    return FlexibleModel(path, planar=True)


def test_dynamics_matrices_follow_section_material_and_spring_parameters(designed):
    """M and K of eq. (1) equal FlexibleModel.matrices at a design away from the nominal one."""
    for planar in (True, False):
        fm = FlexibleModel(designed, planar=planar, joints="annotated")
        assert fm.design_names == ("m1", "d1", "E2", "k2", "mp")
        q = np.array([0.3, -0.7])
        for y in (fm.y0, np.array([0.2, 0.04, 1.5e11, 1e5, 0.6])):
            M0, K0 = fm.matrices(q, y)
            M, _, K, _ = ErlsDynamics(fm, y).linear_terms(q)
            assert np.abs(M - M0).max() <= 1e-13 * np.abs(M0).max()
            assert np.abs(K - K0).max() <= 1e-13 * np.abs(K0).max()


def test_dynamics_at_a_design_rings_at_the_global_fe_frequencies(designed):
    """Eigenfrequencies of eq. (1) at a non-nominal design equal a global FE's (springs)."""
    fm = FlexibleModel(designed, planar=True, joints="annotated")
    m1, d1, E2, k2, mp = 0.2, 0.04, 1.5e11, 1e5, 0.6
    q = np.array([0.3, -0.7])
    M, _, K, _ = ErlsDynamics(fm, [m1, d1, E2, k2, mp]).linear_terms(q)
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    f = np.sqrt(lam[1:6]) / (2 * math.pi)  # one rigid mode: the free base joint
    d2 = 0.03
    area = [math.pi * d1**2 / 4, math.pi * d2**2 / 4]
    inertia = [math.pi * d1**4 / 64, math.pi * d2**4 / 64]
    E = [69e9, E2]
    Kr, Mr = ref.planar_chain_matrices(
        [q[0], q[0] + q[1]], [0.6, 0.45], [4, 3], EI=[E[i] * inertia[i] for i in range(2)],
        rhoA=[2700 * a for a in area], EA=[E[i] * area[i] for i in range(2)],
        end_masses=[m1, mp], joints=[None, k2])
    _, f_ref = ref.solve_frequencies(Kr, Mr, 1)
    assert f == pytest.approx(f_ref[:5], rel=1e-9)
    # and the nominal design is clearly different (the design reached the dynamics)
    lam0 = scipy.linalg.eigh(*ErlsDynamics(fm).linear_terms(q)[2::-2], eigvals_only=True)
    assert abs(np.sqrt(lam0[1]) / (2 * math.pi) / f[0] - 1.0) > 0.05


def test_one_joint_arm_terms_and_responses(one_link):
    """A one-joint arm in eq. (1), FRF and both drives: pinned-free and clamped references."""
    fm = one_link
    dyn = ErlsDynamics(fm)
    th = 0.4
    M, _, K, _ = dyn.linear_terms(np.array([th]))
    Kr, Mr = ref.planar_chain_matrices([th], [10.0], [10], **KANE, joints=[None])
    _, f_free = ref.solve_frequencies(Kr, Mr, 1)
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)
    assert np.sqrt(lam[1:6]) / (2 * math.pi) == pytest.approx(f_free[:5], rel=1e-8)
    Kc, Mc = ref.planar_chain_matrices([th], [10.0], [10], **KANE, joints=["clamped"])
    _, f_locked = ref.solve_frequencies(Kc, Mc, 0)
    # receptance of the tip (world y) to the motor torque: harmonic solve of the global FE
    lp = linear_pose(dyn, [th], [("torque", "q1")],
                     [("displacement", "tool", (0, 0, 0), (0, 1, 0))])
    freqs = np.array([0.3, 1.1, 4.0])
    H = frf(lp, freqs)[:, 0, 0]
    tip_v = ref.planar_chain_dofs([10])[0][-1]
    for fk, hk in zip(freqs, H):
        w = 2 * math.pi * fk
        rhs = np.zeros(Kr.shape[0])
        rhs[0] = 1.0  # the base rotation dof carries the motor torque
        u = np.linalg.solve(Kr - w**2 * Mr, rhs)
        assert hk.real == pytest.approx(u[tip_v[1]], rel=1e-8)
        assert abs(hk.imag) < 1e-12 * abs(hk)
    assert frf_direct(lp, freqs)[:, 0, 0] == pytest.approx(H, rel=1e-9)
    # prescribed drive: residual vibration at the clamped (locked) frequency
    t = np.linspace(0.0, 2.0, 41)
    h = t / 2.0
    traj = Trajectory(t, (0.3 * (10 * h**3 - 15 * h**4 + 6 * h**5))[:, None], ("q1",))
    sim = simulate_prescribed(dyn, traj, after_s=6.0, sample_hz=50.0)
    tip = sim.x[:, -2]  # transverse translation of the tip node (link axes)
    after = sim.times_s > sim.stop_s
    assert dominant_frequency(sim.times_s[after], tip[after]) == pytest.approx(
        f_locked[0], rel=1e-3)
    # torque drive: free vibration at the pinned-free frequency
    x0 = np.zeros(fm.nx)  # the static shape under a tip load: mostly mode 1, 5 cm at the tip
    s_node = np.arange(1, 11) * 1.0
    x0[1::3] = 0.05 * s_node**2 * (30.0 - s_node) / 2000.0
    x0[2::3] = 0.05 * 3.0 * s_node * (20.0 - s_node) / 2000.0
    run = simulate_torque(dyn, q0=[th], x0=x0, duration_s=2.0, sample_hz=200.0, step_s=5e-3)
    assert dominant_frequency(run.times_s, run.x[:, -2]) == pytest.approx(f_free[0], rel=2e-3)
