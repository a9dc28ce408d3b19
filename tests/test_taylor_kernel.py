"""The compiled two-joint evaluation against the NumPy path it replaces, and where it is used.

References: the NumPy ``PowerGrid`` evaluation (run directly), ``jets.evaluate`` (the
coefficient sum Σ c_α δx^α) and the per-sample radius estimate's decisions.
"""

import subprocess
import sys
import warnings

import numpy as np
import pytest
from conftest import TWO_LINK

from pinflex import jets
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError, TaylorRadiusExceeded, TaylorRadiusWarning
from pinflex.parametric import evaluation as taylor
from pinflex.parametric import expand

numba = pytest.importorskip("numba")

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(TWO_LINK, planar=True)


def _numpy_grid(tm, Q, quantity, linear, checked):
    grid = tm._evaluation_plan.grid
    run, _ = grid.new_scratch(Q.shape[0], checked, keep=False)
    return run(np.asarray(Q, dtype=float).T, grid.values[quantity, linear])


def _warned(tm, Q, **kw):
    with warnings.catch_warnings(record=True) as rec:
        warnings.simplefilter("always")
        tm.evaluate(Q, **kw)
    return any(issubclass(r.category, TaylorRadiusWarning) for r in rec)


@pytest.mark.parametrize("order,modes", [(2, (1,)), (4, (1,)), (4, (1, 2, 3)), (7, (2,))])
def test_kernel_equals_the_numpy_grid_path(arm, order, modes):
    """Values to 1e-14 and τ² of the first screen equal the NumPy path's, any sample layout."""
    tm = expand(arm, Q0, order=order, modes=modes, design=[])
    grid = tm._evaluation_plan.grid
    kernel = taylor._grid_kernel()
    assert grid is not None and kernel is not None
    rng = np.random.default_rng(order + 10 * len(modes))
    Q = Q0 + 0.5 * rng.uniform(-1, 1, size=(41, 2))
    for quantity in ("eigval", "freq_hz"):
        ref = jets.evaluate(tm.space, tm.jet(quantity), tm.offsets(Q, warn=False))
        for samples in (np.ascontiguousarray(Q), np.asfortranarray(Q), Q[::2], Q[:1]):
            for linear in (False, True):
                coef = grid.values[quantity, linear]
                value, t2 = kernel(samples, grid.q0, coef, grid.form, grid.k, True)
                nvalue, nt2 = _numpy_grid(tm, samples, quantity, linear, True)
                np.testing.assert_allclose(value, nvalue, rtol=1e-14, atol=0)
                assert t2 == pytest.approx(nt2, rel=1e-14, abs=0)
                got = tm.evaluate(samples, quantity=quantity, linear_in_design=linear,
                                  warn=False)
                assert got.shape == (samples.shape[0], len(modes))
                np.testing.assert_allclose(got, nvalue, rtol=1e-14, atol=0)
                np.testing.assert_allclose(got, ref[: samples.shape[0]] if samples.shape[0] == 1
                                           else ref[::2] if samples.shape[0] == 21 else ref,
                                           rtol=1e-13, atol=0)


def test_kernel_decisions_equal_the_per_sample_estimate(arm):
    """Warn and strict decide as the per-sample estimate at tolerances straddling the worst."""
    assert taylor.prepare_kernel()  # the decisions below are the kernel's
    tm = expand(arm, Q0, order=4, modes=(1, 2), design=[])
    rng = np.random.default_rng(3)
    for scale in (0.05, 0.3, 1.0):
        Q = Q0 + scale * rng.uniform(-1, 1, size=(40, 2))
        est, _ = tm.error_estimate(tm.offsets(Q, warn=False), quantity="freq_hz")
        worst = float(np.max(est))
        for tol in (worst * 0.999, worst * 1.001, 1e-2):
            assert _warned(tm, Q, quantity="freq_hz", tol=tol) == (worst > tol)
            if worst > tol:
                with pytest.raises(TaylorRadiusExceeded):
                    tm.evaluate(Q, quantity="freq_hz", strict=True, tol=tol)
            else:
                got = tm.evaluate(Q, quantity="freq_hz", strict=True, tol=tol)
                ref = jets.evaluate(tm.space, tm.jet("freq_hz"), tm.offsets(Q, warn=False))
                np.testing.assert_allclose(got, ref, rtol=1e-13, atol=0)


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_kernel_screen_never_passes_a_non_finite_sample(arm, bad):
    """τ² is NaN when one offset is not finite; the checked call then refuses the sample."""
    tm = expand(arm, Q0, order=4, modes=(1,), design=[])
    grid = tm._evaluation_plan.grid
    Q = np.tile(Q0, (9, 1)) + 0.01
    Q[4, 1] = bad
    _, t2 = taylor._grid_kernel()(Q, grid.q0, grid.values["freq_hz", False], grid.form,
                                  grid.k, True)
    assert np.isnan(t2)
    with pytest.raises(ConfigurationError, match="sample 4"):
        tm.evaluate(Q, quantity="freq_hz", tol=np.inf)


@pytest.mark.parametrize("case", ["one joint", "design values given", "with design"])
def test_other_models_keep_the_numpy_path(arm, case):
    """Only two-joint models without design get the kernel; the others keep the NumPy path.

    They evaluate by the monomial rows and equal the coefficient sum (three-joint arms: see
    ``test_solver_route_further_arms.py``).
    """
    if case == "one joint":
        tm = expand(arm, Q0, order=4, modes=(1,), joints=["q2"], design=[])
        Q = Q0 + 0.2 * np.random.default_rng(1).uniform(-1, 1, size=(17, 2))
        Q[:, 0] = Q0[0]
        Y = None
    elif case == "design values given":
        tm = expand(arm, Q0, order=3, modes=(1, 2))
        Q = Q0 + 0.2 * np.random.default_rng(2).uniform(-1, 1, size=(17, 2))
        Y = 0.1 + 0.05 * np.random.default_rng(4).uniform(-1, 1, size=(17, tm.y0.size))
    else:
        tm = expand(arm, Q0, order=4, modes=(1, 2))
        Q = Q0 + 0.2 * np.random.default_rng(3).uniform(-1, 1, size=(17, 2))
        Y = None
    assert tm._evaluation_plan.grid is None
    got = tm.evaluate(Q, Y, quantity="freq_hz", warn=False)
    ref = jets.evaluate(tm.space, tm.jet("freq_hz"), tm.offsets(Q, Y, warn=False))
    np.testing.assert_allclose(got, ref, rtol=1e-13, atol=0)


def test_numba_is_loaded_only_by_many_two_joint_evaluations():
    """A few two-joint evaluations do not load numba; many prepare the kernel in the background.

    After ``KERNEL_AFTER`` evaluations the kernel is prepared in a thread and later calls take
    it, with the values of the NumPy path.
    """
    code = (f"import sys, threading, numpy as np\nfrom pinflex.erls import FlexibleModel\n"
            f"from pinflex.parametric import expand, evaluation as model\n"
            f"a = FlexibleModel({str(TWO_LINK)!r}, planar=True)\n"
            f"tm = expand(a, np.array({Q0.tolist()}), order=2, design=[])\n"
            f"Q = np.array([{Q0.tolist()}])\n"
            "print('numba' in sys.modules)\n"
            "for _ in range(model.KERNEL_AFTER - 1): v = tm.evaluate(Q, warn=False)\n"
            "print('numba' in sys.modules, bool(model._KERNEL))\n"
            "w = tm.evaluate(Q, warn=False)\n"
            "[t.join() for t in threading.enumerate() if t.name == 'pinflex-taylor-kernel']\n"
            "print('numba' in sys.modules, model._KERNEL[0] is not None)\n"
            "print(np.array_equal(tm.evaluate(Q, warn=False), w))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "False", "False", "True", "True", "True"]


def test_without_numba_the_numpy_path_gives_the_same_values_and_decisions(arm, monkeypatch):
    """The fallback (kernel unavailable) equals the kernel's values and warns alike."""
    assert taylor.prepare_kernel()
    tm = expand(arm, Q0, order=4, modes=(1, 2), design=[])
    rng = np.random.default_rng(8)
    Q = Q0 + 0.3 * rng.uniform(-1, 1, size=(29, 2))
    with_kernel = tm.evaluate(Q, quantity="freq_hz", warn=False)
    est, _ = tm.error_estimate(tm.offsets(Q, warn=False), quantity="freq_hz")
    worst = float(np.max(est))
    decided = [_warned(tm, Q, quantity="freq_hz", tol=t) for t in (worst * 0.999, worst * 1.001)]
    monkeypatch.setattr(taylor, "_KERNEL", [None])
    np.testing.assert_allclose(tm.evaluate(Q, quantity="freq_hz", warn=False), with_kernel,
                               rtol=1e-14, atol=0)
    assert [_warned(tm, Q, quantity="freq_hz", tol=t)
            for t in (worst * 0.999, worst * 1.001)] == decided == [True, False]
