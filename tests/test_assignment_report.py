"""Assignment outputs as data: per-sample frequencies, active constraints, files."""

from __future__ import annotations

import csv
import json
import warnings

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex.assignment import Target, assign_frequencies
from pinflex.assignment.charts import assignment_charts
from pinflex.assignment.report import assignment_data
from pinflex.assignment.study import user_trajectory
from pinflex.erls import FlexibleModel

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def setup():
    """Benchmark A (planar) and its trajectory."""
    model = FlexibleModel(TWO_LINK, planar=True)
    return model, user_trajectory(model, "benchmark_a")


def _solve(model, traj, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0,
                                  y_before=np.zeros(2), report_modes=(2, 3), **kw)


def test_frequencies_per_sample_and_mode(setup, tmp_path):
    """Exact columns = a fresh exact solve; predicted = the Taylor polynomial's own evaluate."""
    model, traj = setup
    res = _solve(model, traj)
    data = assignment_data(model, traj, res)
    assert data.modes == (1, 2, 3) and data.roles == ("target", "report", "report")
    # (the assignment verifies with tracked eigenpairs: same numbers to solver round-off)
    np.testing.assert_allclose(data.after_hz, model.frequencies(traj.q, res.y)[:, :3],
                               rtol=1e-9)
    np.testing.assert_allclose(data.before_hz, model.frequencies(traj.q, np.zeros(2))[:, :3],
                               rtol=1e-9)
    pred = res.taylor.evaluate(traj.q, res.y, quantity="freq_hz", linear_in_design=True,
                               warn=False)
    np.testing.assert_allclose(data.predicted_hz[:, 0], pred[:, res.taylor.modes.index(1)],
                               rtol=1e-12)
    assert np.all(np.isnan(data.predicted_hz[:, 1:]))  # modes 2, 3 were not expanded
    np.testing.assert_allclose(data.target_hz[:, 0], 190.0)
    # files
    rows = list(csv.DictReader(open(data.to_csv(tmp_path / "a.csv"))))
    assert len(rows) == traj.n_samples * 3
    assert float(rows[3]["after_hz"]) == pytest.approx(data.after_hz[1, 0], rel=1e-15)
    js = json.loads(data.to_json(tmp_path / "a.json").read_text())
    assert js["modes"][0]["after_hz"][5] == pytest.approx(data.after_hz[5, 0], rel=1e-15)
    assert js["modes"][1]["predicted_hz"][0] is None
    charts = assignment_charts(res, traj.times_s, tmp_path / "charts", data)
    assert [p.name for p in charts] == ["mode1_assignment.png", "other_modes.png"]


def test_active_budget_floor_and_bounds(setup):
    """A tight budget and a binding floor are named active; loose ones are not."""
    model, traj = setup
    free = assignment_data(model, traj, _solve(model, traj))
    assert not [c for c in free.constraints if c["kind"] == "budget"]
    total = sum(free.design_after.values())
    tight = _solve(model, traj, mass_budget_kg=0.5 * total)
    data = assignment_data(model, traj, tight)
    budget = [c for c in data.constraints if c["kind"] == "budget"][0]
    assert budget["active"] and abs(sum(tight.design.values()) - 0.5 * total) < 1e-7
    assert "mass budget" in data.active
    loose = assignment_data(model, traj, _solve(model, traj, mass_budget_kg=2.0 * total))
    assert not [c for c in loose.constraints if c["kind"] == "budget"][0]["active"]
    # a floor on mode 1 above the unconstrained prediction's minimum binds
    fmin = float(np.nanmin(free.predicted_hz[:, 0]))
    floored = _solve(model, traj, floors=[(1, fmin + 1.0)])
    fd = assignment_data(model, traj, floored)
    floor = [c for c in fd.constraints if c["kind"] == "floor"][0]
    assert floor["active"], floor
    assert np.nanmin(fd.predicted_hz[:, 0]) == pytest.approx(fmin + 1.0, rel=1e-7)
    assert floor["exact_slack"] == pytest.approx(float(np.min(fd.after_hz[:, 0]) - fmin - 1.0))
    # bounds: every design variable at 0 or 0.25 kg is named
    for c in fd.constraints:
        if c["kind"] in ("lower_bound", "upper_bound"):
            assert c["active"] == (abs(c["slack"]) < 1e-6 * 0.25)


def test_progress_of_the_stages(setup, capsys):
    """progress=True draws the stage bar on stderr and ends it at 4/4 (no refinement)."""
    model, traj = setup
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assign_frequencies(model, traj, [Target(1, 190.0)], q0=Q0, progress=True)
    err = capsys.readouterr().err
    assert "assignment stages" in err and "4/4" in err and "100%" in err


def test_parquet_needs_pyarrow_or_round_trips(setup, tmp_path):
    """Parquet: the same rows as the CSV when pyarrow is there, a named error when not."""
    from pinflex.exceptions import MissingDependency

    model, traj = setup
    data = assignment_data(model, traj, _solve(model, traj))
    try:
        import pyarrow.parquet as pq
    except ImportError:
        with pytest.raises(MissingDependency, match="pip install pyarrow"):
            data.to_parquet(tmp_path / "a.parquet")
        return
    table = pq.read_table(data.to_parquet(tmp_path / "a.parquet"))
    assert table.num_rows == traj.n_samples * len(data.modes)
    np.testing.assert_allclose(table.column("after_hz").to_numpy()[::3], data.after_hz[:, 0])
