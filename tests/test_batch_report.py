"""Tests of pinflex/batch/report.py and the ``batch report`` command."""

from __future__ import annotations

import json

import numpy as np
import pytest

from pinflex.batch.report import build_report, write_histograms
from pinflex.batch.store import ResultStore
from pinflex.batch.tasks import PrbdmStudy, config_hash
from pinflex.cli import main
from pinflex.exceptions import StoreError


@pytest.fixture
def store(tmp_path):
    """A store with 40 ok rows of known errors and 3 failures in one configuration."""
    rng = np.random.default_rng(3)
    errors = 10.0 ** rng.uniform(-6, -2, 40)
    config = PrbdmStudy(seed=1, n_beams=43, links=(3,), truth_modes=3).configs()[0]
    chash = config_hash(config)
    rows = [{"seed": 1, "item": i, "config_hash": chash, "kind": "prbdm", "status": "ok",
             "params": {}, "metrics": {"eigen_error": e, "deflection_error": float("nan")},
             "timings": {"truth_s": 2.0, "fit_s": 1.0}} for i, e in enumerate(errors)]
    failures = ["truth: TruthNotConverged: mode 3 extrapolants differ",
                "truth: TruthNotConverged: mode 2 extrapolants differ",
                "fit: MappingFailed: all 16 starts failed"]
    rows += [{"seed": 1, "item": 40 + k, "config_hash": chash, "kind": "prbdm",
              "status": "failed", "error": text, "params": {}, "metrics": {},
              "timings": {"truth_s": 4.0}} for k, text in enumerate(failures)]
    path = tmp_path / "study.db"
    with ResultStore(path) as s:
        s.add_config(chash, "prbdm", config)
        s.write(rows)
    return path, errors


def test_report_statistics_match_numpy(store):
    """Counts, percentiles and mean times equal those computed directly from the inputs."""
    path, errors = store
    (group,) = build_report(path).groups
    assert (group.n_ok, group.n_failed) == (40, 3)
    stats = group.metrics["eigen_error"]
    assert stats["n"] == 40
    assert stats["p50"] == pytest.approx(np.median(errors), rel=1e-12)
    assert stats["p95"] == pytest.approx(np.percentile(errors, 95), rel=1e-12)
    assert stats["p100"] == pytest.approx(errors.max(), rel=1e-12)
    assert "deflection_error" not in group.metrics  # NaN everywhere: no statistics
    assert group.timings_s["truth_s"] == pytest.approx((40 * 2.0 + 3 * 4.0) / 43)
    assert group.failures[0][:2] == ("truth: TruthNotConverged", 2)
    assert group.failures[1][:2] == ("fit: MappingFailed", 1)
    assert "3R/3 modes" in group.name


def test_histograms_are_png_files(store, tmp_path):
    """One histogram per metric with finite values is written as a PNG."""
    path, _ = store
    files = write_histograms(path, tmp_path / "plots")
    assert [f.name.endswith("eigen_error.png") for f in files] == [True]
    assert files[0].read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_report_command_prints_percent_and_failures(store, capsys):
    """The command prints the median in percent and each failure type."""
    path, errors = store
    assert main(["batch", "report", str(path), "--no-plots"]) == 0
    out = capsys.readouterr().out
    assert f"{100 * np.median(errors):.3g}" in out
    assert "failed 2x truth: TruthNotConverged" in out
    assert main(["batch", "report", str(path), "--json", "--no-plots"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["groups"][0]["n_failed"] == 3


def test_missing_store_is_an_error(tmp_path):
    """Reporting on a file that does not exist raises StoreError."""
    with pytest.raises(StoreError, match="no store"):
        build_report(tmp_path / "none.db")


def test_case_table_has_case_parameters_as_columns(tmp_path, capsys):
    """`batch report` writes one row per assignment case with the swept keys as columns."""
    import csv

    from pinflex.batch.report import case_table

    path = tmp_path / "sweep.db"
    rows = []
    for case, (f, b) in enumerate([(185.0, 0.2), (185.0, -0.1), (190.0, 0.2)]):
        ok = b > 0
        rows.append({
            "seed": 0, "item": 0, "config_hash": f"h{case}", "kind": "assign",
            "status": "ok" if ok else "failed",
            "error": None if ok else "assign: AssignmentInfeasible: budget below zero",
            "params": {"case": case, "overrides": {"targets.0.freq_hz": f,
                                                   "constraints.mass_budget_kg": b}},
            "result": {"design": {"m1": 0.1 + case / 100, "m2": 0.05},
                       "max_error_before": 0.0831, "max_error_after": 0.01 * (case + 1),
                       "predicted_max_error_after": 0.009, "iterations": 7} if ok else None,
            "metrics": {"error_after": 0.01 * (case + 1)} if ok else {},
            "timings": {"task_s": 1.5},
        })
    with ResultStore(path) as s:
        for r in rows:
            s.add_config(r["config_hash"], "assign", {"study_file": "a.toml",
                                                      "study_sha256": "x"})
        s.write(rows)
    table = case_table(path)
    assert table.columns[0] == "case" and table.columns[3] == "status"
    assert set(table.columns[1:3]) == {"targets.0.freq_hz", "constraints.mass_budget_kg"}
    assert [r[0] for r in table.rows] == [0, 1, 2]
    col = {c: i for i, c in enumerate(table.columns)}
    assert [table.rows[2][col[c]] for c in ("targets.0.freq_hz", "constraints.mass_budget_kg",
                                           "status")] == [190.0, 0.2, "ok"]
    assert table.rows[2][table.columns.index("m1_kg")] == pytest.approx(0.12)
    assert table.rows[2][table.columns.index("total_kg")] == pytest.approx(0.17)
    assert table.rows[2][table.columns.index("error_after_%")] == pytest.approx(3.0)
    assert table.rows[1][table.columns.index("m1_kg")] is None
    assert main(["batch", "report", str(path), "--no-plots",
                 "--table", str(tmp_path / "cases.csv")]) == 0
    text = capsys.readouterr().out
    assert "targets.0.freq_hz" in text and "AssignmentInfeasible" in text
    with open(tmp_path / "cases.csv") as fh:
        got = list(csv.DictReader(fh))
    assert len(got) == 3 and got[0]["constraints.mass_budget_kg"] == "0.2"
    assert got[1]["m1_kg"] == "" and got[1]["status"] == "failed"
