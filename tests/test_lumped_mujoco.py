"""Lumped arms exported to MJCF, checked in MuJoCo itself (skipped without ``mujoco``)."""

from __future__ import annotations

import json

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import ROOT, TWO_LINK, UR5
from lumped_ring import clamped_link_urdf, mujoco_tip_deflection, quintic, ring_frequencies
from reference_fe import planar_two_link_frequencies

import pinflex
from pinflex import Beam, Material
from pinflex.beam import hollow_circle
from pinflex.cli import main
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.lumped import fit_lumped, lumped_mjcf
from pinflex.lumped.fit import locked_twin
from pinflex.lumped.visuals import arm_visuals

mujoco = pytest.importorskip("mujoco")


def mujoco_frequencies(m, d) -> np.ndarray:
    """Non-rigid frequencies [Hz] from MuJoCo's mass matrix and joint stiffness.

    Joints without stiffness are free: condensed out.
    """
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    k = np.array(m.jnt_stiffness[m.dof_jntid])
    e, r = k > 0, k == 0
    Mc = M[np.ix_(e, e)]
    if r.any():
        Mc = Mc - M[np.ix_(e, r)] @ np.linalg.solve(M[np.ix_(r, r)], M[np.ix_(r, e)])
    lam = sla.eigh(np.diag(k[e]), Mc, eigvals_only=True)
    return np.sqrt(lam) / (2 * np.pi)


def load_keyframe(path_or_text, text=False):
    """A MuJoCo model and data at its keyframe ``pose``."""
    m = (mujoco.MjModel.from_xml_string(path_or_text) if text
         else mujoco.MjModel.from_xml_path(str(path_or_text)))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    return m, d


def test_benchmark_a_target_command_in_mujoco(tmp_path):
    """Benchmark A's export command: MuJoCo's modes 1, 2 within 0.05 % / 0.1 % of the global FE.

    MuJoCo's own mass matrix and joint stiffness give the lumped model's frequencies to 1e-9
    and the ERLS model's within the fit's stated error; the naive chain misses the FE by
    0.117 % / 0.247 %.
    """
    out, report = tmp_path / "arm.xml", tmp_path / "arm.json"
    assert main(["export", str(TWO_LINK), "--planar", "--q", "0", "0", "--format", "mjcf",
                 "--segments", "4", "--out", str(out), "--report", str(report)]) == 0
    data = json.loads(report.read_text())
    m, d = load_keyframe(out)
    assert m.nv == 8 and m.nu == 2
    f_mj = mujoco_frequencies(m, d)
    lumped = np.array(data["lumped_hz"]["own"][0])
    np.testing.assert_allclose(f_mj[:2], lumped, rtol=1e-9)
    fe = planar_two_link_frequencies([0.0, 0.0], 0.125, 0.125)[1][:2]
    err = np.abs(f_mj[:2] / fe - 1.0)
    assert err[0] < 5e-4 and err[1] < 1e-3, err
    assert np.all(err <= data["worst_error"] + 1e-9)
    naive = np.array(data["naive_mode_errors"]["own"])
    np.testing.assert_allclose(naive, [1.1659e-3, 2.4686e-3], atol=2e-7)


@pytest.mark.parametrize("which", ["ur5", "panda", "ur10_python"])
def test_three_d_arms_in_mujoco_equal_their_lumped_model(which, tmp_path):
    """UR5 and Panda overlays and a UR10 built in Python: mj_fullM modes = lumped to 1e-9."""
    if which == "ur5":
        arm, q = FlexibleModel(UR5), np.array([0.3, -1.0, 1.2, -0.5, 0.7, 0.2])
    elif which == "panda":
        arm = FlexibleModel(ROOT / "urdf" / "panda_flexible.xml")
        q = np.array([0.0, -0.5, 0.0, -2.0, 0.0, 1.5, 0.8, 0.01, 0.01])
    else:
        alu = Material(E=70e9, G=26.3e9, density=2700.0)
        flex = {"upper_arm_link": Beam(hollow_circle(0.11, 0.1), alu, 5, tip=(0, 0, 0.612),
                                       normal=(0, 1, 0)),
                "forearm_link": Beam(hollow_circle(0.09, 0.082), alu, 4, tip=(0, 0, 0.5723),
                                     normal=(0, 1, 0))}
        arm = pinflex.example_robot("ur10", flexible=flex)
        q = np.array([0.1, -1.2, 1.0, 0.3, -0.4, 0.5])
    fit = fit_lumped(arm, 3, poses=q, axial=True, max_evaluations=30)
    visuals = arm_visuals(arm, skip_links=tuple(arm.plan.beams))
    doc = lumped_mjcf(fit.lumped, q, visuals=visuals.shapes)
    path = tmp_path / "arm.xml"
    path.write_text(doc.text)
    m, d = load_keyframe(path)
    f_mj = mujoco_frequencies(m, d)
    f_lumped = fit.lumped.frequencies(q)
    np.testing.assert_allclose(f_mj, f_lumped, rtol=1e-9)
    erls = arm.frequencies(q, n_modes=fit.n_modes)
    assert np.all(np.abs(f_mj[:fit.n_modes] / erls - 1.0) <= fit.worst_error + 1e-9)
    assert m.nu == arm.nv  # one actuator per free joint
    if which != "ur10_python":
        assert m.nmesh > 0  # the rigid links' meshes came along


def test_mujoco_rings_at_the_erls_locked_frequency_after_the_stop():
    """Driven along a motion, then held: MuJoCo rings at the ERLS locked-joint modes.

    Phase 1 drives benchmark A's joints with position servos along a rest-to-rest motion;
    at the stop the joints are held rigidly (the welded export at the end pose, started from
    the hinges' state at the stop). The frequencies read off the simulated ringing equal the
    ERLS locked-joint ones within the fit's stated error over the motion.
    """
    arm = FlexibleModel(TWO_LINK, planar=True)
    T = 0.25
    q0, q1 = np.array([0.0, 0.0]), np.array([0.3, 0.1])
    poses = q0 + np.outer(quintic(np.linspace(0.0, T, 5), T)[0], q1 - q0)
    fit = fit_lumped(arm, 4, poses=poses, max_evaluations=60)

    def load(text, dt):
        m = mujoco.MjModel.from_xml_string(text)
        m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
        m.opt.timestep = dt
        return m, mujoco.MjData(m)

    m, d = load(lumped_mjcf(fit.lumped, q0, actuators="position", kp=1e5,
                            gravity=(0, 0, 0)).text, 5e-5)
    mujoco.mj_resetDataKeyframe(m, d, 0)
    r0, r1 = arm.coord_map @ q0, arm.coord_map @ q1
    names = list(arm.joint_names)

    def jname(model, j):
        return mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_JOINT, j)

    order = [names.index(jname(m, m.actuator_trnid[i, 0])) for i in range(m.nu)]
    while d.time < T - 1e-12:
        d.ctrl[:] = (r0 + quintic(np.array(d.time), T)[0] * (r1 - r0))[order]
        mujoco.mj_step(m, d)
    mw, dw = load(lumped_mjcf(fit.lumped.locked(), q1, gravity=(0, 0, 0)).text, 5e-5)
    assert mw.nu == 0 and mw.nv == fit.lumped.n_hinges
    for j in range(mw.njnt):
        src = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_JOINT, jname(mw, j))
        dw.qpos[mw.jnt_qposadr[j]] = d.qpos[m.jnt_qposadr[src]]
        dw.qvel[mw.jnt_dofadr[j]] = d.qvel[m.jnt_dofadr[src]]
    probe = mw.jnt_qposadr[mujoco.mj_name2id(mw, mujoco.mjtObj.mjOBJ_JOINT, "link1_h1_bz")]
    t, y = [], []
    while dw.time < 0.5:
        mujoco.mj_step(mw, dw)
        t.append(dw.time)
        y.append(dw.qpos[probe])
    assert np.ptp(y) > 1e-5  # it does ring
    guess = fit.lumped.frequencies(q1, "locked")[:4]
    measured = ring_frequencies(np.array(t), np.array(y), guess)[:2]
    erls_locked = locked_twin(arm).frequencies(q1)[:2]
    assert np.all(np.abs(measured / erls_locked - 1.0) <= fit.worst_error + 1e-6)


E_LINK, I_LINK, L_LINK = 69e9, 3.97e-8, 0.6


@pytest.mark.parametrize("n", [3, 4, 6])
def test_static_tip_deflection_in_mujoco_against_euler_bernoulli(n):
    """MuJoCo's static tip deflection of the exported link vs P L^3 / 3 EI (closed form).

    The fitted link: within the fit's reported compliance error. The equal-segment chain
    (k = EI/l, root segment clamped): its closed form (n-1)(2n-1)/(2n^2) of the beam's,
    e.g. 34.4 % short at n = 4 (MuJoCo's 1-D flex rod, clamped by its first edge, gives the
    same: benchmarks/bench_lumped.py).
    """
    link = FlexibleModel(parse(clamped_link_urdf(L_LINK, E_LINK, I_LINK, 1.9, 20)), planar=True)
    fit = fit_lumped(link, n, n_modes=2, warn_above=None)
    force = 10.0
    exact = force * L_LINK**3 / (3 * E_LINK * I_LINK)
    tips = {}
    for name, arm in (("fit", fit.lumped), ("naive", fit.naive)):
        m = mujoco.MjModel.from_xml_string(lumped_mjcf(arm, [0.0], gravity=(0, 0, 0)).text)
        tips[name] = mujoco_tip_deflection(mujoco, m, force, L_LINK) / exact - 1.0
    assert abs(tips["fit"]) <= fit.compliance_error + 1e-9
    np.testing.assert_allclose(tips["naive"], (n - 1) * (2 * n - 1) / (2 * n**2) - 1.0,
                               rtol=1e-10)
    if n >= 4:
        assert abs(tips["fit"]) < 1e-7
