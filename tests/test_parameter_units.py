"""Units of parameters from their use, and parameter values checked like literals."""

import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest

from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ImplausibleValue, InvalidDescription, TrajectoryWarning

ROOT = Path(__file__).resolve().parents[1]


def arm(section1='shape="hollow_circle" outer_diameter="{D}" wall="{t}"',
        material='E="{E}" density="{rho}"', params=None, joint2="revolute", extra=""):
    """A two-link arm (beams 0.6 m and 0.45 m) whose annotations read parameters."""
    params = params if params is not None else (
        '<pinflex:parameter name="D" value="0.04" lower="0.02" upper="0.06" design="true"/>'
        '<pinflex:parameter name="t" value="0.003" lower="0.001" upper="0.008" design="true"/>'
        '<pinflex:parameter name="E" value="7e10" lower="5e10" upper="2.1e11" design="true"/>'
        '<pinflex:parameter name="rho" value="2700" lower="1500" upper="8000" design="true"/>'
        '<pinflex:parameter name="k2" value="1e4" lower="1e3" upper="1e6" design="true"/>'
        '<pinflex:parameter name="m" value="0.2" lower="0" upper="1" design="true"/>')
    axis = '<axis xyz="0 0 1"/>' if joint2 == "revolute" else '<axis xyz="1 0 0"/>'
    return f"""<robot name="units" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="link2"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="q2" type="{joint2}"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.6 0 0"/>{axis}<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  {params}
  <pinflex:flexible link="link1" elements="3" tip="0.6 0 0" normal="0 0 1">
    <pinflex:material {material}/><pinflex:section {section1}/></pinflex:flexible>
  <pinflex:flexible link="link2" elements="2" tip="0.45 0 0" normal="0 0 1">
    <pinflex:material E="7e10" density="2700"/>
    <pinflex:section shape="solid_circle" diameter="0.02"/></pinflex:flexible>
  <pinflex:point_mass name="tip" link="link2" xyz="0.45 0 0" mass="{{m}}"/>
  <pinflex:joint name="q2" stiffness="{{k2}}"/>
  {extra}
</robot>"""


def test_each_parameter_takes_the_unit_of_its_use():
    """Diameter and wall in m, E in Pa, density in kg/m^3, a mass in kg, a revolute spring in
    N m/rad and a prismatic one in N/m (before: every design variable was labelled kg)."""
    model = FlexibleModel(parse(arm()))
    units = {d.name: d.unit for d in model.design}
    assert units == {"D": "m", "t": "m", "E": "Pa", "rho": "kg/m^3", "k2": "N m/rad",
                     "m": "kg"}
    prismatic = FlexibleModel(parse(arm(joint2="prismatic")))
    assert {d.name: d.unit for d in prismatic.design}["k2"] == "N/m"
    res = model.modes([0.1, 0.2], n_modes=1)
    assert "D = 0.04 m" in repr(res) and "E = 7e+10 Pa" in repr(res)
    assert "k2 = 1e+04 N m/rad" in repr(res)


def test_a_parameter_with_two_units_is_refused():
    """One number cannot be a diameter [m] and a mass [kg]."""
    text = arm(extra='<pinflex:point_mass name="p2" link="link1" xyz="0.3 0 0" mass="{D}"/>')
    with pytest.raises(InvalidDescription, match="used with different units"):
        parse(text)


def test_modes_and_assign_print_and_write_the_units(tmp_path):
    """``pinflex modes`` prints and writes each variable's unit."""
    path = tmp_path / "arm.urdf"
    path.write_text(arm())
    out = subprocess.run([sys.executable, "-m", "pinflex", "modes", str(path), "--q", "0.1",
                          "0.2", "--json"], capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["design_units"] == {"D": "m", "t": "m", "E": "Pa", "rho": "kg/m^3",
                                    "k2": "N m/rad", "m": "kg"}
    text = subprocess.run([sys.executable, "-m", "pinflex", "modes", str(path), "--q", "0.1",
                           "0.2"], capture_output=True, text=True, timeout=300).stdout
    assert "D=0.04 m" in text and "rho=2700 kg/m^3" in text and "m=0.2 kg" in text


def test_assignment_report_bounds_carry_the_variable_units():
    """The assignment's JSON: bounds of a diameter in m, of E in Pa (before: "kg")."""
    from pinflex.assignment import Target, assign_frequencies
    from pinflex.assignment.report import assignment_data
    from pinflex.trajectory import Trajectory

    model = FlexibleModel(parse(arm()), joints="free")
    traj = Trajectory(np.linspace(0, 1, 4), np.column_stack([np.zeros(4),
                                                             np.linspace(0.1, 0.4, 4)]),
                      model.joint_names)
    f = model.frequencies(traj.q, n_modes=1)[:, 0]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = assign_frequencies(model, traj, [Target(1, 1.05 * f.mean())], order=2,
                               design=["D", "E"])
    data = assignment_data(model, traj, r).to_dict()
    units = {c["name"].split()[0]: c["unit"] for c in data["constraints"]
             if c["kind"] in ("lower_bound", "upper_bound")}
    assert units == {"D": "m", "E": "Pa"}
    assert data["design_units"]["rho"] == "kg/m^3"


def _outcome(text):
    """The class of the refusal, or of the warnings, of parsing ``text`` (None: quiet)."""
    from pinflex.exceptions import PlausibilityWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            parse(text)
        except ImplausibleValue:
            return ImplausibleValue
    return PlausibilityWarning if any(issubclass(w.category, PlausibilityWarning)
                                      for w in caught) else None


@pytest.mark.parametrize("name, value, literal, expected", [
    ("D", "60", ('outer_diameter="{D}"', 'outer_diameter="60"'), ImplausibleValue),  # 60 m
    ("E", "70", ('E="{E}"', 'E="70"'), ImplausibleValue),  # 70 Pa: GPa forgotten
    ("rho", "2.7", ('density="{rho}"', 'density="2.7"'), "warn"),  # g/cm^3 for kg/m^3
])
def test_parameter_values_pass_the_checks_of_literals(name, value, literal, expected):
    """A plain parameter's value is checked where it is used, as the literal is (before:
    outer_diameter="{D}" with D = 60 m on a 0.6 m link was accepted; the literal refused)."""
    from pinflex.exceptions import PlausibilityWarning

    expected = PlausibilityWarning if expected == "warn" else expected
    values = {"D": "0.04", "t": "0.003", "E": "7e10", "rho": "2700", "k2": "1e4", "m": "0.2"}
    good = "".join(f'<pinflex:parameter name="{n}" value="{v}"/>' for n, v in values.items())
    bad = good.replace(f'name="{name}" value="{values[name]}"', f'name="{name}" value="{value}"')
    assert _outcome(arm(params=good)) is None
    assert _outcome(arm(params=bad)) is expected
    assert _outcome(arm(params=good).replace(*literal)) is expected  # the literal
    # the same value given as an override (values= / --set) is checked too
    if expected is ImplausibleValue:
        with pytest.raises(ImplausibleValue):
            parse(arm(params=good)).with_values({name: float(value)})


def test_a_trajectory_in_degrees_is_named():
    """Joint values beyond one turn are named as looking like degrees, also on continuous
    joints that have no limits (Kinova Jaco2's joints 1, 4 and 6)."""
    from pinflex.assignment import check_trajectory_limits
    from pinflex.trajectory import Trajectory

    model = FlexibleModel(ROOT / "urdf" / "kinova_tubes.xml")
    t = np.linspace(0, 1, 5)
    q = np.tile(np.radians([30.0, 170.0, 80.0, -110.0, 80.0, 10.0]), (5, 1))
    q[:, 0] += np.linspace(0, 0.3, 5)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_trajectory_limits(model, Trajectory(t, q, model.joint_names))  # radians: quiet
    deg = np.degrees(q)
    deg[:, 1:] = q[:, 1:]  # only the continuous joint 1 in degrees: 30..47, no limits there
    with pytest.warns(TrajectoryWarning, match="j2s6s200_joint_1.*look like degrees"):
        check_trajectory_limits(model, Trajectory(t, deg, model.joint_names))
    # the frequencies along a motion (pinflex modes --trajectory) name it too
    from pinflex.erls.along import modes_along

    with pytest.warns(TrajectoryWarning, match="j2s6s200_joint_1.*look like degrees"):
        modes_along(model, Trajectory(t[:2], deg[:2], model.joint_names), modes=1, extra=0)
