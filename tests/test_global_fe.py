"""ERLS frequencies equal an independent global FE model of the same mesh (round-off level)."""

import numpy as np
import pytest
from conftest import TWO_LINK
from reference_fe import Beam, planar_two_link_frequencies, spatial_frame_frequencies

from pinflex.description import parse
from pinflex.erls import FlexibleModel


def test_benchmark_a_matches_global_frame_model_at_random_poses_and_masses():
    """At 24 random poses and point masses benchmark A equals the hinged global frame to 1e-9."""
    model = FlexibleModel(TWO_LINK, planar=True)
    rng = np.random.default_rng(2021)
    worst = 0.0
    for _ in range(24):
        q_abs = rng.uniform(-np.pi, 2 * np.pi, size=2)
        y = rng.uniform(0.0, 0.25, size=2)
        ours = model.frequencies(q_abs, y)
        _, ref = planar_two_link_frequencies(q_abs, y[0], y[1])
        worst = max(worst, np.max(np.abs(ours / ref - 1)))
    assert worst < 1e-9


def _rot(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * k @ k


def _rpy(r, p, y):
    return _rot([0, 0, 1], y) @ _rot([0, 1, 0], p) @ _rot([1, 0, 0], r)


SPATIAL = dict(
    t1=np.array([0.5, 0.1, 0.3]), n1=np.array([0.0, 0.0, 1.0]),
    rpy2=(0.3, -0.4, 0.7), a2=np.array([0.3, 1.0, 0.2]),
    t2=np.array([0.4, -0.2, 0.1]), n2=np.array([0.0, 1.0, 0.0]),
)
SEC1 = dict(E=7e10, G=2.6e10, density=2700.0, A=3e-4, Iy=2.5e-9, Iz=1.1e-8, J=4e-9)
SEC2 = dict(E=2e11, G=8e10, density=7800.0, A=1e-4, Iy=1.2e-9, Iz=0.6e-9, J=1.1e-9)


def _spatial_urdf(m1, m2, e1=5, e2=4):
    s = SPATIAL
    a2 = s["a2"] / np.linalg.norm(s["a2"])

    def vec(v):
        return " ".join(repr(float(x)) for x in v)

    def flex(link, n, tip, normal, sec):
        return (
            f'<pinflex:flexible link="{link}" elements="{n}" tip="{vec(tip)}" '
            f'normal="{vec(normal)}"><pinflex:material E="{sec["E"]}" G="{sec["G"]}" '
            f'density="{sec["density"]}"/><pinflex:section A="{sec["A"]}" Iy="{sec["Iy"]}" '
            f'Iz="{sec["Iz"]}" J="{sec["J"]}"/></pinflex:flexible>'
        )

    return f"""<robot name="spatial" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="l1"/><link name="l2"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/>
    <axis xyz="0 0 1"/><limit lower="-9" upper="9" effort="1" velocity="1"/></joint>
  <joint name="j2" type="continuous"><parent link="l1"/><child link="l2"/>
    <origin xyz="{vec(s['t1'])}" rpy="{vec(s['rpy2'])}"/><axis xyz="{vec(a2)}"/></joint>
  {flex("l1", e1, s["t1"], s["n1"], SEC1)}
  {flex("l2", e2, s["t2"], s["n2"], SEC2)}
  <pinflex:point_mass name="m1" link="l1" xyz="{vec(s['t1'])}" mass="{m1}"/>
  <pinflex:point_mass name="m2" link="l2" xyz="{vec(s['t2'])}" mass="{m2}"/>
</robot>"""


def _reference(q, m1, m2, e1=5, e2=4, *, springs=None, elbow=None):
    s = SPATIAL
    a2 = s["a2"] / np.linalg.norm(s["a2"])
    R1 = _rot([0, 0, 1], q[0])
    p1 = R1 @ s["t1"]
    Rj = R1 @ _rpy(*s["rpy2"])
    R2 = Rj @ _rot(a2, q[1])
    p2 = p1 + R2 @ s["t2"]

    def beam(sec, n, z_world):
        return Beam(
            EA=sec["E"] * sec["A"], GJ=sec["G"] * sec["J"], EIy=sec["E"] * sec["Iy"],
            EIz=sec["E"] * sec["Iz"], rhoA=sec["density"] * sec["A"],
            rho_Ip=sec["density"] * (sec["Iy"] + sec["Iz"]), n_elements=n,
            vecxz=tuple(z_world),
        )

    def z_axis(R, tip, normal):
        x = tip / np.linalg.norm(tip)
        z = normal - x * (normal @ x)
        return R @ (z / np.linalg.norm(z))

    beams = [beam(SEC1, e1, z_axis(R1, s["t1"], s["n1"])),
             beam(SEC2, e2, z_axis(R2, s["t2"], s["n2"]))]
    return spatial_frame_frequencies(
        np.array([np.zeros(3), p1, p2]), beams, [Rj @ a2 if elbow is None else elbow],
        point_masses=[(p1, m1), (p2, m2)], base=np.array([0.0, 0.0, 1.0]), springs=springs,
    )


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spatial_two_link_matches_global_frame_model(seed):
    """A skewed spatial 2-link arm with unequal sections equals the global 3D frame to 1e-9."""
    rng = np.random.default_rng(seed)
    m1, m2 = rng.uniform(0, 0.5, size=2)
    model = FlexibleModel(parse(_spatial_urdf(m1, m2)))
    for q in rng.uniform(-np.pi, np.pi, size=(3, 2)):
        _, ref = _reference(q, m1, m2)
        ours = model.frequencies(q)
        assert ours.shape == ref.shape
        np.testing.assert_allclose(ours, ref, rtol=1e-9)
