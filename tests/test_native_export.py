"""Exports for control design: state-space eigenvalues against the modal problem."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.io
from conftest import TWO_LINK

from pinflex.cli import main
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.native.export import linear_model, save_linear_model
from pinflex.trajectory import Trajectory


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, spatial (free joints, absolute coordinates)."""
    return FlexibleModel(TWO_LINK)


def _elastic_eigs(A: np.ndarray, nv: int) -> np.ndarray:
    ev = np.linalg.eigvals(A)
    ev = ev[np.argsort(np.abs(ev))]
    assert np.abs(ev[: 2 * nv]).max() < 1e-3 * np.abs(ev[2 * nv])  # the rigid zeros
    return ev[2 * nv:]


def test_undamped_eigenvalues_are_plus_minus_i_omega(arm):
    """eig(A) = ±iω of the modal problem (plus 2 nv zeros), inputs act on the joints."""
    q = np.array([1.817, 5.312])
    data = linear_model(arm, q)
    omega = 2 * np.pi * arm.frequencies(q)
    ev = _elastic_eigs(data["A"], arm.nv)
    assert np.abs(ev.real).max() < 1e-6 * omega.max()
    np.testing.assert_allclose(np.sort(ev.imag[ev.imag > 0]), omega, rtol=1e-7)
    # B maps a torque on joint j to M⁻¹ Bu; the generalized reading: M p̈ = Cᵀ τ in
    # absolute coordinates (the default motor torques: tests/test_export_motor_torque.py)
    nd = arm.ndof
    gen = linear_model(arm, q, torque_input="generalized")
    np.testing.assert_allclose(gen["M"] @ gen["B"][nd:], np.vstack([np.zeros((arm.nx, 2)),
                                                                    arm.coord_map.T]),
                               atol=1e-10)
    assert data["coordinates"][-2:].tolist() == list(arm.joint_names)
    assert data["A"].shape == (2 * nd, 2 * nd) and data["C"].shape == (nd, 2 * nd)


def test_modal_damping_gives_damped_pairs(arm):
    """ζ on every elastic mode: λ = −ζω ± iω√(1 − ζ²); rigid modes stay undamped."""
    q = np.array([0.4, 1.1])
    zeta = 0.05
    ev = _elastic_eigs(linear_model(arm, q, zeta=zeta)["A"], arm.nv)
    omega = 2 * np.pi * arm.frequencies(q)
    up = ev[ev.imag > 0]
    up = up[np.argsort(up.imag)]
    np.testing.assert_allclose(-up.real, zeta * omega, rtol=1e-6)
    np.testing.assert_allclose(up.imag, omega * np.sqrt(1 - zeta**2), rtol=1e-7)
    with pytest.raises(ConfigurationError):
        linear_model(arm, q, zeta=-0.1)


def test_rayleigh_and_files_along_a_trajectory(arm, tmp_path):
    """Rayleigh damps the deformation only; npz and mat files hold the stacked models.

    No damping force on the joint rows (tests/test_damping_definition.py checks the rates).
    """
    q = np.array([[0.4, 1.1], [0.5, 1.3], [0.7, 1.6]])
    data = linear_model(arm, q, rayleigh=(0.5, 1e-5))
    assert np.abs(data["damping"][:, arm.nx:]).max() == 0.0
    assert np.abs(data["damping"][:, :, arm.nx:]).max() == 0.0
    assert np.abs(data["damping"][:, : arm.nx, : arm.nx]).max() > 0.0
    assert data["A"].shape[0] == 3
    npz = np.load(save_linear_model(data, tmp_path / "m.npz"))
    np.testing.assert_array_equal(npz["A"], data["A"])
    mat = scipy.io.loadmat(save_linear_model(data, tmp_path / "m.mat"))
    np.testing.assert_allclose(mat["K"], data["K"])
    with pytest.raises(ConfigurationError):
        save_linear_model(data, tmp_path / "m.txt")
    Trajectory(np.array([0, 0.5, 1.0]), q, arm.joint_names).to_csv(tmp_path / "t.csv")
    assert main(["export", str(TWO_LINK), "--trajectory", str(tmp_path / "t.csv"),
                 "--zeta", "0.02", "--out", str(tmp_path / "cli.npz")]) == 0
    cli = np.load(tmp_path / "cli.npz")
    np.testing.assert_allclose(cli["A"], linear_model(arm, q, zeta=0.02)["A"])
    np.testing.assert_allclose(cli["times_s"], [0, 0.5, 1.0])
