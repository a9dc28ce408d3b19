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
from conditioning_cases import (
    A_AT,
    ARM3_CASES,
    CASES,
    D_CANT,
    EI_A,
    LENGTHS,
    MESHES,
    MODULI,
    Q3,
    RATIOS,
    RHOA_A,
    arm3_reference,
    arm3_urdf,
    cantilever,
    case,
    chain,
    circle,
    richardson,
)

import pinflex.exceptions as pex
from pinflex.description import parse
from pinflex.erls import FlexibleModel

# the named warning that says an answer is not the asked model's (a spring treated as free)
_ACCURACY_WARNINGS = (pex.SoftSpringWarning,)


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


def _check_chain(name, n):
    text, joints, y, segments, points, root = case(name, n)
    model = FlexibleModel(parse(text), planar=True, joints=joints)
    ref = planar_chain_hz(segments, points, root, 3, omega_max=4000.0)
    f, g = _both(model, np.zeros(model.nv), y)
    return f, g, ref


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
@pytest.mark.parametrize("name", CASES)
def test_1024_elements_with_spring_lock_or_section_match_continuous_beam(name):
    """1024 elements on a link: within 1e-8 of the continuous beam (the mesh limit)."""
    f, g, ref = _check_chain(name, 1024)
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)


# ---------------------------------------------------------------------------------------
# A bent spatial three-link arm against the extended-precision Richardson limit
# ---------------------------------------------------------------------------------------


def _arm3_check(name, n2):
    joints, ref_kw, area = ARM3_CASES[name]
    meshes = (4, 8, 16)
    vals = np.array([arm3_reference(Q3, (4, m, 4), **ref_kw) for m in meshes])
    limit = richardson(meshes, vals)[0]
    model = FlexibleModel(parse(arm3_urdf((4, n2, 4), area)), joints=joints)
    y = np.array([A_AT]) if area else None
    f, g = _both(model, Q3, y)
    return f, g, limit


@pytest.mark.parametrize("name", list(ARM3_CASES))
def test_bent_spatial_arm_refined_link_matches_extended_precision_limit(name):
    """256 elements on link 2 of a bent spatial arm: within 1e-8 of the Richardson limit.

    On the nodal-coordinate path: 1.3e-6 (spring), and modes() differed from frequencies().
    """
    f, g, limit = _arm3_check(name, 256)
    assert _rel(f, limit) < 1e-8, (f, limit)
    assert _rel(g, limit) < 1e-8, (g, limit)


@pytest.mark.slow
@pytest.mark.parametrize("name", list(ARM3_CASES))
def test_1024_elements_on_a_spatial_link_match_extended_precision_limit(name):
    """The Done-means case: 1024 elements on a link with a spring, a lock or a parameter."""
    f, g, limit = _arm3_check(name, 1024)
    assert _rel(f, limit) < 1e-8, (f, limit)
    assert _rel(g, limit) < 1e-8, (g, limit)


def test_extended_precision_reference_is_converged():
    """The reference limit does not depend on the meshes it is extrapolated from (~1e-10)."""
    joints, ref_kw, _ = ARM3_CASES["spring"]
    vals = {m: arm3_reference(Q3, (4, m, 4), **ref_kw) for m in (4, 6, 8, 12, 16)}
    a = richardson((4, 8, 16), [vals[m] for m in (4, 8, 16)])[0]
    b = richardson((6, 12, 16), [vals[m] for m in (6, 12, 16)])[0]
    assert _rel(a, b) < 1e-9


# ---------------------------------------------------------------------------------------
# Extreme cantilevers: clamped root, tip mass
# ---------------------------------------------------------------------------------------


def _extreme(L, E, ratio, n):
    """'ok', 'refused' or 'warned' (by name), else an AssertionError saying what is wrong."""
    text, ref = cantilever(L, E, ratio, n)
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
    named = [w for w in caught if issubclass(w.category, _ACCURACY_WARNINGS)]
    assert np.all(np.isfinite(f)) and np.all(np.isfinite(g)), (f, g)
    if named:
        return "warned"
    assert _rel(f, ref) <= 1e-6, ("frequencies", f, ref)
    assert _rel(g, ref) <= 1e-6, ("modes", g, ref)
    return "ok"


def test_cantilever_mesh_reference_matches_continuous_beam():
    """The inverse-form mesh reference converges to the transfer-matrix closed form."""
    A, I = circle(D_CANT)  # noqa: E741
    rhoA = 7800.0 * A
    for ratio in (0.0, 1.0, 1e3, 1e6):
        tip = ratio * rhoA
        ref = planar_chain_hz([Segment(1.0, 2e11 * I, rhoA, 2e11 * A)], [Point(mass=tip)],
                              "clamped", 3, omega_max=5e4, omega_min=1e-6)
        mesh = cantilever_mesh_hz(1.0, 2e11 * I, 2e11 * A, rhoA, 256, tip)
        assert _rel(mesh, ref) < 5e-9


@pytest.mark.parametrize("ratio", RATIOS)
@pytest.mark.parametrize("L", (1e-3, 1.0, 100.0))
def test_extreme_cantilevers_right_or_refused_by_name(L, ratio):
    """Tip/beam mass 0-1e6, L 1 mm-100 m, E 1e6 and 1e12, 4-256 elements: ≤ 1e-6 or named.

    On the nodal path a tip/beam ratio of 1e6 at 64 elements was 37 % off, NaN at 256
    (numpy RuntimeWarning only).
    """
    for E in (1e6, 1e12):
        for n in (4, 64, 256):
            _extreme(L, E, ratio, n)


@pytest.mark.slow
def test_all_480_extreme_cantilevers_right_or_refused_by_name():
    """The full set: 6 lengths × 4 moduli × 4 mass ratios × 5 meshes.

    Every answer within 1e-6 (no accuracy warning needed); the only refusals are the 1 mm
    bars, whose 5 mm section is wider than the link (ImplausibleValue).
    """
    outcome: dict[tuple[str, bool], int] = {}
    for L in LENGTHS:
        for E in MODULI:
            for ratio in RATIOS:
                for n in MESHES:
                    key = (_extreme(L, E, ratio, n), L == 1e-3)
                    outcome[key] = outcome.get(key, 0) + 1
    assert outcome == {("ok", False): 400, ("refused", True): 80}, outcome


# ---------------------------------------------------------------------------------------
# modes() equals frequencies() on every joint condition
# ---------------------------------------------------------------------------------------

_SPATIAL_JOINTS = [
    "free", "locked", {"j1": 50.0}, {"j2": 2000.0, "j3": "locked"},
    {"j1": "locked", "j2": 1e-6}, {"j3": 1e8}, {"j1": 300.0, "j2": 300.0, "j3": 300.0},
]


@pytest.mark.parametrize("joints", _SPATIAL_JOINTS, ids=str)
def test_modes_equal_frequencies_on_every_joint_condition(joints):
    """One solve for both: the lowest six modes agree to 1e-10 at 96 elements on link 2."""
    model = FlexibleModel(parse(arm3_urdf((8, 96, 8))), joints=joints)
    for q in (Q3, np.array([-2.0, 0.3, 2.5])):
        f, g = _both(model, q, k=6)
        assert _rel(g, f) < 1e-10, (g, f)
        assert model.modes(q).freq_hz.size == model.n_elastic


def test_modes_equal_frequencies_with_a_section_parameter_and_springs():
    """Design parameter off its nominal value, with a spring and a lock."""
    model = FlexibleModel(parse(arm3_urdf((8, 96, 8), area_param=True)),
                          joints={"j1": 700.0, "j3": "locked"})
    f, g = _both(model, Q3, np.array([A_AT]), k=6)
    assert _rel(g, f) < 1e-10, (g, f)


# ---------------------------------------------------------------------------------------
# Soft springs
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("k", [1e-8, 1e-6, 1e-4, 1e-2, 1.0, 100.0])
def test_soft_root_spring_resolved_against_closed_form(k):
    """A bar on a root spring k: its spring mode (≈ √(3k/ρAL³)) and the next two, 1e-8.

    k = 1e-8 N m/rad was refused as 'not restrained', 1e-4 was 0.3-11 % off.
    """
    model = FlexibleModel(parse(chain([1.0], [128])), planar=True, joints={"j0": k})
    ref = bending_hz([Segment(1.0, EI_A, RHOA_A)], [None], k, 3, omega_max=1000.0,
                     omega_min=1e-8)
    assert abs(ref[0] / (math.sqrt(3 * k / RHOA_A) / (2 * math.pi)) - 1) < 1e-3 + k / EI_A
    f, g = _both(model, np.zeros(1))
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)


@pytest.mark.parametrize("k", [1e-8, 1e-3])
def test_soft_elbow_spring_on_a_flexible_parent(k):
    """Clamped link 1, soft spring at the elbow to link 2: all three modes to 1e-8."""
    model = FlexibleModel(parse(chain([0.6, 0.4], [96, 64])), planar=True,
                          joints={"j0": "locked", "j1": k})
    segs = [Segment(0.6, EI_A, RHOA_A), Segment(0.4, EI_A, RHOA_A)]
    ref = bending_hz(segs, [Point(hinge=k), None], "clamped", 3, omega_max=2000.0,
                     omega_min=1e-8)
    f, g = _both(model, np.zeros(2))
    assert _rel(f, ref) < 1e-8, (f, ref)
    assert _rel(g, ref) < 1e-8, (g, ref)


def test_spring_below_the_threshold_is_a_free_joint_with_a_warning():
    """A spring too soft to matter (k = 1e-30 N m/rad): free joint, said by name."""
    free = FlexibleModel(parse(chain([1.0], [64])), planar=True)
    with pytest.warns(pex.SoftSpringWarning, match="treated as a free joint"):
        soft = FlexibleModel(parse(chain([1.0], [64])), planar=True, joints={"j0": 1e-30})
    assert soft.n_rigid == 1
    np.testing.assert_allclose(soft.frequencies(np.zeros(1)), free.frequencies(np.zeros(1)),
                               rtol=1e-13)


# ---------------------------------------------------------------------------------------
# No false cluster on fine meshes
# ---------------------------------------------------------------------------------------


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


# ---------------------------------------------------------------------------------------
# Taylor expansion on a soft spring
# ---------------------------------------------------------------------------------------


@pytest.mark.parametrize("k", [1e-8, 1e-4])
def test_taylor_expansion_on_a_soft_elbow_spring(k):
    """expand() with a soft elbow spring: right at and near its expansion point.

    The expansion's solver pencil put the spring's huge μ first and left its highest modes
    unresolved; the nodal fallback then gave the spring mode 0.86 % off (k = 1e-4 N m/rad)
    or a negative eigenvalue and a ValueError (k ≤ 1e-6). Reference: the transfer-matrix
    chain (pinned root, hinge spring) at the straight pose; the exact model beside it.
    """
    from pinflex.parametric import expand

    model = FlexibleModel(parse(chain([0.6, 0.4], [96, 64])), planar=True, joints={"j1": k})
    segs = [Segment(0.6, EI_A, RHOA_A, 2e7), Segment(0.4, EI_A, RHOA_A, 2e7)]
    ref = planar_chain_hz(segs, [Point(hinge=k), None], "pinned", 3, omega_max=2000.0,
                          omega_min=1e-8)
    tm = expand(model, np.zeros(2), order=4, modes=(1, 2, 3))
    f0 = tm.evaluate(np.zeros((1, 2)), quantity="freq_hz").ravel()
    assert _rel(f0, model.frequencies(np.zeros(2), n_modes=3)) < 1e-8  # 2e-9 at k = 1e-4
    assert _rel(f0, ref) < 2e-8, (f0, ref)  # the mesh error of mode 3: 1.1e-8
    q = np.array([[0.0, 0.02]])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", pex.TaylorRadiusWarning)
        g = tm.evaluate(q, quantity="freq_hz").ravel()
    assert _rel(g, model.frequencies(q[0], n_modes=3)) < 1e-8  # truncation (0.02)⁵: 2.5e-9


def test_expansion_point_disagreeing_with_the_exact_solve_is_refused(monkeypatch):
    """A Taylor model whose first coefficient is off the exact solve is refused by name.

    Fault injected: the expansion's mass jets scaled by 1 + 1e-4 (a consistent pencil, so the
    eigenpair checks of the recursion pass; only the comparison with the exact solve sees it).
    """
    from pinflex.parametric import expand, expansion

    model = FlexibleModel(parse(chain([0.6, 0.4], [8, 8])), planar=True, joints={"j1": 50.0})
    expand(model, np.zeros(2), order=2, modes=(1,))  # fine as it is
    real = expansion.reduced_solver_jets

    def off(*args, **kwargs):
        space, rspace, keep, M, K, jidx, didx = real(*args, **kwargs)
        return space, rspace, keep, M * (1.0 + 1e-4), K, jidx, didx

    monkeypatch.setattr(expansion, "reduced_solver_jets", off)
    with pytest.raises(pex.EigenSolverError, match="differs from the exact modal solve"):
        expand(model, np.zeros(2), order=2, modes=(1,))
