"""Paper 001's fitted chains exported to MJCF (checked in MuJoCo) and URDF (exact reload)."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from pinflex.cli import main
from pinflex.lumped import load_lumped_urdf
from pinflex.lumped.chain import chain_mjcf, chain_urdf
from pinflex.prbdm.beams import uniform_beam
from pinflex.prbdm.chain import build_chain, chain_frequencies, mass_matrix


@pytest.fixture(scope="module")
def chain():
    """A 3R chain of the uniform beam."""
    return build_chain(uniform_beam(), np.array([0.1, 0.3, 0.35, 0.25]),
                       np.array([9.0e5, 6.0e5, 4.5e5]))


def test_chain_urdf_reloads_exactly(chain, tmp_path):
    """The loader gives the chain's CRBA mass matrix and spring matrix exactly."""
    text, springs = chain_urdf(chain)
    (tmp_path / "c.urdf").write_text(text)
    (tmp_path / "c.springs.json").write_text(springs)
    loaded = load_lumped_urdf(tmp_path / "c.urdf")
    np.testing.assert_array_equal(np.diag(loaded.stiffness), chain.stiffness_nm_rad)
    data = loaded.model.createData()
    import pinocchio as pin

    theta = np.array([0.1, -0.2, 0.3])
    M = pin.crba(loaded.model, data, theta)
    M = np.triu(M) + np.triu(M, 1).T
    np.testing.assert_allclose(M, mass_matrix(chain, theta), rtol=0, atol=1e-14 * np.abs(M).max())
    np.testing.assert_allclose(loaded.frequencies(), chain_frequencies(chain), rtol=1e-12)


def test_chain_mjcf_is_elastic_in_mujoco(chain):
    """MuJoCo loads the springs (jnt_stiffness > 0) and its modes are the chain's to 1e-9."""
    mujoco = pytest.importorskip("mujoco")
    m = mujoco.MjModel.from_xml_string(chain_mjcf(chain, planform=uniform_beam()))
    d = mujoco.MjData(m)
    np.testing.assert_array_equal(m.jnt_stiffness, chain.stiffness_nm_rad)
    mujoco.mj_forward(m, d)
    M = np.zeros((m.nv, m.nv))
    mujoco.mj_fullM(m, d, M)
    f = np.sqrt(sla.eigh(np.diag(m.jnt_stiffness), M, eigvals_only=True)) / (2 * np.pi)
    np.testing.assert_allclose(f, chain_frequencies(chain), rtol=1e-9)


def test_prbdm_cli_exports_the_fitted_chain(tmp_path, capsys):
    """``pinflex prbdm ... --export chain.xml`` writes the fitted chain; again needs --force."""
    out = tmp_path / "chain.xml"
    args = ["prbdm", "--links", "2", "--starts", "1", "--no-progress", "--export", str(out)]
    assert main(args) == 0
    assert "<joint" in out.read_text() and 'stiffness="' in out.read_text()
    assert main(args) == 2
    assert "exists" in capsys.readouterr().err
