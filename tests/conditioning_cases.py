"""Arms, beams and references of the conditioning tests and of benchmarks/bench_conditioning.py.

Straight chains of steel bars on revolute joints (planar bending, closed forms in
``beam_closed_forms``), a bent spatial three-link arm (its extended-precision global frame in
``reference_fe``) and clamped cantilevers with a tip mass. No pinflex code: URDF text and
references only.
"""

from __future__ import annotations

import math

import numpy as np
from arms import _rot, _rpy
from beam_closed_forms import Point, Segment, cantilever_mesh_hz
from reference_fe import Beam, spatial_frame_frequencies_extended

STEEL = dict(E=2.0e11, G=8.0e10, density=7800.0)


def _flex(link, n, L, sec, mat=STEEL, normal="0 0 1"):
    return (f'<pinflex:flexible link="{link}" elements="{n}" tip="{L!r} 0 0" normal="{normal}">'
            f'<pinflex:material E="{mat["E"]!r}" G="{mat["G"]!r}" density="{mat["density"]!r}"/>'
            f"<pinflex:section {sec}/></pinflex:flexible>")


def _joint(name, parent, child, x=0.0):
    return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
            f'<child link="{child}"/><origin xyz="{x!r} 0 0"/><axis xyz="0 0 1"/>'
            '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>')


SEC_A = 'A="1e-4" Iy="2e-9" Iz="1e-9" J="1.5e-9"'  # EI (in plane) = 200 N m², ρA = 0.78 kg/m
EI_A, RHOA_A, EA_A = 200.0, 0.78, 2.0e7


def chain(lengths, elements, *, sec=SEC_A, params="", extra=""):
    """Straight links along x on revolute joints about z (planar bending in x-y)."""
    names = [f"l{i}" for i in range(len(lengths))]
    links = "".join(f'<link name="{n}"/>' for n in names)
    joints = _joint("j0", "base", names[0])
    for i in range(1, len(lengths)):
        joints += _joint(f"j{i}", names[i - 1], names[i], lengths[i - 1])
    flex = "".join(_flex(n, e, L, sec) for n, e, L in zip(names, elements, lengths))
    return (f'<robot name="chain" xmlns:pinflex="urn:pinflex:urdf:1"><link name="base"/>{links}'
            f"{joints}{params}{flex}{extra}</robot>")


D_NOM, D_AT = 0.012, 0.0155  # diameter parameter: nominal and the value analysed


def circle(d):
    """Area and second moment of a solid circle of diameter ``d``."""
    return math.pi * d**2 / 4.0, math.pi * d**4 / 64.0


def case(name, n):
    """(urdf text, joints, design values or None, reference segments, points, root)."""
    seg = lambda L: Segment(L, EI_A, RHOA_A, EA_A)  # noqa: E731
    if name == "root spring":
        return chain([1.0], [n]), {"j0": 2000.0}, None, [seg(1.0)], [None], 2000.0
    if name == "root lock":
        return chain([1.0], [n]), "locked", None, [seg(1.0)], [None], "clamped"
    if name == "elbow spring":
        return (chain([0.6, 0.4], [n, n // 2]), {"j0": "locked", "j1": 2000.0}, None,
                [seg(0.6), seg(0.4)], [Point(hinge=2000.0), None], "clamped")
    if name == "elbow lock":
        return (chain([0.6, 0.4], [n // 2, n]), {"j1": "locked"}, None,
                [seg(0.6), seg(0.4)], [Point(), None], "pinned")
    if name == "section parameter":
        params = (f'<pinflex:parameter name="d" value="{D_NOM!r}" lower="0.005" upper="0.03" '
                  'design="true"/>')
        text = chain([1.0], [n], sec='shape="solid_circle" diameter="{d}"', params=params,
                      extra='<pinflex:point_mass name="tip" link="l0" xyz="1 0 0" mass="0.3"/>')
        A, I = circle(D_AT)  # noqa: E741
        s = Segment(1.0, STEEL["E"] * I, STEEL["density"] * A, STEEL["E"] * A)
        return text, "free", np.array([D_AT]), [s], [Point(mass=0.3)], "pinned"
    raise AssertionError(name)


CASES = ["root spring", "root lock", "elbow spring", "elbow lock", "section parameter"]


ARM = dict(
    t1=np.array([0.5, 0.1, 0.3]), n1=np.array([0.0, 0.0, 1.0]),
    rpy2=(0.3, -0.4, 0.7), a2=np.array([0.3, 1.0, 0.2]),
    t2=np.array([0.4, -0.2, 0.1]), n2=np.array([0.0, 1.0, 0.0]),
    rpy3=(-0.5, 0.2, 0.4), a3=np.array([1.0, 0.2, -0.3]),
    t3=np.array([0.3, 0.15, -0.1]), n3=np.array([0.0, 0.0, 1.0]),
)
SECS = [dict(E=7e10, G=2.6e10, density=2700.0, A=3e-4, Iy=2.5e-9, Iz=1.1e-8, J=4e-9),
        dict(E=2e11, G=8e10, density=7800.0, A=1e-4, Iy=1.2e-9, Iz=0.6e-9, J=1.1e-9),
        dict(E=7e10, G=2.6e10, density=2700.0, A=2e-4, Iy=1.5e-9, Iz=2.0e-9, J=2.5e-9)]
MASSES = (0.3, 0.2, 0.1)
Q3 = np.array([0.4, -1.1, 0.8])
A_NOM, A_AT = 1e-4, 1.3e-4  # area parameter of link 2: nominal and the value analysed


def _vec(v):
    return " ".join(repr(float(x)) for x in v)


def arm3_urdf(n, area_param=False):
    """The bent spatial three-link arm, ``n`` elements per link, optionally an area parameter."""
    s = ARM

    def flex(link, n, tip, normal, sec, area=None):
        A = sec["A"] if area is None else area
        return (f'<pinflex:flexible link="{link}" elements="{n}" tip="{_vec(tip)}" '
                f'normal="{_vec(normal)}"><pinflex:material E="{sec["E"]}" G="{sec["G"]}" '
                f'density="{sec["density"]}"/><pinflex:section A="{A}" Iy="{sec["Iy"]}" '
                f'Iz="{sec["Iz"]}" J="{sec["J"]}"/></pinflex:flexible>')

    def joint(name, parent, child, origin, rpy, axis):
        a = axis / np.linalg.norm(axis)
        return (f'<joint name="{name}" type="revolute"><parent link="{parent}"/>'
                f'<child link="{child}"/><origin xyz="{_vec(origin)}" rpy="{_vec(rpy)}"/>'
                f'<axis xyz="{_vec(a)}"/><limit lower="-9" upper="9" effort="1" velocity="1"/>'
                "</joint>")

    param = (f'<pinflex:parameter name="a2" value="{A_NOM!r}" lower="5e-5" upper="2e-4" '
             'design="true"/>' if area_param else "")
    masses = "".join(
        f'<pinflex:point_mass name="m{i + 1}" link="l{i + 1}" xyz="{_vec(s[f"t{i + 1}"])}" '
        f'mass="{MASSES[i]}"/>' for i in range(3))
    return f"""<robot name="arm3" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="l1"/><link name="l2"/><link name="l3"/>
  {joint("j1", "base", "l1", np.zeros(3), (0.0, 0.0, 0.0), np.array([0.0, 0.0, 1.0]))}
  {joint("j2", "l1", "l2", s["t1"], s["rpy2"], s["a2"])}
  {joint("j3", "l2", "l3", s["t2"], s["rpy3"], s["a3"])}
  {param}
  {flex("l1", n[0], s["t1"], s["n1"], SECS[0])}
  {flex("l2", n[1], s["t2"], s["n2"], SECS[1], "{a2}" if area_param else None)}
  {flex("l3", n[2], s["t3"], s["n3"], SECS[2])}
  {masses}
</robot>"""


def arm3_reference(q, n, *, springs=None, fixed=(), area2=None):
    """Elastic frequencies of the global frame in extended precision (mesh n per link)."""
    s = ARM
    a2 = s["a2"] / np.linalg.norm(s["a2"])
    a3 = s["a3"] / np.linalg.norm(s["a3"])
    R1 = _rot([0, 0, 1], q[0])
    p1 = R1 @ s["t1"]
    Rj2 = R1 @ _rpy(*s["rpy2"])
    R2 = Rj2 @ _rot(a2, q[1])
    p2 = p1 + R2 @ s["t2"]
    Rj3 = R2 @ _rpy(*s["rpy3"])
    R3 = Rj3 @ _rot(a3, q[2])
    p3 = p2 + R3 @ s["t3"]

    def beam(sec, n, R, tip, normal, area=None):
        A = sec["A"] if area is None else area
        x = tip / np.linalg.norm(tip)
        z = normal - x * (normal @ x)
        return Beam(EA=sec["E"] * A, GJ=sec["G"] * sec["J"], EIy=sec["E"] * sec["Iy"],
                    EIz=sec["E"] * sec["Iz"], rhoA=sec["density"] * A,
                    rho_Ip=sec["density"] * (sec["Iy"] + sec["Iz"]), n_elements=n,
                    vecxz=tuple(R @ (z / np.linalg.norm(z))))

    beams = [beam(SECS[0], n[0], R1, s["t1"], s["n1"]),
             beam(SECS[1], n[1], R2, s["t2"], s["n2"], area2),
             beam(SECS[2], n[2], R3, s["t3"], s["n3"])]
    joints = ["fixed" if 2 in fixed else Rj2 @ a2, "fixed" if 3 in fixed else Rj3 @ a3]
    base = "fixed" if 1 in fixed else np.array([0.0, 0.0, 1.0])
    return spatial_frame_frequencies_extended(
        np.array([np.zeros(3), p1, p2, p3]), beams, joints,
        point_masses=[(p1, MASSES[0]), (p2, MASSES[1]), (p3, MASSES[2])], base=base,
        springs=springs, n_modes=3)


def richardson(meshes, values):
    """Limit of f(h) = f0 + a h⁴ + b h⁶ through three meshes (Hermite cubics: O(h⁴))."""
    h = 1.0 / np.asarray(meshes, dtype=float)
    A = np.column_stack([np.ones(3), h**4, h**6])
    return np.linalg.solve(A, np.asarray(values))


ARM3_CASES = {
    "spring": ({"j2": 2000.0}, dict(springs={1: 2000.0}), False),
    "lock": ({"j3": "locked"}, dict(fixed=(3,)), False),
    "area parameter": ("free", dict(area2=A_AT), True),
}


D_CANT = 0.01  # solid circle diameter [m]


def cantilever(L, E, ratio, n):
    """A clamped steel-section bar with a tip mass: (URDF text, same-mesh reference [Hz])."""
    A, I = circle(D_CANT)  # noqa: E741
    rhoA = 7800.0 * A
    tip = ratio * rhoA * L
    sec = f'A="{A!r}" Iy="{I!r}" Iz="{I!r}" J="{2 * I!r}"'
    mat = dict(E=E, G=E / 2.6, density=7800.0)
    text = (f'<robot name="cantilever" xmlns:pinflex="urn:pinflex:urdf:1"><link name="base"/>'
            f'<link name="bar"/>{_joint("j", "base", "bar")}{_flex("bar", n, L, sec, mat)}'
            f'<pinflex:point_mass name="tip" link="bar" xyz="{L!r} 0 0" mass="{tip!r}"/>'
            "</robot>")
    ref = cantilever_mesh_hz(L, E * I, E * A, rhoA, n, tip, n=min(3, 3 * n))
    return text, ref


LENGTHS = (1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0)
MODULI = (1e6, 1e8, 1e10, 1e12)
RATIOS = (0.0, 1.0, 1e3, 1e6)
MESHES = (1, 4, 16, 64, 256)


