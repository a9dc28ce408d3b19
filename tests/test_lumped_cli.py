"""``pinflex export --format mjcf|urdf``: outputs, refusals and the segment choice."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.cli import main
from pinflex.erls import FlexibleModel
from pinflex.lumped.fidelity import segments_for_tolerance


def _export(tmp_path, *extra, out="arm.urdf"):
    return main(["export", str(TWO_LINK), "--planar", "--q", "0", "0", "--out",
                 str(tmp_path / out), *extra])


def test_urdf_export_writes_the_urdf_and_its_spring_data(tmp_path, capsys):
    """--out arm.urdf writes arm.urdf and arm.springs.json; an existing file needs --force."""
    assert _export(tmp_path, "--segments", "3", "--rayleigh", "0", "1e-5") == 0
    springs = json.loads((tmp_path / "arm.springs.json").read_text())
    assert springs["format"] == "pinflex-springs/1"
    hinge = springs["joints"]["link1_h1_bz"]
    assert hinge["damping"] == pytest.approx(1e-5 * hinge["stiffness"], rel=1e-12)
    out = capsys.readouterr().out
    assert "equal segments with k = EI/l" in out
    assert "mode shapes, MAC with the ERLS modes" in out
    assert _export(tmp_path, "--segments", "3") == 2
    assert "exists; pass --force" in capsys.readouterr().err
    assert _export(tmp_path, "--segments", "3", "--force") == 0


@pytest.mark.parametrize("args, message", [
    (["--segments", "60"], "too short for 60 segments"),
    (["--segments", "2", "--modes", "9"], "9 modes asked"),
    (["--segments", "2", "--rayleigh", "2", "0"], "alpha"),
])
def test_bad_lumped_exports_exit_2_with_a_named_error(tmp_path, capsys, args, message):
    """Refusals are one line on stderr, exit status 2, and no file is written."""
    assert _export(tmp_path, *args, out="arm.xml") == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "arm.xml").exists()


def test_motion_outside_the_joint_limits_is_refused(tmp_path, capsys):
    """A trajectory sample beyond a joint limit is refused before any fit."""
    csv = tmp_path / "t.csv"
    csv.write_text("t,q1,q2\n0,0,0\n1,7.0,7.0\n")
    assert main(["export", str(TWO_LINK), "--planar", "--trajectory", str(csv), "--format",
                 "mjcf", "--segments", "3", "--out", str(tmp_path / "a.xml")]) == 2
    assert "outside the limits" in capsys.readouterr().err


def test_tolerance_picks_the_fewest_segments_that_meet_it():
    """--tol: the chosen count meets the tolerance and every smaller count misses it."""
    arm = FlexibleModel(TWO_LINK, planar=True)
    choice = segments_for_tolerance(arm, 1e-3, max_segments=5, max_evaluations=80)
    assert choice.estimate <= 1e-3
    assert all(max(w, c) > 1e-3 for n, w, c in choice.levels if n < choice.n_segments)
    assert choice.levels[-1][0] == choice.n_segments
    np.testing.assert_allclose(choice.estimate, max(choice.fit.worst_error,
                                                    choice.fit.compliance_error))
