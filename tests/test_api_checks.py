"""Public API and CLI arguments: every bad value is a named pinflex error, before work starts."""

import os
import warnings

import numpy as np
import pytest
from conftest import TWO_LINK, single_link_urdf

from pinflex.cli import main
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    ConfigurationError,
    InvalidTrajectory,
    OutputError,
    PinflexError,
    ResourceLimitExceeded,
)
from pinflex.outputs import atomic_path, save_figure, write_text
from pinflex.resources import MAX_TAYLOR_ORDER, check_modal, taylor_estimate

Q0 = [1.817, 5.312]


@pytest.mark.parametrize("n_modes", [0, -1, 2.5, True, "3"])
def test_bad_n_modes_is_refused(two_link_planar, n_modes):
    """``n_modes`` must be a positive int: 0, -1, 2.5, True and "3" are refused by name."""
    for call in (two_link_planar.modes, two_link_planar.frequencies):
        with pytest.raises(ConfigurationError, match="n_modes"):
            call(Q0, n_modes=n_modes)


@pytest.mark.parametrize("q", ["abc", ["1", "x"], [np.nan, 1.0], [np.inf, 0.0], [[1, 2], [3]],
                               None])
def test_bad_joint_values_are_refused(two_link_planar, q):
    """Strings, NaN/inf, ragged and missing joint values raise ConfigurationError."""
    with pytest.raises(ConfigurationError, match="joint values"):
        two_link_planar.modes(q)


def test_design_of_the_wrong_shape_is_not_silently_cut(two_link_planar):
    """modes() refuses several design vectors instead of using the first row."""
    with pytest.raises(ConfigurationError, match="one design vector"):
        two_link_planar.modes(Q0, y=np.zeros((3, 2)))
    with pytest.raises(ConfigurationError, match="expected 2 design values"):
        two_link_planar.modes(Q0, y=[0.1, 0.1, 0.1])
    one = two_link_planar.modes(Q0, y=[[0.1, 0.2]]).freq_hz
    np.testing.assert_array_equal(one, two_link_planar.modes(Q0, y=[0.1, 0.2]).freq_hz)


def test_with_values_refuses_nan_and_arrays(two_link_planar):
    """Point-mass values must be one finite number."""
    model = FlexibleModel(TWO_LINK, planar=True)
    for bad in (np.nan, [0.1, 0.2], "heavy"):
        with pytest.raises(ConfigurationError):
            model.with_values(m1=bad)


def test_taylor_order_is_bounded_before_work(two_link_planar):
    """Orders above the documented maximum, or not whole numbers, are refused at once."""
    import pinflex

    for order in (MAX_TAYLOR_ORDER + 1, 40, -1, 2.5, True):
        with pytest.raises(ConfigurationError, match="order"):
            pinflex.expand(two_link_planar, Q0, order=order)


def test_memory_estimate_refuses_huge_models_before_assembly(monkeypatch):
    """A model whose dense matrices exceed the memory limit is refused when it is built."""
    monkeypatch.setenv("PINFLEX_MAX_MEMORY_GB", "0.01")
    with pytest.raises(ResourceLimitExceeded, match="would need about .* GiB"):
        FlexibleModel(parse(single_link_urdf(elements=400)))
    with pytest.raises(ResourceLimitExceeded):
        check_modal(23, n_poses=10**6)
    monkeypatch.setenv("PINFLEX_MAX_MEMORY_GB", "many")
    with pytest.raises(ConfigurationError):
        check_modal(23)


def test_taylor_estimate_counts_coefficients():
    """The memory estimate holds C(v + p, p) coefficient matrices per M, K and design mass."""
    nbytes, _ = taylor_estimate(4, 4, 23, ndesign=2)
    assert nbytes == 70 * 6 * 23 * 23 * 8


def test_missing_and_malformed_csv(tmp_path):
    """A missing or binary trajectory CSV raises InvalidTrajectory."""
    from pinflex.trajectory import Trajectory

    with pytest.raises(InvalidTrajectory, match="does not exist"):
        Trajectory.from_csv(tmp_path / "missing.csv")
    binary = tmp_path / "t.csv"
    binary.write_bytes(b"\xff\xfe\x00\x01" * 10)
    with pytest.raises(InvalidTrajectory):
        Trajectory.from_csv(binary)


def test_outputs_are_atomic(tmp_path):
    """A failed write leaves the previous file intact and no temporary file behind."""
    target = tmp_path / "page.html"
    write_text(target, "good")
    with pytest.raises(RuntimeError):
        with atomic_path(target) as tmp:
            tmp.write_text("half a pa")
            raise RuntimeError("interrupted")
    assert target.read_text() == "good"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["page.html"]
    write_text(target, "better")
    assert target.read_text() == "better"


def test_failed_figure_keeps_the_old_png(tmp_path):
    """A figure whose rendering fails does not replace the previous PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots()
    ax.plot([0, 1], [0, 1])
    path = save_figure(fig, tmp_path / "chart.png")
    good = path.read_bytes()
    assert good.startswith(b"\x89PNG")
    plt.close(fig)

    class DiskFull:
        def savefig(self, target, **kwargs):
            with open(target, "wb") as stream:
                stream.write(b"\x89PNG half")
            raise OSError(28, "No space left on device")

    with pytest.raises(OutputError, match="No space left"):
        save_figure(DiskFull(), path)
    assert path.read_bytes() == good
    assert [p.name for p in tmp_path.iterdir()] == ["chart.png"]


def test_unwritable_outputs_are_named(tmp_path):
    """Writing into a folder that is a file, or onto a folder, raises OutputError."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    with pytest.raises(OutputError, match="is a file"):
        write_text(blocker / "page.html", "x")
    with pytest.raises(OutputError, match="is a folder"):
        write_text(tmp_path, "x")


def _cli(capsys, *argv):
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err
    return code, err


@pytest.mark.parametrize(
    "argv, match",
    [
        (["modes", TWO_LINK, "--planar", "--modes", "0"], "n_modes must be >= 1"),
        (["modes", TWO_LINK, "--planar", "--q", "nan", "1"], "finite"),
        (["modes", TWO_LINK, "--planar", "--set", "m1=nan"], "not a finite number"),
        (["modes", "no-such-file.urdf"], "does not exist"),
        (["prbdm", "--seed", "-1", "--beam", "random", "--no-progress"], "--seed"),
        (["prbdm", "--starts", "0", "--no-progress"], "--starts"),
        (["view", TWO_LINK, "--planar", "--amplitude", "nan", "--html", "x.html"],
         "--amplitude"),
    ],
)
def test_cli_refuses_bad_arguments_in_one_line(capsys, argv, match):
    """Bad CLI values print one error line and exit 2."""
    code, err = _cli(capsys, *argv)
    assert code == 2, err
    assert match in err and err.count("\n") == 1 and "Traceback" not in err


def test_cli_outputs_checked_before_work(capsys, tmp_path):
    """`--html DIR`, `--out FILE` and a folder that is a file are refused before any work."""
    blocker = tmp_path / "file"
    blocker.write_text("x")
    cases = [
        (["view", TWO_LINK, "--planar", "--html", tmp_path], "is a folder"),
        (["view", TWO_LINK, "--planar", "--html", blocker / "a.html"], "is a file"),
        (["assign", "examples/benchmark_a.toml", "--out", blocker], "is a file"),
        (["prbdm", "--html", tmp_path, "--no-progress"], "is a folder"),
    ]
    for argv, match in cases:
        code, err = _cli(capsys, *argv)
        assert code == 2 and match in err and err.count("\n") == 1, (argv, err)
    assert blocker.read_text() == "x"


def test_bad_scheduler_address_is_a_batch_error(tmp_path):
    """A malformed --scheduler address is a BatchError, not a Dask ValueError."""
    pytest.importorskip("distributed")
    from pinflex.batch.runner import connect
    from pinflex.exceptions import BatchError

    with pytest.raises(BatchError, match="no Dask scheduler answers at foo"):
        connect("foo")


def test_every_named_error_is_a_pinflex_error():
    """The classes raised by the checks all derive from PinflexError."""
    import pinflex.exceptions as ex

    for name in ("SchemaError", "UnknownElement", "UnknownAttribute", "InvalidAttribute",
                 "ImplausibleValue", "UnreadableFile", "NoFlexibleLink", "StudyError",
                 "ResourceLimitExceeded", "OutputError", "ViewerServerError"):
        assert issubclass(getattr(ex, name), PinflexError)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert os.path.isfile(TWO_LINK)


def test_every_file_writer_goes_through_the_atomic_helper():
    """No module writes an output file except through pinflex.outputs (temp file + rename)."""
    import re

    from conftest import ROOT

    patterns = [
        re.compile(r"\.savefig\((?!tmp\b)"),
        re.compile(r"\.write_text\("),
        re.compile(r"\.write_bytes\("),
        re.compile(r"open\((?!tmp\b)[^)]*[\"'][wax]b?[\"']"),
        re.compile(r"np\.save[zt]?(_compressed)?\((?!stream\b)"),
        re.compile(r"savemat\((?!stream\b)"),
        re.compile(r"write_table\((?!table, str\(tmp\))"),
    ]
    offenders = []
    for path in sorted((ROOT / "pinflex").rglob("*.py")):
        if path.name == "outputs.py":
            continue
        for number, line in enumerate(path.read_text().splitlines(), 1):
            if any(p.search(line) for p in patterns):
                offenders.append(f"{path.relative_to(ROOT)}:{number}: {line.strip()}")
    assert offenders == []


def test_expand_and_model_flags_are_strict(two_link_planar):
    """Mode lists of floats or strings, and planar='no', are refused instead of coerced."""
    import pinflex

    for modes in ((1.5,), "1", []):
        with pytest.raises(ConfigurationError, match="whole mode numbers"):
            pinflex.expand(two_link_planar, Q0, order=2, modes=modes)
    with pytest.raises(ConfigurationError, match="planar must be True or False"):
        FlexibleModel(TWO_LINK, planar="no")
