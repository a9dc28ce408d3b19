"""TOML studies: every table is checked, and one error lists every problem of the file."""

import pytest
from conftest import ROOT

from pinflex.assignment.study import load_config
from pinflex.assignment.study_schema import STUDY, check_override
from pinflex.exceptions import StudyError

EXAMPLE = (ROOT / "examples" / "benchmark_a.toml").read_text()


def _study(tmp_path, text, name="study.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _errors(tmp_path, text):
    with pytest.raises(StudyError) as info:
        load_config(_study(tmp_path, text))
    return info.value


@pytest.mark.parametrize(
    "old, new, where, match",
    [
        ("order = 4", "ordr = 4", "expansion.ordr", "did you mean 'order'"),
        ('quantity = "freq_hz"', 'quantity = "freq_hz"\nmass_budjet_kg = 1', "expansion.",
         "unknown key"),
        ("report_modes = [2, 3, 4]", "report_mode = [2, 3, 4]", "options.report_mode",
         "did you mean 'report_modes'"),
        ("planar = true", 'planar = "no"', "planar", "expected true or false, got the string"),
        ("mode = 1", "mode = 1.7", "targets[0].mode", "expected a whole number, got 1.7"),
        ("mode = 1", "mode = true", "targets[0].mode", "expected a number, got the boolean"),
        ("order = 4", "order = 40", "expansion.order", "40 must be at most 12"),
        ("order = 4", "order = 4.0", "expansion.order", "expected a whole number"),
        ("freq_hz = 190.0", "freq_hz = nan", "targets[0].freq_hz", "must be finite"),
        ("freq_hz = 190.0", "freq_hz = -190.0", "targets[0].freq_hz", "must be a positive number"),
        ("mode = 1", "mode = 30", "targets[0].mode", "mode 30 does not exist"),
        ("m1 = 0.125, m2 = 0.125 }", "m1 = 0.125, m3 = 0.125 }", "expansion.y0.m3",
         "is not a design variable"),
        ("m1 = 0.125, m2 = 0.125 }", "m1 = 0.125, m2 = 0.9 }", "expansion.y0.m2",
         "outside the bounds"),
        ("q0 = [1.817, 5.312]", "q0 = [1.817]", "expansion.q0", "has 1 values"),
        ('builtin = "benchmark_a"', 'builtin = "benchmark_b"', "trajectory.builtin",
         "did you mean 'benchmark_a'"),
        ('builtin = "benchmark_a"', 'csv = "missing.csv"', "trajectory.csv",
         "does not exist"),
        ("[options]", "[options]\nrefine = 1", "options.refine", "expected true or false"),
        ('robot = "builtin:two_link.urdf"', 'robot = "builtin:two_links.urdf"', "robot",
         "no built-in description"),
    ],
)
def test_each_problem_is_named_where_it_is(tmp_path, old, new, where, match):
    """Unknown keys, wrong types, bad ranges and model mismatches are refused by location."""
    assert old in EXAMPLE
    err = _errors(tmp_path, EXAMPLE.replace(old, new, 1))
    assert any(p.where.startswith(where) and match in p.message for p in err.problems), err


def test_one_error_lists_every_problem(tmp_path):
    """A file with seven mistakes gets one error naming all seven, on one line."""
    text = (EXAMPLE.replace("order = 4", "ordr = 4\norder = 40")
            .replace("mode = 1", "mode = 1.7")
            .replace('quantity = "freq_hz"', 'quantity = "hz"')
            .replace("report_modes = [2, 3, 4]", "report_mode = [2]")
            + "\n[constraints]\nmass_budjet_kg = 0.3\n"
            + "bands = [{ mode = 3, low_hz = 700.0, high_hz = 650.0 }]\n")
    err = _errors(tmp_path, text)
    wheres = {p.where for p in err.problems}
    assert {"expansion.ordr", "expansion.order", "targets[0].mode", "expansion.quantity",
            "options.report_mode", "constraints.mass_budjet_kg",
            "constraints.bands[0].low_hz"} <= wheres
    assert str(err).startswith(f"{tmp_path / 'study.toml'}: ")
    assert "\n" not in str(err)


def test_band_and_floor_modes_are_checked_against_the_model(tmp_path):
    """Floors and bands on modes the model does not have are refused before any solve."""
    text = EXAMPLE + ("\n[constraints]\nfloors = [{ mode = 99, freq_hz = 400.0 }]\n"
                      "bands = [{ mode = 0, low_hz = 1.0, high_hz = 2.0 }]\n")
    err = _errors(tmp_path, text)
    msgs = {p.where: p.message for p in err.problems}
    assert "mode 99 does not exist" in msgs["constraints.floors[0].mode"]
    assert "0 must be >= 1" in msgs["constraints.bands[0].mode"]


def test_unreadable_and_malformed_files(tmp_path):
    """Missing, binary and malformed TOML files raise StudyError."""
    with pytest.raises(StudyError, match="does not exist"):
        load_config(tmp_path / "none.toml")
    binary = tmp_path / "b.toml"
    binary.write_bytes(b"\x00\x01\x02")
    with pytest.raises(StudyError, match="binary"):
        load_config(binary)
    with pytest.raises(StudyError, match="not valid TOML"):
        load_config(_study(tmp_path, "robot = [", "bad.toml"))


def test_the_example_study_loads():
    """The shipped example passes the schema unchanged."""
    cfg = load_config(ROOT / "examples" / "benchmark_a.toml")
    assert cfg.order == 4 and cfg.targets[0].mode == 1 and cfg.planar is True


def test_sweep_values_are_checked_with_the_same_schema():
    """``--sweep planar=no`` or ``expansion.order=40`` is refused like the file would be."""
    assert check_override("planar", "no")[0].message.startswith("expected true or false")
    assert "at most 12" in check_override("expansion.order", 40)[0].message
    assert "did you mean 'freq_hz'" in check_override("targets.0.freq", 190.0)[0].message
    assert check_override("targets.0.freq_hz", 185.0) == []
    assert check_override("options.baseline.m1", 0.1) == []


def test_schema_documents_every_key():
    """Each key of the study schema carries a line of documentation."""
    def walk(keys):
        for name, k in keys.items():
            assert k.doc, name
            walk(k.keys)

    walk(STUDY)
