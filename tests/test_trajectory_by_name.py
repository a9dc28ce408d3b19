"""Trajectory files are read by joint name everywhere, through one reader.

A header ``t,q2,q1`` holds the same motion as ``t,q1,q2`` with the columns swapped: every
consumer (study files of ``assign``, ``modes``, ``export``, ``view``) must see the same
samples. Unknown, missing, duplicate and extra columns are refused by name.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.assignment.study import load_config, run_config, user_trajectory
from pinflex.cli import main
from pinflex.erls import FlexibleModel
from pinflex.exceptions import InvalidTrajectory
from pinflex.trajectory import Trajectory

STUDY = f"""robot = "{TWO_LINK}"
planar = true
[trajectory]
csv = "motion.csv"
[expansion]
q0 = [1.817, 5.312]
order = 3
[[targets]]
mode = 1
freq_hz = 190.0
[options]
baseline = {{ m1 = 0.0, m2 = 0.0 }}
report_modes = [2]
"""


def _write(path, header, times, cols):
    lines = [",".join(header)] + [",".join(repr(float(v)) for v in (t, *row))
                                  for t, row in zip(times, cols)]
    path.write_text("\n".join(lines) + "\n")


@pytest.fixture(scope="module")
def motion():
    model = FlexibleModel(TWO_LINK, planar=True)
    tr = user_trajectory(model, "benchmark_a")
    keep = np.arange(0, tr.n_samples, 6)  # 26 samples: enough to tell the joints apart
    return model, tr.times_s[keep], tr.q[keep]


def _answer(tmp_path, header, times, q):
    _write(tmp_path / "motion.csv", header, times, q)
    (tmp_path / "study.toml").write_text(STUDY)
    cfg = load_config(tmp_path / "study.toml")
    model, traj, result = run_config(cfg)
    return result


@pytest.mark.filterwarnings("ignore::pinflex.exceptions.TaylorRadiusWarning")
def test_swapped_columns_give_the_same_assignment(tmp_path, motion):
    """`t,q2,q1` with the columns swapped gives the answer of `t,q1,q2` (it was 0.25 vs 0.237)."""
    _, times, q = motion
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    ref = _answer(tmp_path / "a", ["t", "q1", "q2"], times, q)
    swapped = _answer(tmp_path / "b", ["t", "q2", "q1"], times, q[:, ::-1])
    assert ref.design == pytest.approx(swapped.design, rel=1e-12, abs=1e-14)
    assert swapped.max_error_after == pytest.approx(ref.max_error_after, rel=1e-12)
    # the columns really matter: read positionally, the swapped file is another motion
    wrong = _answer(tmp_path / "b", ["t", "q1", "q2"], times, q[:, ::-1])
    assert abs(wrong.design["m1"] - ref.design["m1"]) > 1e-3


@pytest.mark.parametrize(
    "header, match",
    [
        (["t", "a", "b"], "column 'a' names no joint"),
        (["t", "q1"], "no column for joint 'q2'"),
        (["t", "q1", "q2", "q3"], "column 'q3' names no joint"),
        (["t", "q1", "q1"], "duplicate column 'q1'"),
        (["t", "q1", "Q2"], "did you mean 'q2'"),
        (["time", "q1", "q2"], "header 't, <joint names"),
    ],
)
def test_bad_headers_are_refused_by_name(tmp_path, motion, header, match):
    """Unknown, missing, extra and duplicate columns: InvalidTrajectory naming them."""
    _, times, q = motion
    cols = np.zeros((len(times), len(header) - 1))
    _write(tmp_path / "m.csv", header, times, cols)
    with pytest.raises(InvalidTrajectory, match=match):
        Trajectory.from_csv(tmp_path / "m.csv", joint_names=("q1", "q2"))


@pytest.mark.parametrize("cell", ["1_0", "٠.٥", "１", "\u00a00.5", "nan", "inf", "0x1", ""])
def test_cells_follow_the_number_grammar(tmp_path, cell):
    """A cell Python's float() would read (1_0, Unicode digits, NBSP) is refused by name."""
    (tmp_path / "m.csv").write_text(f"t,q1,q2\n0,0,0\n1,{cell},0\n", encoding="utf-8")
    with pytest.raises(InvalidTrajectory, match="sample 2, column 'q1'"):
        Trajectory.from_csv(tmp_path / "m.csv", joint_names=("q1", "q2"))


def test_row_count_is_bounded_before_parsing(tmp_path):
    """More rows than allowed are refused with the count, before any cell is parsed."""
    (tmp_path / "m.csv").write_text("t,q1,q2\n" + "".join(f"{k},x,0\n" for k in range(50)))
    with pytest.raises(InvalidTrajectory, match="50 samples, more than the 20"):
        Trajectory.from_csv(tmp_path / "m.csv", max_samples=20)


@pytest.mark.parametrize("command", ["modes", "export", "view"])
def test_cli_reads_by_name(tmp_path, motion, capsys, command):
    """modes/export/view --trajectory see the same samples whatever the column order."""
    _, times, q = motion
    outs = []
    for k, (header, cols) in enumerate(((["t", "q1", "q2"], q[:4]),
                                        (["t", "q2", "q1"], q[:4, ::-1]))):
        path = tmp_path / f"m{k}.csv"
        _write(path, header, times[:4], cols)
        args = [command, str(TWO_LINK), "--planar", "--trajectory", str(path)]
        if command == "modes":
            args += ["--json"]
        elif command == "export":
            args += ["--out", str(tmp_path / f"e{k}.npz")]
        else:
            args += ["--html", str(tmp_path / f"v{k}.html")]
        assert main(args) == 0
        out = capsys.readouterr().out
        if command == "modes":
            outs.append(json.loads(out)["frequencies_hz"])
        elif command == "export":
            outs.append(np.load(tmp_path / f"e{k}.npz")["K"])
        else:
            outs.append(out.splitlines()[0])
    np.testing.assert_array_equal(np.asarray(outs[0]), np.asarray(outs[1]))
    bad = tmp_path / "bad.csv"
    _write(bad, ["t", "q1", "q3"], times[:4], q[:4])
    assert main([command, str(TWO_LINK), "--planar", "--trajectory", str(bad)]
                + (["--out", str(tmp_path / "x.npz")] if command == "export" else [])
                + (["--html", str(tmp_path / "x.html")] if command == "view" else [])) == 2
    err = capsys.readouterr().err
    assert "column 'q3' names no joint" in err and err.count("\n") == 1


def test_in_memory_trajectories_match_by_name(motion):
    """A Trajectory with named columns is reordered; unnamed columns are taken in order."""
    model, times, q = motion
    named = Trajectory(times, q[:, ::-1], ("q2", "q1"))
    np.testing.assert_array_equal(named.in_order(model.joint_names), q)
    np.testing.assert_array_equal(Trajectory(times, q).in_order(model.joint_names), q)
    with pytest.raises(InvalidTrajectory, match="duplicate column 'q1'"):
        Trajectory(times, q, ("q1", "q1"))
    with pytest.raises(InvalidTrajectory, match="names no joint"):
        Trajectory(times, q, ("a", "b")).in_order(model.joint_names)
