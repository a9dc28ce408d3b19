"""Each example runs and computes what it says."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest
from reference_fe import planar_two_link_frequencies

import pinflex

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def _load(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_ur5_example_heavier_payload_lowers_mode_1():
    """The UR5 example's first mode drops with a heavier payload and its shapes are normalised."""
    ex = _load("ur5_flexible_modes")
    assert ex.heavier < ex.result.freq_hz[0]
    M, _ = ex.arm.matrices(ex.q)
    np.testing.assert_allclose(ex.result.shapes.T @ M @ ex.result.shapes, np.eye(6), atol=1e-9)


def test_benchmark_a_taylor_example_meets_the_paper():
    """The Taylor example's error along the trajectory is below the paper's 0.09 %."""
    ex = _load("benchmark_a_taylor")
    assert ex.max_error < 0.0009  # paper 000: 0.09 % at p = 4
    # the example's exact frequencies agree with the independent global FE at the worst sample
    worst = int(np.argmax(np.abs(ex.poly_hz / ex.exact_hz - 1)))
    _, fe_hz = planar_two_link_frequencies(ex.traj.q[worst], 0.0, 0.0)
    assert ex.exact_hz[worst] == pytest.approx(fe_hz[0], rel=1e-9)
    # and the error is the truncation error: one order more shrinks it
    p5 = pinflex.expand(ex.arm, [1.817, 5.312], order=5, modes=(1,))
    p5_hz = p5.evaluate(ex.traj.q, [0.0, 0.0], quantity="freq_hz")[:, 0]
    assert np.max(np.abs(p5_hz / ex.exact_hz - 1)) < 0.5 * ex.max_error
