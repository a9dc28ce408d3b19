"""Lumped arms (pinflex/lumped/model.py) against formulas written here without pinflex."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla
from conftest import TWO_LINK, single_link_urdf
from reference_fe import cantilever_hz, planar_two_link_frequencies

from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.lumped import LinkSegments, build, equal_lumped, layout_of

EI = 69e9 * 3.97e-8
RHOA = 1.9
LENGTHS = (0.6, 0.45)
TIP_MASS = 0.125


def planar_chain_mass(q_abs, stations, masses=(TIP_MASS, TIP_MASS)):
    """Mass matrix of benchmark A as rigid segments, from the kinetic energy (no pinflex).

    Coordinates: base angle, link-1 hinges, elbow angle, link-2 hinges (relative angles).
    Bodies: uniform segments (mass rhoA l, inertia rhoA l^3/12 about z) and point masses at
    the link tips. M = sum_b m_b Jv^T Jv + I_b Jw^T Jw.
    """
    dofs = []          # (position of the joint) filled per pose
    bodies = []        # (mass, inertia, com, index of the last dof moving it)
    angle = 0.0
    origin = np.zeros(2)
    for link, (L, st, q) in enumerate(zip(LENGTHS, stations, q_abs)):
        angle = q  # absolute link angle at its root (hinges at rest)
        e = np.array([math.cos(angle), math.sin(angle)])
        dofs.append(origin.copy())
        bounds = np.concatenate([[0.0], st, [L]])
        for j in range(len(bounds) - 1):
            if j > 0:
                dofs.append(origin + bounds[j] * e)
            length = bounds[j + 1] - bounds[j]
            com = origin + 0.5 * (bounds[j] + bounds[j + 1]) * e
            bodies.append((RHOA * length, RHOA * length**3 / 12.0, com, len(dofs) - 1))
        tip = origin + L * e
        bodies.append((masses[link], 0.0, tip, len(dofs) - 1))
        origin = tip
    n = len(dofs)
    M = np.zeros((n, n))
    for mass, inertia, com, last in bodies:
        Jv = np.zeros((2, n))
        Jw = np.zeros(n)
        for k in range(last + 1):
            r = com - dofs[k]
            Jv[:, k] = (-r[1], r[0])
            Jw[k] = 1.0
        M += mass * Jv.T @ Jv + inertia * np.outer(Jw, Jw)
    return M


def naive_hinges(n):
    """Stations and k = EI/l of n equal segments per link."""
    st = [np.linspace(0.0, L, n + 1)[1:-1] for L in LENGTHS]
    k = [np.full(n - 1, EI * n / L) for L in LENGTHS]
    return st, k


def chain_frequencies(M, k_list):
    """Elastic frequencies with the two joints free (condensed), k per hinge in dof order."""
    n1 = len(k_list[0])
    K = np.diag(np.concatenate([[0.0], k_list[0], [0.0], k_list[1]]))
    free = np.zeros(M.shape[0], dtype=bool)
    free[[0, n1 + 1]] = True
    e = ~free
    Mc = M[np.ix_(e, e)] - M[np.ix_(e, free)] @ np.linalg.solve(M[np.ix_(free, free)],
                                                               M[np.ix_(free, e)])
    lam = sla.eigh(K[np.ix_(e, e)], Mc, eigvals_only=True)
    return np.sqrt(lam) / (2 * np.pi)


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(TWO_LINK, planar=True)


def test_mass_matrix_equals_the_kinetic_energy_of_rigid_segments(arm):
    """CRBA of the lumped model equals the segments' kinetic energy at an uneven pose."""
    layout = layout_of(arm)
    stations = [np.array([0.05, 0.31, 0.5]), np.array([0.11, 0.2, 0.43])]
    segs = {link: LinkSegments(link, L, st, np.ones((1, 3)), ("bz",))
            for link, L, st in zip(("link1", "link2"), LENGTHS, stations)}
    lumped = build(layout, segs)
    q_abs = np.array([0.7, 2.1])  # the file's absolute angles
    M = lumped.mass_matrix(q_abs)
    ref = planar_chain_mass(q_abs, stations)
    np.testing.assert_allclose(M, ref, rtol=0, atol=1e-13 * np.abs(ref).max())


def test_naive_chain_is_the_textbook_chain_and_misses_the_global_fe(arm):
    """K = EI/l on 4 equal segments: 0.117 % / 0.247 % below the global FE of the same mesh."""
    lumped = equal_lumped(layout_of(arm), 4, naive=True)
    st, k = naive_hinges(4)
    f_ref = chain_frequencies(planar_chain_mass([0.0, 0.0], st), k)
    np.testing.assert_allclose(lumped.frequencies([0.0, 0.0]), f_ref, rtol=1e-11)
    fe = planar_two_link_frequencies([0.0, 0.0], TIP_MASS, TIP_MASS)[1]
    err = f_ref[:2] / fe[:2] - 1.0
    np.testing.assert_allclose(err, [-1.1659e-3, -2.4686e-3], atol=2e-7)


@pytest.mark.parametrize("n", [8, 16, 32])
def test_equal_segments_converge_to_the_cantilever_at_second_order(n):
    """A clamped bar as n equal segments (law with c = 1): mode-1 error falls as 1/n^2."""
    bar = FlexibleModel(parse(single_link_urdf(elements=8)), planar=True, joints="locked")
    EIz, rhoA = 2.0e11 * 1.0e-9, 7800.0 * 1.0e-4
    exact = cantilever_hz(1.0, EIz, rhoA, 2)
    errs = []
    for m in (n, 2 * n):
        f = equal_lumped(layout_of(bar), m, naive=False).frequencies([0.0], "own")[:2]
        errs.append(abs(f[0] / exact[0] - 1.0))
    order = math.log2(errs[0] / errs[1])
    assert 1.8 < order < 2.2, (errs, order)


def test_a_rigid_body_on_a_beam_rides_on_its_segment():
    """A <pinflex:body> at a clamped rod's tip: in the lumped arm's mass, fitted to the ERLS modes.

    The joint's inertia of the straight lumped rod (hinges at rest) equals the closed form
    rhoA L^3/3 + m L^2 + J_z, and the fitted frequencies (joint free and locked) the ERLS
    model's, which carries the body. Runs where the description supports bodies.
    """
    from pinflex.description import parse
    from pinflex.lumped import fit_lumped

    L, d, E, rho, mass, J = 0.6, 0.02, 70e9, 2700.0, 0.5, 2e-3
    text = f"""<robot name="tip" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="rod"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="rod"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="rod" elements="32" tip="{L} 0 0" normal="0 0 1">
    <pinflex:material E="{E}" density="{rho}"/>
    <pinflex:section shape="solid_circle" diameter="{d}"/></pinflex:flexible>
  <pinflex:body name="tool" link="rod" xyz="{L} 0 0" mass="{mass}"
                ixx="{J / 2}" iyy="{J / 2}" izz="{J}"/>
</robot>"""
    from pinflex.exceptions import PinflexError

    try:
        rod = FlexibleModel(parse(text), planar=True)
    except PinflexError as exc:  # a build without <pinflex:body>
        if "pinflex:body" not in str(exc):
            raise
        pytest.skip(f"no <pinflex:body> in this build: {exc}")
    if not getattr(rod.plan, "bodies", ()):
        pytest.skip("no <pinflex:body> in this build")
    fit = fit_lumped(rod, 4, poses=[0.4])
    M = fit.lumped.mass_matrix([0.4])
    i = fit.lumped.arm_index[0]
    np.testing.assert_allclose(M[i, i], rho * np.pi * d**2 / 4 * L**3 / 3 + mass * L**2 + J,
                               rtol=1e-12)
    assert fit.worst_error < 1e-8 and fit.compliance_error < 1e-6
