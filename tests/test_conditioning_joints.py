"""Springs, locks and section parameters on fine meshes: right or refused, one answer.

The references are written here or in the tests' own modules, with no pinflex code:

* straight beam chains against the transfer-matrix solution of the continuous beam
  (``beam_closed_forms``): a root or elbow spring, a locked root or elbow, a section
  parameter; 256 elements per link by default, 1024 in the slow variants (the mesh error of
  the lowest three modes is then below 2e-9, so the continuous frequency is the mesh limit);
* a bent spatial three-link arm against the Richardson limit (4, 8, 16 elements on the
  refined link, h⁴ and h⁶ terms) of the global spatial frame assembled in extended
  precision (``reference_fe.spatial_frame_frequencies_extended``, good to ~1e-10);
* clamped cantilevers with a tip mass, over lengths, moduli, mass ratios and meshes, against
  the same mesh solved from its exact flexibility in inverse form;
* soft springs against the transfer-matrix spring mode (``≈ √(k/J)``) and the free joint.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
from beam_closed_forms import Point, Segment, bending_hz, cantilever_mesh_hz, planar_chain_hz
from reference_fe import Beam, spatial_frame_frequencies_extended
from test_global_fe import _rot, _rpy

import pinflex.exceptions as pex
from pinflex.description import parse
from pinflex.erls import FlexibleModel

# named warnings that say a number has fewer digits than asked (or a spring treated as free)
_ACCURACY_WARNINGS = tuple(
    c for c in (getattr(pex, "ConditioningWarning", None), getattr(pex, "SoftSpringWarning", None))
    if c is not None
)

STEEL = dict(E=2.0e11, G=8.0e10, density=7800.0)

# Springs, locks and section parameters still take the nodal-coordinate pencil, whose low modes
# lose digits like ε·λmax/λ1 as the mesh is refined: these tests record where (strict: a fix
# turns them into failures until the mark is removed).
NODAL = pytest.mark.xfail(strict=True, reason="springs, locks and section parameters are still "
                          "solved on the nodal-coordinate pencil")
SOFT = pytest.mark.xfail(strict=True, reason="no stated threshold below which a spring is free")
CLUSTER = pytest.mark.xfail(strict=True, reason="the cluster test's absolute tolerance scales "
                            "with the largest eigenvalue of the mesh")


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


def _chain(lengths, elements, *, sec=SEC_A, params="", extra=""):
    """Straight links along x on revolute joints about z (planar bending in x-y)."""
    names = [f"l{i}" for i in range(len(lengths))]
    links = "".join(f'<link name="{n}"/>' for n in names)
    joints = _joint("j0", "base", names[0])
    for i in range(1, len(lengths)):
        joints += _joint(f"j{i}", names[i - 1], names[i], lengths[i - 1])
    flex = "".join(_flex(n, e, L, sec) for n, e, L in zip(names, elements, lengths))
    return (f'<robot name="chain" xmlns:pinflex="urn:pinflex:urdf:1"><link name="base"/>{links}'
            f"{joints}{params}{flex}{extra}</robot>")


def _both(model, q, y=None, k=3):
    """``frequencies()`` and ``modes()`` at one pose (no numpy RuntimeWarning allowed)."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        f = model.frequencies(q, y, n_modes=k)
        g = model.modes(q, y, n_modes=k).freq_hz
    return f, g


def _rel(a, b):
    return float(np.max(np.abs(np.asarray(a) / np.asarray(b) - 1.0)))


# ---------------------------------------------------------------------------------------
# Straight chains against the continuous beam
# ---------------------------------------------------------------------------------------

D_NOM, D_AT = 0.012, 0.0155  # diameter parameter: nominal and the value analysed


def _circle(d):
    return math.pi * d**2 / 4.0, math.pi * d**4 / 64.0


def _case(name, n):
    """(urdf text, joints, design values or None, reference segments, points, root)."""
    seg = lambda L: Segment(L, EI_A, RHOA_A, EA_A)  # noqa: E731
    if name == "root spring":
        return _chain([1.0], [n]), {"j0": 2000.0}, None, [seg(1.0)], [None], 2000.0
    if name == "root lock":
        return _chain([1.0], [n]), "locked", None, [seg(1.0)], [None], "clamped"
    if name == "elbow spring":
        return (_chain([0.6, 0.4], [n, n // 2]), {"j0": "locked", "j1": 2000.0}, None,
                [seg(0.6), seg(0.4)], [Point(hinge=2000.0), None], "clamped")
    if name == "elbow lock":
        return (_chain([0.6, 0.4], [n // 2, n]), {"j1": "locked"}, None,
                [seg(0.6), seg(0.4)], [Point(), None], "pinned")
    if name == "section parameter":
        params = (f'<pinflex:parameter name="d" value="{D_NOM!r}" lower="0.005" upper="0.03" '
                  'design="true"/>')
        text = _chain([1.0], [n], sec='shape="solid_circle" diameter="{d}"', params=params,
                      extra='<pinflex:point_mass name="tip" link="l0" xyz="1 0 0" mass="0.3"/>')
        A, I = _circle(D_AT)
        s = Segment(1.0, STEEL["E"] * I, STEEL["density"] * A, STEEL["E"] * A)
        return text, "free", np.array([D_AT]), [s], [Point(mass=0.3)], "pinned"
    raise AssertionError(name)


CASES = ["root spring", "root lock", "elbow spring", "elbow lock", "section parameter"]


def _check_chain(name, n):
    text, joints, y, segments, points, root = _case(name, n)
    model = FlexibleModel(parse(text), planar=True, joints=joints)
    ref = planar_chain_hz(segments, points, root, 3, omega_max=4000.0)
    f, g = _both(model, np.zeros(model.nv), y)
    return f, g, ref


@NODAL
@pytest.mark.parametrize("name", CASES)
def test_fine_mesh_with_spring_lock_or_section_matches_continuous_beam(name):
    """256 elements: the lowest three modes within 1e-8 of the transfer-matrix solution.

    On the nodal-coordinate path these were 2e-6 (root spring) to 1e-5 off, and modes()
    disagreed with frequencies().
    """
    f, g, ref = _check_chain(name, 256)
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)
    assert _rel(g, f) < 1e-11


@pytest.mark.slow
@NODAL
@pytest.mark.parametrize("name", CASES)
def test_1024_elements_with_spring_lock_or_section_match_continuous_beam(name):
    """1024 elements on a link: within 1e-8 of the continuous beam (the mesh limit)."""
    f, g, ref = _check_chain(name, 1024)
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)


# ---------------------------------------------------------------------------------------
# A bent spatial three-link arm against the extended-precision Richardson limit
# ---------------------------------------------------------------------------------------

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


def _arm3_urdf(n, area_param=False):
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


def _arm3_reference(q, n, *, springs=None, fixed=(), area2=None):
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


def _richardson(meshes, values):
    """Limit of f(h) = f0 + a h⁴ + b h⁶ through three meshes (Hermite cubics: O(h⁴))."""
    h = 1.0 / np.asarray(meshes, dtype=float)
    A = np.column_stack([np.ones(3), h**4, h**6])
    return np.linalg.solve(A, np.asarray(values))


ARM3_CASES = {
    "spring": ({"j2": 2000.0}, dict(springs={1: 2000.0}), False),
    "lock": ({"j3": "locked"}, dict(fixed=(3,)), False),
    "area parameter": ("free", dict(area2=A_AT), True),
}


def _arm3_check(name, n2):
    joints, ref_kw, area = ARM3_CASES[name]
    meshes = (4, 8, 16)
    vals = np.array([_arm3_reference(Q3, (4, m, 4), **ref_kw) for m in meshes])
    limit = _richardson(meshes, vals)[0]
    model = FlexibleModel(parse(_arm3_urdf((4, n2, 4), area)), joints=joints)
    y = np.array([A_AT]) if area else None
    f, g = _both(model, Q3, y)
    return f, g, limit


@NODAL
@pytest.mark.parametrize("name", list(ARM3_CASES))
def test_bent_spatial_arm_refined_link_matches_extended_precision_limit(name):
    """256 elements on link 2 of a bent spatial arm: within 1e-8 of the Richardson limit.

    On the nodal-coordinate path: 1.3e-6 (spring), and modes() differed from frequencies().
    """
    f, g, limit = _arm3_check(name, 256)
    assert _rel(f, limit) < 1e-8, (f, limit)
    assert _rel(g, limit) < 1e-8, (g, limit)


@pytest.mark.slow
@NODAL
@pytest.mark.parametrize("name", list(ARM3_CASES))
def test_1024_elements_on_a_spatial_link_match_extended_precision_limit(name):
    """The Done-means case: 1024 elements on a link with a spring, a lock or a parameter."""
    f, g, limit = _arm3_check(name, 1024)
    assert _rel(f, limit) < 1e-8, (f, limit)
    assert _rel(g, limit) < 1e-8, (g, limit)


def test_extended_precision_reference_is_converged():
    """The reference limit does not depend on the meshes it is extrapolated from (~1e-10)."""
    joints, ref_kw, _ = ARM3_CASES["spring"]
    vals = {m: _arm3_reference(Q3, (4, m, 4), **ref_kw) for m in (4, 6, 8, 12, 16)}
    a = _richardson((4, 8, 16), [vals[m] for m in (4, 8, 16)])[0]
    b = _richardson((6, 12, 16), [vals[m] for m in (6, 12, 16)])[0]
    assert _rel(a, b) < 1e-9


# ---------------------------------------------------------------------------------------
# Extreme cantilevers: clamped root, tip mass
# ---------------------------------------------------------------------------------------

D_CANT = 0.01  # solid circle diameter [m]


def _cantilever(L, E, ratio, n):
    A, I = _circle(D_CANT)
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


def _extreme(L, E, ratio, n):
    """'ok', 'refused' or 'warned' (by name), else an AssertionError saying what is wrong."""
    text, ref = _cantilever(L, E, ratio, n)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            model = FlexibleModel(parse(text), planar=True, joints="locked")
            k = ref.size
            f = model.frequencies(np.zeros(1), n_modes=k)
            g = model.modes(np.zeros(1), n_modes=k).freq_hz
        except pex.PinflexError:
            return "refused"
    numpy_warnings = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    assert not numpy_warnings, [str(w.message) for w in numpy_warnings]
    named = [w for w in caught if _ACCURACY_WARNINGS and issubclass(w.category,
                                                                     _ACCURACY_WARNINGS)]
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(g)), (f, g)
    if named:
        return "warned"
    assert _rel(f, ref) <= 1e-6, ("frequencies", f, ref)
    assert _rel(g, ref) <= 1e-6, ("modes", g, ref)
    return "ok"


def test_cantilever_mesh_reference_matches_continuous_beam():
    """The inverse-form mesh reference converges to the transfer-matrix closed form."""
    A, I = _circle(D_CANT)
    rhoA = 7800.0 * A
    for ratio in (0.0, 1.0, 1e3, 1e6):
        tip = ratio * rhoA
        ref = planar_chain_hz([Segment(1.0, 2e11 * I, rhoA, 2e11 * A)], [Point(mass=tip)],
                              "clamped", 3, omega_max=5e4, omega_min=1e-6)
        mesh = cantilever_mesh_hz(1.0, 2e11 * I, 2e11 * A, rhoA, 256, tip)
        assert _rel(mesh, ref) < 5e-9


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("L", (1e-3, pytest.param(1.0, marks=NODAL),
                               pytest.param(100.0, marks=NODAL)))
def test_extreme_cantilevers_right_or_refused_by_name(L, ratio):
    """Tip/beam mass 0-1e6, L 1 mm-100 m, E 1e6 and 1e12, 4-256 elements: ≤ 1e-6 or named.

    On the nodal path a tip/beam ratio of 1e6 at 64 elements was 37 % off, NaN at 256
    (numpy RuntimeWarning only).
    """
    for E in (1e6, 1e12):
        for n in (4, 64, 256):
            _extreme(L, E, ratio, n)


@pytest.mark.slow
@NODAL
def test_all_480_extreme_cantilevers_right_or_refused_by_name():
    """The full set: 6 lengths × 4 moduli × 4 mass ratios × 5 meshes."""
    outcome: dict[str, int] = {}
    for L in LENGTHS:
        for E in MODULI:
            for ratio in RATIOS:
                for n in MESHES:
                    r = _extreme(L, E, ratio, n)
                    outcome[r] = outcome.get(r, 0) + 1
    assert sum(outcome.values()) == 480
    assert outcome.get("ok", 0) >= 400, outcome


# ---------------------------------------------------------------------------------------
# modes() equals frequencies() on every joint condition
# ---------------------------------------------------------------------------------------

_SPATIAL_JOINTS = [
    "free", "locked", {"j1": 50.0}, {"j2": 2000.0, "j3": "locked"},
    {"j1": "locked", "j2": 1e-6}, {"j3": 1e8}, {"j1": 300.0, "j2": 300.0, "j3": 300.0},
]


@pytest.mark.parametrize("joints", ["free"] + [pytest.param(j, marks=NODAL)
                                              for j in _SPATIAL_JOINTS[1:]], ids=str)
def test_modes_equal_frequencies_on_every_joint_condition(joints):
    """One solve for both: the lowest six modes agree to 1e-10 at 96 elements on link 2."""
    model = FlexibleModel(parse(_arm3_urdf((8, 96, 8))), joints=joints)
    for q in (Q3, np.array([-2.0, 0.3, 2.5])):
        f, g = _both(model, q, k=6)
        assert _rel(g, f) < 1e-10, (g, f)
        assert model.modes(q).freq_hz.size == model.n_elastic


@NODAL
def test_modes_equal_frequencies_with_a_section_parameter_and_springs():
    """Design parameter off its nominal value, with a spring and a lock."""
    model = FlexibleModel(parse(_arm3_urdf((8, 96, 8), area_param=True)),
                          joints={"j1": 700.0, "j3": "locked"})
    f, g = _both(model, Q3, np.array([A_AT]), k=6)
    assert _rel(g, f) < 1e-10, (g, f)


# ---------------------------------------------------------------------------------------
# Soft springs
# ---------------------------------------------------------------------------------------


@NODAL
@pytest.mark.parametrize("k", [1e-8, 1e-6, 1e-4, 1e-2, 1.0, 100.0])
def test_soft_root_spring_resolved_against_closed_form(k):
    """A bar on a root spring k: its spring mode (≈ √(3k/ρAL³)) and the next two, 1e-8.

    k = 1e-8 N m/rad was refused as 'not restrained', 1e-4 was 0.3-11 % off.
    """
    model = FlexibleModel(parse(_chain([1.0], [128])), planar=True, joints={"j0": k})
    ref = bending_hz([Segment(1.0, EI_A, RHOA_A)], [None], k, 3, omega_max=1000.0,
                     omega_min=1e-8)
    assert abs(ref[0] / (math.sqrt(3 * k / RHOA_A) / (2 * math.pi)) - 1) < 1e-3 + k / EI_A
    f, g = _both(model, np.zeros(1))
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)


@NODAL
@pytest.mark.parametrize("k", [1e-8, 1e-3])
def test_soft_elbow_spring_on_a_flexible_parent(k):
    """Clamped link 1, soft spring at the elbow to link 2: all three modes to 1e-8."""
    model = FlexibleModel(parse(_chain([0.6, 0.4], [96, 64])), planar=True,
                          joints={"j0": "locked", "j1": k})
    segs = [Segment(0.6, EI_A, RHOA_A), Segment(0.4, EI_A, RHOA_A)]
    ref = bending_hz(segs, [Point(hinge=k), None], "clamped", 3, omega_max=2000.0,
                     omega_min=1e-8)
    f, g = _both(model, np.zeros(2))
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)


@SOFT
def test_spring_below_the_threshold_is_a_free_joint_with_a_warning():
    """A spring too soft to matter (k = 1e-30 N m/rad): free joint, said by name."""
    free = FlexibleModel(parse(_chain([1.0], [64])), planar=True)
    with pytest.warns(pex.PinflexWarning, match="free"):
        soft = FlexibleModel(parse(_chain([1.0], [64])), planar=True, joints={"j0": 1e-30})
    assert soft.n_rigid == 1
    np.testing.assert_allclose(soft.frequencies(np.zeros(1)), free.frequencies(np.zeros(1)),
                               rtol=1e-13)


# ---------------------------------------------------------------------------------------
# No false cluster on fine meshes
# ---------------------------------------------------------------------------------------


@CLUSTER
def test_no_false_repeated_eigenvalue_on_a_fine_mesh():
    """Benchmark A, 224 + 224 elements (1346 dof): modes 1 and 2 (4.9x apart) expand.

    The cluster test used an absolute tolerance of 100 n ε max|λ| (λ_max ≈ 1e17 here), which
    put 0, 0, 1.47e6 and 7.19e6 rad²/s² in one cluster.
    """
    from conftest import TWO_LINK

    from pinflex.parametric import expand

    text = TWO_LINK.read_text().replace('link="link1" elements="4"', 'link="link1" elements="224"')
    text = text.replace('link="link2" elements="3"', 'link="link2" elements="224"')
    model = FlexibleModel(parse(text), planar=True)
    assert model.ndof == 1346
    q = np.array([1.817, 5.312])
    tm = expand(model, q, order=2, modes=(1, 2))
    f = model.frequencies(q, n_modes=2)
    np.testing.assert_allclose(tm.evaluate(q[None], quantity="freq_hz").ravel(), f, rtol=1e-10)
