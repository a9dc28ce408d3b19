"""Tests of pinflex.parametric.eigen: Taylor recursion of eigenvalues and eigenvectors."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest
import scipy.linalg as sla

from pinflex import jets as J
from pinflex.exceptions import EigenSolverError, RepeatedEigenvalue
from pinflex.parametric.eigen import eigen_jets, find_cluster, radius_estimate, spectrum_slopes


def _spd(rng, n, shift):
    a = rng.standard_normal((n, n))
    return a @ a.T / n + shift * np.eye(n)


@dataclass
class Family:
    """A pencil (M(x), K(x)) in two variables, exact (complex-friendly) and as jets."""

    x0: np.ndarray
    mats: dict

    def exact(self, x):
        """M(x), K(x) for a real or complex point x."""
        m = self.mats
        M = m["M0"] + x[0] * m["M1"] + x[0] ** 2 * m["M2"] + x[1] * m["M3"]
        K = m["K0"] + np.sin(x[0]) * m["K1"] + np.cos(x[0] + x[1]) * m["K2"]
        return M, K

    def jets(self, space):
        """Jets of M and K at x0, built with jet arithmetic."""
        m = self.mats
        x1 = J.variable(space, 0, self.x0[0])
        x2 = J.variable(space, 1, self.x0[1])
        (s1, c1), (s2, c2) = (J.sin_cos_of_variable(space, k, self.x0[k]) for k in (0, 1))
        cos12 = J.mul(space, c1, c2) - J.mul(space, s1, s2)

        def times(jet, mat):
            return jet[:, None, None] * mat

        M = J.constant(space, m["M0"]) + times(x1, m["M1"]) + times(J.mul(space, x1, x1), m["M2"])
        M = M + times(x2, m["M3"])
        K = J.constant(space, m["K0"]) + times(s1, m["K1"]) + times(cos12, m["K2"])
        return M, K


def _dense_family(seed=0, n=6):
    """Generic dense pencil with well separated eigenvalues."""
    rng = np.random.default_rng(seed)
    mats = {
        "M0": _spd(rng, n, 1.0),
        "M1": 0.3 * _spd(rng, n, 0.0),
        "M2": 0.1 * _spd(rng, n, 0.0),
        "M3": 0.2 * _spd(rng, n, 0.0),
        "K0": 10 * _spd(rng, n, 2.0),
        "K1": _spd(rng, n, 0.0),
        "K2": _spd(rng, n, 0.0),
    }
    return Family(np.array([0.3, -0.2]), mats)


def _rigid_family(seed=1):
    """ERLS-like pencil: K = diag(Ke(x), 0, 0) has a double zero eigenvalue, M couples all."""
    rng = np.random.default_rng(seed)
    n, ne = 5, 3

    def pad(a):
        out = np.zeros((n, n))
        out[:ne, :ne] = a
        return out

    mats = {
        "M0": _spd(rng, n, 1.0),
        "M1": 0.2 * _spd(rng, n, 0.0),
        "M2": 0.1 * _spd(rng, n, 0.0),
        "M3": 0.2 * _spd(rng, n, 0.0),
        "K0": pad(20 * _spd(rng, ne, 1.0)),
        "K1": pad(_spd(rng, ne, 0.0)),
        "K2": pad(2 * _spd(rng, ne, 0.0)),
    }
    return Family(np.array([0.5, 0.1]), mats)


def _complex_eigenpair(M, K, lam_ref, phi_ref, M_ref):
    """Eigenpair of the complex-symmetric pencil nearest to lam_ref, with φᵀMφ = 1."""
    w, V = sla.eig(K, M)
    i = int(np.argmin(np.abs(w - lam_ref)))
    phi = V[:, i] / np.sqrt(V[:, i] @ M @ V[:, i])
    if (phi_ref @ M_ref @ phi).real < 0:
        phi = -phi
    return w[i], phi


def _cauchy_coefficients(family, lam0, phi0, radius, npts=16):
    """Taylor coefficients c[α1, α2] of λ and φ from Cauchy integrals over a polydisk."""
    M0, _ = family.exact(family.x0)
    theta = 2 * np.pi * np.arange(npts) / npts
    z = radius * np.exp(1j * theta)
    lam = np.empty((npts, npts), complex)
    phi = np.empty((npts, npts, phi0.size), complex)
    for a, z1 in enumerate(z):
        for b, z2 in enumerate(z):
            M, K = family.exact(family.x0 + np.array([z1, z2]))
            lam[a, b], phi[a, b] = _complex_eigenpair(M, K, lam0, phi0, M0)
    scale = radius ** (np.arange(npts)[:, None] + np.arange(npts)[None, :])
    c_lam = np.fft.fft2(lam) / npts**2 / scale
    c_phi = np.fft.fft2(phi, axes=(0, 1)) / npts**2 / scale[:, :, None]
    return c_lam, c_phi


@pytest.mark.parametrize(
    ("family", "modes"), [(_dense_family(), [0, 2, 5]), (_rigid_family(), [2, 4])]
)
def test_coefficients_match_cauchy_integrals(family, modes):
    """Every λ and φ coefficient up to order 5 equals the Cauchy integral of the exact eigenpair."""
    space = J.JetSpace(2, 5)
    lam, phi = eigen_jets(space, *family.jets(space), modes)
    radius = 0.1
    for j in range(len(modes)):
        c_lam, c_phi = _cauchy_coefficients(family, lam[0, j], phi[0, :, j], radius)
        for c, (a1, a2) in enumerate(space.multi_indices.tolist()):
            scale = radius ** (a1 + a2)
            assert abs(lam[c, j] - c_lam[a1, a2]) * scale < 1e-10 * abs(lam[0, j])
            np.testing.assert_allclose(phi[c, :, j] * scale, c_phi[a1, a2] * scale, atol=1e-10)


def test_first_order_matches_complex_step():
    """Gradients of the eigenvalues equal complex-step derivatives of the exact eigenvalues."""
    family = _dense_family(seed=2)
    space = J.JetSpace(2, 1)
    modes = [0, 1, 3]
    lam, _ = eigen_jets(space, *family.jets(space), modes)
    h = 1e-20
    for k in range(2):
        dx = np.zeros(2, complex)
        dx[k] = 1j * h
        M, K = family.exact(family.x0 + dx)
        w = sla.eig(K, M, right=False)
        for j, m in enumerate(modes):
            exact = w[np.argmin(np.abs(w - lam[0, j]))]
            alpha = [int(i == k) for i in range(2)]
            assert J.derivative(space, lam[:, j], alpha) == pytest.approx(exact.imag / h, rel=1e-9)


@pytest.mark.parametrize("order", [1, 2, 4])
def test_truncation_error_is_order_p_plus_one(order):
    """λ^p, φ^p differ from eigh's eigenpairs by O(|δx|^{p+1}), mass-normalised to that order."""
    family = _dense_family(seed=3)
    space = J.JetSpace(2, order)
    modes = [0, 4]
    lam, phi = eigen_jets(space, *family.jets(space), modes)
    direction = np.array([0.8, -0.6])
    hs = np.array([0.04, 0.02, 0.01])
    err_lam, err_phi, err_norm = [], [], []
    for h in hs:
        x = family.x0 + h * direction
        M, K = family.exact(x)
        w, V = sla.eigh(K, M)
        lam_p = J.evaluate(space, lam, h * direction)
        phi_p = J.evaluate(space, phi, h * direction)
        V = V[:, modes] * np.sign(np.sum(V[:, modes] * phi_p, axis=0))
        err_lam.append(np.abs(lam_p - w[modes]).max())
        err_phi.append(np.abs(phi_p - V).max())
        err_norm.append(np.abs(np.einsum("im,ij,jm->m", phi_p, M, phi_p) - 1).max())
    for errors in (err_lam, err_phi, err_norm):
        rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
        assert np.all(rates > order + 0.6), rates


def test_modes_are_computed_independently():
    """Asking several modes at once gives the same jets as asking each alone."""
    family = _dense_family(seed=4)
    space = J.JetSpace(2, 3)
    M, K = family.jets(space)
    lam, phi = eigen_jets(space, M, K, [1, 3, 5])
    for j, m in enumerate([1, 3, 5]):
        lam1, phi1 = eigen_jets(space, M, K, m)
        np.testing.assert_allclose(lam[:, j], lam1[:, 0], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(phi[:, :, j], phi1[:, :, 0], rtol=1e-12, atol=1e-12)


def test_sign_convention_and_supplied_eigenpairs():
    """φ(x0)'s largest entry is positive by default; supplied eigenvectors keep their sign."""
    family = _dense_family(seed=5)
    space = J.JetSpace(2, 3)
    M, K = family.jets(space)
    lam, phi = eigen_jets(space, M, K, [0, 2])
    big = np.argmax(np.abs(phi[0]), axis=0)
    assert np.all(phi[0][big, [0, 1]] > 0)
    w = sla.eigh(K[0], M[0], eigvals_only=True)
    flipped = -3.0 * phi[0]  # other sign and scale: rescaled to φᵀMφ = 1, sign kept
    lam2, phi2 = eigen_jets(space, M, K, [0, 2], eigvals0=w, eigvecs0=flipped)
    np.testing.assert_allclose(lam2, lam, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(phi2, -phi, rtol=1e-10, atol=1e-12)


def _ring_family(split=0.0):
    """Four equal masses on a ring of equal springs: a double eigenvalue at x = 0 by symmetry."""
    k, kg = 3.0, 1.0
    shift = np.roll(np.eye(4), 1, axis=1)
    K0 = (kg + 2 * k) * np.eye(4) - k * (shift + shift.T) + split * np.diag([1.0, 0, 0, 0])
    mats = {
        "M0": np.eye(4),
        "M1": np.zeros((4, 4)),
        "M2": np.zeros((4, 4)),
        "M3": np.diag([0.0, 0.5, 0.0, 0.0]),
        "K0": K0,
        "K1": np.diag([1.0, 0.0, 0.0, 0.0]),
        "K2": np.zeros((4, 4)),
    }
    return Family(np.array([0.0, 0.0]), mats)


def test_double_eigenvalue_raises_with_cluster():
    """At a symmetric pose with a double eigenvalue, both modes of the pair raise a named error."""
    family = _ring_family()
    space = J.JetSpace(2, 3)
    M, K = family.jets(space)
    for mode in (1, 2):
        with pytest.raises(RepeatedEigenvalue) as info:
            eigen_jets(space, M, K, [0, mode])
        assert info.value.mode == mode
        assert info.value.cluster == [1, 2]
        np.testing.assert_allclose(info.value.eigvals, [7.0, 7.0])
        assert "modes [1, 2]" in str(info.value)
    lam, _ = eigen_jets(space, M, K, [0, 3])  # the simple modes still expand
    np.testing.assert_allclose(lam[0], [1.0, 13.0])


def test_nearly_repeated_eigenvalue_raises():
    """A relative eigenvalue gap of 1e-10 is reported as a cluster, not expanded."""
    family = _ring_family(split=7e-10)
    space = J.JetSpace(2, 2)
    with pytest.raises(RepeatedEigenvalue) as info:
        eigen_jets(space, *family.jets(space), 2)
    assert info.value.cluster == [1, 2] and 0 < info.value.gap < 1e-9


def test_condition_check_catches_what_the_gap_test_misses():
    """With cluster tolerances zero, the bordered matrix's condition still flags a double root."""
    family = _ring_family()
    space = J.JetSpace(2, 2)
    with pytest.raises(RepeatedEigenvalue) as info:
        eigen_jets(space, *family.jets(space), 1, cluster_rtol=0.0, cluster_atol=0.0)
    assert set(info.value.cluster) == {1, 2}


def test_rigid_modes_raise_but_elastic_neighbours_expand():
    """A zero mode of a double rigid eigenvalue raises; the next, simple, mode expands correctly."""
    family = _rigid_family()
    space = J.JetSpace(2, 3)
    M, K = family.jets(space)
    w = sla.eigh(K[0], M[0], eigvals_only=True)
    assert find_cluster(w, 0) == [0, 1] and find_cluster(w, 2) == [2]
    for mode in (0, 1):
        with pytest.raises(RepeatedEigenvalue) as info:
            eigen_jets(space, M, K, mode)
        assert info.value.cluster == [0, 1]
    lam, _ = eigen_jets(space, M, K, 2)
    assert lam[0, 0] == pytest.approx(w[2], rel=1e-12)


def _branch_family(c=3.0, x0=(0.25, 0.25)):
    """K = c I + [[1, s], [s, −1]] + x3 I with s = x1 + x2: λ = c + x3 ± √(1 + s²)."""
    space = J.JetSpace(3, 8)
    s = J.variable(space, 0, x0[0]) + J.variable(space, 1, x0[1])
    x3 = J.variable(space, 2, 0.0)
    K = np.zeros((space.ncoef, 2, 2))
    K[:, 0, 1] = K[:, 1, 0] = s
    K[:, 0, 0] = J.constant(space, c + 1) + x3
    K[:, 1, 1] = J.constant(space, c - 1) + x3
    return space, J.constant(space, np.eye(2)), K


def test_radius_estimate_is_the_root_test_and_scales_with_the_ray():
    """Root test on λ = 3 + x3 ± √(1 + s²): optimistic at low order, tightening with p."""
    space, M, K = _branch_family()
    lam, _ = eigen_jets(space, M, K, [0, 1])
    true = np.hypot(0.5, 1.0)  # s0 = 0.5, branch points at s = ±i
    axes = radius_estimate(space, lam)
    # by hand from the ray coefficients: min over j >= p/2 of |c0 / cj|^(1/j)
    c = np.abs(J.ray_coefficients(space, lam, np.eye(3)))
    by_hand = np.min([(c[:, 0] / c[:, j]) ** (1 / j) for j in range(4, 9)], axis=0)
    np.testing.assert_allclose(axes[:2], by_hand[:2], rtol=1e-12)
    assert np.all(np.isinf(axes[2]))  # λ is linear in x3
    diagonal = radius_estimate(space, lam, np.array([1.0, 1.0, 0.0]))
    np.testing.assert_allclose(diagonal, axes[0] / 2, rtol=1e-12)  # s moves twice as fast
    assert np.all(axes[0] > true)  # the value's offset makes it optimistic ...
    deep = J.JetSpace(3, 24)
    s = J.variable(deep, 0, 0.25) + J.variable(deep, 1, 0.25)
    Kd = np.zeros((deep.ncoef, 2, 2))
    Kd[:, 0, 1] = Kd[:, 1, 0] = s
    Kd[:, 0, 0] = J.constant(deep, 4.0) + J.variable(deep, 2, 0.0)
    Kd[:, 1, 1] = J.constant(deep, 2.0) + J.variable(deep, 2, 0.0)
    lam_d, _ = eigen_jets(deep, J.constant(deep, np.eye(2)), Kd, [0, 1])
    tight = radius_estimate(deep, lam_d, np.array([1.0, 0.0, 0.0]))
    assert np.all(tight < axes[0]) and np.all(tight > true)  # ... and tightens with the order


def test_invalid_inputs_raise():
    """Non-symmetric or indefinite matrices, bad modes and bad eigenvector shapes are refused."""
    family = _dense_family(seed=6)
    space = J.JetSpace(2, 2)
    M, K = family.jets(space)
    with pytest.raises(ValueError, match="modes"):
        eigen_jets(space, M, K, 6)
    bad = K.copy()
    bad[0, 0, 1] += 1.0
    with pytest.raises(ValueError, match="symmetric"):
        eigen_jets(space, M, bad, 0)
    with pytest.raises(EigenSolverError):
        eigen_jets(space, -M, K, 0)
    w, V = sla.eigh(K[0], M[0])
    with pytest.raises(ValueError, match="eigvecs0"):
        eigen_jets(space, M, K, [0, 1], eigvals0=w, eigvecs0=V[:, :3])
    with pytest.raises(EigenSolverError, match="residual"):
        eigen_jets(space, M, K, [0], eigvals0=w, eigvecs0=V[:, [1]])
    with pytest.raises(ValueError, match="together"):
        eigen_jets(space, M, K, 0, eigvals0=w)


def test_constant_stiffness_as_one_matrix_equals_its_jet():
    """A 2-D stiffness (constant) gives the jets and slopes of the same stiffness as a jet."""
    family = _dense_family(seed=6)
    space = J.JetSpace(3, 4)
    M, K = family.jets(space)
    K_const = np.zeros_like(K)
    K_const[0] = K[0]
    lam, phi = eigen_jets(space, M, K_const, [0, 2, 3])
    lam2, phi2 = eigen_jets(space, M, K[0], [0, 2, 3])
    np.testing.assert_allclose(lam2, lam, rtol=1e-13, atol=1e-13 * np.abs(lam).max())
    np.testing.assert_allclose(phi2, phi, rtol=1e-12, atol=1e-12 * np.abs(phi).max())
    w, V = sla.eigh(K[0], M[0])
    np.testing.assert_allclose(spectrum_slopes(space, M, K[0], w, V),
                               spectrum_slopes(space, M, K_const, w, V), rtol=1e-13, atol=1e-12)
    assert np.abs(lam[1:]).max() > 1e-3 * np.abs(lam[0]).max()  # M alone moves λ
