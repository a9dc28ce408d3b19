"""Bounds and refusals found by the third round of fuzzing (each case passed before).

Indefinite link inertias, text inside annotations, point masses far off their beam, models
too large to assemble, deeply nested TOML, trajectories in the wrong units, outputs that
would replace a device, and command-line counts and sizes without a bound (a sweep of 10^5
cases, 10^5 Dask workers, 10^9 multistart points) are refused by name before any work.
"""

from __future__ import annotations

import math
import os
import stat
import warnings

import numpy as np
import pytest
from conftest import ROOT, TWO_LINK
from fuzz_inputs import _assign, _example_robot, _torque, _trajectory_kw

from pinflex.description import parse
from pinflex.exceptions import (
    ConfigurationError,
    InvalidDescription,
    InvalidTrajectory,
    OutputError,
    PlausibilityWarning,
    ResourceLimitExceeded,
    UnknownElement,
)
from pinflex.validation import load_toml

BASE = TWO_LINK.read_text()
# a rigid, moving link with its own inertia (the tool of the two-link arm)
TOOL = ('<link name="tool"><inertial><mass value="0.5"/>'
        '<inertia ixx="{ixx}" ixy="0" ixz="0" iyy="1e-3" iyz="{iyz}" izz="1e-3"/>'
        '</inertial></link>')


def _tool(ixx="1e-3", iyz="0"):
    return BASE.replace('<link name="tool"/>', TOOL.format(ixx=ixx, iyz=iyz), 1)


def test_an_indefinite_link_inertia_is_refused():
    """iyz = 0.5 with iyy = izz = 1e-3 gives principal moments (-0.499, 0.001, 0.501): the
    mass matrix would be indefinite. Pinocchio takes it."""
    from pinflex.erls import FlexibleModel

    FlexibleModel(parse(_tool()), planar=True)  # the valid tool inertia loads
    with pytest.raises(InvalidDescription, match=r"not positive semi-definite.*-0\.499"):
        parse(_tool(iyz="0.5"))


def test_an_inertia_against_the_triangle_inequality_warns():
    """Principal moments (1e-3, 1e-3, 1) belong to no rigid body: warned, not refused
    (upstream URDFs have such tensors; they keep the mass matrix positive)."""
    with pytest.warns(PlausibilityWarning, match="triangle inequality"):
        parse(_tool(ixx="1"))


@pytest.mark.parametrize("inner", ["hello", "<![CDATA[0.5]]>"])
def test_text_inside_an_annotation_is_refused(inner):
    """A value written as element text would be ignored without a word."""
    text = BASE.replace('<pinflex:coordinates convention="absolute"/>',
                        f'<pinflex:coordinates convention="absolute">{inner}'
                        '</pinflex:coordinates>', 1)
    with pytest.raises(UnknownElement, match="holds the text"):
        parse(text)


def test_a_point_mass_far_beyond_its_beam_warns():
    """x = 6 m on a 0.6 m beam rides on the tip through a 5.4 m rigid lever: warned."""
    text = BASE.replace('link="link1" xyz="0.6 0 0"', 'link="link1" xyz="6 0 0"', 1)
    with pytest.warns(PlausibilityWarning, match=r"5\.4 m"):
        parse(text)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PlausibilityWarning)
        parse(BASE)  # masses at the tips: no warning


def test_a_model_too_large_is_refused_before_any_matrix(monkeypatch):
    """Two links of 4096 elements: 24,578 dof, each beam assembled densely on 24,582 rows
    (4.5 GiB); it was a MemoryError (or the OOM killer) inside the plan."""
    from pinflex.erls import FlexibleModel

    monkeypatch.setenv("PINFLEX_MAX_MEMORY_GB", "2")
    text = BASE.replace('elements="4"', 'elements="4096"').replace('elements="3"',
                                                                    'elements="4096"')
    with pytest.raises(ResourceLimitExceeded, match=r"24578 dof, 4096 elements"):
        FlexibleModel(parse(text), planar=True)
    FlexibleModel(parse(BASE), planar=True)  # the shipped arm is far below


def test_a_hollow_circle_with_a_wall_of_half_the_diameter_is_the_solid_rod():
    """wall = D/2 is a tube without a hole: accepted, with the area of the solid rod."""
    text = BASE.replace(
        'A="7.07e-4" Iy="3.97e-8" Iz="3.97e-8" J="7.94e-8"',
        'shape="hollow_circle" outer_diameter="0.03" wall="0.015"', 1)
    desc = parse(text)
    d = 0.03
    assert desc.flexible["link1"].section.A == pytest.approx(math.pi * d**2 / 4, rel=1e-12)
    assert desc.flexible["link1"].section.Iy == pytest.approx(math.pi * d**4 / 64, rel=1e-12)


def test_deeply_nested_toml_is_a_named_error():
    """tomllib recursed past Python's limit (RecursionError)."""
    with pytest.raises(ConfigurationError, match="nested too deeply"):
        load_toml("x = " + "[" * 5000 + "]" * 5000 + "\n", "s.toml")


@pytest.mark.parametrize("rows, match", [
    ("0,1.8,5.3\n0.1,1e300,5.31\n", r"q beyond 1e\+06 .* at samples 1"),
    ("0,1.8,5.3\n1e300,1.81,5.31\n", r"times_s beyond 1e\+09 s at samples 1"),
    ("0,1.8,5.3\n0.2,1.81,5.31\n0.1,1.82,5.32\n", r"t\[1\] = 0\.2 >= t\[2\] = 0\.1$"),
])
def test_trajectory_values_in_the_wrong_units_are_refused(tmp_path, rows, match):
    """Joint values of 1e300 rad and times of 1e300 s were accepted."""
    from pinflex.trajectory import Trajectory

    path = tmp_path / "t.csv"
    path.write_text("t,q1,q2\n" + rows)
    with pytest.raises(InvalidTrajectory, match=match):
        Trajectory.from_csv(path, joint_names=("q1", "q2"))


def test_a_utf16_trajectory_is_named_as_such(tmp_path):
    from pinflex.trajectory import Trajectory

    path = tmp_path / "t.csv"
    path.write_bytes("t,q1,q2\n0,1,2\n".encode("utf-16"))
    with pytest.raises(InvalidTrajectory, match="not a trajectory CSV .*UTF-16"):
        Trajectory.from_csv(path, joint_names=("q1", "q2"))


def test_an_output_never_replaces_a_pipe_or_device(tmp_path):
    """As root, ``--csv /dev/full`` replaced the device node with the CSV (os.replace)."""
    from pinflex.outputs import write_text

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    with pytest.raises(OutputError, match="device, pipe or socket"):
        write_text(fifo, "x", "CSV")
    assert stat.S_ISFIFO(fifo.lstat().st_mode)
    assert not [p for p in tmp_path.iterdir() if p.name.endswith(".tmp")]


CLI_REFUSALS = [
    (["modes", "{u}", "--planar", "--set", "m1=0.1", "--set", "m1=0.2"], "given twice"),
    (["modes", "{u}", "--planar", "--trajectory", "{t}", "--csv", ""], "empty value"),
    (["modes", "{u}", "--planar", "--q", "1e300", "0"], "beyond 1e\\+06"),
    (["path", "{u}", "--frame", "tool", "--through", "0.5", "0.5", "0", "--q", "1e9", "0",
      "--out", "{d}/p.csv"], "beyond 1e\\+06"),
    (["export", "{u}", "--planar", "--rayleigh", "1e300", "0", "--out", "{d}/e.npz"],
     "alpha <= 1e6"),
    (["view", "{u}", "--planar", "--modes", "100000", "--html", "{d}/v.html"], "give 1 to 21"),
    (["view", "{u}", "--planar", "--amplitude", "1e300", "--html", "{d}/v.html"], "up to 1000"),
    (["view", "{u}", "--planar", "--serve-seconds", "1e300", "--html", "{d}/v.html"],
     "up to 1e\\+07"),
    (["view", "{u}", "--planar", "--bind", "999.1.1.1"], "not an IP address"),
    (["assign", "{s}", "--target-tol", "1e300"], "up to 1000"),
    (["simulate", "{s}", "--exaggeration", "-1"], "from 0"),
    (["prbdm", "--starts", "1000000000"], "between 1 and 1000"),
    (["batch", "prbdm", "--beams", "0", "--store", "{d}/s.db"], "between 1 and"),
    (["batch", "prbdm", "--beams", "1", "--workers", "100000", "--store", "{d}/s.db"],
     "--workers 100000 must be between 1 and"),
    (["batch", "assign", "{s}", "--store", "{d}/a.db", "--sweep",
      "targets.0.freq_hz=" + ",".join(["190"] * 20_000)], "20000 cases"),
]


@pytest.mark.parametrize("argv, match", CLI_REFUSALS, ids=lambda v: " ".join(v[:3])
                         if isinstance(v, list) else None)
def test_unbounded_or_meaningless_command_lines_exit_2_in_one_line(tmp_path, capsys, argv,
                                                                   match):
    """Each ran (a sweep of 10^5 cases, 10^5 worker processes, 10^9 starts), hung on a host
    name, crashed with exit 1 (OverflowError, ValueError) or took the last of two values."""
    import re

    from pinflex.cli import main

    csv = tmp_path / "t.csv"
    csv.write_text("t,q1,q2\n0,1.8,5.3\n0.1,1.81,5.31\n")
    words = [w.format(u=TWO_LINK, s=ROOT / "examples" / "benchmark_a.toml", t=csv, d=tmp_path)
             for w in argv]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(words)
    err = [line for line in capsys.readouterr().err.splitlines() if line.strip()]
    assert code == 2, err
    assert len(err) == 1 and re.search(match, err[0]), err
    assert not list(tmp_path.glob("*.db")) or argv[0] == "batch"


def test_python_beam_and_mass_specifications_round_trip():
    """The Python specifications write exactly what they were given (no float() of strings)."""
    from pinflex import Beam, Mass, Material
    from pinflex.beam import solid_circle

    beam = Beam(solid_circle(0.03), Material(E=69e9, linear_density=1.9), elements=5,
                tip=(0.6, 0.0, 0.0))
    el = beam.element("link1")
    assert el.get("elements") == "5" and el.get("tip") == "0.6 0.0 0.0"
    mass = Mass("link1", np.float64(0.125), xyz=np.array([0.6, 0.0, 0.0]), design=True,
                upper=0.25)
    got = mass.element("m1").attrib
    assert (got["mass"], got["xyz"], got["lower"], got["upper"]) == (
        "0.125", "0.6 0.0 0.0", "0.0", "0.25")


@pytest.mark.parametrize("call, match", [
    (lambda m, tm: tm.evaluate([1.8, 5.3], quantity=["freq_hz"]), "quantity"),
    (lambda m, tm: _trajectory_kw(name=3.5), "name must be a string"),
    (lambda m, tm: _trajectory_kw(joint_names=None), "joint_names must be a sequence"),
    (lambda m, tm: _trajectory_kw().check_limits(-1.0, 1.0, on_violation=None),
     "on_violation"),
    (lambda m, tm: _assign(m, None), "targets must be a list of pinflex Target"),
    (lambda m, tm: _assign(m, [1, "a"]), "targets must be a list of pinflex Target"),
    (lambda m, tm: _torque(m, kp="1"), "kp"),
    (lambda m, tm: _torque(m, duration_s=None), "duration_s"),
    (lambda m, tm: _torque(m, duration_s=True), "duration_s"),
    (lambda m, tm: _example_robot(None), "named by a string"),
])
def test_api_arguments_of_the_wrong_type_are_named(call, match):
    """Each was a TypeError, AttributeError or ValueError from deep inside, or (a boolean
    duration, any PD gain without a reference motion) accepted."""
    from pinflex.erls import FlexibleModel
    from pinflex.exceptions import PinflexError
    from pinflex.parametric import expand

    model = FlexibleModel(TWO_LINK, planar=True)
    tm = expand(model, [1.8, 5.3], order=1, modes=[1])
    with pytest.raises(PinflexError, match=match):
        call(model, tm)

