"""Taylor coefficients in solver coordinates equal those of the nodal-coordinate assembly."""

import numpy as np
import scipy.linalg as sla
from conftest import UR5

from pinflex import jets
from pinflex.erls import FlexibleModel
from pinflex.jets import JetSpace
from pinflex.parametric import expand, matrix_jets
from pinflex.parametric.algebra import SparseJetAlgebra
from pinflex.parametric.eigen import eigen_jets


def test_sparse_jet_product_equals_dense_product():
    """Products that skip zero coefficients equal the dense truncated product."""
    space = JetSpace(4, 4)
    rng = np.random.default_rng(3)
    a = rng.normal(size=(space.ncoef, 5, 3))
    b = rng.normal(size=(space.ncoef, 3, 7))
    a[space.multi_indices[:, 2] > 0] = 0.0  # a does not depend on variable 2
    b[space.multi_indices[:, 0] > 1] = 0.0
    np.testing.assert_allclose(SparseJetAlgebra(space).mm(a, b), jets.matmul(space, a, b),
                               rtol=1e-13, atol=1e-13)


def test_ur5_eigenvalue_jets_equal_nodal_coordinate_jets():
    """UR5, p = 3, 6 joints + payload: λ coefficients of modes 1-3 equal the nodal route's."""
    model = FlexibleModel(UR5)
    q0 = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
    tm = expand(model, q0, order=3, modes=(1, 2, 3))
    space, M, K, _, _ = matrix_jets(model, q0, order=3)
    w, V = sla.eigh(K[0], M[0])
    idx = [model.n_rigid + k for k in range(3)]
    lam, _ = eigen_jets(space, M, K, idx, eigvals0=w, eigvecs0=V)
    for d in range(4):
        s = space.degree_slice(d)
        scale = np.abs(lam[s]).max(axis=0)
        assert np.max(np.abs(tm.eigval_jets[s] - lam[s]) / scale) < 1e-9


def test_static_joints_are_those_the_spectrum_ignores():
    """Static joints: the UR5's base pan joint; none on benchmark A.

    The UR5's frequencies do not change with the pan angle (the shoulder lift's do);
    benchmark A in absolute angles has none (its first coordinate also sets link 2's angle).
    """
    from pinflex.cases.benchmark_a import benchmark_model
    from pinflex.parametric.conditioned import static_joints

    model = FlexibleModel(UR5)
    assert static_joints(model) == {0}
    assert static_joints(benchmark_model()) == frozenset()
    q = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
    Q = np.repeat(q[None], 3, axis=0)
    Q[1, 0] += 0.9  # pan
    Q[2, 1] += 0.9  # shoulder lift
    f = model.frequencies(Q, n_modes=4)
    np.testing.assert_allclose(f[1], f[0], rtol=1e-11)
    assert np.max(np.abs(f[2] / f[0] - 1)) > 1e-3
