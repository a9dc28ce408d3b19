"""Models from Pinocchio objects in memory and from example-robot-data by name."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

import pinflex
from pinflex import Beam, FlexibleModel, Mass, Material
from pinflex.beam import hollow_circle, rectangle
from pinflex.checks import check_q
from pinflex.description import robot_data_dir
from pinflex.exceptions import (
    ConfigurationError,
    InvalidDescription,
    LinkNotFound,
    UnsupportedJoint,
)

ALU = Material(E=70e9, G=26.3e9, density=2700.0)
UR10_OVERLAY = """<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" name="ur10_flexible"
    base="example-robot-data:ur_description/urdf/ur10_robot.urdf">
  <pinflex:flexible link="upper_arm_link" elements="5" tip="0 0 0.612" normal="0 1 0">
    <pinflex:material E="70e9" G="26.3e9" density="2700"/>
    <pinflex:section shape="hollow_circle" outer_diameter="0.11" inner_diameter="0.1"/>
  </pinflex:flexible>
  <pinflex:flexible link="forearm_link" elements="4" tip="0 0 0.5723" normal="0 1 0">
    <pinflex:material E="70e9" G="26.3e9" density="2700"/>
    <pinflex:section shape="hollow_circle" outer_diameter="0.09" inner_diameter="0.082"/>
  </pinflex:flexible>
  <pinflex:point_mass name="payload" link="ee_link" xyz="0.05 0 0" mass="2.0"
                      design="true" lower="0" upper="8"/>
</pinflex:overlay>"""
UR10_FLEX = {
    "upper_arm_link": Beam(hollow_circle(0.11, 0.1), ALU, 5, tip=(0, 0, 0.612), normal=(0, 1, 0)),
    "forearm_link": Beam(hollow_circle(0.09, 0.082), ALU, 4, tip=(0, 0, 0.5723),
                         normal=(0, 1, 0)),
}
UR10_MASSES = {"payload": Mass("ee_link", 2.0, xyz=(0.05, 0, 0), design=True, upper=8.0)}
Q_UR10 = np.array([0.4, -1.1, 1.3, -0.5, 0.9, 0.2])


@pytest.fixture(scope="module")
def ur10_overlay(tmp_path_factory):
    """UR10 with two aluminium tubes, from an overlay file written here."""
    path = tmp_path_factory.mktemp("ur10") / "ur10_flexible.xml"
    path.write_text(UR10_OVERLAY)
    return FlexibleModel(path)


def _ur10_pin_model() -> pin.Model:
    return pin.buildModelFromUrdf(str(robot_data_dir() / "ur_description/urdf/ur10_robot.urdf"))


def _same_model(a: FlexibleModel, b: FlexibleModel, q: np.ndarray) -> None:
    assert a.joint_names == b.joint_names and a.x_names == b.x_names
    Ma, Ka = a.matrices(q)
    Mb, Kb = b.matrices(q)
    np.testing.assert_allclose(Mb, Ma, rtol=0, atol=1e-12 * np.abs(Ma).max())
    np.testing.assert_allclose(Kb, Ka, rtol=0, atol=1e-12 * np.abs(Ka).max())
    np.testing.assert_allclose(b.frequencies(q), a.frequencies(q), rtol=1e-10)


def test_ur10_from_pinocchio_equals_overlay_file(ur10_overlay):
    """A pin.Model in memory plus Python specs equals the overlay file."""
    arm = FlexibleModel.from_pinocchio(_ur10_pin_model(), flexible=UR10_FLEX,
                                       masses=UR10_MASSES)
    _same_model(ur10_overlay, arm, Q_UR10)
    assert arm.design_names == ("payload",) and arm.design[0].upper == 8.0


def test_ur10_example_robot_equals_overlay_file(ur10_overlay):
    """example_robot("ur10") plus Python specs equals the overlay file."""
    arm = pinflex.example_robot("ur10", flexible=UR10_FLEX, masses=UR10_MASSES)
    _same_model(ur10_overlay, arm, Q_UR10)


def test_robot_wrapper_and_joint_name_keys(ur10_overlay):
    """A RobotWrapper is accepted; joint names stand for the links they carry."""
    robot = pin.RobotWrapper(_ur10_pin_model())
    flex = {"shoulder_lift_joint": UR10_FLEX["upper_arm_link"],
            "elbow_joint": UR10_FLEX["forearm_link"]}
    arm = FlexibleModel.from_pinocchio(robot, flexible=flex, masses=UR10_MASSES)
    _same_model(ur10_overlay, arm, Q_UR10)


def test_hand_built_model_equals_handwritten_urdf(tmp_path):
    """A planar double pendulum built with addJoint equals the URDF written by hand."""
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "j1")
    model.appendBodyToJoint(j1, pin.Inertia(0.1, np.array([0.25, 0, 0]), np.eye(3) * 1e-4),
                            pin.SE3.Identity())
    j2 = model.addJoint(j1, pin.JointModelRZ(), pin.SE3(np.eye(3), np.array([0.5, 0, 0])), "j2")
    model.appendBodyToJoint(j2, pin.Inertia(0.2, np.array([0.2, 0, 0]), np.eye(3) * 2e-4),
                            pin.SE3.Identity())
    sec = rectangle(0.02, 0.004)
    steel = Material(E=210e9, G=81e9, density=7850.0)
    arm = FlexibleModel.from_pinocchio(
        model,
        flexible={"j1": Beam(sec, steel, 4, tip=(0.5, 0, 0), normal=(0, 0, 1))},
        masses={"tip": Mass("j2_body", 0.3, xyz=(0.4, 0, 0))},
    )
    urdf = tmp_path / "pendulum.urdf"
    urdf.write_text(f"""<robot name="p" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="universe"/>
  <link name="j1_body"><inertial><origin xyz="0.25 0 0"/><mass value="0.1"/>
    <inertia ixx="1e-4" iyy="1e-4" izz="1e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="j2_body"><inertial><origin xyz="0.2 0 0"/><mass value="0.2"/>
    <inertia ixx="2e-4" iyy="2e-4" izz="2e-4" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="j1" type="continuous"><parent link="universe"/><child link="j1_body"/>
    <axis xyz="0 0 1"/></joint>
  <joint name="j2" type="continuous"><parent link="j1_body"/><child link="j2_body"/>
    <origin xyz="0.5 0 0"/><axis xyz="0 0 1"/></joint>
  <pinflex:flexible link="j1_body" elements="4" tip="0.5 0 0" normal="0 0 1">
    <pinflex:material E="210e9" G="81e9" density="7850"/>
    <pinflex:section A="{sec.A!r}" Iy="{sec.Iy!r}" Iz="{sec.Iz!r}" J="{sec.J!r}"/>
  </pinflex:flexible>
  <pinflex:point_mass name="tip" link="j2_body" xyz="0.4 0 0" mass="0.3"/>
</robot>""")
    ref = FlexibleModel(urdf)
    # pin.JointModelRZ is a bounded revolute; the hand URDF says continuous (nq = 4): same
    # physics, different configuration vectors
    assert ref.model.nq == 4 and arm.model.nq == 2
    q = np.array([0.3, -0.7])
    Ma, Ka = ref.matrices(q)
    Mb, Kb = arm.matrices(q)
    np.testing.assert_allclose(Mb, Ma, rtol=0, atol=1e-13 * np.abs(Ma).max())
    np.testing.assert_allclose(Kb, Ka, rtol=0, atol=1e-13 * np.abs(Ka).max())


def test_configuration_of_length_nq_is_converted():
    """Continuous joints: (cos, sin) configurations give the same results as angles."""
    flex = {"link1": Beam(rectangle(0.02, 0.004), ALU, 3, normal=(0, 1, 0))}
    arm = pinflex.example_robot("double_pendulum_continuous", flexible=flex)
    assert arm.model.nq == 2 * arm.nv
    q = np.array([2.5, -2.9])
    qpin = arm.pin_configuration(q)
    np.testing.assert_allclose(qpin[:2], [np.cos(2.5), np.sin(2.5)])
    np.testing.assert_allclose(arm.from_configuration(qpin), q, atol=1e-15)
    np.testing.assert_allclose(arm.frequencies(qpin), arm.frequencies(q), rtol=1e-10)
    Q = np.stack([q, -q])
    np.testing.assert_allclose(check_q(arm, arm.pin_configuration(-q)), -q, atol=1e-15)
    assert arm.frequencies(np.stack([arm.pin_configuration(x) for x in Q])).shape[0] == 2
    with pytest.raises(ConfigurationError, match="not a unit vector"):
        arm.frequencies(np.array([1.0, 1.0, 1.0, 0.0]))
    with pytest.raises(ConfigurationError, match="Pinocchio configuration of 4"):
        arm.frequencies(np.zeros(3))


def test_effective_inertias_closed_form_and_crba(ur10_overlay):
    """Beam inertias: slender-rod closed forms; CRBA of the effective model = rigid block."""
    arm = ur10_overlay
    spec = arm.description.flexible["upper_arm_link"]
    L = spec.length_m
    m = spec.rhoA * L
    inertia = arm.effective_inertias()["upper_arm_link"]
    # uniform slender rod along z: mass, centre at L/2, m L²/12 across, ρIp L about the axis
    assert inertia.mass == pytest.approx(2700.0 * np.pi * (0.055**2 - 0.05**2) * 0.612, 1e-12)
    np.testing.assert_allclose(inertia.lever, [0, 0, L / 2], atol=1e-15)
    np.testing.assert_allclose(np.diag(inertia.inertia), [m * L**2 / 12, m * L**2 / 12,
                                                        spec.rhoIp * L], rtol=1e-12)
    # the URDF inertia stays on arm.model: 12.93 kg upper arm in ur10_robot.urdf
    jid = arm.model.getJointId("shoulder_lift_joint")
    assert arm.model.inertias[jid].mass == pytest.approx(12.93)
    # the effective model: beam + the part of the URDF link beyond it (motors, flanges) kept
    # as a rigid body = the URDF link itself
    eff = arm.effective_model()
    assert arm.effective_model(point_masses=False).inertias[jid].mass == pytest.approx(12.93)
    np.testing.assert_allclose(eff.inertias[jid].lever, arm.model.inertias[jid].lever,
                               atol=1e-12)
    np.testing.assert_allclose(eff.inertias[jid].inertia, arm.model.inertias[jid].inertia,
                               atol=1e-12)
    # Pinocchio's CRBA of the effective model = the modal model's rigid block
    M, _ = arm.matrices(Q_UR10)
    Mq = pin.crba(eff, eff.createData(), arm.pin_configuration(Q_UR10))
    Mq = np.triu(Mq) + np.triu(Mq, 1).T
    np.testing.assert_allclose(Mq, M[arm.nx:, arm.nx:], rtol=0,
                               atol=1e-12 * np.abs(Mq).max())


def test_bad_inputs_raise_named_errors():
    """Wrong objects, joints, links, names and materials raise named errors."""
    with pytest.raises(ConfigurationError, match="pinocchio.Model or a pinocchio RobotWrapper"):
        FlexibleModel.from_pinocchio("ur10.urdf")
    ff = pin.Model()
    ff.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "root")
    with pytest.raises(UnsupportedJoint, match="JointModelFreeFlyer"):
        FlexibleModel.from_pinocchio(ff)
    with pytest.raises(LinkNotFound):
        pinflex.example_robot("ur10", flexible={"no_such_link": UR10_FLEX["forearm_link"]})
    with pytest.raises(LinkNotFound):
        pinflex.example_robot("ur10", masses={"m": Mass("nowhere", 1.0)})
    with pytest.raises(InvalidDescription, match="unknown example robot"):
        pinflex.example_robot("ur11")
    with pytest.raises(InvalidDescription, match="exactly one of density"):
        Material(E=1e9)
    with pytest.raises(InvalidDescription, match="must be a pinflex.Beam"):
        pinflex.example_robot("ur10", flexible={"forearm_link": 3})


def test_modal_result_repr_is_a_short_table(ur10_overlay):
    """print(result) is a table of at most 16 lines."""
    res = ur10_overlay.modes(Q_UR10)
    text = repr(res)
    lines = text.splitlines()
    assert len(lines) <= 16
    assert f"{res.freq_hz[0]:.6g}" in lines[4]
    assert f"{res.eigvals.size - 10} more" in text


def test_joint_conditions_pass_through(ur10_overlay):
    """joints= of from_pinocchio is the constructor's: locked joints give the same model."""
    locked_file = FlexibleModel(ur10_overlay.description, joints="locked")
    arm = FlexibleModel.from_pinocchio(_ur10_pin_model(), flexible=UR10_FLEX,
                                       masses=UR10_MASSES, joints="locked")
    np.testing.assert_allclose(arm.frequencies(Q_UR10), locked_file.frequencies(Q_UR10),
                               rtol=1e-10)
    assert not np.allclose(arm.frequencies(Q_UR10)[:3], ur10_overlay.frequencies(Q_UR10)[:3])
