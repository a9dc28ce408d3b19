"""Each example runs and computes what it says."""

import importlib.util
from pathlib import Path

import numpy as np
import pytest

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
    assert ex.max_error < 0.0009
    assert ex.max_error == pytest.approx(0.00077, abs=0.0001)
