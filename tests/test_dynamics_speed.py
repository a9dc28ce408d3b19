"""The arm at speed: terms="full", modes at speed and the validity indicator of eq. (1).

References written here with no pinflex code: the classical geometric stiffness of a beam
element, a rotating-frame finite-element model of Kane, Ryan and Banerjee's spin-up beam, and
the published frequencies of a rotating cantilever (Hamza-Cherif and Houmat, 24th ICAS
Congress, 2004, Table 2: slenderness ratio 70, dimensionless speeds 2-50).
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import scipy.integrate
from arms import CHORDWISE, FLAPWISE, rotating_cantilever, table_close
from reference_fe import beam_fe

from pinflex import FlexibleModel, beam
from pinflex.cases.spin_up import KANE_URDF, SPIN_UP_S, SpinUp
from pinflex.dynamics import ErlsDynamics, simulate_prescribed
from pinflex.dynamics.modes import modes_at_speed
from pinflex.exceptions import ModelValidityError, ModelValidityWarning

#: Kane, Ryan and Banerjee (1987): L = 10 m, EI = 1.4e4 N m², ρA = 1.2 kg/m (EA = 1.4e7 N);
#: the model under test, as the package ships it (the references below do not use it).
KANE, TS = KANE_URDF, SPIN_UP_S
OMEGA1 = 1.875104068711961**2 * math.sqrt(1.4e4 / (1.2 * 10.0**4))  # cantilever, rad/s



def rotating_frame_matrices(*, n=10, L=10.0, EI=1.4e4, EA=1.4e7, rhoA=1.2):
    """``(M, G, K, KG, fu, fv)`` of the beam clamped to the hub, rotating frame
    (:func:`reference_fe.beam_fe`): ``KG`` is the geometric stiffness per unit θ̇² of
    ``N = ρA (L² − s²)/2``, ``G = Muvᵀ − Muv`` the Coriolis/Euler coupling; the root node is
    clamped; the tip's ``v`` is entry ``-2``.
    """
    return beam_fe(n, lambda s: rhoA * (L * L - s * s) / 2.0, L=L, EI=EI, EA=EA, rhoA=rhoA)


def rotating_frame_fe(motion, times, *, full, n=10, L=10.0, EI=1.4e4, EA=1.4e7, rhoA=1.2):
    """Tip deflection v(L, t) of the beam clamped to the hub, in the rotating frame.

    Axial (linear) and bending (cubic Hermite) fields, consistent matrices by Gauss
    quadrature; linearised in the elastic displacement ``(u, v)``:

        ρA (ü − 2θ̇v̇ − θ̈v − θ̇²u) − EA u'' = ρA θ̇² s,
        ρA (v̈ + 2θ̇u̇ + θ̈u − θ̇²v) + EI v'''' − (N v')' = −ρA θ̈ s,  N = ρA θ̇² (L² − s²)/2,

    where eq. (1) keeps only the Coriolis terms ``2θ̇u̇``, ``−2θ̇v̇`` (``full=False``).
    """
    M, G, K, KG, fu, fv = rotating_frame_matrices(n=n, L=L, EI=EI, EA=EA, rhoA=rhoA)
    Mi = np.linalg.inv(M)
    m = M.shape[0]

    def stiffness(thd, thdd):
        return K - thd**2 * M + thdd * G + thd**2 * KG if full else K

    def fun(t, y):
        _, thd, thdd = (float(v[0]) for v in motion(t))
        acc = Mi @ (thd**2 * fu - thdd * fv - 2 * thd * G @ y[m:] - stiffness(thd, thdd) @ y[:m])
        return np.concatenate([y[m:], acc])

    def jac(t, y):
        _, thd, thdd = (float(v[0]) for v in motion(t))
        J = np.zeros((2 * m, 2 * m))
        J[:m, m:] = np.eye(m)
        J[m:, :m] = -Mi @ stiffness(thd, thdd)
        J[m:, m:] = -2 * thd * Mi @ G
        return J

    sol = scipy.integrate.solve_ivp(fun, (0.0, TS), np.zeros(2 * m), method="Radau", jac=jac,
                                    rtol=1e-7, atol=1e-10, dense_output=True)
    return sol.sol(times)[m - 2]  # the tip node's v


@pytest.fixture(scope="module")
def kane(tmp_path_factory):
    """Kane's beam on a hub joint, planar."""
    path = tmp_path_factory.mktemp("kane") / "kane.urdf"
    path.write_text(KANE)
    return ErlsDynamics(FlexibleModel(path, planar=True))


def test_geometric_stiffness_of_a_constant_axial_force_is_the_classical_matrix():
    """K_G of a constant N is N/(30 L)[[36, 3L, −36, 3L], ...] in each bending plane."""
    L, N = 0.7, 1234.5
    cl = N / (30 * L) * np.array([[36, 3 * L, -36, 3 * L], [3 * L, 4 * L**2, -3 * L, -L**2],
                                  [-36, -3 * L, 36, -3 * L], [3 * L, -(L**2), -3 * L, 4 * L**2]])
    KG = beam.element_geometric_stiffness(L, N)
    v = [1, 5, 7, 11]  # (v, θz) at both nodes
    assert KG[np.ix_(v, v)] == pytest.approx(cl, rel=1e-13, abs=1e-12 * N)
    w = [2, 4, 8, 10]  # (w, θy) with θy = −w'
    flip = np.diag([1, -1, 1, -1])
    assert KG[np.ix_(w, w)] == pytest.approx(flip @ cl @ flip, rel=1e-13, abs=1e-12 * N)
    others = np.setdiff1d(np.arange(12), v + w)
    assert not np.any(KG[others]) and not np.any(KG[:, others])
    # a force linear along the element: the integral of the two end values' average shape
    xi = beam.GEOMETRIC_POINTS
    KG_lin = beam.element_geometric_stiffness(L, 100.0 + 50.0 * xi)
    assert np.trace(KG_lin) == pytest.approx(
        np.trace(beam.element_geometric_stiffness(L, 100.0)) + 50.0 * np.trace(
            beam.element_geometric_stiffness(L, xi)), rel=1e-13)


@pytest.mark.parametrize("omega_s", [1.0, 4.0, 6.0, 10.0])
def test_spin_up_full_terms_match_a_rotating_frame_fe(kane, omega_s):
    """Kane's spin-up, terms='full': the tip deflection equals the rotating-frame FE's to 1e-4.

    Ωs / ω₁ = 0.26, 1.05, 1.58, 2.63. Eq. (1) (``terms='eq1'``) differs from both by far more.
    """
    motion = SpinUp(omega_s)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelValidityWarning)
        sim = simulate_prescribed(kane, motion, after_s=0.01, sample_hz=20.0, terms="full",
                                  start="rest", grid_per_interval=4, tol=1e-6)
    during = sim.times_s <= TS
    tip = sim.x[during, -2]
    ref = rotating_frame_fe(motion, sim.times_s[during], full=True)
    peak = np.abs(ref).max()
    assert np.abs(tip - ref).max() <= 1e-4 * peak
    assert abs(np.abs(tip).max() / peak - 1.0) <= 1e-4
    assert sim.terms == "full" and sim.validity is not None
    assert sim.validity.max_speed_ratio == pytest.approx((omega_s / OMEGA1) ** 2, rel=2e-3)
    # eq. (1) is the other model: its peak is off the full one's by more than 0.3 %
    eq1 = rotating_frame_fe(motion, sim.times_s[during], full=False)
    assert abs(np.abs(eq1).max() / peak - 1.0) > 3e-3


def test_eq1_warns_on_a_fast_spin_up_and_strict_refuses(kane):
    """The validity indicator warns above its threshold and strict refuses before the run."""
    with pytest.warns(ModelValidityWarning, match="terms='full'"):
        sim = simulate_prescribed(kane, SpinUp(4.0, knots_s=0.5), after_s=0.01,
                                  sample_hz=2.0, start="rest", grid_per_interval=2)
    v = sim.validity
    assert v.indicator == pytest.approx((4.0 / OMEGA1) ** 2, rel=2e-3)
    # |α|/ω₁² peaks at 2 Ωs/Ts at t = Ts/2
    assert v.max_accel_ratio == pytest.approx(2 * 4.0 / TS / OMEGA1**2, rel=2e-3)
    with pytest.raises(ModelValidityError):
        simulate_prescribed(kane, SpinUp(4.0, knots_s=0.5), sample_hz=2.0, strict=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelValidityWarning)
        slow = simulate_prescribed(kane, SpinUp(0.5, knots_s=0.5), after_s=0.01,
                                   sample_hz=2.0, start="rest", grid_per_interval=2)
    assert slow.validity.indicator < slow.validity.threshold


def test_modes_at_speed_of_a_rotating_cantilever_match_the_published_table(tmp_path):
    """Flapwise and chordwise ω √(ρA L⁴ / EI) at speeds γ = Ω √(ρA L⁴ / EI) of 2 to 50.

    Hamza-Cherif and Houmat (24th ICAS Congress, 2004), Table 2: slenderness ratio
    L √(A / I) = 70, no hub. Within the table's last digit plus 2e-4 (chordwise: in-plane
    model of 40 elements, axial stretching and Coriolis coupling included; flapwise: spatial
    model of 20 elements).
    """
    chord_path, flap_path, T = rotating_cantilever(tmp_path, KANE)
    chord = ErlsDynamics(FlexibleModel(chord_path, planar=True))
    spatial = FlexibleModel(flap_path)
    flap = ErlsDynamics(spatial)
    out_of_plane = [i for i, n in enumerate(spatial.x_names) if n.endswith(("uz", "ry"))]
    in_plane = [i for i, n in enumerate(spatial.x_names) if n.endswith(("uy", "rz"))]

    def lowest_flapwise(res):
        share = np.abs(res.shapes)
        is_flap = share[out_of_plane].sum(0) > share[in_plane].sum(0)
        return 2 * math.pi * res.freq_hz[is_flap][0] * T

    for gamma in FLAPWISE:
        res = modes_at_speed(chord, [0.0], [gamma / T], n_modes=2)
        assert not res.unstable
        assert table_close(2 * math.pi * res.freq_hz[0] * T, CHORDWISE[gamma]), gamma
        res = modes_at_speed(flap, [0.0], [gamma / T], n_modes=6)
        assert table_close(lowest_flapwise(res), FLAPWISE[gamma]), gamma
    # eq. (1) alone (gyroscopic terms only) misses the stiffening: far below at γ = 10
    res = modes_at_speed(flap, [0.0], [10.0 / T], terms="eq1", n_modes=6)
    assert lowest_flapwise(res) < 0.5 * FLAPWISE[10]


def test_modes_along_a_spinning_hub_report_and_warn_the_validity(tmp_path):
    """Modes along θ = Ω t of Kane's beam on a free hub: ``|ω|²/ω₁² = (Ω/ω₁)²`` per sample.

    ``ω₁`` of the free-joint (pinned-free) beam is ``3.926602² √(EI / ρA L⁴)``; the angular
    acceleration is zero. Above the threshold a ModelValidityWarning names the remedy and
    ``strict`` refuses; the CSV and JSON carry the ratios.
    """
    import json

    from pinflex.erls.along import modes_along
    from pinflex.trajectory import Trajectory

    path = tmp_path / "kane.urdf"
    path.write_text(KANE)
    model = FlexibleModel(path, planar=True)
    w1 = 3.926602312047919**2 * math.sqrt(1.4e4 / (1.2 * 10.0**4))
    t = np.linspace(0.0, 2.0, 41)
    for omega, warns in ((0.2 * w1, False), (0.5 * w1, True)):
        traj = Trajectory(t, (omega * t)[:, None], ("hub",))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = modes_along(model, traj, modes=2)
        got = [w for w in caught if issubclass(w.category, ModelValidityWarning)]
        assert bool(got) is warns
        v = res.validity
        assert v.speed_ratio[:, 0] == pytest.approx((omega / w1) ** 2, rel=1e-4)
        assert v.max_accel_ratio == pytest.approx(0.0, abs=1e-9)
    assert json.loads(res.to_json())["validity"]["exceeded"] is True
    res.to_csv(tmp_path / "m.csv")
    head, first = (tmp_path / "m.csv").read_text().splitlines()[:2]
    assert head.endswith("speed_ratio,accel_ratio")
    assert float(first.split(",")[-2]) == pytest.approx(0.25, rel=1e-4)
    with pytest.raises(ModelValidityError):
        modes_along(model, traj, modes=2, strict=True)


@pytest.mark.parametrize("terms", ["full", "eq1"])
def test_receptance_of_the_spinning_beam_equals_the_rotating_frame_fe(kane, terms):
    """The linearised model about a moving state: Kane's beam spinning at Ω = 6 rad/s.

    Tip transverse force to tip transverse displacement, undamped, away from resonance,
    against the rotating-frame FE ``(K_Ω − ω² M + 2iωΩ G)⁻¹`` written here
    (``K_Ω = K − Ω² M + Ω² K_G`` with the full terms, ``K`` with eq. (1)'s).
    """
    from pinflex.dynamics.frf import frf, frf_direct, linear_pose

    omega = 6.0
    M, G, K, KG, _, _ = rotating_frame_matrices()
    K_rot = K - omega**2 * M + omega**2 * KG if terms == "full" else K
    e = np.zeros(M.shape[0])
    e[-2] = 1.0  # the tip's v
    tip = ("beam", (10.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    lp = linear_pose(kane, [0.0], [("force", *tip)], [("displacement", *tip)],
                     joints="locked", qd=[omega], terms=terms)
    freqs = np.array([0.05, 0.3, 0.9, 2.5, 7.0])
    ref = np.array([e @ np.linalg.solve(K_rot - w**2 * M + 2j * w * omega * G, e)
                    for w in 2 * np.pi * freqs])
    got = frf(lp, freqs)[:, 0, 0]
    assert np.abs(got - ref).max() <= 1e-6 * np.abs(ref).max()
    assert np.array_equal(got, frf_direct(lp, freqs)[:, 0, 0])  # gyroscopic: solved directly
    with pytest.raises(Exception, match="joints='locked'"):
        linear_pose(kane, [0.0], [("force", *tip)], [("displacement", *tip)], qd=[omega])


def test_modes_at_speed_along_a_constant_spin_equal_the_rotating_frame_fe(kane):
    """Along a constant spin (Ω = 6 rad/s) the modes are the rotating-frame FE's.

    The imaginary parts of the gyroscopic eigenvalues of ``M ÿ + 2Ω G ẏ + K_Ω y = 0``.
    """
    from pinflex.dynamics.modes import modes_at_speed_along

    omega = 6.0
    M, G, K, KG, _, _ = rotating_frame_matrices()
    K_rot = K - omega**2 * M + omega**2 * KG
    m = M.shape[0]
    A = np.zeros((2 * m, 2 * m))
    A[:m, m:] = np.eye(m)
    A[m:, :m] = -np.linalg.solve(M, K_rot)
    A[m:, m:] = -np.linalg.solve(M, 2 * omega * G)
    lam = np.linalg.eigvals(A)
    ref = np.sort(np.abs(lam.imag[lam.imag > 0]))[:3] / (2 * math.pi)
    # after the spin-up the hub turns at Ωs with exact rates
    res = modes_at_speed_along(kane, SpinUp(omega), times=np.array([TS, TS + 0.5, TS + 2.0]))
    assert not res.unstable.any()
    for row in res.freq_hz:
        assert row == pytest.approx(ref, rel=1e-7)


def test_gravity_preload_buckles_a_standing_column_at_greenhills_load(tmp_path):
    """terms='full' at rest under gravity: the geometric stiffness of the self-weight.

    A uniform column clamped at its foot, standing in gravity, buckles when its weight per
    length reaches ``q L³ / EI = 7.83735`` (Greenhill's self-weight buckling constant). Here:
    the smallest gravity at which the locked arm's stiffness with the speed terms loses
    positiveness, within 1e-5 (20 elements; measured 7.837350); upside down the column hangs
    and its modes rise (modes_at_speed: the gravity preload in the modal analysis).
    """
    from pinflex.dynamics.modes import modes_at_speed
    from pinflex.dynamics.prescribed import locked_coefficients

    L, EI, rhoA = 2.0, 50.0, 0.8
    urdf = KANE.replace('elements="10" normal="0 0 1" tip="10 0 0"',
                        f'elements="20" tip="0 0 {L}"').replace(
        '<axis xyz="0 0 1"/>', '<axis xyz="1 0 0"/>').replace(
        'linear_density="1.2"', f'linear_density="{rhoA}"').replace(
        'A="2e-4" Iy="2e-7" Iz="2e-7" J="4e-7"',
        f'A="1e-4" Iy="{EI / 7e10}" Iz="{EI / 7e10}" J="{2 * EI / 7e10}"')
    path = tmp_path / "column.urdf"
    path.write_text(urdf)
    model = FlexibleModel(path, joints="locked")

    def stiffness(g):
        dyn = ErlsDynamics(model, gravity=[0.0, 0.0, -g])
        return locked_coefficients(dyn, [0.0], [0.0], [0.0], terms="full").K

    K0, K1 = stiffness(0.0), stiffness(1.0)
    lam = np.linalg.eigvals(np.linalg.solve(K0, K0 - K1))  # K(g) = K0 − g (K0 − K1)
    g_cr = 1.0 / lam.real.max()
    assert g_cr * rhoA * L**3 / EI == pytest.approx(7.83735, rel=1e-5)
    standing = modes_at_speed(ErlsDynamics(model, gravity=[0, 0, -0.5 * g_cr]), [0.0])
    hanging = modes_at_speed(ErlsDynamics(model, gravity=[0, 0, 0.5 * g_cr]), [0.0])
    still = modes_at_speed(ErlsDynamics(model), [0.0])
    assert standing.freq_hz[0] < still.freq_hz[0] < hanging.freq_hz[0]
