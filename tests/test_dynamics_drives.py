"""Joint drives in the dynamics: armature in M, dampers in C, as the modal model has them.

Reference: the ERLS assembly (FlexibleModel.matrices, pinflex.erls.joints.damping_matrices),
a second formulation of the same terms; the receptance with the dampers against the modal
model's own matrices.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pinflex import JointSpec
from pinflex.dynamics import ErlsDynamics
from pinflex.dynamics.frf import frf_direct, linear_pose
from pinflex.erls import FlexibleModel
from pinflex.erls.joints import damping_matrices

URDF = Path(__file__).resolve().parents[1] / "urdf" / "two_link.urdf"
Q = np.array([1.8, 5.3])


def test_armature_and_dampers_equal_the_modal_model():
    """Dynamics M and the joints' C equal the ERLS assembly's at a pose.

    Springs, armature and dampers on both joints, the elbow on the flexible upper arm.
    """
    joints = {"q1": JointSpec(stiffness=2e4, damping=3.0, armature=0.02),
              "q2": JointSpec(stiffness=5e3, damping=1.5, armature=0.01)}
    model = FlexibleModel(URDF, planar=True, joints=joints)
    dyn = ErlsDynamics(model, y=[0.1, 0.05])
    M, _, K, _ = dyn.linear_terms(Q)
    Mref, Kref = model.matrices(Q, [0.1, 0.05])
    assert M == pytest.approx(Mref, abs=1e-9 * np.abs(Mref).max())
    assert K == pytest.approx(Kref, abs=1e-9 * np.abs(Kref).max())
    Cref = damping_matrices(model, Q)
    assert dyn.joint_damping(Q) == pytest.approx(Cref, abs=1e-12 * np.abs(Cref).max())
    assert np.abs(Cref).max() > 0.0


def test_receptance_with_joint_drives_equals_the_modal_models():
    """Tip receptance to the base torque with springs, armature and dampers.

    The dynamics' direct solve = (K − ω²M + iωC)⁻¹ of the ERLS assembly with the joints' C,
    to 1e-8.
    """
    joints = {"q1": JointSpec(stiffness=2e4, damping=3.0, armature=0.02),
              "q2": JointSpec(stiffness=5e3, damping=1.5, armature=0.01)}
    model = FlexibleModel(URDF, planar=True, joints=joints)
    dyn = ErlsDynamics(model, y=[0.1, 0.05])
    tip = ("displacement", "tool", (0, 0, 0), (0, 1, 0))
    lp = linear_pose(dyn, Q, [("torque", "q1")], [tip])
    freqs = np.array([3.0, 12.0, 40.0, 120.0])
    got = frf_direct(lp, freqs)[:, 0, 0]
    M, K = model.matrices(Q, [0.1, 0.05])
    C = damping_matrices(model, Q)
    G = model.relative_motion_rows(Q)
    ref = np.array([lp.Y[0] @ np.linalg.solve(K - w**2 * M + 1j * w * C, G[0])
                    for w in 2 * np.pi * freqs])
    assert np.abs(got - ref).max() <= 1e-8 * np.abs(ref).max()
