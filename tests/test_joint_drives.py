"""Joint drives as real robots have them: armature (reflected rotor inertia) and damping.

References: a rod on a torsional spring in the stiff-beam limit (``ω² = k / (J + a)``,
``ζ = c / (2 √(k (J + a)))``), Pinocchio's CRBA with ``model.armature`` for the joint block of
M, and the servo reduction of a PD law written out in the test.
"""

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

import pinflex
from pinflex.description import parse
from pinflex.erls import FlexibleModel, modal
from pinflex.erls.joints import damping_matrices

ROOT = Path(__file__).resolve().parents[1]
RHO_A = 2700 * np.pi * 0.02**2 / 4  # solid aluminium rod, 20 mm
L = 0.5


def one_link(E="7e13", k="100", a="0", c="0", locked=False):
    """A 0.5 m rod on a ground joint about z (beam-only inertia)."""
    held = 'locked="true"' if locked else f'stiffness="{k}" damping="{c}"'
    return f"""<robot name="one" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="arm"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="arm"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="arm" elements="4" tip="{L} 0 0" normal="0 0 1" inertia="beam-only">
    <pinflex:material E="{E}" density="2700"/>
    <pinflex:section shape="solid_circle" diameter="0.02"/></pinflex:flexible>
  <pinflex:joint name="q1" {held} armature="{a}"/>
</robot>"""


def _model(text, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # a deliberately stiff rod (E = 70 TPa)
        return FlexibleModel(parse(text), planar=True, **kw)


@pytest.mark.parametrize("a", [0.0, 0.01, 0.05])
def test_armature_on_a_sprung_rod_matches_the_closed_form(a):
    """Rod on a 100 N m/rad spring, stiff limit: the rod's flexibility lowers f² by a term in
    1/E (extrapolated from E = 7 and 70 TPa; the armature moves f by 0-46 %):
    f = √(k / (ρA L³/3 + a)) / 2π to 2e-7."""
    f1 = _model(one_link(E="7e12", a=str(a))).frequencies([0.3], n_modes=1)[0]
    f2 = _model(one_link(E="7e13", a=str(a))).frequencies([0.3], n_modes=1)[0]
    f = np.sqrt((10 * f2**2 - f1**2) / 9)  # f² = f∞² − b / E
    J = RHO_A * L**3 / 3
    assert f == pytest.approx(np.sqrt(100.0 / (J + a)) / (2 * np.pi), rel=2e-7)
    assert f2 == pytest.approx(f, rel=2e-5)


def test_a_locked_joint_rotor_does_not_turn():
    """Locked: the armature changes nothing (the joint's relative motion is zero)."""
    f0 = _model(one_link(E="7e10", locked=True, a="0")).frequencies([0.3], n_modes=3)
    f1 = _model(one_link(E="7e10", locked=True, a="0.05")).frequencies([0.3], n_modes=3)
    np.testing.assert_allclose(f1, f0, rtol=1e-13)


def test_joint_damper_gives_the_damping_ratio_of_the_closed_form():
    """Stiff rod, k = 100, c = 0.2, a = 0.01: the lowest mode of (M, C, K) has
    ζ = c / (2 √(k (J + a))) and ω_d = ω_n √(1 − ζ²)."""
    k, c, a = 100.0, 0.2, 0.01
    model = _model(one_link(k=str(k), c=str(c), a=str(a)))
    q = np.array([0.3])
    M, K = model.matrices(q)
    C = damping_matrices(model, q)
    n = M.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)],
                  [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    s = np.linalg.eigvals(A)
    low = s[np.argmin(np.abs(s))]
    J = RHO_A * L**3 / 3
    wn = np.sqrt(k / (J + a))
    zeta = c / (2 * np.sqrt(k * (J + a)))
    # the rod's own flexibility (E = 70 TPa) is ~1e-5 of the joint mode (first test)
    assert -low.real / abs(low) == pytest.approx(zeta, rel=5e-5)
    assert abs(low.imag) == pytest.approx(wn * np.sqrt(1 - zeta**2), rel=2e-5)


def test_armature_equals_pinocchio_crba_with_model_armature(tmp_path):
    """UR3 with an armature per joint, all joints free: the armature's part of the joint
    block of M is Pinocchio's CRBA with model.armature (the diagonal, on a ground-fixed
    chain whose joints' parents do not deform at the joint axes... and in general g gᵀ)."""
    path = ROOT / "urdf" / "ur3_tubes.xml"
    text = path.read_text()
    armature = [0.4, 0.35, 0.2, 0.05, 0.04, 0.03]
    names = ["shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint", "wrist_1_joint",
             "wrist_2_joint", "wrist_3_joint"]
    for n, a in zip(names, armature):
        text = text.replace(f'<pinflex:joint name="{n}" stiffness="{{k_servo}}"/>',
                            f'<pinflex:joint name="{n}" stiffness="{{k_servo}}" armature="{a}"/>')
    tmp = tmp_path / "ur3_armature.xml"
    tmp.write_text(text)
    model = FlexibleModel(tmp, joints="free")
    pm = model.effective_model(point_masses=True)
    rigid_only = FlexibleModel(path, joints="free")
    for q in ([0.1, -1.2, 1.4, -1.8, -1.57, 0.2], [1.0, -0.3, 0.7, 0.4, 1.2, -0.5]):
        q = np.array(q)
        M, _ = model.matrices(q)
        M0, _ = rigid_only.matrices(q)
        pm.armature = np.array(armature)
        ref = pin.crba(pm, pm.createData(), q)
        ref = np.triu(ref) + np.triu(ref, 1).T
        pm.armature = np.zeros(6)
        ref0 = pin.crba(pm, pm.createData(), q)
        ref0 = np.triu(ref0) + np.triu(ref0, 1).T
        nx = model.nx
        np.testing.assert_allclose(M[nx:, nx:] - M0[nx:, nx:], ref - ref0, atol=1e-12)
        np.testing.assert_allclose(M[nx:, nx:] - M0[nx:, nx:], np.diag(armature), atol=1e-12)
    # the conditioned solve (relative joint values) sees the armature as the nodal pencil does,
    # free and on the servo springs
    for joints in ("free", "annotated"):
        arm = FlexibleModel(tmp, joints=joints)
        M, K = arm.matrices(q)
        lam = modal.eigvals_from(arm, M, K)
        np.testing.assert_allclose(arm.frequencies(q, n_modes=4),
                                   np.sqrt(lam[:4]) / (2 * np.pi), rtol=1e-8)  # nodal rounding
        assert arm.frequencies(q, n_modes=1)[0] < FlexibleModel(
            path, joints=joints).frequencies(q, n_modes=1)[0] * (1 - 1e-3)


def test_servo_reduction_and_python_route_equal_the_xml():
    """servo(): k = Kp, c = Kd on the joint side; N² Kp, N² Kd on the motor side; armature
    N² I_r. A JointSpec mapping gives the same M, K and C as the XML annotations."""
    s = pinflex.servo(2e4, 3.0, gear_ratio=100.0, rotor_inertia=5e-5)
    assert (s.stiffness, s.damping, s.armature) == (2e4, 3.0, pytest.approx(0.5))
    m = pinflex.servo(2.0, 3e-4, gear_ratio=100.0, rotor_inertia=5e-5, gains="motor")
    assert (m.stiffness, m.damping) == (pytest.approx(2e4), pytest.approx(3.0))
    xml = one_link(E="7e10", k="2e4", c="3", a="0.5")
    by_xml = _model(xml)
    by_spec = _model(xml.replace('<pinflex:joint name="q1" stiffness="2e4" damping="3" '
                                 'armature="0.5"/>', ""), joints={"q1": s})
    q = np.array([0.7])
    for A, B in zip(by_xml.matrices(q), by_spec.matrices(q)):
        np.testing.assert_array_equal(A, B)
    np.testing.assert_array_equal(damping_matrices(by_xml, q), damping_matrices(by_spec, q))
    assert by_xml.joint_labels() == {"q1": "k=2e+04 c=3 a=0.5"}


def test_bad_drive_values_are_named():
    """Negative damping or armature, gains of the wrong kind: named errors."""
    from pinflex.exceptions import ConfigurationError, InvalidBeamProperty, InvalidDescription

    with pytest.raises(InvalidDescription):
        parse(one_link(c="-1"))
    with pytest.raises(InvalidBeamProperty):
        pinflex.JointSpec(stiffness=1e3, armature=-0.1)
    with pytest.raises(InvalidDescription):
        pinflex.JointSpec(locked=True, damping=1.0)
    with pytest.raises(ConfigurationError):
        pinflex.servo(1e3, gains="rotor")


def test_linear_model_export_carries_the_joint_damper():
    """pinflex export's state space: the lowest pole of A has the closed form's ζ (was
    undamped: the export's damping held only modal/Rayleigh terms)."""
    from pinflex.native.export import linear_model

    k, c, a = 100.0, 0.2, 0.01
    model = _model(one_link(k=str(k), c=str(c), a=str(a)))
    data = linear_model(model, np.array([0.3]))
    np.testing.assert_allclose(data["damping"], damping_matrices(model, np.array([0.3])),
                               rtol=0, atol=0)
    s = np.linalg.eigvals(data["A"])
    low = s[np.argmin(np.abs(s))]
    J = RHO_A * L**3 / 3
    assert -low.real / abs(low) == pytest.approx(c / (2 * np.sqrt(k * (J + a))), rel=5e-5)
