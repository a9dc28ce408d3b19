"""Small arms shared by several test files (URDF text and their independent references)."""

from __future__ import annotations

import numpy as np
import reference_fe as ref
from reference_fe import Beam, spatial_frame_frequencies

from pinflex.trajectory import Trajectory


def two_link(section1, section2, *, params="", material='E="69e9" density="2687"',
             extra="", joints=""):
    """Benchmark A's geometry with the given sections, parameters and extras."""
    return f"""<robot name="tubes" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="link2"/><link name="tool"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <joint name="q2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="0.6 0 0"/><axis xyz="0 0 1"/>
    <limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="link2"/><child link="tool"/>
    <origin xyz="0.45 0 0"/></joint>
  <pinflex:coordinates convention="absolute"/>
  {params}
  <pinflex:flexible link="link1" elements="4" normal="0 0 1">
    <pinflex:material {material}/><pinflex:section {section1}/></pinflex:flexible>
  <pinflex:flexible link="link2" elements="3" normal="0 0 1">
    <pinflex:material {material}/><pinflex:section {section2}/></pinflex:flexible>
  {extra}{joints}
</robot>"""


PRISMATIC = """<robot name="slider" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="carriage"><inertial><origin xyz="0 0 0.05"/><mass value="2"/>
    <inertia ixx="0.01" ixy="0" ixz="0" iyy="0.02" iyz="0" izz="0.015"/></inertial></link>
  <link name="arm"/><link name="fore"/>
  <joint name="s" type="prismatic"><parent link="base"/><child link="carriage"/>
    <origin xyz="0.1 0 0" rpy="0.2 0 0"/><axis xyz="1 0 0"/>
    <limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <joint name="r" type="revolute"><parent link="carriage"/><child link="arm"/>
    <origin xyz="0 0.05 0.1" rpy="0 0.3 0"/><axis xyz="0 0 1"/>
    <limit lower="-4" upper="4" effort="1" velocity="1"/></joint>
  <joint name="e" type="revolute"><parent link="arm"/><child link="fore"/>
    <origin xyz="0.5 0 0" rpy="0.4 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-4" upper="4" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="arm" elements="3" tip="0.5 0 0" normal="0 0 1">
    <pinflex:material E="7e10" density="2700"/>
    <pinflex:section shape="rectangle" width="0.02" height="0.03"/></pinflex:flexible>
  <pinflex:flexible link="fore" elements="2" tip="0.4 0 0" normal="0 1 0">
    <pinflex:material E="7e10" density="2700"/>
    <pinflex:section shape="hollow_circle" outer_diameter="0.03" inner_diameter="0.02"/>
  </pinflex:flexible>
  <pinflex:point_mass name="tool" link="fore" xyz="0.4 0 0.02" mass="0.3"
     design="true" lower="0" upper="1"/>
</robot>"""


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


def spatial_urdf(m1, m2, e1=5, e2=4):
    """A skewed spatial two-link arm (unequal sections, point masses m1, m2 at the tips)."""
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


def spatial_reference(q, m1, m2, e1=5, e2=4, *, springs=None, elbow=None):
    """Frequencies of :func:`spatial_urdf` at q from the global 3-D frame model."""
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


def move(q_start, q_end, duration, n=41, t0=0.0):
    """Minimum-jerk joint motion (rest to rest) sampled at n points."""
    t = np.linspace(0.0, duration, n)
    s = t / duration
    h = 10 * s**3 - 15 * s**4 + 6 * s**5
    q = np.asarray(q_start)[None] + h[:, None] * (np.asarray(q_end) - np.asarray(q_start))[None]
    return Trajectory(t + t0, q, ("q1", "q2"))


def locked_global_fe(q_abs, m1, m2):
    """Global FE of benchmark A with the base clamped and the elbow welded (independent)."""
    K, M = ref.planar_two_link_matrices(q_abs, m1, m2)
    n = K.shape[0]
    T = np.zeros((n, n - 2))
    keep = [i for i in range(n) if i not in (0, 13)]
    for col, i in enumerate(keep):
        T[i, col] = 1.0
    T[13, keep.index(12)] = 1.0  # link-2 rotation at the elbow = link-1 rotation there
    return T.T @ K @ T, T.T @ M @ T, keep


def tubes_alone(path):
    """The description of an overlay without the rigid bodies its beam links keep of the
    URDF inertia (motors, flanges): the tubes alone, as ``inertia="beam-only"``."""
    import dataclasses

    from pinflex.description import load

    return dataclasses.replace(load(path), bodies=())


#: Hamza-Cherif and Houmat (24th ICAS Congress, 2004), Table 2: a rotating cantilever of
#: slenderness ratio L √(A / I) = 70, no hub: dimensionless flapwise and chordwise frequencies
#: ω √(ρA L⁴ / EI) at dimensionless speeds γ = Ω √(ρA L⁴ / EI).
FLAPWISE = {2: 4.1373, 4: 5.5850, 6: 7.3603, 8: 9.2568, 10: 11.2023, 50: 51.0805}
CHORDWISE = {2: 3.6195, 4: 3.888, 6: 4.2393, 8: 4.6105, 10: 4.97, 50: 7.3362}


def table_close(value, ref):
    """Within the table's last printed digit (half a unit) plus 2e-4 relative."""
    digits = len(str(ref).split(".")[1])
    return abs(value - ref) <= 0.5 * 10.0**-digits + 2e-4 * ref


def rotating_cantilever(folder, urdf_text):
    """The table's beam (square 10 mm aluminium bar, slenderness 70) on the hub of ``urdf_text``.

    ``urdf_text`` is the spin-up beam's description (:data:`pinflex.cases.spin_up.KANE_URDF`).

    Returns:
        ``(chord, flap, T)``: an in-plane description of 40 elements (chordwise modes, axial
        stretching and Coriolis coupling), a spatial one of 20 elements (flapwise modes) and
        the time scale ``T = √(ρA L⁴ / EI)`` [s].
    """
    import math
    from pathlib import Path

    W = 0.01
    A, inertia = W * W, W**4 / 12
    L = 70.0 * math.sqrt(inertia / A)
    E, rho = 70e9, 2700.0
    text = urdf_text.replace(
        '<pinflex:material E="7e10" linear_density="1.2"/>',
        f'<pinflex:material E="{E}" G="{E / 2.6}" density="{rho}"/>').replace(
        '<pinflex:section A="2e-4" Iy="2e-7" Iz="2e-7" J="4e-7"/>',
        f'<pinflex:section shape="rectangle" width="{W}" height="{W}"/>')
    chord, flap = Path(folder) / "chord.urdf", Path(folder) / "flap.urdf"
    chord.write_text(text.replace('elements="10" normal="0 0 1" tip="10 0 0"',
                                  f'elements="40" normal="0 0 1" tip="{L} 0 0"'))
    flap.write_text(text.replace('elements="10" normal="0 0 1" tip="10 0 0"',
                                 f'elements="20" tip="{L} 0 0"'))
    return chord, flap, math.sqrt(rho * A * L**4 / (E * inertia))
