"""Tests of pinflex/batch/sweep.py: --sweep parsing and assignment cases."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from pinflex.batch.sweep import (
    apply_overrides,
    parse_sweeps,
    plan_cases,
    run_assign_case,
    split_values,
    sweep_cases,
)
from pinflex.exceptions import InvalidSweep

STUDY = Path(__file__).resolve().parents[1] / "examples" / "benchmark_a.toml"


def test_values_split_on_top_level_commas_only():
    """Commas inside brackets or quotes do not split values."""
    assert split_values("185,190, 195") == ["185", "190", "195"]
    assert split_values("[1.8,5.3],[1.9,5.2]") == ["[1.8,5.3]", "[1.9,5.2]"]
    assert split_values('"a,b",c') == ['"a,b"', "c"]


def test_sweeps_parse_toml_literals_and_form_a_product():
    """Values are TOML literals (bare strings otherwise); sweeps combine, first one slowest."""
    sweeps = parse_sweeps(["targets.0.freq_hz=185,190", "expansion.q0=[1.8,5.3],[1.9,5.2]",
                           "trajectory.csv=a.csv"])
    assert sweeps[0] == ("targets.0.freq_hz", [185, 190])
    assert sweeps[1] == ("expansion.q0", [[1.8, 5.3], [1.9, 5.2]])
    assert sweeps[2] == ("trajectory.csv", ["a.csv"])
    cases = sweep_cases(sweeps)
    assert len(cases) == 4
    assert [c["targets.0.freq_hz"] for c in cases] == [185, 185, 190, 190]
    assert sweep_cases([]) == [{}]


@pytest.mark.parametrize("option, message", [
    ("targets.0.freq_hz", "expected KEY=V1,V2"),
    ("constraints.mass_kg=0.1", "not sweepable"),
    ("targets.x.freq_hz=1", "not sweepable"),
    ("expansion.order=2,,4", "empty value"),
])
def test_bad_sweeps_name_the_fix(option, message):
    """Malformed or unknown sweep options raise InvalidSweep."""
    with pytest.raises(InvalidSweep, match=message):
        parse_sweeps([option])


def test_overrides_change_a_copy_of_the_study():
    """Overrides reach the right fields and leave the loaded study untouched."""
    from pinflex.assignment.study import load_config

    base = load_config(STUDY)
    cfg = apply_overrides(base, {"targets.0.freq_hz": 185, "constraints.mass_budget_kg": 0.2,
                                 "expansion.order": 2, "expansion.y0.m1": 0.05})
    assert cfg.targets[0].freq_hz == 185.0 and cfg.targets[0].mode == 1
    assert cfg.mass_budget_kg == 0.2 and cfg.order == 2 and cfg.y0["m1"] == 0.05
    assert base.targets[0].freq_hz == 190.0 and base.mass_budget_kg is None
    assert base.order == 4 and base.y0["m1"] == 0.125
    with pytest.raises(InvalidSweep, match="has 1 entries"):
        apply_overrides(base, {"targets.3.freq_hz": 185})


def test_case_hashes_follow_overrides_and_the_study_text(tmp_path):
    """Equal cases share a hash; another value or an edited study file changes it."""
    sweeps = parse_sweeps(["targets.0.freq_hz=185,190"])
    a = [h for h, *_ in plan_cases(STUDY, sweeps)]
    assert a == [h for h, *_ in plan_cases(STUDY, sweeps)] and a[0] != a[1]
    edited = tmp_path / "study.toml"
    edited.write_text(STUDY.read_text() + "\n# edited\n")
    b = [h for h, *_ in plan_cases(edited, sweeps)]
    assert set(a).isdisjoint(b)


def test_benchmark_a_case_reproduces_the_paper():
    """The 190 Hz case gives the paper's 8.31 % error before and about 1.5 % after."""
    ((chash, _, cfg, overrides),) = plan_cases(STUDY, parse_sweeps(["targets.0.freq_hz=190"]))
    (row,) = run_assign_case(cfg, overrides, chash, 0)
    assert row["status"] == "ok", row["error"]
    # the row's errors are the exact model's, recomputed here directly from its design
    from pinflex.cases.benchmark_a import benchmark_model, benchmark_trajectory

    model = benchmark_model()
    q = benchmark_trajectory(model).q
    y = np.array([row["result"]["design"]["m1"], row["result"]["design"]["m2"]])
    before = np.max(np.abs(model.frequencies(q, np.zeros(2), n_modes=1)[:, 0] / 190.0 - 1))
    after = np.max(np.abs(model.frequencies(q, y, n_modes=1)[:, 0] / 190.0 - 1))
    assert row["metrics"]["error_before"] == pytest.approx(before, rel=1e-9)
    assert row["metrics"]["error_after"] == pytest.approx(after, rel=1e-9)
    assert row["metrics"]["error_before"] == pytest.approx(0.0831, abs=5e-4)  # paper: 8.31 %
    assert after < 0.02
    assert row["result"]["design"]["m2"] == pytest.approx(0.0, abs=1e-6)
    assert row["result"]["design"]["m1"] == pytest.approx(0.2254, abs=0.02)


def test_budget_holds_and_an_infeasible_case_is_recorded():
    """A mass budget caps the design; a negative budget is a failed row, not an exception."""
    cases = plan_cases(STUDY, parse_sweeps(["constraints.mass_budget_kg=0.1,-0.1"]))
    rows = [run_assign_case(cfg, ov, h, i)[0] for i, (h, _, cfg, ov) in enumerate(cases)]
    ((h0, _, cfg0, ov0),) = plan_cases(STUDY, [])
    (free,) = run_assign_case(cfg0, ov0, h0, 2)
    assert free["status"] == "ok" and sum(free["result"]["y"]) > 0.1  # the budget must bind
    assert rows[0]["status"] == "ok"
    assert sum(rows[0]["result"]["y"]) <= 0.1 + 1e-9
    # capping the mass below the unconstrained optimum can only cost accuracy
    assert rows[0]["metrics"]["error_after"] > free["metrics"]["error_after"]
    assert np.isclose(sum(rows[0]["result"]["y"]), 0.1, atol=1e-6)  # the budget is active
    assert rows[1]["status"] == "failed"
    assert rows[1]["error"].startswith("assign: AssignmentInfeasible:")
    assert rows[1]["params"] == {"case": 1, "overrides": {"constraints.mass_budget_kg": -0.1}}


def test_cases_sharing_an_expansion_equal_cases_run_alone():
    """3 targets x 2 budgets: one group; every row equals the case solved on its own."""
    from pinflex.batch.sweep import expansion_key, run_assign_group

    sweeps = parse_sweeps(["targets.0.freq_hz=185,190,195",
                           "constraints.mass_budget_kg=0.15,-0.1"])
    cases = plan_cases(STUDY, sweeps)
    assert len({expansion_key(cfg) for _, _, cfg, _ in cases}) == 1
    other = plan_cases(STUDY, parse_sweeps(["expansion.order=2,4"]))
    assert len({expansion_key(cfg) for _, _, cfg, _ in other}) == 2
    items = [(cfg, ov, h, i) for i, (h, _, cfg, ov) in enumerate(cases)]
    shared = run_assign_group(items)
    assert [r["config_hash"] for r in shared] == [h for h, *_ in cases]
    for (cfg, ov, h, i), row in zip(items, shared):
        (alone,) = run_assign_case(cfg, ov, h, i)
        assert row["status"] == alone["status"]
        if alone["status"] == "ok":
            np.testing.assert_allclose(row["result"]["y"], alone["result"]["y"], atol=1e-9)
            assert row["metrics"]["error_after"] == pytest.approx(
                alone["metrics"]["error_after"], rel=1e-9)
            assert row["metrics"]["error_before"] == pytest.approx(
                alone["metrics"]["error_before"], rel=1e-12)
            assert row["timings"]["shared_by"] == 6.0
        else:
            assert row["error"] == alone["error"]
    assert sum(r["status"] == "failed" for r in shared) == 3  # the negative budgets
