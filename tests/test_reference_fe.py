"""Self-checks of the independent finite-element references in ``reference_fe``.

These tests check the references alone, against closed forms and against each other, so
that the pinflex tests can trust them.
"""

import math

import numpy as np
import pytest
import scipy.linalg
from reference_fe import (
    RIGID_RTOL,
    Beam,
    axial_fixed_free_hz,
    cantilever_hz,
    euler_bernoulli_roots,
    pinned_free_hz,
    planar_chain_matrices,
    planar_two_link_frequencies,
    planar_two_link_matrices,
    solve_frequencies,
    spatial_frame_frequencies,
    spatial_frame_model,
    torsion_fixed_free_hz,
)

# Benchmark A (SPEC §5): solid aluminium rod, 30 mm diameter.
E_AL, G_AL = 69e9, 26e9
AREA, I_AL = 7.07e-4, 3.97e-8
RHOA_AL = 1.9
RHO_AL = RHOA_AL / AREA
Q0_ABS = (1.817, 5.312)

# A steel bar with a 20 mm x 10 mm rectangular section (width along local y).
E_ST, G_ST, RHO_ST = 210e9, 81e9, 7850.0
B_ST, H_ST = 0.02, 0.01
IZ_ST = H_ST * B_ST**3 / 12  # bending about local z: deflection along local y
IY_ST = B_ST * H_ST**3 / 12  # bending about local y: deflection along local z
J_ST = 0.229 * B_ST * H_ST**3  # Saint-Venant constant for b/h = 2 (any positive value works)
IP_ST = IY_ST + IZ_ST


def steel_beam(n_elements, vecxz=None):
    """The steel test bar as a spatial :class:`Beam`."""
    return Beam(
        EA=E_ST * B_ST * H_ST,
        GJ=G_ST * J_ST,
        EIy=E_ST * IY_ST,
        EIz=E_ST * IZ_ST,
        rhoA=RHO_ST * B_ST * H_ST,
        rho_Ip=RHO_ST * IP_ST,
        n_elements=n_elements,
        vecxz=vecxz,
    )


def rod_fe_hz(L, stiffness, inertia, n_elements, kappa):
    """Exact eigenfrequencies [Hz] of a uniform linear-element rod, consistent mass.

    Modes sin(kappa x) or cos(kappa x) sampled at the nodes satisfy the discrete equations
    exactly for fixed–free (kappa = (2k-1) pi / 2L) and free–free (kappa = k pi / L)
    rods: omega^2 = 6 c^2 / h^2 (1 - cos kappa h) / (2 + cos kappa h), c^2 = stiffness/inertia.
    """
    h = L / n_elements
    ch = np.cos(np.asarray(kappa) * h)
    return np.sqrt(6 * stiffness / inertia / h**2 * (1 - ch) / (2 + ch)) / (2 * math.pi)


def nearest(values, targets):
    """Indices of the entries of ``values`` nearest to each target, and relative errors."""
    values = np.asarray(values)
    idx = np.array([int(np.argmin(np.abs(values - t))) for t in targets])
    return idx, values[idx] / np.asarray(targets) - 1


def rotation(axis, angle):
    """Rotation matrix of ``angle`` [rad] about ``axis`` (Rodrigues)."""
    a = np.asarray(axis, float) / np.linalg.norm(axis)
    k = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(angle) * k + (1 - math.cos(angle)) * k @ k


# --- closed forms -----------------------------------------------------------------------


def test_beam_roots_match_published_tables():
    """The bracketed roots reproduce the published βL values of SPEC §6 to six decimals."""
    np.testing.assert_allclose(
        euler_bernoulli_roots("cantilever", 5),
        [1.875104, 4.694091, 7.854757, 10.995541, 14.137168],
        atol=5e-7,
    )
    np.testing.assert_allclose(
        euler_bernoulli_roots("pinned-free", 3), [3.926602, 7.068583, 10.210176], atol=5e-7
    )
    np.testing.assert_allclose(
        euler_bernoulli_roots("clamped-clamped", 3), [4.730041, 7.853205, 10.995608], atol=5e-7
    )


@pytest.mark.parametrize(
    ("kind", "residual"),
    [
        ("cantilever", lambda x: np.cos(x) * np.cosh(x) + 1),
        ("pinned-free", lambda x: np.tan(x) - np.tanh(x)),
        ("free-free", lambda x: np.cos(x) * np.cosh(x) - 1),
    ],
)
def test_beam_roots_solve_their_equation_to_round_off(kind, residual):
    """Each root zeroes its characteristic equation to round-off, relative to its terms."""
    roots = euler_bernoulli_roots(kind, 6)
    scale = np.cosh(roots) if kind != "pinned-free" else 1 / np.cos(roots) ** 2
    assert np.all(np.abs(residual(roots)) / scale < 1e-14)
    assert np.all(np.diff(roots) > 2.5)  # distinct, spaced by ~pi


# --- (a) planar model -------------------------------------------------------------------


def test_planar_single_link_reproduces_pinned_free_roots():
    """A single pinned link meshed with 40 elements gives the pinned–free βL roots within 0.01 %."""
    L, EI, EA = 0.6, E_AL * I_AL, E_AL * AREA
    K, M = planar_chain_matrices([0.7], [L], [40], EI=EI, rhoA=RHOA_AL, EA=EA)
    _, freqs = solve_frequencies(K, M, n_rigid=1)
    omega = 2 * math.pi * freqs
    beta_l = np.sqrt(omega * L**2 / math.sqrt(EI / RHOA_AL))
    # the three lowest elastic modes are bending (the first axial mode is above 2 kHz)
    assert axial_fixed_free_hz(L, EA, RHOA_AL, 1)[0] > pinned_free_hz(L, EI, RHOA_AL, 3)[-1]
    np.testing.assert_allclose(beta_l[:3], [3.926602, 7.068583, 10.210176], rtol=1e-4)
    np.testing.assert_allclose(beta_l[:3], euler_bernoulli_roots("pinned-free", 3), rtol=1e-5)


def test_planar_bending_error_converges_at_fourth_order():
    """Halving the element length divides the first pinned–free frequency error by about 16."""
    L, EI, EA = 0.6, E_AL * I_AL, E_AL * AREA
    exact = pinned_free_hz(L, EI, RHOA_AL, 1)[0]
    errors = []
    for n in (4, 8, 16):
        K, M = planar_chain_matrices([0.0], [L], [n], EI=EI, rhoA=RHOA_AL, EA=EA)
        errors.append(solve_frequencies(K, M, 1)[1][0] / exact - 1)
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(np.array(errors) > 0)  # consistent mass: upper bounds
    np.testing.assert_allclose(rates, 4.0, atol=0.15)


def test_planar_two_link_layout_and_matrices():
    """Benchmark A's planar model has 23 dofs, K ⪰ 0, M ≻ 0 and masses on the documented dofs."""
    K0, M0 = planar_two_link_matrices(Q0_ABS, 0.0, 0.0)
    K1, M1 = planar_two_link_matrices(Q0_ABS, 0.1, 0.2)
    assert K0.shape == M0.shape == (23, 23)
    np.testing.assert_array_equal(K0, K0.T)
    np.testing.assert_array_equal(M0, M0.T)
    assert np.linalg.eigvalsh(K0)[0] > -1e-9 * np.abs(K0).max()
    assert np.linalg.eigvalsh(M0)[0] > 0
    np.testing.assert_array_equal(K1, K0)
    expected = np.zeros((23, 23))
    expected[[10, 11], [10, 11]] = 0.1  # elbow u, v
    expected[[20, 21], [20, 21]] = 0.2  # tip u, v
    np.testing.assert_allclose(M1 - M0, expected, atol=1e-15)


# --- (b) spatial model against closed forms ---------------------------------------------

L_ST = 0.8
DIR_ST = np.array([1.0, 2.0, 2.0]) / 3.0
VECXZ_ST = (0.3, -1.0, 0.5)
N_ST = 40
# linear rod elements overestimate by about (kappa h)^2 / 24; cubic Hermite bending
# elements converge like (beta h)^4, below 1e-5 for the modes checked at 40 elements
BENDING_RTOL = 1e-5


def rod_rtol(kappa):
    """Bound on a linear rod element's relative frequency error, 5 % above its leading term."""
    return 1.05 * (np.asarray(kappa) * L_ST / N_ST) ** 2 / 24


def single_beam_modes(vecxz, **model_kwargs):
    """Elastic frequencies [Hz] of one steel beam along DIR_ST, sorted by mode shape.

    Each mode of a straight beam is purely axial, torsional, or bending along local y or
    z; the family is read off the mode shape in local axes (x along the beam, z the part
    of ``vecxz`` normal to it), and the test fails if a mode is not pure to 1e-6.
    """
    model = spatial_frame_model(
        [[0, 0, 0], L_ST * DIR_ST], [steel_beam(N_ST, tuple(vecxz))], **model_kwargs
    )
    eigvals, vecs = scipy.linalg.eigh(model.K, model.M)
    z = np.asarray(vecxz, float) - np.dot(vecxz, DIR_ST) * DIR_ST
    z /= np.linalg.norm(z)
    axes = np.vstack([DIR_ST, np.cross(z, DIR_ST), z])
    families = {"axial": [], "torsion": [], "bending y": [], "bending z": []}
    for lam, phi in zip(eigvals[model.n_rigid :], vecs[:, model.n_rigid :].T):
        nodal = (model.T @ phi).reshape(-1, 6)
        du, dth = nodal[:, :3] @ axes.T, L_ST * nodal[:, 3:] @ axes.T  # local, same units
        parts = {
            "axial": np.linalg.norm(du[:, 0]),
            "torsion": np.linalg.norm(dth[:, 0]),
            "bending y": np.linalg.norm(du[:, 1]) + np.linalg.norm(dth[:, 2]),
            "bending z": np.linalg.norm(du[:, 2]) + np.linalg.norm(dth[:, 1]),
        }
        name = max(parts, key=parts.get)
        assert sum(parts.values()) - parts[name] < 1e-6 * parts[name], parts
        families[name].append(math.sqrt(lam) / (2 * math.pi))
    return model.n_rigid, {k: np.array(v) for k, v in families.items()}


def test_spatial_clamped_beam_matches_closed_forms():
    """A clamped oblique beam (Iy ≠ Iz) gives the bending, torsion and axial closed forms."""
    beam = steel_beam(N_ST)
    n_rigid, modes = single_beam_modes(VECXZ_ST)
    kappa = (2 * np.arange(1, 3) - 1) * math.pi / (2 * L_ST)
    assert n_rigid == 0
    for name, exact, rtol in (
        ("bending z", cantilever_hz(L_ST, beam.EIy, beam.rhoA, 4), BENDING_RTOL),
        ("bending y", cantilever_hz(L_ST, beam.EIz, beam.rhoA, 4), BENDING_RTOL),
        ("torsion", torsion_fixed_free_hz(L_ST, G_ST, J_ST, RHO_ST, IP_ST, 2), rod_rtol(kappa)),
        ("axial", axial_fixed_free_hz(L_ST, beam.EA, beam.rhoA, 2), rod_rtol(kappa)),
    ):
        err = modes[name][: len(exact)] / exact - 1
        assert np.all((err > -1e-8) & (err < rtol)), (name, err)  # consistent mass: from above
    # the rod families equal the exact discrete solution to round-off
    for name, stiffness, inertia in (
        ("torsion", beam.GJ, beam.rho_Ip),
        ("axial", beam.EA, beam.rhoA),
    ):
        discrete = rod_fe_hz(L_ST, stiffness, inertia, N_ST, kappa)
        np.testing.assert_allclose(modes[name][:2], discrete, rtol=1e-10)


def test_spatial_first_mode_bends_in_the_softer_plane():
    """With EIy < EIz the first mode deflects along local z, vecxz's part normal to the beam."""
    assert IY_ST < IZ_ST
    model = spatial_frame_model([[0, 0, 0], L_ST * DIR_ST], [steel_beam(N_ST, VECXZ_ST)])
    _, vecs = scipy.linalg.eigh(model.K, model.M)
    tip = (model.T @ vecs[:, 0])[-6:-3]
    z = np.asarray(VECXZ_ST) - np.dot(VECXZ_ST, DIR_ST) * DIR_ST
    assert np.linalg.norm(np.cross(tip, z / np.linalg.norm(z))) < 1e-8 * np.linalg.norm(tip)


def test_spatial_revolute_base_normal_to_beam_gives_pinned_free_bending():
    """A base hinge normal to the beam makes one bending plane pinned–free, the other clamped."""
    beam = steel_beam(N_ST)
    axis = np.cross(DIR_ST, VECXZ_ST)  # normal to the beam; used as vecxz: local z = axis
    n_rigid, modes = single_beam_modes(axis, base=axis)
    kappa = (2 * np.arange(1, 3) - 1) * math.pi / (2 * L_ST)
    assert n_rigid == 1
    np.testing.assert_allclose(
        modes["bending y"][:3], pinned_free_hz(L_ST, beam.EIz, beam.rhoA, 3), rtol=BENDING_RTOL
    )
    np.testing.assert_allclose(
        modes["bending z"][:3], cantilever_hz(L_ST, beam.EIy, beam.rhoA, 3), rtol=BENDING_RTOL
    )
    np.testing.assert_allclose(
        modes["torsion"][:2], rod_fe_hz(L_ST, beam.GJ, beam.rho_Ip, N_ST, kappa), rtol=1e-10
    )


def test_spatial_revolute_base_along_beam_frees_torsion():
    """A base hinge along the beam makes torsion free–free and keeps bending clamped."""
    beam = steel_beam(N_ST)
    n_rigid, modes = single_beam_modes(VECXZ_ST, base=DIR_ST)
    kappa = np.arange(1, 3) * math.pi / L_ST
    free_free = np.arange(1, 3) / (2 * L_ST) * math.sqrt(beam.GJ / beam.rho_Ip)
    assert n_rigid == 1
    err = modes["torsion"][:2] / free_free - 1
    assert np.all((err > 0) & (err < rod_rtol(kappa))), err
    np.testing.assert_allclose(
        modes["torsion"][:2], rod_fe_hz(L_ST, beam.GJ, beam.rho_Ip, N_ST, kappa), rtol=1e-10
    )
    for name, EI in (("bending z", beam.EIy), ("bending y", beam.EIz)):
        exact = cantilever_hz(L_ST, EI, beam.rhoA, 3)
        np.testing.assert_allclose(modes[name][:3], exact, rtol=BENDING_RTOL)


# --- (c) spatial model of benchmark A against the planar model ---------------------------


def benchmark_a_spatial(q_abs, m1, m2, n1=4, n2=3, tilt=None):
    """Benchmark A as a spatial chain in the world xy-plane (or rotated by ``tilt``)."""
    c1, s1, c2, s2 = math.cos(q_abs[0]), math.sin(q_abs[0]), math.cos(q_abs[1]), math.sin(q_abs[1])
    points = np.array(
        [[0, 0, 0], [0.6 * c1, 0.6 * s1, 0], [0.6 * c1 + 0.45 * c2, 0.6 * s1 + 0.45 * s2, 0]]
    )
    z = np.array([0.0, 0.0, 1.0])
    rot = np.eye(3) if tilt is None else tilt
    points, z = points @ rot.T, rot @ z
    section = dict(
        EA=E_AL * AREA,
        GJ=G_AL * 2 * I_AL,
        EIy=E_AL * I_AL,
        EIz=E_AL * I_AL,
        rhoA=RHOA_AL,
        rho_Ip=RHO_AL * 2 * I_AL,
        vecxz=tuple(z),
    )
    beams = [Beam(n_elements=n1, **section), Beam(n_elements=n2, **section)]
    masses = [(points[1], m1), (points[2], m2)]
    return points, beams, [z], masses, z


@pytest.mark.parametrize(
    ("q_abs", "m1", "m2"),
    [(Q0_ABS, 0.125, 0.125), (Q0_ABS, 0.0, 0.0), ((0.4, 2.9), 0.25, 0.03), ((1.0, 1.0), 0.1, 0.0)],
)
def test_spatial_benchmark_a_contains_planar_frequencies(q_abs, m1, m2):
    """Every planar frequency of benchmark A is a spatial frequency to 1e-9 relative."""
    ev_p, f_planar = planar_two_link_frequencies(q_abs, m1, m2)
    points, beams, joints, masses, z = benchmark_a_spatial(q_abs, m1, m2)
    ev_s, f_spatial = spatial_frame_frequencies(points, beams, joints, point_masses=masses, base=z)
    assert len(ev_p) - len(f_planar) == len(ev_s) - len(f_spatial) == 2
    idx, err = nearest(f_spatial, f_planar)
    assert len(set(idx)) == len(f_planar) == 21
    assert np.all(np.abs(err) < 1e-9), err


def test_spatial_benchmark_a_in_plane_modes_are_the_planar_modes():
    """The spatial modes of benchmark A without out-of-plane motion are the 23 planar ones."""
    ev_p, f_planar = planar_two_link_frequencies(Q0_ABS, 0.125, 0.125)
    points, beams, joints, masses, z = benchmark_a_spatial(Q0_ABS, 0.125, 0.125)
    model = spatial_frame_model(points, beams, joints, point_masses=masses, base=z)
    ev_s, vecs = scipy.linalg.eigh(model.K, model.M)
    nodal = (model.T @ vecs).reshape(-1, 6, len(ev_s))  # (node, dof, mode)
    in_plane = np.linalg.norm(nodal[:, [0, 1, 5]], axis=(0, 1))
    out_of_plane = np.linalg.norm(nodal[:, [2, 3, 4]], axis=(0, 1))
    planar_like = out_of_plane < 1e-8 * in_plane
    assert np.all(planar_like | (in_plane < 1e-8 * out_of_plane))  # every mode is one or the other
    assert planar_like.sum() == 23 and np.all(planar_like[:2])  # rigid modes are in-plane
    f_in_plane = np.sqrt(ev_s[planar_like][2:]) / (2 * math.pi)
    np.testing.assert_allclose(f_in_plane, f_planar, rtol=1e-9)


def test_planar_benchmark_a_near_paper_target():
    """At q0 the first elastic frequency is near 190 Hz (193 Hz at y0, 202 Hz without masses)."""
    f_y0 = planar_two_link_frequencies(Q0_ABS, 0.125, 0.125)[1][0]
    f_bare = planar_two_link_frequencies(Q0_ABS, 0.0, 0.0)[1][0]
    assert 185 < f_y0 < f_bare < 210


def test_spatial_frequencies_do_not_depend_on_world_orientation():
    """Rotating the structure, hinge axes and vecxz included, leaves every frequency unchanged."""
    rot = rotation([0.2, -0.7, 0.4], 1.1)
    base = benchmark_a_spatial(Q0_ABS, 0.1, 0.2)
    turned = benchmark_a_spatial(Q0_ABS, 0.1, 0.2, tilt=rot)
    f0 = spatial_frame_frequencies(base[0], base[1], base[2], point_masses=base[3], base=base[4])[1]
    f1 = spatial_frame_frequencies(
        turned[0], turned[1], turned[2], point_masses=turned[3], base=turned[4]
    )[1]
    np.testing.assert_allclose(f1, f0, rtol=1e-10)


# --- (d) rigid modes --------------------------------------------------------------------

CHAIN_POINTS = np.array([[0, 0, 0], [0.5, 0, 0], [0.5, 0.4, 0.1], [0.2, 0.6, 0.5]])
AXIS_1 = np.array([0.0, 1.0, 1.0]) / math.sqrt(2)
AXIS_2 = np.array([1.0, -0.3, 0.2])


@pytest.mark.parametrize(
    ("base", "joints", "n_rigid"),
    [
        ("fixed", ["fixed", "fixed"], 0),
        ((0, 0, 1), ["fixed", "fixed"], 1),
        ("fixed", [AXIS_1, "fixed"], 1),
        ((0, 0, 1), [AXIS_1, "fixed"], 2),
        ((0, 0, 1), [AXIS_1, AXIS_2], 3),
    ],
)
def test_spatial_rigid_mode_count_and_shapes(base, joints, n_rigid):
    """A 3D chain has one zero mode per revolute joint: that joint's zero-energy rotation."""
    beams = [steel_beam(3), steel_beam(2), steel_beam(3)]
    model = spatial_frame_model(
        CHAIN_POINTS, beams, joints, point_masses=[(CHAIN_POINTS[2], 0.3)], base=base
    )
    eigvals, freqs = solve_frequencies(model.K, model.M, model.n_rigid)
    assert model.n_rigid == n_rigid
    assert np.sum(np.abs(eigvals) <= RIGID_RTOL * np.abs(eigvals).max()) == n_rigid
    assert len(freqs) == len(eigvals) - n_rigid and freqs[0] > 1.0
    # rigid rotation of everything beyond each revolute joint, in nodal dofs
    hinges = [(-1, base)] + list(enumerate(joints))
    for j, spec in hinges:
        if isinstance(spec, str):
            continue
        a = np.asarray(spec, float) / np.linalg.norm(spec)
        pivot = CHAIN_POINTS[j + 1]
        d = np.zeros(model.T.shape[0])
        for r, (x, b) in enumerate(zip(model.nodes, model.beam_of_node)):
            if b > j:
                d[6 * r : 6 * r + 3] = np.cross(a, x - pivot)
                d[6 * r + 3 : 6 * r + 6] = a
        z = np.linalg.lstsq(model.T, d, rcond=None)[0]
        assert np.linalg.norm(model.T @ z - d) < 1e-12 * np.linalg.norm(d)  # admissible
        assert np.linalg.norm(model.K @ z) < 1e-12 * np.linalg.norm(model.K, 2) * np.linalg.norm(z)


def test_planar_two_link_has_two_rigid_modes():
    """Benchmark A's planar model has exactly two zero eigenvalues and 21 elastic frequencies."""
    eigvals, freqs = planar_two_link_frequencies(Q0_ABS, 0.125, 0.125)
    assert len(eigvals) == 23 and len(freqs) == 21
    assert np.sum(np.abs(eigvals) <= RIGID_RTOL * np.abs(eigvals).max()) == 2
    assert eigvals[2] > 1e-6 * eigvals[-1]


def test_rigid_count_mismatch_is_reported():
    """The wrong number of rigid modes raises instead of returning shifted frequencies."""
    K, M = planar_two_link_matrices(Q0_ABS, 0.0, 0.0)
    with pytest.raises(RuntimeError, match="expected 1 rigid modes, found 2"):
        solve_frequencies(K, M, n_rigid=1)


def test_point_mass_off_node_is_rejected():
    """A point mass that does not sit on a node is an error, not silently moved."""
    with pytest.raises(ValueError, match="not at a node"):
        spatial_frame_model(
            [[0, 0, 0], [1, 0, 0]], [steel_beam(4)], point_masses=[((0.3, 0, 0), 1.0)]
        )
