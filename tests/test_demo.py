"""``pinflex demo`` end to end, in an empty folder, against independent recomputations."""

import contextlib
import io
import json
import os

import numpy as np
import pytest

from pinflex.cases.benchmark_a import (
    TARGET_HZ,
    benchmark_model,
    benchmark_trajectory,
    design_grid,
)
from pinflex.cli import main
from pinflex.cli.demo import SECTIONS


@pytest.fixture(scope="module")
def arm():
    """Benchmark A's arm and trajectory."""
    model = benchmark_model()
    return model, benchmark_trajectory(model)


@pytest.fixture(scope="module")
def demo(tmp_path_factory):
    """One ``pinflex demo --json --no-brute-force`` run in an empty folder: (folder, JSON)."""
    folder = tmp_path_factory.mktemp("empty")
    stdout, here = io.StringIO(), os.getcwd()
    os.chdir(folder)
    try:
        with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(io.StringIO()):
            assert main(["demo", "--json", "--no-brute-force"]) == 0
    finally:
        os.chdir(here)
    return folder, json.loads(stdout.getvalue())


def test_demo_writes_its_outputs_and_reports_exact_errors(demo, arm):
    """The demo's JSON errors equal the exact model's errors of the design it reports."""
    folder, data = demo
    out = folder / "pinflex-demo"
    assert {p.name for p in out.iterdir()} >= {"mode1_assignment.png", "preview.html"}
    assert (out / "mode1_assignment.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    model, traj = arm
    y = np.array([data["design"]["m1"], data["design"]["m2"]])
    f_after = model.frequencies(traj.q, y, n_modes=1)[:, 0]
    f_before = model.frequencies(traj.q, np.zeros(2), n_modes=1)[:, 0]
    assert data["max_error_after"] == pytest.approx(np.max(np.abs(f_after / TARGET_HZ - 1)),
                                                    rel=1e-9)
    assert data["max_error_before"] == pytest.approx(
        np.max(np.abs(f_before / TARGET_HZ - 1)), rel=1e-9)
    assert data["max_error_after"] < data["max_error_before"]
    assert "brute_force" not in data and data["ndof"] == model.ndof == 23


def test_demo_taylor_errors_match_a_direct_evaluation(demo, arm):
    """The demo's Taylor error over the design grid bounds one recomputed pose by pose."""
    from pinflex.parametric import expand

    errs = demo[1]["taylor_errors_percent"]
    model, _ = arm
    Y = design_grid()
    Q = np.tile([1.817, 5.312], (len(Y), 1))
    exact = np.array([model.modes(q, y, n_modes=1).freq_hz[0] for q, y in zip(Q[::97], Y[::97])])
    tm = expand(model, [1.817, 5.312], model.y0, order=4)
    approx = tm.evaluate(Q[::97], Y[::97], quantity="freq_hz", warn=False)[:, 0]
    assert errs["taylor_y_full"] >= 100 * np.max(np.abs(approx / exact - 1)) - 1e-9
    assert 0.0 < errs["taylor_y_full"] < errs["taylor_y_lin"] < 2.0


def test_demo_sections_are_a_list_of_functions():
    """A new demo section is one function in SECTIONS (modes, Taylor, assignment, outputs)."""
    assert [s.__name__ for s in SECTIONS] == ["modes_section", "taylor_section",
                                               "assignment_section", "outputs_section",
                                               "vibration_section"]
