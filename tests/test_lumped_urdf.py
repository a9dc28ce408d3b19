"""Lumped arms exported to URDF plus spring data, read back into Pinocchio."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from conftest import TWO_LINK, UR5
from lumped_ring import quintic, ring_frequencies

from pinflex.erls import FlexibleModel
from pinflex.exceptions import InvalidDescription
from pinflex.lumped import fit_lumped, load_lumped_urdf, lumped_urdf
from pinflex.lumped.fit import locked_twin


def _write(tmp_path, lumped, q, damping=None):
    text, springs = lumped_urdf(lumped, q, damping=damping)
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    (tmp_path / "arm.springs.json").write_text(springs)
    return path


@pytest.mark.parametrize("which", ["planar", "ur5"])
def test_reload_gives_the_lumped_modes_in_pinocchio_and_in_flexible_model(which, tmp_path):
    """The loader's CRBA + stiffness and FlexibleModel(joints='annotated') equal the lumped arm."""
    if which == "planar":
        arm, q = FlexibleModel(TWO_LINK, planar=True), np.array([0.4, 1.9])
    else:
        arm, q = FlexibleModel(UR5), np.array([0.3, -1.0, 1.2, -0.5, 0.7, 0.2])
    fit = fit_lumped(arm, 3, poses=q, axial=which == "ur5", max_evaluations=20)
    path = _write(tmp_path, fit.lumped, q)
    loaded = load_lumped_urdf(path)
    f_lumped = fit.lumped.frequencies(q)
    np.testing.assert_allclose(loaded.frequencies(), f_lumped, rtol=1e-9)
    k = np.diag(loaded.stiffness)
    assert np.count_nonzero(k) == fit.lumped.n_hinges
    flex = FlexibleModel(path, joints="annotated")
    pose = np.array([loaded.pose[flex.model.joints[flex.model.getJointId(n)].idx_q]
                     for n in flex.joint_names])
    np.testing.assert_allclose(flex.frequencies(pose), f_lumped, rtol=1e-9)


def test_loader_refuses_files_that_disagree(tmp_path):
    """A stiffness that differs between the URDF and its spring data is refused by name."""
    arm = FlexibleModel(TWO_LINK, planar=True)
    fit = fit_lumped(arm, 2, max_evaluations=5)
    path = _write(tmp_path, fit.lumped, [0.0, 0.0])
    springs = tmp_path / "arm.springs.json"
    data = json.loads(springs.read_text())
    data["joints"]["link1_h1_bz"]["stiffness"] *= 1.01
    springs.write_text(json.dumps(data))
    with pytest.raises(InvalidDescription, match="link1_h1_bz"):
        load_lumped_urdf(path)
    data["joints"]["link1_h1_bz"]["stiffness"] /= 1.01
    data["joints"]["nowhere"] = {"stiffness": 1.0}
    springs.write_text(json.dumps(data))
    with pytest.raises(InvalidDescription, match="nowhere"):
        load_lumped_urdf(path)


def test_pinocchio_reload_rings_at_the_erls_locked_frequency_after_the_stop(tmp_path):
    """Joints driven exactly along a motion, then held: the reload rings at the ERLS modes.

    The arm joints' motion is prescribed (hybrid dynamics with Pinocchio's CRBA and RNEA on
    the reloaded model); the hinges respond; after the stop the joints hold still.
    """
    arm = FlexibleModel(TWO_LINK, planar=True)
    T = 0.25
    q0, q1 = np.array([0.0, 0.0]), np.array([0.3, 0.1])
    poses = q0 + np.outer(quintic(np.linspace(0.0, T, 5), T)[0], q1 - q0)
    fit = fit_lumped(arm, 4, poses=poses, max_evaluations=60)
    loaded = load_lumped_urdf(_write(tmp_path, fit.lumped, q0))
    model, data = loaded.model, loaded.model.createData()
    assert model.nq == model.nv
    k = np.diag(loaded.stiffness)
    driven = np.array([model.joints[model.getJointId(n)].idx_v for n in arm.joint_names])
    free = np.setdiff1d(np.arange(model.nv), driven)
    r0, r1 = arm.coord_map @ q0, arm.coord_map @ q1

    def rhs(t, z):
        s, ds, dds = quintic(np.array(t), T)
        q, v = z[:model.nv].copy(), z[model.nv:].copy()
        q[driven], v[driven] = r0 + s * (r1 - r0), ds * (r1 - r0)
        a = np.zeros(model.nv)
        a[driven] = dds * (r1 - r0)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        bias = pin.rnea(model, data, q, v, a)  # with the free accelerations zero
        rhs_ = -k * (q - loaded.springref) - bias
        acc = np.zeros(model.nv)
        acc[free] = np.linalg.solve(M[np.ix_(free, free)], rhs_[free])
        return np.concatenate([v, acc])

    # classical Runge-Kutta, h = 1e-4 s: omega h <= 0.8 on the highest hinge mode (stable);
    # its frequency error on modes 1-2 (omega h <= 0.07) is below 1e-8
    h, z, t = 1e-4, np.concatenate([loaded.pose, np.zeros(model.nv)]), 0.0
    probe = model.joints[model.getJointId("link1_h1_bz")].idx_q
    times, y = [], []
    while t < T + 0.5 - 1e-12:
        k1 = rhs(t, z)
        k2 = rhs(t + h / 2, z + h / 2 * k1)
        k3 = rhs(t + h / 2, z + h / 2 * k2)
        k4 = rhs(t + h, z + h * k3)
        z, t = z + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4), t + h
        if t > T + 0.01:
            times.append(t)
            y.append(z[probe])
    assert np.ptp(y) > 1e-5
    guess = fit.lumped.frequencies(q1, "locked")[:4]
    measured = ring_frequencies(np.array(times), np.array(y), guess)[:2]
    erls_locked = locked_twin(arm).frequencies(q1)[:2]
    assert np.all(np.abs(measured / erls_locked - 1.0) <= fit.worst_error + 1e-6)
