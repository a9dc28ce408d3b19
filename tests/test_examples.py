"""Each example runs and computes the number that docs/examples.md quotes for it.

The examples compute when imported (scikit-fem style) and print under ``__main__``; each test
imports one, checks what it computes against an independent reference where there is one, and
asserts that the documentation quotes the value it computes. The slow examples are marked
``slow`` (run by ``.ci/run``).
"""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from reference_fe import planar_two_link_frequencies

import pinflex

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
PAGE = ROOT / "docs" / "examples.md"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _section(name: str) -> str:
    """The part of the examples page about ``name`` (a file of examples/)."""
    text = PAGE.read_text()
    start = text.index(f"## `{name}`")
    end = text.find("\n## ", start + 4)
    return " ".join(text[start: end if end > 0 else None].replace("*", "").split())


def test_every_example_has_its_section_and_a_test():
    """Every script and study of examples/ is on the page and tested here."""
    text = PAGE.read_text()
    tests = Path(__file__).read_text()
    for path in sorted(EXAMPLES.rglob("*")):
        name = path.relative_to(EXAMPLES).as_posix()
        if path.suffix in (".py", ".toml"):
            assert f"## `{name}`" in text, name
        if path.suffix == ".py":
            assert f'_load("{path.stem}")' in tests, name
        if path.suffix == ".toml":
            assert f'"{name}"' in tests, name


def test_ur5_example_heavier_payload_lowers_mode_1():
    """The UR5 example's first mode drops with a heavier payload and its shapes are normalised."""
    ex = _load("ur5_flexible_modes")
    assert ex.heavier < ex.result.freq_hz[0]
    M, _ = ex.arm.matrices(ex.q)
    np.testing.assert_allclose(ex.result.shapes.T @ M @ ex.result.shapes, np.eye(6), atol=1e-9)
    page = _section("ur5_flexible_modes.py")
    assert f"mode 1: {ex.result.freq_hz[0]:.3f} Hz" in page
    assert f"{ex.heavier:.3f} Hz with 2 kg" in page
    assert f"{ex.arm.ndof} dof" in page


def test_benchmark_a_taylor_example_meets_the_paper():
    """The Taylor example's error along the trajectory is below the paper's 0.09 %."""
    ex = _load("benchmark_a_taylor")
    assert ex.max_error < 0.0009  # paper 000: 0.09 % at p = 4
    assert f"max error {100 * ex.max_error:.3f} %" in _section("benchmark_a_taylor.py")
    # the example's exact frequencies agree with the independent global FE at the worst sample
    worst = int(np.argmax(np.abs(ex.poly_hz / ex.exact_hz - 1)))
    _, fe_hz = planar_two_link_frequencies(ex.traj.q[worst], 0.0, 0.0)
    assert ex.exact_hz[worst] == pytest.approx(fe_hz[0], rel=1e-9)
    # and the error is the truncation error: one order more shrinks it
    p5 = pinflex.expand(ex.arm, [1.817, 5.312], order=5, modes=(1,))
    p5_hz = p5.evaluate(ex.traj.q, [0.0, 0.0], quantity="freq_hz")[:, 0]
    assert np.max(np.abs(p5_hz / ex.exact_hz - 1)) < 0.5 * ex.max_error


def test_benchmark_a_tubes_example_finds_the_exact_optimum():
    """The tube sizing meets its floor on the exact model and matches SLSQP's least mass."""
    ex = _load("benchmark_a_tubes")
    ours, ref = ex.summary["pinflex"], ex.summary["scipy_slsqp_exact"]
    # the floor holds on the exact model, along the whole motion
    f = ex.arm.frequencies(ex.traj.q, np.array([ours["design"][n] for n in ex.arm.design_names]),
                           n_modes=1)[:, 0]
    assert f.min() >= ex.floor - 1e-6
    assert ours["margin_hz"] == pytest.approx(f.min() - ex.floor, abs=1e-6)
    # the same least mass as an optimiser on the exact model, to 0.1 %
    assert ours["mass_kg"] == pytest.approx(ref["mass_kg"], rel=1e-3)
    d = {k: 1e3 * v for k, v in ours["design"].items()}
    page = _section("benchmark_a_tubes.py")
    assert (f"D1 = {d['D1']:.2f} mm, t1 = {d['t1']:.2f} mm, D2 = {d['D2']:.2f} mm, "
            f"t2 = {d['t2']:.2f} mm, link mass {ex.mass_orig:.4f} → {ours['mass_kg']:.4f} kg"
            ) in page
    assert f"(floor {ex.floor:.2f} Hz)" in page


@pytest.mark.slow
def test_ur5_tubes_example_matches_the_exact_optimisers():
    """The UR5 tube sizing meets 70 Hz on the exact model with SLSQP's mass, below the grid's."""
    ex = _load("ur5_tubes")
    ours = ex.summary["pinflex"]
    x = np.array([ours["design"][n] for n in ex.DESIGN])
    assert ex.mode1(x).min() >= ex.FLOOR_HZ - 1e-6
    assert ours["mass_kg"] == pytest.approx(ex.summary["scipy_slsqp_exact"]["mass_kg"], rel=1e-3)
    grid = ex.summary["exact_grid_9x9"]
    assert grid is not None and ours["mass_kg"] <= grid["mass_kg"]
    page = _section("ur5_tubes.py")
    assert (f"D_upper = {1e3 * x[0]:.2f} mm, D_fore = {1e3 * x[1]:.2f} mm, "
            f"{ours['mass_kg']:.4f} kg") in page
    assert f"SLSQP: {ex.summary['scipy_slsqp_exact']['mass_kg']:.4f} kg" in page
    assert f"grid's best: {grid['mass_kg']:.4f} kg" in page


def test_benchmark_a_study_assigns_what_the_page_says(tmp_path):
    """The study file reproduces the assignment the examples page quotes."""
    from pinflex.assignment.study import load_config, run_config

    cfg = load_config(EXAMPLES / "benchmark_a.toml")  # "benchmark_a.toml"
    _, _, result = run_config(cfg)
    m1, m2 = result.y
    page = _section("benchmark_a.toml")
    assert f"m1 = {m1:.3f} kg" in page and abs(m2) < 1e-9
    before, after = 100 * result.max_error_before, 100 * result.max_error_after
    assert f"{before:.2f} % → {after:.2f} %" in page


def _cli_json(argv: list[str], capsys) -> dict:
    import json
    import warnings

    from pinflex.cli import main

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        code = main(argv + ["--json"])
    out = capsys.readouterr().out
    assert code == 0, out[-2000:]
    return json.loads(out)


@pytest.mark.slow
def test_kinova_assignment_study_meets_its_target_on_the_exact_model(capsys):
    """The Kinova tube assignment is confirmed on the exact model with the quoted errors."""
    name = "real_arms/kinova_assign.toml"
    out = _cli_json(["assign", str(EXAMPLES / name)], capsys)
    assert out["status"] == "met" and out["improved"]
    before, after = 100 * out["max_error_before"], 100 * out["max_error_after"]
    assert f"{before:.2f} % → {after:.2f} %" in _section(name)


@pytest.mark.slow
def test_kinova_sizing_study_holds_its_floor_with_the_quoted_mass(capsys):
    """The Kinova tube sizing keeps mode 1 at 40 Hz on the exact model with the quoted mass."""
    name = "real_arms/kinova_size.toml"
    out = _cli_json(["size", str(EXAMPLES / name)], capsys)
    page = _section(name)
    assert out["status"] == "met" and out["margin_hz"] >= 0.0
    assert f"design mass {out['mass_start_kg']:.4f} kg → {out['mass_kg']:.4f} kg" in page
    start, end = out["min_freq_start_hz"][0], out["min_freq_hz"][0]
    assert f"{start:.2f} Hz to {end:.2f} Hz" in page
