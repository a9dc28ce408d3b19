"""The pinflex URDF schema refuses unknown names and impossible values, and says where."""

import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import ROOT, TWO_LINK

from pinflex.description import load, parse
from pinflex.description.schema import MAX_ELEMENTS_PER_LINK, SCHEMA
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    ImplausibleValue,
    InvalidAttribute,
    InvalidDescription,
    NoFlexibleLink,
    PlausibilityWarning,
    UnknownAttribute,
    UnknownElement,
    UnreadableFile,
)

BASE = TWO_LINK.read_text()
UR5_OVERLAY = (ROOT / "urdf" / "ur5_flexible.xml").read_text()


def _line_of(text: str, needle: str) -> int:
    """Line of the start tag of the element containing ``needle``."""
    start = text.rfind("<", 0, text.index(needle) + 1)
    return text[:start].count("\n") + 1


def _first(old: str, new: str, text: str = BASE) -> str:
    assert old in text, old
    return text.replace(old, new, 1)


@pytest.mark.parametrize(
    "old, new, error, hint",
    [
        ('<pinflex:flexible link="link1" elements="4" normal="0 0 1">',
         '<pinflex:flexibel link="link1" elements="4" normal="0 0 1">', UnknownElement,
         "did you mean <pinflex:flexible>"),
        ('elements="4"', 'elements="4" tipp="0.6 0 0"', UnknownAttribute, "did you mean 'tip'"),
        ('design="true"', 'designx="true"', UnknownAttribute, "did you mean 'design'"),
        ('lower="0"', 'lowerx="0"', UnknownAttribute, "did you mean 'lower'"),
        ('E="69e9"', 'e="69e9"', UnknownAttribute, "did you mean 'E'"),
        ('<pinflex:point_mass name="m1"', '<point_mass name="m1"', UnknownElement,
         "did you mean <pinflex:point_mass>"),
        ('<pinflex:material E="69e9" linear_density="1.9"/>',
         '<material E="69e9" linear_density="1.9"/>', UnknownElement,
         "did you mean <pinflex:material>"),
    ],
)
def test_misspelt_names_are_refused_with_the_closest_name(old, new, error, hint):
    """A misspelt element or attribute is refused with its line and the closest valid name."""
    text = _first(old, new)
    if "flexibel" in new:
        text = text.replace("</pinflex:flexible>", "</pinflex:flexibel>", 1)
    if new.startswith("<material"):
        text = text.replace(new, new.replace("<material", "<pinflex:material", 1), 0)
    with pytest.raises(error) as info:
        parse(text, source="arm.urdf")
    msg = str(info.value)
    assert hint in msg
    assert msg.startswith("arm.urdf: ")
    assert f"line {_line_of(text, new.split()[0] if new.startswith('<') else new)}" in msg


def test_inner_diam_is_refused_on_a_hollow_section():
    """``inner_diam`` on a hollow circle names ``inner_diameter``; the section is not defaulted."""
    text = _first('A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"',
                  'shape="hollow_circle" outer_diameter="0.03" inner_diam="0.01"')
    with pytest.raises(UnknownAttribute, match="'inner_diam'.*did you mean 'inner_diameter'"):
        parse(text)


@pytest.mark.parametrize("uri", ["urn:pinflex:urdf:2", "urn:pinflx:urdf:1", "http://x.org/y"])
def test_wrong_namespace_is_refused(uri):
    """Annotations in another namespace (which would leave every link rigid) are refused."""
    with pytest.raises(UnknownElement, match="urn:pinflex:urdf:1"):
        parse(BASE.replace("urn:pinflex:urdf:1", uri))


def test_element_in_a_near_miss_namespace_is_refused():
    """An element declared in a namespace close to pinflex's is refused even with its own prefix."""
    text = _first("<pinflex:coordinates convention=\"absolute\"/>",
                  '<pf:coordinates xmlns:pf="urn:pinflex:urdf:01" convention="absolute"/>')
    with pytest.raises(UnknownElement, match="namespace 'urn:pinflex:urdf:01'"):
        parse(text)


@pytest.mark.parametrize(
    "old, new, match",
    [
        ('design="true"', 'design="maybe"', "design='maybe': expected true or false"),
        ('<pinflex:section A', '<pinflex:section A="1e-4" Iy="1e-9" Iz="1e-9" J="2e-9"/>'
         '\n<pinflex:section A', "a second <pinflex:section>"),
        ('<pinflex:section A', '<pinflex:section shape="solid_circle" diameter="0.03" A',
         "give either the shape or explicit 'A', not both"),
        ('mass="0.125"', 'mass="0.5"', r"nominal mass 0.5 kg is outside its bounds \[0, 0.25\]"),
        ('lower="0" upper="0.25"', 'lower="0.2" upper="0.1"', "lower bound 0.2 kg is above"),
        ('elements="4"', 'elements="four"', "'four' is not an integer"),
        ('elements="4"', 'elements="4.5"', "'4.5' is not a whole number"),
        ('elements="4"', f'elements="{MAX_ELEMENTS_PER_LINK + 1}"',
         f"must be at most {MAX_ELEMENTS_PER_LINK}"),
        ('E="69e9"', 'E="NaN"', "'NaN' is not a finite number"),
        ('E="69e9"', 'E="1e400"', "too large to be a finite number"),
        ('E="69e9"', 'E="-69e9"', "must be a positive number"),
        ('xyz="0.6 0 0" mass', 'xyz="0.6 0" mass', "expected three numbers"),
        ('<pinflex:material E="69e9" linear_density="1.9"/>', "",
         "<pinflex:material> is missing"),
        ('E="69e9" linear_density="1.9"', 'E="69e9" linear_density="1.9" density="2700"',
         "exactly one of density"),
        ('E="69e9" linear_density="1.9"', 'E="69e9" G="26e9" poisson="0.3" linear_density="1.9"',
         "G or poisson, not both"),
    ],
)
def test_impossible_values_are_refused(old, new, match):
    """Impossible or contradictory values are refused with a reason (InvalidAttribute)."""
    with pytest.raises(InvalidAttribute, match=match):
        parse(_first(old, new))


def test_every_problem_of_a_file_in_one_error():
    """One error lists every problem of the file, each with its line."""
    text = _first('elements="4"', 'elemnts="4"')
    text = _first('E="69e9"', 'E="abc"', text)
    text = _first('design="true"', 'design="yes please"', text)
    with pytest.raises(UnknownAttribute) as info:
        parse(text)
    assert len(info.value.problems) >= 3
    assert str(info.value).count("line ") >= 3


@pytest.mark.parametrize(
    "old, new, match",
    [
        ('E="69e9"', 'E="70"', r"E=70 \[Pa\] is outside .* not physical"),
        ('A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"',
         'shape="hollow_circle" outer_diameter="120" inner_diameter="0.02"',
         "120 m across but the link is 0.6 m long"),
        ('Iy="3.97e-8" Iz="3.97e-8"', 'Iy="3.97e-4" Iz="3.97e-4"', "1.4987 m across"),
        ('A="7.07e-4"', 'A="7.07e-2"', "below half of A\\^2/\\(2 pi\\)"),
        ('linear_density="1.9"', 'linear_density="1900"', "density is 2.687e\\+06 kg/m\\^3"),
    ],
)
def test_non_physical_values_are_refused_and_can_be_downgraded(old, new, match):
    """Non-physical values are refused with the reason; plausibility='warn' makes them warn."""
    text = _first(old, new)
    with pytest.raises(ImplausibleValue, match=match):
        parse(text)
    with pytest.warns(PlausibilityWarning, match=match):
        parse(text, plausibility="warn")


def test_implausible_values_warn():
    """An unusually soft material loads with a PlausibilityWarning naming the reason."""
    with pytest.warns(PlausibilityWarning, match="E=5e7 .* unusual"):
        parse(_first('E="69e9"', 'E="5e7"'))


@pytest.mark.parametrize(
    "old, new, error, match",
    [
        ('<parent link="base"/>', "", InvalidDescription, "joint 'q1' has no <parent"),
        ('<parent link="base"/>', '<parent link="bsae"/>', InvalidDescription,
         "did you mean 'base'"),
        ('lower="-6.2832" upper="6.2832"', 'lower="3" upper="1"', InvalidDescription,
         "lower limit 3 is above upper limit 1"),
        ('lower="-6.2832"', 'lower="low"', InvalidDescription, "'low' is not a number"),
        ('<mass value="0.855"/>', '<mass value="-1"/>', InvalidDescription,
         "mass cannot be negative"),
        ('<mass value="0.855"/>', '<mass value="nan"/>', InvalidDescription,
         "not a finite number"),
        ('<origin xyz="0.6 0 0"/>', '<origin xyz="0.6 zero 0"/>', InvalidDescription,
         "'zero' is not a number"),
    ],
)
def test_urdf_joints_limits_and_masses_are_checked(old, new, error, match):
    """Joints without parent, inverted limits, non-numeric or negative masses are refused."""
    with pytest.raises(error, match=match):
        parse(_first(old, new))


def test_zero_mass_with_inertia_is_refused_in_own_file_and_warns_upstream(tmp_path):
    """A moved rigid link of mass 0 with an inertia is refused; upstream it warns."""
    from conftest import single_link_urdf

    extra = ('<link name="hand"><inertial><mass value="0"/><inertia ixx="1e-3" ixy="0" '
             'ixz="0" iyy="1e-3" iyz="0" izz="1e-3"/></inertial></link><joint name="w" '
             'type="fixed"><parent link="bar"/><child link="hand"/>'
             '<origin xyz="1 0 0"/></joint>')
    text = single_link_urdf(elements=2, extra=extra)
    with pytest.raises(InvalidDescription, match="link 'hand' has mass 0"):
        parse(text)
    base = tmp_path / "base.urdf"
    base.write_text(text.replace('<pinflex:flexible', '<!--').replace(
        '</pinflex:flexible>', '-->'))
    overlay = tmp_path / "arm.xml"
    overlay.write_text(
        '<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" base="base.urdf">'
        '<pinflex:flexible link="bar" elements="2" tip="1 0 0" normal="0 0 1">'
        '<pinflex:material E="2e11" density="7800"/>'
        '<pinflex:section shape="solid_circle" diameter="0.01"/></pinflex:flexible>'
        '</pinflex:overlay>')
    with pytest.warns(PlausibilityWarning, match="mass 0 with a non-zero inertia"):
        load(overlay)


def test_overlay_errors_name_the_overlay_file_and_line(tmp_path):
    """A misspelling in an overlay names the overlay file and its line."""
    bad = UR5_OVERLAY.replace('inner_diameter="0.08"', 'inner_diam="0.08"')
    path = tmp_path / "ur5.xml"
    path.write_text(bad)
    with pytest.raises(UnknownAttribute) as info:
        load(path)
    assert str(info.value).startswith(f"{path}: ")
    assert f"line {_line_of(bad, 'inner_diam=')}" in str(info.value)
    assert "inner_diameter" in str(info.value)


def test_unreadable_files_are_refused(tmp_path):
    """Binary, non-UTF-8, missing and folder inputs raise UnreadableFile, not a decode error."""
    binary = tmp_path / "arm.urdf"
    binary.write_bytes(bytes(range(256)))
    with pytest.raises(UnreadableFile, match="binary"):
        load(binary)
    latin = tmp_path / "latin.urdf"
    latin.write_bytes(BASE.replace("two_link", "two_l\xefnk").encode("latin-1"))
    with pytest.raises(UnreadableFile, match="not UTF-8"):
        load(latin)
    with pytest.raises(UnreadableFile, match="does not exist"):
        load(tmp_path / "missing.urdf")
    with pytest.raises(UnreadableFile, match="not a regular file"):
        load(tmp_path)


def test_entity_declarations_are_refused():
    """DTD entities (the 'billion laughs' expansion) are refused before any expansion."""
    bomb = '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaa">]><robot name="x">&a;</robot>'
    with pytest.raises(InvalidDescription, match="entity"):
        parse(bomb)


def test_robot_without_flexible_link_raises_a_named_error():
    """Modes of a robot with no flexible link raise NoFlexibleLink, not an argmax error."""
    text = BASE
    while "<pinflex:flexible" in text:
        a = text.index("<pinflex:flexible")
        b = text.index("</pinflex:flexible>") + len("</pinflex:flexible>")
        text = text[:a] + text[b:]
    model = FlexibleModel(parse(text), planar=True)
    with pytest.raises(NoFlexibleLink, match="no flexible link"):
        model.modes([1.0, 2.0])
    with pytest.raises(NoFlexibleLink):
        model.frequencies([1.0, 2.0])


def test_shipped_files_load_without_warnings():
    """The shipped URDF and overlays pass the schema without a warning, except one.

    The Panda's upstream URDF couples its fingers with <mimic>: pinflex moves them
    independently and says so once (a file of the user's own is refused instead).
    """
    for path in sorted((ROOT / "urdf").iterdir()):
        with warnings.catch_warnings(record=True) as seen:
            warnings.simplefilter("always")
            load(path)
        messages = [str(w.message) for w in seen]
        if path.name.startswith("panda"):
            assert len(messages) == 1 and "panda_finger_joint2 mimics" in \
                messages[0].replace("'", ""), messages
        else:
            assert messages == [], messages


def test_schema_documents_every_attribute():
    """Each element and attribute of the table carries a line of documentation."""
    for name, spec in SCHEMA.items():
        assert spec.doc, name
        for key, attr in spec.attrs.items():
            assert attr.doc, (name, key)


def test_valid_file_values_are_unchanged():
    """The schema checks do not change what a valid file means (benchmark A's frequencies)."""
    m = FlexibleModel(parse(BASE), planar=True)
    ref = FlexibleModel(TWO_LINK, planar=True)
    np.testing.assert_array_equal(m.frequencies([1.817, 5.312]), ref.frequencies([1.817, 5.312]))
    assert Path(TWO_LINK).is_file()
