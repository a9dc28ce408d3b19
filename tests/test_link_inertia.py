"""The link's own inertia: what a beam link keeps of its URDF inertia, and rigid bodies with
full inertia on beams.

References: Pinocchio's CRBA of the URDF itself (beam + kept excess = the URDF link, so the
rigid block of M is the original robot's), the frequency equation of a clamped beam with a tip
mass and rotary inertia (boundary conditions written out below, roots by brentq), and the
excess inertia computed here from the URDF numbers and a uniform rod's formulas.
"""

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from scipy.optimize import brentq

import pinflex
from pinflex.description import load, parse
from pinflex.erls import FlexibleModel

ROOT = Path(__file__).resolve().parents[1]


def _beam_only(overlay, tmp_path) -> Path:
    """The shipped overlay with inertia="beam-only" on every flexible link, in tmp_path."""
    text = (ROOT / "urdf" / overlay).read_text().replace(
        "<pinflex:flexible ", '<pinflex:flexible inertia="beam-only" ')
    path = tmp_path / overlay
    path.write_text(text)
    return path


def _crba(pmodel, q):
    M = pin.crba(pmodel, pmodel.createData(), q)
    return np.triu(M) + np.triu(M, 1).T


@pytest.mark.parametrize("overlay, q", [
    ("ur3_tubes.xml", [0.1, -1.2, 1.4, -1.8, -1.57, 0.2]),
    ("ur5_flexible.xml", [0.4, -1.0, 1.2, 0.3, 0.5, -0.2]),
    ("kinova_tubes.xml", [0.0, 2.9, 1.3, -2.07, 1.4, 0.0]),
])
def test_beam_plus_kept_excess_is_the_urdf_robot(overlay, q, tmp_path):
    """keep-excess (the default): the rigid block of M with every joint free equals
    Pinocchio's CRBA of the unchanged URDF (beam-only: of the model with the beams' inertias)."""
    arm = FlexibleModel(ROOT / "urdf" / overlay, joints="free", values=None)
    if arm.ny:  # point masses (the UR5 payload) are not in the URDF: set them to zero
        arm = arm.with_values({n: 0.0 for n in arm.point_mass_values})
    q = np.array(q)
    M, _ = arm.matrices(q)
    nx = arm.nx
    ref = _crba(arm.model, arm.pin_configuration(q))
    np.testing.assert_allclose(M[nx:, nx:], ref, atol=1e-12 * np.abs(ref).max())
    only = FlexibleModel(_beam_only(overlay, tmp_path), joints="free")
    if only.ny:
        only = only.with_values({n: 0.0 for n in only.point_mass_values})
    M0, _ = only.matrices(q)
    eff = only.effective_model(point_masses=False)
    np.testing.assert_allclose(M0[nx:, nx:], _crba(eff, only.pin_configuration(q)),
                               atol=1e-12 * np.abs(ref).max())
    assert not np.allclose(M0[nx:, nx:], ref, rtol=1e-3)  # the motors matter


def test_kept_inertia_lowers_the_ur3_servo_modes_and_says_so(tmp_path):
    """UR3 on 2e4 N m/rad servos: beam-only rings higher than the arm with its motors."""
    q = np.array([0.0, -1.2, 1.4, -1.8, -1.57, 0.0])
    arm = FlexibleModel(ROOT / "urdf" / "ur3_tubes.xml")
    only = FlexibleModel(_beam_only("ur3_tubes.xml", tmp_path))
    f, f0 = arm.frequencies(q, n_modes=3), only.frequencies(q, n_modes=3)
    assert np.all(f < f0 * 0.95)
    notes = arm.description.inertia_notes
    assert notes[0].startswith("upper_arm_link: kept 3.067 kg of the URDF link's 3.42 kg")
    assert "dropped (inertia=\"beam-only\")" in only.description.inertia_notes[0]


def test_benchmark_a_keeps_nothing():
    """Benchmark A's URDF inertials are its rods' (1.9 kg/m): the excess is zero, nothing is
    kept, and the model equals the beam-only one."""
    desc = load(ROOT / "urdf" / "two_link.urdf")
    assert desc.bodies == ()
    assert all("nothing kept" in n for n in desc.inertia_notes)
    text = (ROOT / "urdf" / "two_link.urdf").read_text().replace(
        "<pinflex:flexible ", '<pinflex:flexible inertia="beam-only" ')
    a = FlexibleModel(desc, planar=True).matrices([1.817, 5.312])
    b = FlexibleModel(parse(text), planar=True).matrices([1.817, 5.312])
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


def test_an_excess_that_is_no_rigid_body_is_projected_and_said():
    """Panda link 4: URDF minus the beam is not a rigid body's inertia; the kept body has the
    excess mass and centre and the nearest physical inertia (second moments clipped at 0),
    recomputed here from the URDF numbers and the rod's formulas."""
    desc = load(ROOT / "urdf" / "panda_flexible.xml")
    note = next(n for n in desc.inertia_notes if n.startswith("panda_link4"))
    assert "projected to the nearest one" in note
    body = next(b for b in desc.bodies if b.link == "panda_link4")
    f = desc.flexible["panda_link4"]
    u = desc.inertias["panda_link4"]
    L = np.linalg.norm(f.tip)
    mb, cb = f.rhoA * L, f.tip / 2
    Ib = f.rotation @ np.diag([f.rhoIp * L, f.rhoA * L**3 / 12, f.rhoA * L**3 / 12]) @ \
        f.rotation.T

    def at_origin(m, c, I):
        return I + m * (c @ c * np.eye(3) - np.outer(c, c))

    me = u.mass - mb
    ce = (u.mass * u.com - mb * cb) / me
    Ie = at_origin(u.mass, u.com, u.inertia) - at_origin(mb, cb, Ib) - me * (
        ce @ ce * np.eye(3) - np.outer(ce, ce))
    P = 0.5 * np.trace(Ie) * np.eye(3) - Ie
    w, V = np.linalg.eigh(P)
    assert w.min() < 0  # not a rigid body's
    P = (V * np.maximum(w, 0)) @ V.T
    assert body.mass == pytest.approx(me, rel=1e-12)
    np.testing.assert_allclose(body.com, ce, atol=1e-12)
    np.testing.assert_allclose(body.inertia, np.trace(P) * np.eye(3) - P, atol=1e-12)


def _tip_roots(mu, eta, n=2):
    """Roots λ = βL of a clamped beam with tip mass μ ρAL and rotary inertia η ρA L³.

    w = A (cosh βx − cos βx) + B (sinh βx − sin βx) (clamped root); at the tip the moment and
    shear balance the body, EI w'' = ω² J w' and EI w''' = −ω² M w (Hamilton's principle with
    the tip's kinetic energy ½ M ẇ² + ½ J ẇ'²), and ω² = β⁴ EI / ρA. In λ = βL and derivatives
    per λ: w'' = η λ³ w' and w''' = −μ λ w, the 2 × 2 determinant below.
    """
    def det(lam):
        ch, sh, c, s = np.cosh(lam), np.sinh(lam), np.cos(lam), np.sin(lam)
        w = np.array([ch - c, sh - s])
        w1 = np.array([sh + s, ch - c])
        w2 = np.array([ch + c, sh + s])
        w3 = np.array([sh - s, ch + c])
        row1 = w2 - eta * lam**3 * w1
        row2 = w3 + mu * lam * w
        return (row1[0] * row2[1] - row1[1] * row2[0]) / np.cosh(lam) ** 2

    grid = np.linspace(0.05, 12.0, 4000)
    vals = [det(x) for x in grid]
    roots = [brentq(det, a, b, xtol=1e-14) for a, b, fa, fb in
             zip(grid[:-1], grid[1:], vals[:-1], vals[1:]) if fa * fb < 0]
    return np.array(roots[:n])


@pytest.mark.parametrize("mass, J", [(0.5, 0.0), (0.5, 2e-3), (0.2, 1e-2)])
def test_a_rigid_body_at_the_tip_of_a_clamped_beam_matches_the_frequency_equation(mass, J):
    """A clamped rod (joint locked) with a <pinflex:body> at its tip: mass and rotary inertia
    about the bending axis; modes 1-2 against the frequency equation to 1e-5 (32 elements)."""
    L, d, E, rho = 0.6, 0.02, 70e9, 2700.0
    A, I = np.pi * d**2 / 4, np.pi * d**4 / 64
    text = f"""<robot name="tip" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="rod"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="rod"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="rod" elements="32" tip="{L} 0 0" normal="0 0 1">
    <pinflex:material E="{E}" density="{rho}"/>
    <pinflex:section shape="solid_circle" diameter="{d}"/></pinflex:flexible>
  <pinflex:body name="tool" link="rod" xyz="{L} 0 0" mass="{mass}"
                ixx="{J / 2}" iyy="{J / 2}" izz="{J}"/>
  <pinflex:joint name="q1" locked="true"/>
</robot>"""
    model = FlexibleModel(parse(text), planar=True)
    f = model.frequencies([0.4], n_modes=2)
    lam = _tip_roots(mass / (rho * A * L), J / (rho * A * L**3))
    ref = lam**2 / L**2 * np.sqrt(E * I / (rho * A)) / (2 * np.pi)
    np.testing.assert_allclose(f, ref, rtol=1e-5)


def test_python_body_and_xml_body_are_the_same_model():
    """pinflex.Body in masses= gives the <pinflex:body> model (M equal)."""
    body = pinflex.Body("forearm_link", 1.2, xyz=(0, 0.01, 0.2),
                        inertia=[[0.01, 0, 0], [0, 0.012, 0.001], [0, 0.001, 0.008]])
    beam = pinflex.Beam(pinflex.beam.hollow_circle(0.07, 0.062), pinflex.Material(
        E=70e9, G=26.3e9, density=2700.0), elements=4, tip=(0, 0, 0.39225), normal=(0, 1, 0))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        a = pinflex.example_robot("ur5", flexible={"forearm_link": beam},
                                  masses={"tool": body})
        b = pinflex.example_robot("ur5", flexible={"forearm_link": beam})
    assert [x.name for x in a.description.bodies] == ["forearm_link.urdf", "tool"]
    q = np.array([0.4, -1.0, 1.2, 0.3, 0.5, -0.2])
    Ma, _ = a.matrices(q)
    Mb, _ = b.matrices(q)
    assert not np.allclose(Ma, Mb)
    nx = a.nx
    pb = b.model.copy()
    f = pb.frames[pb.getFrameId("forearm_link", pin.FrameType.BODY)]
    moved = f.placement.act(pin.Inertia(1.2, np.array([0, 0.01, 0.2]), np.array(
        body.inertia)))
    pb.inertias[f.parentJoint] = pb.inertias[f.parentJoint] + moved
    np.testing.assert_allclose(Ma[nx:, nx:], _crba(pb, q), atol=1e-12)


def test_an_unphysical_body_inertia_is_refused():
    """Principal moments 0.1, 0.1, 0.5 break the triangle inequality: refused by name."""
    from pinflex.exceptions import ImplausibleValue

    text = (ROOT / "urdf" / "two_link.urdf").read_text().replace(
        "</robot>", '<pinflex:body name="bad" link="link2" xyz="0.45 0 0" mass="0.2" '
        'ixx="0.1" iyy="0.1" izz="0.5"/></robot>')
    with pytest.raises(ImplausibleValue, match="not a rigid body's"):
        parse(text)


def test_lumped_chain_carries_the_kept_urdf_inertia(tmp_path):
    """The spring-chain arm of beam links that keep their URDF motors: what the kept bodies
    add to the chain's rigid-body mass matrix at the joints (hinges at rest) is what they add
    to Pinocchio's CRBA of the model the modal analysis sees (beam-only vs keep-excess)."""
    from pinflex.lumped import equal_lumped, layout_of

    path = ROOT / "urdf" / "ur5_flexible.xml"
    bare = tmp_path / "ur5_beam_only.xml"
    bare.write_text(path.read_text().replace("<pinflex:flexible ",
                                             '<pinflex:flexible inertia="beam-only" '))
    q = np.array([0.3, -1.0, 1.2, -0.5, 0.7, 0.2])

    def joint_blocks(file):
        arm = FlexibleModel(file)
        chain = equal_lumped(layout_of(arm), 3).model
        full = pin.neutral(chain)
        cols = []
        for k, name in enumerate(arm.joint_names):
            j = chain.joints[chain.getJointId(name)]
            full[j.idx_q] = q[k]
            cols.append(j.idx_v)
        Mc = pin.crba(chain, chain.createData(), full)
        eff = arm.effective_model()
        Me = pin.crba(eff, eff.createData(), arm.pin_configuration(q))
        return np.triu(Mc)[np.ix_(cols, cols)], np.triu(Me), len(arm.description.bodies)

    Mc, Me, n = joint_blocks(path)
    Mc0, Me0, n0 = joint_blocks(bare)
    assert n == 2 and n0 == 0
    added = Me - Me0
    assert np.abs(added).max() > 0.5  # 8.3 kg of motors and flanges
    np.testing.assert_allclose(Mc - Mc0, added, rtol=0, atol=1e-9 * np.abs(Me).max())
