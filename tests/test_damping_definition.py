"""One meaning of Rayleigh damping (α, β) in the simulations, the receptances and the exports.

Rayleigh damps the deformation with the mass and stiffness of the arm whose motors are held:
every locked-joint mode decays at α/2 + β ω²/2 and the rigid motion is not damped.
References: the global planar frame FE of benchmark A with C = α M + β K (tests/reference_fe.py,
no pinflex code) and that closed form.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import scipy.linalg
from arms import locked_global_fe

from pinflex.dynamics import Damping, ErlsDynamics
from pinflex.dynamics.frf import frf, linear_pose
from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.prescribed import PrescribedSystem
from pinflex.erls import FlexibleModel
from pinflex.native.export import linear_model
from pinflex.trajectory import Trajectory

URDF = Path(__file__).resolve().parents[1] / "urdf" / "two_link.urdf"
Q = np.array([1.8, 5.3])
Y = (0.1, 0.05)
ALPHA, BETA = 0.4, 2e-5


def _decay_rates(M, C, K):
    """``−Re λ`` and ``|Im λ|`` of the oscillating eigenvalues of ``M ẍ + C ẋ + K x = 0``."""
    n = M.shape[0]
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -np.linalg.solve(M, K)
    A[n:, n:] = -np.linalg.solve(M, C)
    lam = np.linalg.eigvals(A)
    lam = lam[lam.imag > 1e-6 * np.abs(lam).max()]
    order = np.argsort(lam.imag)
    return -lam.real[order], lam.imag[order]


def test_locked_receptance_equals_the_damped_global_fe():
    """Tip receptance of the locked arm with Rayleigh (α, β) = the FE's with C = α M + β K."""
    dyn = ErlsDynamics(FlexibleModel(URDF, planar=True), y=list(Y))
    tip = ("displacement", "tool", (0, 0, 0), (0, 1, 0))
    lp = linear_pose(dyn, Q, [("force", "tool", (0, 0, 0), (0, 1, 0))], [tip],
                     joints="locked", damping=Damping("rayleigh", ALPHA, BETA))
    Kt, Mt, keep = locked_global_fe(Q, *Y)
    e = np.zeros(Kt.shape[0])
    e[keep.index(21)] = 1.0  # world y of the tip node
    w1 = np.sqrt(scipy.linalg.eigh(Kt, Mt, eigvals_only=True)[0])
    freqs = np.array([0.5, 0.98, 1.0, 1.02, 3.0]) * w1 / (2 * np.pi)
    ref = np.array([e @ np.linalg.solve(Kt - w**2 * Mt + 1j * w * (ALPHA * Mt + BETA * Kt), e)
                    for w in 2 * np.pi * freqs])
    got = frf(lp, freqs)[:, 0, 0]
    assert np.abs(got - ref).max() <= 1e-6 * np.abs(ref).max()


def test_every_locked_mode_decays_at_the_closed_form_rate_everywhere():
    """α/2 + β ω²/2 in the prescribed drive's hold, the locked FRF model and the export."""
    model = FlexibleModel(URDF, planar=True)
    dyn = ErlsDynamics(model, y=list(Y))
    traj = Trajectory(np.array([0.0, 0.1]), np.array([Q, Q]), ("q1", "q2"))
    system = PrescribedSystem(dyn, JointMotion(traj), Damping("rayleigh", ALPHA, BETA))
    c = system.coefficients(0.05)
    rate, omega = _decay_rates(c.M, c.C, c.K)
    wn = np.sqrt(omega**2 + rate**2)
    assert rate == pytest.approx(ALPHA / 2 + BETA * wn**2 / 2, rel=1e-9)
    locked = FlexibleModel(URDF, planar=True, joints="locked")
    data = linear_model(locked, Q, y=Y, rayleigh=(ALPHA, BETA))
    rate_x, omega_x = _decay_rates(data["M"], data["damping"], data["K"])
    wn_x = np.sqrt(omega_x**2 + rate_x**2)
    assert rate_x == pytest.approx(ALPHA / 2 + BETA * wn_x**2 / 2, rel=1e-9)
    # the two are the same arm: the same frequencies and the same decay
    assert wn_x[:3] == pytest.approx(wn[:3], rel=1e-8)
    assert rate_x[:3] == pytest.approx(rate[:3], rel=1e-8)


def test_free_joints_rigid_motion_is_not_damped_and_held_modes_decay_at_the_closed_form():
    """Free joints: the rigid motion is undamped; the motors-held motions decay as locked.

    Zero eigenvalues stay in the export and no damping force reaches the FRF model's joint
    rows; restricted to the motors-held motions every mode decays at α/2 + β ω²/2.
    """
    model = FlexibleModel(URDF, planar=True)
    data = linear_model(model, Q, y=Y, rayleigh=(ALPHA, 0.0))
    ev = np.linalg.eigvals(data["A"])
    small = np.sort(np.abs(ev))[: 2 * model.nv]
    assert small.max() <= 1e-9 * np.abs(ev).max()  # a damped rigid motion would give −α
    dyn = ErlsDynamics(model, y=list(Y))
    lp = linear_pose(dyn, Q, [("torque", "q1")], [("displacement", "tool", (0, 0, 0),
                                                     (0, 1, 0))],
                     damping=Damping("rayleigh", ALPHA, BETA))
    A = dyn.joint_offsets(Q)[0]
    Z = np.vstack([np.eye(dyn.nx), A])
    rate, omega = _decay_rates(Z.T @ lp.M @ Z, Z.T @ lp.C @ Z, Z.T @ lp.K @ Z)
    wn = np.sqrt(omega**2 + rate**2)
    assert rate == pytest.approx(ALPHA / 2 + BETA * wn**2 / 2, rel=1e-9)
    assert np.abs(lp.C[dyn.nx:]).max() == 0.0 and np.abs(lp.C[:, dyn.nx:]).max() == 0.0
