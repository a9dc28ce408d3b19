"""Tests of pinflex.jets: truncated multivariate Taylor arithmetic."""

from __future__ import annotations

import math
from itertools import product

import numpy as np
import pytest

from pinflex import jets as J


def _dsin(k: int, x: float) -> float:
    """k-th derivative of sin at x."""
    return (math.sin(x), math.cos(x), -math.sin(x), -math.cos(x))[k % 4]


def _dcos(k: int, x: float) -> float:
    """k-th derivative of cos at x."""
    return (math.cos(x), -math.sin(x), -math.cos(x), math.sin(x))[k % 4]


def _sin_cos(space, x0):
    """Jets of sin and cos of every variable."""
    return [J.sin_cos_of_variable(space, k, x) for k, x in enumerate(x0)]


def test_multi_index_layout():
    """Multi-indices are graded, descending-lexicographic within a degree, indexed both ways."""
    space = J.JetSpace(3, 4)
    mi = space.multi_indices
    assert space.ncoef == math.comb(3 + 4, 4) == mi.shape[0]
    assert np.all(np.diff(mi.sum(axis=1)) >= 0)
    for d in range(space.order + 1):
        block = [tuple(r) for r in mi[space.degree_slice(d)].tolist()]
        assert block == sorted(block, reverse=True)
        assert len(block) == math.comb(d + 2, 2)
    for c, alpha in enumerate(mi.tolist()):
        assert space.index[tuple(alpha)] == c == space.position(alpha)
        assert space.factorials[c] == math.prod(math.factorial(a) for a in alpha)
    two = [[0, 0], [1, 0], [0, 1], [2, 0], [1, 1], [0, 2]]
    assert J.JetSpace(2, 2).multi_indices.tolist() == two
    assert J.JetSpace(3, 4) == space and hash(J.JetSpace(3, 4)) == hash(space)


def test_product_of_sines_matches_closed_form():
    """Jet products give sin(x+y)·cos(x) = ½[sin(2x+y) + sin(y)] coefficient by coefficient."""
    space = J.JetSpace(2, 7)
    x0, y0 = 0.37, -1.1
    (sx, cx), (sy, cy) = _sin_cos(space, (x0, y0))
    sin_sum = J.mul(space, sx, cy) + J.mul(space, cx, sy)
    f = J.mul(space, sin_sum, cx)
    for c, (i, j) in enumerate(space.multi_indices.tolist()):
        ref = 0.5 * 2**i * _dsin(i + j, 2 * x0 + y0) / (math.factorial(i) * math.factorial(j))
        if i == 0:
            ref += 0.5 * _dsin(j, y0) / math.factorial(j)
        assert f[c] == pytest.approx(ref, abs=1e-14)


def test_pythagorean_identity_holds_to_every_order():
    """sin² + cos² of a sum of variables is the constant 1 up to the truncation order."""
    space = J.JetSpace(3, 6)
    (s1, c1), (s2, c2), _ = _sin_cos(space, (0.3, 1.2, -0.4))
    s = J.mul(space, s1, c2) + J.mul(space, c1, s2)
    c = J.mul(space, c1, c2) - J.mul(space, s1, s2)
    one = J.mul(space, s, s) + J.mul(space, c, c)
    np.testing.assert_allclose(one, J.constant(space, 1.0), atol=1e-14)


def _g(x):
    """Test function x0² sin(x1) cos(x2) (1 + x0 x1), numpy and complex friendly."""
    return x[0] ** 2 * np.sin(x[1]) * np.cos(x[2]) * (1 + x[0] * x[1])


def _g_jet(space, x0):
    """Jet of _g built from jet arithmetic."""
    v = [J.variable(space, k, x0[k]) for k in range(3)]
    (_, _), (s1, _), (_, c2) = _sin_cos(space, x0)
    one_plus = J.constant(space, 1.0) + J.mul(space, v[0], v[1])
    return J.mul(space, J.mul(space, J.mul(space, v[0], v[0]), J.mul(space, s1, c2)), one_plus)


def test_first_derivatives_match_complex_step():
    """First partial derivatives of a product jet equal complex-step derivatives to round-off."""
    space = J.JetSpace(3, 3)
    x0 = np.array([0.7, -0.3, 0.9])
    jet = _g_jet(space, x0)
    h = 1e-30
    for k in range(3):
        e = np.zeros(3, complex)
        e[k] = 1j * h
        ref = _g(x0 + e).imag / h
        alpha = [int(i == k) for i in range(3)]
        assert J.derivative(space, jet, alpha) == pytest.approx(ref, rel=1e-13)


def test_second_derivatives_match_complex_step_finite_difference():
    """Second partial derivatives equal central differences of complex-step derivatives."""
    space = J.JetSpace(3, 3)
    x0 = np.array([0.7, -0.3, 0.9])
    jet = _g_jet(space, x0)
    h, delta = 1e-30, 1e-4
    for k, m in product(range(3), repeat=2):
        ek = np.zeros(3, complex)
        ek[k] = 1j * h
        em = np.zeros(3)
        em[m] = delta
        ref = (_g(x0 + ek + em).imag - _g(x0 + ek - em).imag) / (2 * h * delta)
        alpha = [int(i == k) + int(i == m) for i in range(3)]
        assert J.derivative(space, jet, alpha) == pytest.approx(ref, rel=1e-7, abs=1e-9)


def test_evaluate_matches_direct_sum():
    """Evaluation and monomials agree with the sum Σ c_α δx^α written out term by term."""
    rng = np.random.default_rng(3)
    space = J.JetSpace(3, 4)
    jet = rng.standard_normal((space.ncoef, 2, 5))
    dx = rng.standard_normal((7, 3)) * 0.3
    ref = np.zeros((7, 2, 5))
    for c, alpha in enumerate(space.multi_indices):
        ref += np.prod(dx**alpha, axis=1)[:, None, None] * jet[c]
    np.testing.assert_allclose(J.evaluate(space, jet, dx), ref, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(J.evaluate(space, jet, dx[2]), ref[2], rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(J.monomials(space, dx)[4], J.monomials(space, dx[4]))


@pytest.mark.parametrize("order", [2, 3, 5])
def test_truncation_error_falls_as_order_plus_one(order):
    """The truncated Taylor polynomial of a trigonometric product has error O(|δx|^{p+1})."""
    space = J.JetSpace(3, order)
    x0 = np.array([0.7, -0.3, 0.9])
    jet = _g_jet(space, x0)
    direction = np.array([0.6, -0.5, 0.8])
    hs = np.array([0.04, 0.02, 0.01])
    errors = [abs(J.evaluate(space, jet, h * direction) - _g(x0 + h * direction)) for h in hs]
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.abs(rates - (order + 1)) < 0.3)


def _rotation_jet(space, angle_jets):
    """2×2 rotation matrix jet from (sin, cos) jets."""
    s, c = angle_jets
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def test_matmul_of_rotations_matches_closed_form():
    """R(θ1) R(θ2) computed by jet matmul equals the closed-form jet of R(θ1 + θ2)."""
    space = J.JetSpace(2, 6)
    t0 = (0.4, 1.3)
    sc = _sin_cos(space, t0)
    prod = J.matmul(space, _rotation_jet(space, sc[0]), _rotation_jet(space, sc[1]))
    s0 = sum(t0)
    for c, (i, j) in enumerate(space.multi_indices.tolist()):
        fac = math.factorial(i) * math.factorial(j)
        cos_c, sin_c = _dcos(i + j, s0) / fac, _dsin(i + j, s0) / fac
        np.testing.assert_allclose(prod[c], [[cos_c, -sin_c], [sin_c, cos_c]], atol=1e-14)


def test_matmul_of_low_degree_polynomials_is_exact():
    """Jets of polynomial matrices whose degrees sum to ≤ p multiply exactly, batched or not."""
    rng = np.random.default_rng(4)
    space = J.JetSpace(3, 4)
    low = space.degree_offsets[3]  # coefficients of degree ≤ 2
    A = np.zeros((space.ncoef, 4, 3))
    B = np.zeros((space.ncoef, 3, 5))
    A[:low] = rng.standard_normal((low, 4, 3))
    B[:low] = rng.standard_normal((low, 3, 5))
    C = J.matmul(space, A, B)
    dx = rng.standard_normal((6, 3))
    ref = J.evaluate(space, A, dx) @ J.evaluate(space, B, dx)
    np.testing.assert_allclose(J.evaluate(space, C, dx), ref, rtol=1e-11, atol=1e-11)
    batched = J.matmul(space, A[:, None], np.stack([B, 2 * B], axis=1))
    np.testing.assert_allclose(batched[:, 0], C, atol=1e-13)
    np.testing.assert_allclose(batched[:, 1], 2 * C, atol=1e-13)
    vec = J.matmul(space, A, B[:, :, 0])
    np.testing.assert_allclose(vec, C[:, :, 0], atol=1e-13)


def test_mul_broadcasts_scalar_jets_over_matrices():
    """A scalar jet times a matrix jet equals the product taken entry by entry."""
    rng = np.random.default_rng(5)
    space = J.JetSpace(2, 3)
    a = rng.standard_normal(space.ncoef)
    B = rng.standard_normal((space.ncoef, 2, 3))
    out = J.mul(space, a, B)
    for i, j in product(range(2), range(3)):
        np.testing.assert_allclose(out[:, i, j], J.mul(space, a, B[:, i, j]), atol=1e-14)


def test_sqrt_matches_binomial_series():
    """The square root of the jet of c + x1 + 2 x2 has the binomial coefficients of √(c + s)."""
    space = J.JetSpace(2, 6)
    c0 = 2.5
    f = J.constant(space, c0) + J.variable(space, 0) + 2 * J.variable(space, 1)
    root = J.sqrt(space, f)
    for c, (i, j) in enumerate(space.multi_indices.tolist()):
        k = i + j
        ref = math.prod(0.5 - m for m in range(k)) / math.factorial(k) * c0 ** (0.5 - k)
        ref *= math.comb(k, i) * 2**j
        assert root[c] == pytest.approx(ref, rel=1e-13, abs=1e-15)
    with pytest.raises(ValueError):
        J.sqrt(space, -f)


def test_truncate_and_restrict_agree_with_direct_construction():
    """Truncating or freezing variables gives the jet built directly in the smaller space."""
    big, small = J.JetSpace(3, 5), J.JetSpace(3, 2)
    x0 = np.array([0.7, -0.3, 0.9])
    np.testing.assert_allclose(J.truncate(big, _g_jet(big, x0), small), _g_jet(small, x0))
    sub, sub_jet = J.restrict(big, _g_jet(big, x0), [2, 0])
    dx = np.array([[0.05, -0.02], [0.01, 0.03]])
    full_dx = np.zeros((2, 3))
    full_dx[:, [2, 0]] = dx
    np.testing.assert_allclose(
        J.evaluate(sub, sub_jet, dx), J.evaluate(big, _g_jet(big, x0), full_dx), atol=1e-15
    )
    with pytest.raises(ValueError):
        J.truncate(small, _g_jet(small, x0), big)


def test_design_split_reconstructs_partial_linearization():
    """l0(q) + Σ_j l_j(q) δy_j equals the jet with |β| ≥ 2 terms dropped, and is linear in δy."""
    rng = np.random.default_rng(6)
    space = J.JetSpace(4, 4)
    jet = rng.standard_normal((space.ncoef, 3))
    design = [3, 1]
    q_space, l0, l1 = J.design_split(space, jet, design)
    assert q_space == J.JetSpace(2, 4) and l1.shape == (2, q_space.ncoef, 3)
    assert np.all(l1[:, q_space.degree_slice(4)] == 0.0)
    lin = J.partially_linear(space, jet, design)
    dx = rng.standard_normal((5, 4)) * 0.2
    mq = J.monomials(q_space, dx[:, [0, 2]])
    recon = mq @ l0 + np.einsum("sc,jcm,sj->sm", mq, l1, dx[:, design])
    np.testing.assert_allclose(recon, J.evaluate(space, lin, dx), atol=1e-13)
    # Exactly linear in δy: the second difference along y vanishes.
    ey = np.zeros(4)
    ey[3] = 0.3
    values = [J.evaluate(space, lin, dx + sign * ey) for sign in (1, 0, -1)]
    second = values[0] - 2 * values[1] + values[2]
    np.testing.assert_allclose(second, 0.0, atol=1e-12)
    kept = J.partially_linear_mask(space, design)
    assert kept.sum() == q_space.ncoef + 2 * int(q_space.degree_offsets[4])


def test_ray_coefficients_match_univariate_series():
    """Coefficients along a ray of sin(x+y)·cos(x) equal the closed-form univariate series."""
    space = J.JetSpace(2, 6)
    x0, y0 = 0.2, 0.5
    (sx, cx), (sy, cy) = _sin_cos(space, (x0, y0))
    f = J.mul(space, J.mul(space, sx, cy) + J.mul(space, cx, sy), cx)
    v = np.array([0.8, -0.3])
    rc = J.ray_coefficients(space, f, v[None])[0]
    for k in range(space.order + 1):
        ref = 0.5 * (2 * v[0] + v[1]) ** k * _dsin(k, 2 * x0 + y0) / math.factorial(k)
        ref += 0.5 * v[1] ** k * _dsin(k, y0) / math.factorial(k)
        assert rc[k] == pytest.approx(ref, abs=1e-14)


def test_invalid_arguments_raise():
    """Wrong shapes, variable indices and multi-indices raise ValueError naming the problem."""
    space = J.JetSpace(2, 3)
    with pytest.raises(ValueError, match="coefficient axis first"):
        J.mul(space, np.zeros(3), np.zeros(space.ncoef))
    with pytest.raises(ValueError, match="variable index"):
        J.variable(space, 2)
    with pytest.raises(ValueError, match="not in the jet space"):
        J.derivative(space, np.zeros(space.ncoef), (2, 2))
    with pytest.raises(ValueError, match="expected"):
        J.monomials(space, np.zeros((4, 3)))
    with pytest.raises(ValueError, match="inner dimensions"):
        J.matmul(space, np.zeros((space.ncoef, 2, 3)), np.zeros((space.ncoef, 2, 3)))
    with pytest.raises(ValueError):
        J.JetSpace(0, 2)
