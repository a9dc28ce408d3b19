"""One number grammar, parameter references checked like literals, named refusals of bad input.

Each case here was accepted in silence, or crashed with a foreign exception, before: Unicode
digits read as 0.855 kg by pinflex and 0 kg by Pinocchio, ``elements="{ne}"`` past the 4096
limit, a 60 m tube through a parameter, API arguments of the wrong type.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.description import parse
from pinflex.exceptions import (
    ConfigurationError,
    ImplausibleValue,
    InvalidAttribute,
    InvalidBeamProperty,
    InvalidDescription,
    OutputError,
    PinflexError,
    StudyError,
    UnreadableFile,
    UnsupportedJoint,
)
from pinflex.validation import load_toml, parse_int, parse_number

BASE = TWO_LINK.read_text()
SECTION = 'A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"'


def _with_param(text: str, param: str) -> str:
    return text.replace("<pinflex:coordinates", param + "\n  <pinflex:coordinates", 1)


# --------------------------------------------------------------------- the grammar itself
@pytest.mark.parametrize("text", ["0.855", "-1", "+.5", "5.", "1e-3", "2E+10", " 7\t"])
def test_plain_decimals_are_numbers(text):
    """ASCII decimals with sign, point and exponent read as Python would."""
    assert parse_number(text) == float(text)


@pytest.mark.parametrize("text, why", [
    ("\u0660.\u0668\u0665\u0665", "digit outside ASCII"),       # Arabic-Indic 0.855
    ("\uff10.\uff18\uff15\uff15", "digit outside ASCII"),       # full-width 0.855
    ("\u00a00.855", "whitespace outside ASCII"),                # leading no-break space
    ("1_0", "digit separators"),
    ("nan", "not a finite number"), ("-inf", "not a finite number"),
    ("Infinity", "not a finite number"), ("1e400", "too large"),
    ("0x10", "not a number"), ("1,5", "not a number"), ("", "empty"),
])
def test_what_python_float_accepts_the_grammar_refuses(text, why):
    """float() reads all of these; the grammar refuses each with the reason."""
    with pytest.raises(ValueError, match=why):
        parse_number(text)


def test_integers():
    """Whole numbers: ASCII digits only, no point, no separator, bounded length."""
    assert parse_int("4096") == 4096
    for bad in ("4.0", "\u0663", "1_0", "12345678901234567890", "4e3"):
        with pytest.raises(ValueError):
            parse_int(bad)


def test_toml_numbers_follow_the_grammar():
    """TOML allows 1_000 and 0x10; a study does not (the line is named)."""
    assert load_toml("a = 1.5\nm1_2 = 3\ns = '1_0'", "s") == {"a": 1.5, "m1_2": 3, "s": "1_0"}
    with pytest.raises(StudyError, match="line 2: '1_0': digit separators"):
        load_toml("a = 1\nb = 1_0\n", "s", StudyError)
    with pytest.raises(StudyError, match="hexadecimal"):
        load_toml("x = [1, 0x10]", "s", StudyError)


# --------------------------------------------------------------------- URDF attributes
@pytest.mark.parametrize("old, new", [
    ('<mass value="0.855"/>', '<mass value="\u0660.\u0668\u0665\u0665"/>'),
    ('<mass value="0.855"/>', '<mass value="\u00a00.855"/>'),
    ('<mass value="0.855"/>', '<mass value="0.855 "/>'),  # urdfdom skips the inertial
    ('<origin xyz="0.6 0 0"/>', '<origin xyz="0.6\u00a00 0"/>'),
    ('izz="0.01443"', 'izz="\uff10.01443"'),
    ('upper="6.2832"', 'upper="6.2832\u2009"'),
    ('E="69e9"', 'E="\uff16\uff19e9"'),
    ('elements="4"', 'elements="\u0664"'),
])
def test_urdf_numbers_pinocchio_would_read_differently_are_refused(old, new):
    """Every number Pinocchio reads (mass, inertia, origins, limits) and every annotation."""
    assert old in BASE
    with pytest.raises(InvalidDescription, match="ASCII|spaces|three numbers"):
        parse(BASE.replace(old, new, 1))


def test_pinocchio_and_pinflex_readings_are_compared():
    """A model Pinocchio built differently from pinflex's reading is refused by name."""
    import pinocchio as pin

    from pinflex.description.crosscheck import check_pinocchio_reading

    desc = parse(BASE)
    check_pinocchio_reading(desc, pin.buildModelFromXML(desc.urdf_xml))
    for old, new, what in [('<mass value="0.855"/>', '<mass value="0.9"/>', "carries"),
                           ('<origin xyz="0.6 0 0"/>', '<origin xyz="0.61 0 0"/>', "is at"),
                           ('upper="6.2832"', 'upper="6"', "limits")]:
        other = pin.buildModelFromXML(BASE.replace(old, new, 1))
        with pytest.raises(InvalidDescription, match=f"differently.*{what}"):
            check_pinocchio_reading(desc, other)


def test_urdf_magnitudes_are_bounded():
    """A joint origin of 1e300 (LinAlgError before) and negative inertias are refused."""
    with pytest.raises(InvalidDescription, match="beyond 1e\\+06 m"):
        parse(BASE.replace('<origin xyz="0.6 0 0"/>', '<origin xyz="1e300 0 0"/>'))
    with pytest.raises(InvalidDescription, match="effort"):
        parse(BASE.replace('effort="100"', 'effort="-1"', 1))


def test_mimic_joints_are_refused():
    """<mimic> would be ignored (every joint moves on its own in pinflex)."""
    text = BASE.replace('velocity="10"/>\n  </joint>\n  <joint name="tool_joint"',
                        'velocity="10"/><mimic joint="q1"/>\n  </joint>\n  '
                        '<joint name="tool_joint"')
    with pytest.raises(UnsupportedJoint, match="q2' mimics joint 'q1'"):
        parse(text)


# --------------------------------------------------------------------- parameter references
def test_element_count_through_a_parameter_is_bounded():
    """elements="{ne}" with ne = 5000 is refused like elements="5000" (it bypassed 4096)."""
    text = _with_param(BASE.replace('elements="4"', 'elements="{ne}"'),
                       '<pinflex:parameter name="ne" value="5000"/>')
    with pytest.raises(InvalidAttribute, match='elements="\\{ne\\}" = 5000 must be at most 4096'):
        parse(text)
    with pytest.raises(InvalidAttribute, match="at most 4096"):
        parse(BASE.replace('elements="4"', 'elements="5000"'))
    ok = _with_param(BASE.replace('elements="4"', 'elements="{ne}"'),
                     '<pinflex:parameter name="ne" value="6"/>')
    assert parse(ok).flexible["link1"].elements == 6
    with pytest.raises(InvalidAttribute, match="not a whole number"):
        parse(ok, values={"ne": 6.5})


def test_references_pass_the_plausibility_checks_of_literals():
    """A 60 m tube or E = 70 Pa through a parameter (or --set) is refused like the literal."""
    tube = 'shape="hollow_circle" outer_diameter="{D}" wall="0.002"'
    lit = BASE.replace(SECTION, tube.replace("{D}", "60"), 1)
    ref = _with_param(BASE.replace(SECTION, tube, 1), '<pinflex:parameter name="D" value="60"/>')
    for text in (lit, ref):
        with pytest.raises(ImplausibleValue, match="60 m across but the link is 0.6 m long"):
            parse(text)
    design = _with_param(BASE.replace(SECTION, tube, 1),
                         '<pinflex:parameter name="D" value="0.03" lower="0.02" upper="60" '
                         'design="true"/>')
    with pytest.raises(ImplausibleValue, match="upper bound of its design parameter"):
        parse(design)
    soft = _with_param(BASE.replace('E="69e9"', 'E="{E}"', 1),
                       '<pinflex:parameter name="E" value="69e9"/>')
    assert parse(soft).flexible["link1"].E == 69e9
    with pytest.raises(ImplausibleValue, match='E="\\{E\\}" = 70 \\[Pa\\]'):
        parse(soft, values={"E": 70.0})
    with pytest.warns(Warning, match="not physical"):
        parse(soft, values={"E": 70.0}, plausibility="warn")


def test_point_mass_bounds_may_reference_parameters():
    """lower="{p}" on a point mass was float("{p}"): ValueError, exit 1."""
    text = _with_param(BASE.replace('lower="0" upper="0.25"/>\n  <pinflex:point_mass name="m2"',
                                    'lower="{p}" upper="0.25"/>\n  <pinflex:point_mass '
                                    'name="m2"', 1),
                       '<pinflex:parameter name="p" value="0.01"/>')
    desc = parse(text)
    assert desc.point_masses[0].lower == 0.01


def test_parameter_names_and_use():
    """A parameter named like a point mass, or a design parameter nothing uses: refused."""
    with pytest.raises(InvalidAttribute, match="name of a point mass"):
        parse(_with_param(BASE, '<pinflex:parameter name="m1" value="0.2"/>'))
    with pytest.raises(InvalidAttribute, match="referenced by no attribute"):
        parse(_with_param(BASE, '<pinflex:parameter name="u" value="1" lower="0" upper="2" '
                          'design="true"/>'))
    with pytest.warns(Warning, match="referenced by no attribute"):
        parse(_with_param(BASE, '<pinflex:parameter name="u" value="1"/>'))


# --------------------------------------------------------------------- API arguments
def _api_cases():
    from pinflex import Material
    from pinflex.erls import FlexibleModel

    model = FlexibleModel(TWO_LINK, planar=True)
    return model, [
        ("FlexibleModel(None)", lambda: FlexibleModel(None), UnreadableFile),
        ("FlexibleModel(3)", lambda: FlexibleModel(3), UnreadableFile),
        ("joints={'q1': None}", lambda: FlexibleModel(TWO_LINK, joints={"q1": None}),
         ConfigurationError),
        ("values={'m1': None}", lambda: FlexibleModel(TWO_LINK, values={"m1": None}),
         ConfigurationError),
        ("values={'m1': '0.2'}", lambda: FlexibleModel(TWO_LINK, values={"m1": "0.2"}),
         ConfigurationError),
        ("values={'D_upper': None} (a parameter)",
         lambda: FlexibleModel(TWO_LINK.with_name("ur5_tubes.xml"), values={"D_upper": None}),
         ConfigurationError),
        ("Material(E=None)", lambda: Material(E=None, density=2700.0), InvalidBeamProperty),
        ("Material(E='70e9')", lambda: Material(E="70e9", density=2700.0), InvalidBeamProperty),
        ("frequencies complex", lambda: model.frequencies(np.array([1.8 + 1j, 5.3])),
         ConfigurationError),
        ("frequencies booleans", lambda: model.frequencies(np.array([True, False])),
         ConfigurationError),
        ("frequencies masked", lambda: model.frequencies(np.ma.array([1.8, 5.3],
                                                                     mask=[0, 1])),
         ConfigurationError),
        ("frequencies [1, 'a']", lambda: model.frequencies([1, "a"]), ConfigurationError),
    ]


def test_api_arguments_of_the_wrong_type_are_named():
    """Each of these was a TypeError/ValueError/AttributeError (exit 1) or a silent result."""
    _, cases = _api_cases()
    for label, call, error in cases:
        with pytest.raises(error):
            call()


def test_taylor_evaluation_arguments():
    """evaluate(Q=[1,'a']) crashed; linear_in_design="no" was truthy; tol=nan disabled the
    check; complex, boolean and masked joint values were silently converted."""
    from pinflex.erls import FlexibleModel
    from pinflex.parametric import expand

    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, [1.8, 5.3], order=2, modes=[1])
    q = np.array([1.8, 5.3])
    assert tm.evaluate(q).shape == (1, 1)
    for kwargs in ({"Q": [1, "a"]}, {"Q": q, "linear_in_design": "no"},
                   {"Q": q, "tol": math.nan}, {"Q": np.array([1.8 + 1j, 5.3])},
                   {"Q": np.array([True, False])}, {"Q": np.ma.array(q, mask=[0, 1])},
                   {"Q": q, "warn": "yes"}):
        with pytest.raises(ConfigurationError):
            tm.evaluate(**kwargs)


def test_dynamics_and_export_arguments():
    """simulate_prescribed(damping="rayleigh") crashed; gravity 1e300 and a NaN Rayleigh
    factor were accepted (Infinity in --json, NaN matrices)."""
    from pinflex.assignment.study import user_trajectory
    from pinflex.dynamics.simulate import simulate_prescribed
    from pinflex.dynamics.terms import ErlsDynamics
    from pinflex.erls import FlexibleModel
    from pinflex.native.export import linear_model

    model = FlexibleModel(TWO_LINK, planar=True)
    traj = user_trajectory(model, "benchmark_a")
    with pytest.raises(ConfigurationError, match="Damping"):
        simulate_prescribed(ErlsDynamics(model), traj, damping="rayleigh")
    with pytest.raises(ConfigurationError, match="gravity"):
        ErlsDynamics(model, gravity=[0, -1e300, 0])
    for kwargs in ({"rayleigh": (math.nan, 0.0)}, {"rayleigh": (1.0,)}, {"zeta": "0.1"},
                   {"zeta": 2.0}):
        with pytest.raises(ConfigurationError):
            linear_model(model, [1.8, 5.3], **kwargs)


def test_json_output_is_never_invalid():
    """NaN or inf in a result is refused by name instead of printing 'Infinity'."""
    from pinflex.outputs import json_text

    assert json_text({"a": [1.0, 2]}) == '{"a": [1.0, 2]}'
    with pytest.raises(OutputError, match="at b\\[1\\]"):
        json_text({"a": 1.0, "b": [0.0, math.inf]})


# --------------------------------------------------------------------- studies
STUDY = """robot = "builtin:two_link.urdf"
planar = true
[trajectory]
builtin = "benchmark_a"
[[targets]]
mode = 1
freq_hz = 190.0
"""


def _load(tmp_path, text, name="s.toml"):
    from pinflex.assignment.study import load_config

    (tmp_path / name).write_text(text, encoding="utf-8")
    return load_config(tmp_path / name)


@pytest.mark.parametrize("extra, where, match", [
    ("[constraints]\nfloors = [{ mode = 2, freq_hz = 400.0 }, { mode = 2, freq_hz = 500.0 }]\n",
     "constraints.floors[1].mode", "already has a floor"),
    ("[simulation]\nsample_hz = 1e12\n", "simulation.sample_hz", "at most 1e+06"),
    ("[simulation]\nafter_s = 1e6\n", "simulation.after_s", "at most 10000"),
    ("[simulation]\ntol = 1e-16\n", "simulation.tol", "round-off"),
    ("[simulation]\ngravity = [0, -1e300, 0]\n", "simulation.gravity[1]", "must be >= -1000"),
    ("[simulation]\nrtol = 1e-3\n", "simulation.rtol", "belongs to drive = 'torque'"),
    ("[simulation]\nsampel_hz = 10.0\n", "simulation.sampel_hz", "did you mean 'sample_hz'"),
])
def test_study_tables_are_bounded_and_checked(tmp_path, extra, where, match):
    """Work sizes and physical ranges of every table, by the one schema engine."""
    with pytest.raises(StudyError) as info:
        _load(tmp_path, STUDY + extra)
    assert any(p.where == where and match in p.message for p in info.value.problems), \
        info.value


def test_a_lone_target_of_weight_zero_is_refused(tmp_path):
    """The cost would be zero: nothing to assign."""
    with pytest.raises(StudyError, match="every target has weight 0"):
        _load(tmp_path, STUDY + "weight = 0.0\n")


def test_per_sample_targets_of_the_wrong_length(tmp_path):
    """freq_hz with another length than the trajectory: a named error (it was exit 1)."""
    from pinflex.assignment.study import run_config

    cfg = _load(tmp_path, STUDY.replace("freq_hz = 190.0", "freq_hz = [190.0, 191.0, 192.0]"))
    with pytest.raises(StudyError, match="targets\\[0\\].freq_hz has 3 values"):
        run_config(cfg)


def test_simulation_study_files_are_read_like_every_input(tmp_path):
    """A non-UTF-8 study was a UnicodeDecodeError in `pinflex simulate` (exit 1)."""
    from pinflex.dynamics.study import load_simulation_study

    path = tmp_path / "s.toml"
    path.write_bytes(STUDY.encode() + b"# \xff\xfe\n")
    with pytest.raises(PinflexError, match="not UTF-8"):
        load_simulation_study(path)
    path.write_text(STUDY + "[simulation]\nsample_hz = 1_000\n")
    with pytest.raises(PinflexError, match="digit separators"):
        load_simulation_study(path)


def test_long_paths_are_named_errors(tmp_path, capsys):
    """A file name longer than the system allows was an OSError (exit 1) in every command."""
    from pinflex.cli import main

    long = str(tmp_path / ("x" * 300 + ".urdf"))
    for argv in (["modes", long], ["assign", long.replace(".urdf", ".toml")],
                 ["modes", str(TWO_LINK), "--trajectory", long]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and "too long" in err, err


def test_the_shipped_files_still_load_unchanged():
    """Nothing above refuses the shipped descriptions and example study."""
    from conftest import ROOT

    from pinflex.description import load

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for path in sorted((ROOT / "urdf").iterdir()):
            load(path)
    _ = load_toml((ROOT / "examples" / "benchmark_a.toml").read_text(), "example")


# --------------------------------------------------------------------- paths and outputs
def test_overlay_bases_and_meshes_are_confined(tmp_path, monkeypatch):
    """An overlay's base and the meshes of the visuals stay in the model's folder and the
    package roots (absolute, file:// and .. names refused) unless allowed explicitly."""
    from pinflex.description import load
    from pinflex.description.source import check_mesh_paths
    from pinflex.exceptions import UnsafePath

    inner = tmp_path / "inner"
    inner.mkdir()
    (tmp_path / "robot.urdf").write_text(BASE)
    (inner / "robot.urdf").write_text(BASE)
    overlay = inner / "o.xml"
    for base, ok in (("robot.urdf", True), ("../robot.urdf", False), (str(TWO_LINK), False),
                     (f"file://{TWO_LINK}", False),
                     ("example-robot-data:../../../../etc/hostname", False)):
        overlay.write_text(f'<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" '
                           f'base="{base}"/>')
        if ok:
            load(overlay)
        else:
            with pytest.raises(UnsafePath, match="outside the model's folder"):
                load(overlay)
    overlay.write_text('<pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1" '
                       'base="../robot.urdf"/>')
    assert load(overlay, allow_paths=True).allow_paths
    outside = tmp_path / "ros"
    (outside / "nopkg").mkdir(parents=True)
    (outside / "nopkg" / "x.stl").write_text("solid x")
    monkeypatch.setenv("ROS_PACKAGE_PATH", str(outside))  # searched by Pinocchio, not a root
    for name in ("../x.stl", "/etc/x.stl", "file:///etc/x.stl", "package://nopkg/x.stl"):
        text = BASE.replace('<cylinder radius="0.015" length="0.6"/>',
                            f'<mesh filename="{name}"/>', 1)
        with pytest.raises(UnsafePath):
            check_mesh_paths(text, inner, [inner])
        check_mesh_paths(text, inner, [inner], allow=True)
    for name in ("meshes/x.stl", "package://missing/x.stl"):  # inside, or found nowhere
        check_mesh_paths(BASE.replace('<cylinder radius="0.015" length="0.6"/>',
                                      f'<mesh filename="{name}"/>', 1), inner, [inner])


def test_stale_temporary_files_are_cleaned_on_the_next_write(tmp_path):
    """A killed write leaves .NAME.PID-XXXX.tmp; the next write of NAME removes it if that
    process is gone, and leaves the files of running writers alone."""
    import os
    import subprocess
    import sys

    from pinflex.outputs import write_text

    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"],
                          capture_output=True, text=True, check=True).stdout.strip()
    stale = tmp_path / f".out.json.{dead}-abcd.tmp"
    stale.write_text("partial")
    mine = tmp_path / f".out.json.{os.getpid()}-efgh.tmp"
    mine.write_text("in progress")
    old = tmp_path / ".out.json.legacy.tmp"
    old.write_text("partial")
    os.utime(old, (0, 0))
    other = tmp_path / ".other.json.1-x.tmp"
    other.write_text("another target")
    write_text(tmp_path / "out.json", "{}")
    left = sorted(p.name for p in tmp_path.iterdir())
    assert left == sorted(["out.json", mine.name, other.name]), left


def test_store_under_a_file_is_a_named_error(tmp_path, capsys):
    """`--store FILE/s.db` was a NotADirectoryError (exit 1)."""
    from conftest import ROOT

    from pinflex.cli import main

    (tmp_path / "file").write_text("x")
    assert main(["batch", "assign", str(ROOT / "examples" / "benchmark_a.toml"), "--store",
                 str(tmp_path / "file" / "s.db"), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "is a file, not a folder" in err and err.count("\n") == 1


def test_sweep_with_a_bad_design_name_fails_the_command(tmp_path, capsys):
    """It was stored as a failed row with exit 0; now the command refuses before any task."""
    from conftest import ROOT

    from pinflex.cli import main

    store = tmp_path / "s.db"
    assert main(["batch", "assign", str(ROOT / "examples" / "benchmark_a.toml"), "--sweep",
                 "expansion.y0.m9=0.1", "--store", str(store), "--no-progress"]) == 2
    err = capsys.readouterr().err
    assert "'m9'" in err.replace('"', "'") or "m9" in err
    assert "is not a design variable" in err and err.count("\n") == 1
    assert not store.exists()


def test_urdfdom_messages_do_not_leak(tmp_path, capfd):
    """A URDF Pinocchio refuses (a limit without effort) is one line on stderr, naming
    urdfdom's reason; urdfdom's own multi-line report is kept off the terminal."""
    from pinflex.cli import main

    path = tmp_path / "r.urdf"
    path.write_text(BASE.replace(' effort="100" velocity="10"', "", 1))
    assert main(["modes", str(path)]) == 2
    err = capfd.readouterr().err
    assert err.count("\n") == 1 and "limit has no effort" in err, err


def test_simulation_output_size_is_bounded_before_work():
    """sample_hz x time within their bounds can still exceed memory: refused with the
    estimate (sample_hz = 1e12 asked for 5.5 TiB before)."""
    from pinflex.dynamics.study import check_simulation_size, parse_simulation_table
    from pinflex.exceptions import ResourceLimitExceeded

    big = parse_simulation_table({"sample_hz": 1e6, "after_s": 1e4})
    with pytest.raises(ResourceLimitExceeded, match="1e\\+10 output samples"):
        check_simulation_size(big, 1.5, 44, 2)
    check_simulation_size(parse_simulation_table({}), 1.5, 44, 2)


def test_walk_from_a_far_expansion_point_is_bounded():
    """q0 = [1000, 1000] ran past 120 s ([1e6, 1e6]: MemoryError): refused with the count."""
    from pinflex.assignment.study import user_trajectory
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import ResourceLimitExceeded
    from pinflex.erls.tracking import track_modes

    model = FlexibleModel(TWO_LINK, planar=True)
    traj = user_trajectory(model, "benchmark_a")
    for q0 in ([1000.0, 1000.0], [1e6, 1e6]):
        with pytest.raises(ResourceLimitExceeded, match="modal analyses"):
            track_modes(model, traj.q, reference=(q0, None))


def test_python_specifications_take_numbers_only():
    """Beam/Mass/Material values went through float() and int(): "٣" elements, "1_0" masses
    and design="no" (truthy) were accepted."""
    from pinflex import Beam, Mass, Material
    from pinflex.beam import solid_circle
    from pinflex.exceptions import InvalidDescription

    alu = Material(E=70e9, density=2700.0)
    for elements in ("4", "\u0663", None, 2.5, True):
        with pytest.raises(InvalidBeamProperty, match="Beam.elements"):
            Beam(solid_circle(0.03), alu, elements=elements).element("l")
    with pytest.raises(InvalidDescription, match="tip"):
        Beam(solid_circle(0.03), alu, tip=("0.5", 0, 0)).element("l")
    for kwargs in ({"mass": "0.2"}, {"mass": None}, {"mass": 0.2, "design": "no"},
                   {"mass": 0.2, "xyz": (0, True, 0)}):
        with pytest.raises(InvalidDescription):
            Mass("l", **kwargs).element("m")
    el = Mass("l", 0.2, design=True, lower=0.0).element("m")
    assert "upper" not in el.attrib  # unbounded above: no attribute
