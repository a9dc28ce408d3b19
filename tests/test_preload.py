"""Gravity and payload preload of the modal analysis (pinflex.erls.preload).

References written here with no pinflex code: the heavy vertical cantilever
``EI w'''' − (N w')' = ρA ω² w`` with ``N(x) = ±ρAg(L − x) + P`` solved by shooting (two
fundamental solutions from the clamp integrated to the free end, roots of the free-end
determinant), Greenhill's self-weight buckling constant ``q L³/EI = 7.83735``, Euler's tip-load
column ``P L²/EI = π²/4``, the spring-held pendulum ``ω² = (k + V'') / I`` and Pinocchio's
generalized gravity and its derivatives.
"""

from __future__ import annotations

import contextlib
import functools
import json
import math
import warnings

import numpy as np
import pinocchio as pin
import pytest
import scipy.integrate
import scipy.optimize

from pinflex import FlexibleModel, PointForce, Preload
from pinflex.cli import main
from pinflex.exceptions import (
    ConfigurationError,
    PinflexWarning,
    PlausibilityWarning,
    PreloadBendingWarning,
    PreloadBuckles,
    PreloadNotInEquilibrium,
)

L, EI, RHOA = 2.0, 50.0, 0.8  # column [m, N m², kg/m]
COLUMN = """<?xml version="1.0"?>
<robot name="column" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="beam"/>
  <joint name="foot" type="revolute"><parent link="base"/><child link="beam"/>
    <origin xyz="0 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="beam" elements="{n}" tip="0 0 {L}">
    <pinflex:material E="7e10" linear_density="{rhoA}"/>
    <pinflex:section A="1e-4" Iy="{I}" Iz="{I}" J="{J}"/>
  </pinflex:flexible>
</robot>
"""


def column(tmp_path, n: int, planar: bool = True, joints="locked") -> FlexibleModel:
    """A uniform column clamped at its foot (the origin), standing along +z."""
    path = tmp_path / f"column{n}.urdf"
    path.write_text(COLUMN.format(n=n, L=L, rhoA=RHOA, I=EI / 7e10, J=2 * EI / 7e10))
    return FlexibleModel(path, planar=planar, joints=joints)


# ---------------------------------------------------------------- independent reference


def _free_end_det(om2: float, gamma: float, p: float, mu: float = 0.0,
                  delta: float = 0.0) -> float:
    """Free-end determinant of ``w'''' = Ω² w + (n w')'``, ``n(ξ) = γ(1 − ξ) + p``, clamped at 0.

    Dimensionless: ``ξ = x/L``, ``n = N L²/EI`` (tension positive), ``Ω² = ρA ω² L⁴/EI``. At
    the free end a rigid massless bar of length ``δ L`` along the axis carries a point mass
    ``μ ρA L`` whose weight is the end force ``p = μ γ`` (or a bare dead force ``p`` with
    ``μ = 0``). With ``u = w + δ w'`` the mass's lateral motion, the end conditions are
    ``w'' + p δ w' − Ω² μ δ u = 0`` (moments: the bar's weight lever ``p δ``) and
    ``w''' − p w' + Ω² μ u = 0`` (transverse forces).
    """
    def rhs(x, y):
        n, dn = gamma * (1.0 - x) + p, -gamma
        return [y[1], y[2], y[3], om2 * y[0] + dn * y[1] + n * y[2]]

    cols = []
    for y0 in ([0.0, 0.0, 1.0, 0.0], [0.0, 0.0, 0.0, 1.0]):
        s = scipy.integrate.solve_ivp(rhs, (0.0, 1.0), y0, method="DOP853", rtol=1e-13,
                                      atol=1e-14)
        w, w1, w2, w3 = s.y[:, -1]
        u = w + delta * w1
        cols.append((w2 + p * delta * w1 - om2 * mu * delta * u, w3 - p * w1 + om2 * mu * u))
    return cols[0][0] * cols[1][1] - cols[0][1] * cols[1][0]


@functools.lru_cache(maxsize=None)
def heavy_column_hz(gamma: float, p: float = 0.0, k: int = 3, mu: float = 0.0,
                    delta: float = 0.0) -> np.ndarray:
    """The lowest ``k`` bending frequencies [Hz] of the column (shooting, module doc).

    ``gamma = g ρA L³/EI`` (positive: the weight pulls towards the free end, tension),
    ``p = P L²/EI`` (a tip force, tension positive), ``mu``, ``delta``: a tip mass on a rigid
    bar (:func:`_free_end_det`).
    """
    beta = np.arange(0.3, 9.0, 0.3)  # Ω = β², roots spaced about π in β
    roots = []
    args = (gamma, p, mu, delta)
    vals = [_free_end_det(b**4, *args) for b in beta]
    for a, b, fa, fb in zip(beta[:-1], beta[1:], vals[:-1], vals[1:]):
        if np.sign(fa) != np.sign(fb):
            om2 = scipy.optimize.brentq(_free_end_det, a**4, b**4, args=args, xtol=1e-13,
                                        rtol=1e-15)
            roots.append(math.sqrt(om2))
            if len(roots) == k:
                break
    out = np.array(roots) * math.sqrt(EI / (RHOA * L**4)) / (2.0 * math.pi)
    out.setflags(write=False)
    return out


def test_reference_solver_gives_the_clamped_free_roots():
    """Without load the shooting reference returns the cantilever's βL roots (1e-10)."""
    beta_l = np.array([1.875104068711961, 4.694091132974175, 7.854757438237613])
    exact = beta_l**2 * math.sqrt(EI / (RHOA * L**4)) / (2 * math.pi)
    assert heavy_column_hz(0.0) == pytest.approx(exact, rel=1e-10)


# ---------------------------------------------------------------- (a) hanging and standing


@pytest.mark.parametrize("gamma", [5.0, -5.0])
def test_hanging_and_standing_cantilever_match_the_heavy_column(tmp_path, gamma):
    """Self-weight ``g ρA L³/EI = 5``: hanging (tension) and standing (compression) columns.

    The weight shifts mode 1 by +28 % (hanging) and −38 % (standing). At 60 elements the
    first three bending frequencies are within 3e-7 of the shooting solution; the Richardson
    value of 30 and 60 elements (Hermite elements, h⁴) within 2e-8.
    """
    g = gamma * EI / (RHOA * L**3)  # +z pulls the free end away from the foot: tension
    ref = heavy_column_hz(gamma)
    still = heavy_column_hz(0.0)
    assert abs(ref[0] / still[0] - 1) > 0.25
    bending30 = column(tmp_path, 30).frequencies([0.0], gravity=[0, 0, g], n_modes=3)
    bending60 = column(tmp_path, 60).frequencies([0.0], gravity=[0, 0, g], n_modes=3)
    assert bending60 == pytest.approx(ref, rel=3e-7)
    richardson = bending60 + (bending60 - bending30) / 15.0
    assert richardson == pytest.approx(ref, rel=2e-8)


def test_spatial_column_has_the_pairs_and_the_same_frequencies(tmp_path):
    """Spatial column (circular section): each bending frequency twice, as planar (1e-8: the
    preloaded solve is the nodal pencil, whose rounding is about ε λ_max/λ_1)."""
    g = -3.0 * EI / (RHOA * L**3)
    fs = column(tmp_path, 12, planar=False).frequencies([0.0], gravity=[0, 0, g], n_modes=4)
    fp = column(tmp_path, 12).frequencies([0.0], gravity=[0, 0, g], n_modes=2)
    assert fs == pytest.approx(np.repeat(fp, 2), rel=1e-8)


def test_standing_column_buckles_at_greenhills_load(tmp_path):
    """Just below ``q L³/EI = 7.83735`` mode 1 nearly vanishes; just above: PreloadBuckles."""
    model = column(tmp_path, 30)
    crit = 7.83735 * EI / (RHOA * L**3)
    f0 = model.frequencies([0.0], n_modes=1)[0]
    near = model.frequencies([0.0], gravity=[0, 0, -0.999 * crit], n_modes=1)[0]
    assert near < 0.05 * f0
    with pytest.raises(PreloadBuckles, match="unstable"):
        model.frequencies([0.0], gravity=[0, 0, -1.001 * crit])


def test_modes_carry_the_preload_and_agree_with_the_dynamics(tmp_path):
    """``modes()`` records the preload; its frequencies equal ``frequencies()`` and the moving
    arm's ``modes_at_speed`` at rest (the same geometric stiffness), to 1e-8 (nodal pencils
    solved by different routines)."""
    from pinflex.dynamics import ErlsDynamics
    from pinflex.dynamics.modes import modes_at_speed

    model = column(tmp_path, 16)
    g = [0.0, 0.0, -20.0]
    res = model.modes([0.0], gravity=g, n_modes=3)
    assert res.preload == Preload((0.0, 0.0, -20.0))
    assert "preload: gravity (0, 0, -20)" in repr(res)
    assert res.freq_hz == pytest.approx(model.frequencies([0.0], gravity=g, n_modes=3),
                                        rel=1e-8)
    dyn = modes_at_speed(ErlsDynamics(model, gravity=g), [0.0], n_modes=3)
    assert res.freq_hz == pytest.approx(dyn.freq_hz, rel=1e-8)


# ---------------------------------------------------------------- (b) payload at the tip


@pytest.mark.parametrize("p, gamma", [(1.5, 0.0), (-1.5, 0.0), (-1.0, -2.0)])
def test_tip_force_matches_the_loaded_column(tmp_path, p, gamma):
    """A dead tip force ``P L²/EI = ±1.5`` (and with the weight): shooting, within 3e-7.

    Compression 1.5 is 61 % of Euler's tip-load column ``π²/4``.
    """
    P = p * EI / L**2
    g = gamma * EI / (RHOA * L**3)
    model = column(tmp_path, 60)
    f = model.frequencies([0.0], gravity=[0, 0, g] if gamma else None,
                          loads=[PointForce("beam", (0.0, 0.0, L), (0.0, 0.0, P))], n_modes=3)
    assert f == pytest.approx(heavy_column_hz(gamma, p), rel=3e-7)


def test_tip_force_buckles_at_eulers_load(tmp_path):
    """Compression ``P L²/EI`` just above ``π²/4`` buckles the column; just below it stands."""
    model = column(tmp_path, 30)
    crit = math.pi**2 / 4 * EI / L**2
    tip = (0.0, 0.0, L)
    near = model.frequencies([0.0], loads=[PointForce("beam", tip, (0, 0, -0.999 * crit))],
                             n_modes=1)[0]
    assert near < 0.05 * model.frequencies([0.0], n_modes=1)[0]
    with pytest.raises(PreloadBuckles):
        model.frequencies([0.0], loads=[PointForce("beam", tip, (0, 0, -1.001 * crit))])


BAR = """<link name="bar"><inertial><origin xyz="0 0 {d}"/><mass value="{m}"/>
    <inertia ixx="1e-12" iyy="1e-12" izz="1e-12" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="wrist" type="revolute"><parent link="beam"/><child link="bar"/>
    <origin xyz="0 0 {L}" rpy="0 0 0.4"/><axis xyz="0 1 0"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/></joint>
"""


@pytest.mark.parametrize("gamma", [3.0, -2.0])
@pytest.mark.parametrize("carrier", ["point mass", "rigid link"])
def test_tip_mass_on_a_rigid_lever(tmp_path, gamma, carrier):
    """A mass ``0.5 ρA L`` on a rigid bar ``0.3 L`` beyond the tip, hanging (γ = 3) and
    standing (γ = −2): the weight's lever on the tip rotation (``½ M g d θ²``) and the bar's
    end force. Carried as a point mass off the beam's end, or as a rigid link on a locked,
    turned joint (spatial); 40 elements, within 5e-7 of the shooting solution."""
    mu, delta = 0.5, 0.3
    m, d = mu * RHOA * L, delta * L
    text = COLUMN.format(n=40, L=L, rhoA=RHOA, I=EI / 7e10, J=2 * EI / 7e10)
    if carrier == "point mass":
        extra = f'<pinflex:point_mass name="tip" link="beam" xyz="0 0 {L + d}" mass="{m}"/>'
    else:
        extra = BAR.format(d=d, m=m, L=L)
    path = tmp_path / "lever.urdf"
    path.write_text(text.replace("</robot>", extra + "</robot>"))
    said = (pytest.warns(PlausibilityWarning, match="rigid lever") if carrier == "point mass"
            else contextlib.nullcontext())
    with said:
        model = FlexibleModel(path, joints="locked", planar=carrier == "point mass")
    g = gamma * EI / (RHOA * L**3)
    f = model.frequencies(np.zeros(model.nv), gravity=[0, 0, g], n_modes=6)
    f = f[:3] if carrier == "point mass" else f[::2]  # spatial: each bending mode twice
    ref = heavy_column_hz(gamma, mu * gamma, mu=mu, delta=delta)
    assert f == pytest.approx(ref, rel=5e-7)
    no_lever = heavy_column_hz(gamma, 0.0, mu=mu, delta=delta)  # the bar's weight left out
    assert np.abs(ref / no_lever - 1).max() > 0.02


TWO = """<?xml version="1.0"?>
<robot name="two" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="a"/><link name="b"/>
  <joint name="foot" type="revolute"><parent link="base"/><child link="a"/>
    <origin xyz="0 0 0"/><axis xyz="1 0 0"/><limit lower="-9" upper="9" effort="1" velocity="1"/>
  </joint>
  <joint name="mid" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0 0 {h}" rpy="0 0 0.7"/><axis xyz="0.6 0.8 0"/>
    <limit lower="-9" upper="9" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="a" elements="10" tip="0 0 {h}">
    <pinflex:material E="7e10" linear_density="{rhoA}"/>
    <pinflex:section A="1e-4" Iy="{I}" Iz="{I}" J="{J}"/></pinflex:flexible>
  <pinflex:flexible link="b" elements="10" tip="0 0 {h}">
    <pinflex:material E="7e10" linear_density="{rhoA}"/>
    <pinflex:section A="1e-4" Iy="{I}" Iz="{I}" J="{J}"/></pinflex:flexible>
  {joints}
</robot>
"""


@pytest.mark.parametrize("g", [15.0, -15.0])
def test_two_beams_on_a_locked_joint_equal_one_column(tmp_path, g):
    """Two beams joined by a locked (turned, tilted-axis) joint are one column: the same
    preloaded frequencies as the 20-element column, 2e-9; a stiff spring (1e9 N m/rad) at the
    joint approaches them (1e-5). The child turns about the joint's displaced point (ERLS
    turns it about the undeformed one: 9 % off on mode 1 without that term)."""
    fmt = dict(h=L / 2, rhoA=RHOA, I=EI / 7e10, J=2 * EI / 7e10)
    path = tmp_path / "two.urdf"
    path.write_text(TWO.format(joints="", **fmt))
    locked = FlexibleModel(path, joints="locked")
    path.write_text(TWO.format(joints='<pinflex:joint name="foot" locked="true"/>'
                               '<pinflex:joint name="mid" stiffness="1e9"/>', **fmt))
    with pytest.warns(PinflexWarning, match="lose about"):
        sprung = FlexibleModel(path)
    ref = column(tmp_path, 20, planar=False).frequencies([0.0], gravity=[0, 0, g], n_modes=6)
    assert locked.frequencies([0, 0], gravity=[0, 0, g], n_modes=6) == pytest.approx(
        ref, rel=2e-9)
    assert sprung.frequencies([0, 0], gravity=[0, 0, g], n_modes=6) == pytest.approx(
        ref, rel=1e-5)


# ---------------------------------------------------------------- (c) spring-held pendulum

PENDULUM = """<?xml version="1.0"?>
<robot name="pendulum" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/>
  <link name="arm"><inertial><origin xyz="{c[0]} {c[1]} {c[2]}"/><mass value="{m}"/>
    <inertia ixx="{Ic}" iyy="{Ic}" izz="{Ic}" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <joint name="hinge" type="revolute"><parent link="base"/><child link="arm"/>
    <origin xyz="0 0 0" rpy="{rpy[0]} {rpy[1]} {rpy[2]}"/><axis xyz="1 0 0"/>
    <limit lower="-10" upper="10" effort="1" velocity="1"/></joint>
  {joint}
</robot>
"""


def rpy_matrix(r, p, y):
    """URDF's fixed-axis roll-pitch-yaw rotation ``Rz(y) Ry(p) Rx(r)``."""
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


@pytest.mark.parametrize("below", [True, False])
def test_spring_held_pendulum_matches_its_closed_form(tmp_path, below):
    """A rigid link on a torsional spring ``k`` (tilted axis): ``ω² = (k + V'') / I``.

    ``V'' = m (g·c − (g·a)(a·c))`` is the weight's stiffness about the axis ``a`` (world) of a
    centre of mass at ``c``, ``I = I_c + m (|c|² − (a·c)²)``; hanging (``V'' > 0``) it rises,
    standing it falls. Within 1e-9.
    """
    m, Ic, k, length = 2.0, 0.01, 30.0, 0.5
    rpy = (0.3, 0.2, 0.1)
    R = rpy_matrix(*rpy)
    c_link = np.array([0.0, 0.1, -length if below else length])
    path = tmp_path / "pendulum.urdf"
    path.write_text(PENDULUM.format(c=c_link, m=m, Ic=Ic, rpy=rpy,
                                    joint=f'<pinflex:joint name="hinge" stiffness="{k}"/>'))
    model = FlexibleModel(path)
    g = np.array([0.0, 0.0, -9.81])
    a, c = R @ np.array([1.0, 0.0, 0.0]), R @ c_link
    V2 = m * (g @ c - (g @ a) * (a @ c))
    inertia = Ic + m * (c @ c - (a @ c) ** 2)
    expected = math.sqrt((k + V2) / inertia) / (2 * math.pi)
    plain = math.sqrt(k / inertia) / (2 * math.pi)
    f = model.frequencies([0.0], gravity=g)
    assert f[0] == pytest.approx(expected, rel=1e-9)
    assert (f[0] > plain) == below and abs(f[0] / plain - 1) > 0.1
    assert model.frequencies([0.0])[0] == pytest.approx(plain, rel=1e-12)


def test_free_joint_under_load_is_refused(tmp_path):
    """A free joint loaded by the weight: PreloadNotInEquilibrium names it and the remedy; a
    free joint the weight leaves neutral (vertical axis) keeps its rigid mode."""
    model = column(tmp_path, 4, joints="free")
    with pytest.raises(PreloadNotInEquilibrium, match=r"'foot'.*N m.*[Ll]ock"):
        model.frequencies([0.2], gravity=[0, 0, -9.81])
    with pytest.raises(PreloadNotInEquilibrium):  # in equilibrium, but the weight loads it
        model.frequencies([0.0], gravity=[0, 0, -9.81])
    ur5 = FlexibleModel("urdf/ur5_flexible.xml", joints={
        "shoulder_lift_joint": "locked", "elbow_joint": "locked", "wrist_1_joint": "locked",
        "wrist_2_joint": "locked", "wrist_3_joint": "locked"})
    assert ur5.n_rigid == 1  # the pan joint's axis is vertical
    with pytest.warns(PreloadBendingWarning, match="upper_arm_link"):
        f = ur5.frequencies([0.3, -1, 1.2, -0.5, 0.4, 0.2], gravity=[0, 0, -9.81], n_modes=3)
    assert np.all(f > 0)


# ---------------------------------------------------------------- spatial arm, design, batch

Q_UR5 = np.array([0.3, -1.0, 1.2, -0.5, 0.4, 0.2])


def test_zero_preload_equals_the_plain_modes_on_the_ur5_overlay():
    """On example-robot-data's UR5 overlay (locked joints), a preload of zero gravity equals
    the nodal pencil of ``matrices()`` and the conditioned solve to 1e-10 (the rounding of the
    nodal pencil on 72 elastic coordinates)."""
    import scipy.linalg

    model = FlexibleModel("urdf/ur5_flexible.xml", joints="locked")
    f = model.frequencies(Q_UR5, gravity=[0, 0, 0], n_modes=6)
    M, K = model.matrices(Q_UR5)
    lam = scipy.linalg.eigh(K, M, eigvals_only=True)[:6]
    assert f == pytest.approx(np.sqrt(lam) / (2 * math.pi), rel=1e-10)
    assert f == pytest.approx(model.frequencies(Q_UR5, n_modes=6), rel=1e-10)


@pytest.mark.parametrize("arm", ["ur5", "slider"])
def test_joint_terms_equal_pinocchios_gravity_and_its_derivatives(arm):
    """The generalized static load on the joints and its Hessian equal Pinocchio's generalized
    gravity and ``computeGeneralizedGravityDerivatives`` of the same inertias (1e-12, 1e-9):
    the UR5 overlay, and a prismatic-revolute arm with tilted joints (tests/arms.py)."""
    from arms import PRISMATIC

    from pinflex.description import parse
    from pinflex.erls import preload as pl

    if arm == "ur5":
        model, q = FlexibleModel("urdf/ur5_flexible.xml", joints="locked"), Q_UR5
    else:
        model, q = FlexibleModel(parse(PRISMATIC), joints="locked"), np.array([0.2, 0.7, -0.4])
    groups = pl.static_loads(model, Preload((0.0, 0.0, -9.81)), model.y0)
    H, F = pl.preload_hessian(model, groups, q, None)
    rigid = model.effective_model()
    data = rigid.createData()
    rigid.gravity.linear = np.array([0.0, 0.0, -9.81])
    qp = model.pin_configuration(q)
    grav = pin.computeGeneralizedGravity(rigid, data, qp)
    dgrav = pin.computeGeneralizedGravityDerivatives(rigid, data, qp)
    nx = model.nx
    assert np.abs(F[nx:] + grav).max() < 1e-12 * np.abs(grav).max()
    assert np.abs(H[nx:, nx:] - dgrav).max() < 1e-9 * np.abs(dgrav).max()
    assert np.array_equal(H, H.T)


def test_batched_poses_springs_and_design_values():
    """Kinova overlay on its servo springs: poses batched = one by one; a design value given
    as ``y`` = the model ``with_values`` (1e-9, two assemblies through the nodal pencil);
    gravity shifts the modes."""
    model = FlexibleModel("urdf/kinova_tubes.xml")
    assert {c.kind for c in model.joint_conditions} == {"spring"}
    rng = np.random.default_rng(3)
    Q = rng.uniform(-1.0, 1.0, (3, model.nv))
    g = [0.0, 0.0, -9.81]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", PreloadBendingWarning)  # asserted elsewhere
        batch = model.frequencies(Q, gravity=g, n_modes=4)
        for q, row in zip(Q, batch):
            assert row == pytest.approx(model.frequencies(q, gravity=g, n_modes=4), rel=1e-12)
        assert np.abs(batch / model.frequencies(Q, n_modes=4) - 1).max() > 1e-4
    d = next(d for d in model.design if d.kind == "parameter")
    value = 0.5 * (d.nominal + d.upper)
    y = model.y0.copy()
    y[model.design_names.index(d.name)] = value
    moved = model.with_values({d.name: value})
    with pytest.warns(PreloadBendingWarning):
        ours = model.frequencies(Q[0], y, gravity=g, n_modes=4)
    with pytest.warns(PreloadBendingWarning):
        assert ours == pytest.approx(moved.frequencies(Q[0], gravity=g, n_modes=4), rel=1e-9)


def test_bent_links_are_named_and_columns_are_not(tmp_path):
    """A preload across a link (a tilted column) warns with the link and its share of load
    across the axis; along the axis (the upright column) it does not."""
    model = column(tmp_path, 6)
    with warnings.catch_warnings():
        warnings.simplefilter("error", PreloadBendingWarning)
        model.frequencies([0.0], gravity=[0, 0, -9.81])
    g = 9.81 * np.array([0.0, math.sin(0.3), -math.cos(0.3)])  # 0.3 rad off the axis
    with pytest.warns(PreloadBendingWarning, match=r"'beam' \(30%\)"):
        model.frequencies([0.0], gravity=g)


def test_preload_arguments_are_checked(tmp_path):
    """Bad gravity, unknown links, both forms at once: named errors."""
    model = column(tmp_path, 4)
    with pytest.raises(ConfigurationError, match="3 finite numbers"):
        model.frequencies([0.0], gravity=[0, 9.81])
    with pytest.raises(ConfigurationError, match="either"):
        model.frequencies([0.0], gravity=[0, 0, -9.81], preload=Preload())
    from pinflex.exceptions import LinkNotFound

    with pytest.raises(LinkNotFound):
        model.frequencies([0.0], loads=[PointForce("nowhere", (0, 0, 0), (0, 0, 1))])


# ---------------------------------------------------------------- command line


def test_cli_gravity_records_the_preload(tmp_path, capsys):
    """``pinflex modes ARM --gravity`` (9.81 along −z) prints and records the preload; it
    equals the API; free joints under load exit 2 with the remedy."""
    model = column(tmp_path, 8)
    path = str(tmp_path / "column8.urdf")
    assert main(["modes", path, "--joints", "locked", "--planar", "--gravity", "--json",
                 "--modes", "2"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["preload"] == {"gravity_m_s2": [0.0, 0.0, -9.81], "forces": []}
    assert out["frequencies_hz"] == pytest.approx(
        model.frequencies([0.0], gravity=[0, 0, -9.81], n_modes=2), rel=1e-12)
    assert main(["modes", path, "--joints", "locked", "--planar", "--gravity", "0", "0", "5",
                 "--modes", "1"]) == 0
    assert "preload: gravity (0, 0, 5) m/s^2" in capsys.readouterr().out
    assert main(["modes", path, "--joints", "free", "--q", "0.3", "--gravity"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "lock" in err.lower()
    assert main(["modes", path, "--gravity", "1", "2"]) == 2
    assert "three values" in capsys.readouterr().err

