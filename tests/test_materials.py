"""One Material for ERLS beams and PRBDM planforms, checked against closed forms."""

import numpy as np
import pinocchio as pin
import pytest

import pinflex
from pinflex import Beam, FlexibleModel, Material
from pinflex.beam import rectangle
from pinflex.exceptions import InvalidBeamProperty
from pinflex.prbdm.beams import Planform, segment_properties, uniform_beam

BETA1 = 1.8751040687119611  # first root of cos(b) cosh(b) = -1 (clamped-free beam)


def _cantilever(material: Material, length: float, section) -> FlexibleModel:
    """One flexible link on a locked revolute joint: a clamped-free beam."""
    model = pin.Model()
    j1 = model.addJoint(0, pin.JointModelRZ(), pin.SE3.Identity(), "j1")
    model.appendBodyToJoint(j1, pin.Inertia(0.1, np.array([0.25, 0, 0]), np.eye(3) * 1e-4),
                            pin.SE3.Identity())
    beam = Beam(section, material, 16, tip=(length, 0, 0), normal=(0, 0, 1))
    return FlexibleModel.from_pinocchio(model, flexible={"j1": beam}, joints="locked")


def test_one_material_class_everywhere():
    """pinflex.Material, the Python specs' and the PRBDM's are the same class."""
    from pinflex.materials import Material as shared
    from pinflex.native.spec import Material as spec
    from pinflex.prbdm.beams import Material as prbdm

    assert pinflex.Material is shared is spec is prbdm


def test_an_erls_beam_reads_the_material():
    """Both bending frequencies of a clamped rectangular strip equal Euler-Bernoulli's."""
    E, rho, L = 210e9, 7850.0, 0.5
    sec = rectangle(0.02, 0.004)
    model = _cantilever(Material(E=E, G=81e9, density=rho), L, sec)
    f = model.frequencies(np.array([0.3]))
    for i, moment in enumerate(sorted((sec.Iy, sec.Iz))):
        closed = BETA1**2 / (2 * np.pi) * np.sqrt(E * moment / (rho * sec.A * L**4))
        assert f[i] == pytest.approx(closed, rel=1e-6)
    # the same beam by mass per length: the same model
    per_length = _cantilever(Material(E=E, G=81e9, linear_density=rho * sec.A), L, sec)
    np.testing.assert_allclose(per_length.frequencies(np.array([0.3])), f, rtol=1e-13)
    # G from Poisson's ratio: E / (2 (1 + nu))
    nu = Material(E=E, poisson=0.25, density=rho)
    assert nu.shear_modulus == pytest.approx(E / 2.5, rel=1e-15)


def test_a_planform_reads_the_same_material():
    """Mass and bending compliance of a uniform planform from the material's E and density."""
    E, rho, L, w, t = 70e9, 2700.0, 0.8, 0.05, 0.004
    beam = uniform_beam(length_m=L, width_m=w, thickness_m=t,
                        material=Material(E=E, G=26e9, density=rho, name="aluminium"))
    seg = segment_properties(beam, 0.0, L)
    assert seg.mass_kg == pytest.approx(rho * w * t * L, rel=1e-13)
    assert seg.compliance_1_n_m == pytest.approx(L / (E * w * t**3 / 12.0), rel=1e-12)
    assert beam.material.youngs_modulus_pa == E and beam.material.density_kg_m3 == rho


@pytest.mark.parametrize("kwargs, match", [
    ({"E": 0.0, "density": 1.0}, "E"),
    ({"E": float("nan"), "density": 1.0}, "E"),
    ({"E": 1e9, "G": -1.0, "density": 1.0}, "G"),
    ({"E": 1e9, "poisson": 0.5, "density": 1.0}, "poisson"),
    ({"E": 1e9}, "exactly one"),
    ({"E": 1e9, "density": 1.0, "linear_density": 1.0}, "exactly one"),
    ({"E": 1e9, "linear_density": float("inf")}, "linear_density"),
    ({"E": True, "density": 1.0}, "E"),
])
def test_bad_materials_raise_named_errors(kwargs, match):
    """Every field is checked where the material is made."""
    with pytest.raises(InvalidBeamProperty, match=match):
        Material(**kwargs)


def test_a_linear_density_has_no_volumetric_reading():
    """A material by mass per length cannot stand for a planform's volumetric density."""
    per_length = Material(E=1e9, linear_density=2.0, name="strip")
    with pytest.raises(InvalidBeamProperty, match="'strip'.*volumetric"):
        _ = per_length.density_kg_m3
    assert per_length.attributes() == {"E": "1000000000.0", "poisson": "0.3",
                                       "linear_density": "2.0"}
    with pytest.raises(pinflex.exceptions.InvalidBeam, match="volumetric density"):
        Planform(np.array([0.0, 1.0]), np.array([0.1, 0.1]), 0.01, per_length)
