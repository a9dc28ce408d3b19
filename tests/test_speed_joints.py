"""terms='full' for joints on deforming links: a beam split into links at held joints.

A beam cut into two or three links joined by revolute joints that the motors hold straight is
the one beam it was. Spinning, or hanging under its weight, its modes must be the one beam's.
References written here with no pinflex code: a finite-element model of the one beam in the
rotating frame (axial and cubic Hermite fields, consistent matrices by Gauss quadrature:
centrifugal softening, Coriolis coupling and the geometric stiffness of the axial force), in
plane and across the plane, and the published rotating-cantilever frequencies
(``tests/arms.py``). Before the joints' terms (the subtree turning by the joint's elastic
offset, the joint turning about its displaced point) the split beam was 79 % off at γ = 10.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest
import scipy.integrate
import scipy.linalg
from arms import CHORDWISE, rotating_cantilever, table_close
from reference_fe import beam_fe as _beam_fe

from pinflex import FlexibleModel
from pinflex.cases.spin_up import KANE_URDF, SPIN_UP_S, SpinUp
from pinflex.dynamics import ErlsDynamics, simulate_prescribed
from pinflex.dynamics.modes import modes_at_speed
from pinflex.exceptions import ModelValidityWarning

#: Kane, Ryan and Banerjee's beam (L = 10 m, EI = 1.4e4 N m², EA = 1.4e7 N, ρA = 1.2 kg/m).
L, EI, EA, RHOA = 10.0, 1.4e4, 1.4e7, 1.2


def beam_fe(n, N):
    """Kane's beam of ``n`` elements under the axial force ``N(s)`` (``reference_fe.beam_fe``)."""
    return _beam_fe(n, N, L=L, EI=EI, EA=EA, rhoA=RHOA)


def spin_n(omega):
    """Axial force of the beam spinning at ``omega`` [rad/s] about its root (tension)."""
    return lambda s: RHOA * omega**2 * (L * L - s * s) / 2.0


def lowest_hz(M, C, K, k):
    """The ``k`` lowest |Im λ| / 2π of ``M ẍ + C ẋ + K x = 0`` (from ``1/λ``: the low modes to
    round-off beside the stiff axial ones)."""
    m = M.shape[0]
    B = np.zeros((2 * m, 2 * m))
    B[:m] = -np.linalg.solve(K, np.hstack([C, M]))
    B[m:, :m] = np.eye(m)
    lam = 1.0 / np.linalg.eigvals(B)
    return np.sort(np.abs(lam.imag[lam.imag > 0.0]))[:k] / (2.0 * math.pi)


def split_urdf(cuts, *, planar=True, n=10, condition=""):
    """Kane's beam of ``n`` elements cut at the fractions ``cuts`` into links joined by
    revolute joints about z (``condition``: a ``<pinflex:joint>`` attribute for each)."""
    normal = 'normal="0 0 1" ' if planar else ""
    marks = [0.0, *cuts, 1.0]
    text = KANE_URDF
    flex = text[text.index("<pinflex:flexible"):text.index("</pinflex:flexible>")]
    flex += "</pinflex:flexible>"
    text = text.replace(flex, "")
    links, joints, beams = [], [], []
    for i in range(len(marks) - 1):
        name = "beam" if i == 0 else f"part{i}"
        length = (marks[i + 1] - marks[i]) * L
        elements = round((marks[i + 1] - marks[i]) * n)
        beams.append(flex.replace('link="beam"', f'link="{name}"').replace(
            'elements="10" normal="0 0 1" tip="10 0 0"',
            f'elements="{elements}" {normal}tip="{length!r} 0 0"'))
        if i:
            parent = "beam" if i == 1 else f"part{i - 1}"
            links.append(f'<link name="{name}"/>')
            joints.append(
                f'<joint name="cut{i}" type="revolute"><parent link="{parent}"/>'
                f'<child link="{name}"/><origin xyz="{(marks[i] - marks[i - 1]) * L!r} 0 0"/>'
                '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>'
                "</joint>")
            if condition:
                joints.append(f'<pinflex:joint name="cut{i}" {condition}/>')
    return text.replace('<link name="beam"/>', '<link name="beam"/>' + "".join(links)).replace(
        "</robot>", "".join(joints) + "".join(beams) + "</robot>")


def split_model(tmp_path, cuts, **kw):
    path = tmp_path / f"split{len(cuts)}.urdf"
    path.write_text(split_urdf(cuts, **{k: v for k, v in kw.items() if k != "joints"}))
    return FlexibleModel(path, planar=kw.get("planar", True),
                         **({"joints": kw["joints"]} if "joints" in kw else {}))


def spinning(dyn, omega, k):
    q = np.zeros(dyn.nv)
    qd = np.zeros(dyn.nv)
    qd[0] = omega
    return modes_at_speed(dyn, q, qd, n_modes=k).freq_hz


@pytest.mark.parametrize("cuts, condition", [
    ((0.3,), ""), ((0.5,), 'locked="true"'), ((0.8,), 'stiffness="50"'),
    ((0.3, 0.7), ""), ((0.4, 0.5), 'locked="true"')])
def test_split_beam_spinning_in_plane_is_the_rotating_frame_fe(tmp_path, cuts, condition):
    """In plane, Ω = 1, 4, 10 rad/s (Ωs/ω₁ up to 2.63): the four lowest modes equal the FE's
    to 1e-9, wherever the cuts are (one or two joints; a one-element middle link makes the
    second joint's offset change with the first one's), free, locked or sprung joints
    (the motors hold them all)."""
    dyn = ErlsDynamics(split_model(tmp_path, cuts, condition=condition))
    for omega in (1.0, 4.0, 10.0):
        M, G, K, KN, _, _ = beam_fe(10, spin_n(omega))
        ref = lowest_hz(M, 2.0 * omega * G, K - omega**2 * M + KN, 4)
        got = spinning(dyn, omega, 4)
        assert got == pytest.approx(ref, rel=1e-9)
        assert ref[0] > 1.05 * spinning(dyn, 0.0, 1)[0] if omega > 3 else True


def test_split_beam_spinning_across_the_plane_is_the_rotating_frame_fe(tmp_path):
    """Spatial beams cut at 0.3 and 0.6: the flapwise modes (``K + K_N`` across the plane, no
    softening) and the chordwise ones (in plane) each equal the FE's to 1e-9."""
    dyn = ErlsDynamics(split_model(tmp_path, (0.3, 0.6), planar=False))
    for omega in (2.0, 10.0):
        M, G, K, KN, _, _ = beam_fe(10, spin_n(omega))
        chord = lowest_hz(M, 2.0 * omega * G, K - omega**2 * M + KN, 2)
        bend = np.arange(M.shape[0]) % 3 != 0  # (v, θ) only: the flapwise plane
        lam = scipy.linalg.eigh((K + KN)[np.ix_(bend, bend)], M[np.ix_(bend, bend)],
                                eigvals_only=True)[:2]
        flap = np.sqrt(lam) / (2.0 * math.pi)
        got = spinning(dyn, omega, 6)
        for ref in (*chord, *flap):
            assert np.abs(got / ref - 1.0).min() <= 1e-9


@pytest.mark.parametrize("g", [9.81, -9.81])
def test_split_beam_hanging_or_standing_is_the_one_beam_under_its_weight(tmp_path, g):
    """At rest under gravity along the beam (hanging: tension, standing: compression): the
    geometric stiffness of ``N = ±ρA g (L − s)`` in the FE; in plane and across it, 1e-9."""
    for planar in (True, False):
        model = split_model(tmp_path, (0.4, 0.5), planar=planar)
        dyn = ErlsDynamics(model, gravity=[g, 0.0, 0.0])
        M, _, K, KN, _, _ = beam_fe(10, lambda s: RHOA * g * (L - s))
        ref = np.sqrt(scipy.linalg.eigh(K + KN, M, eigvals_only=True)[:3]) / (2 * math.pi)
        got = modes_at_speed(dyn, np.zeros(dyn.nv), n_modes=6 if not planar else 3).freq_hz
        for r in ref:
            assert np.abs(got / r - 1.0).min() <= 1e-9


def test_split_cantilever_gives_the_published_chordwise_frequencies(tmp_path):
    """The slenderness-70 cantilever (40 elements) cut in half at a held joint: chordwise
    mode 1 within the table's last digit + 2e-4 at γ = 4, 10, 50 (it was 21 % and 79 % above
    at γ = 4 and 10 before the joints' terms)."""
    chord, _, T = rotating_cantilever(tmp_path, KANE_URDF)
    text = chord.read_text()
    length = float(text.split('elements="40" normal="0 0 1" tip="')[1].split(" ")[0])
    half = text.replace(f'elements="40" normal="0 0 1" tip="{length} 0 0"',
                        f'elements="20" normal="0 0 1" tip="{length / 2!r} 0 0"')
    flex = half[half.index("<pinflex:flexible"):half.index("</pinflex:flexible>")]
    flex += "</pinflex:flexible>"
    split = tmp_path / "split_cantilever.urdf"
    split.write_text(half.replace('<link name="beam"/>', '<link name="beam"/><link name="out"/>')
                     .replace("</robot>", '<joint name="cut" type="revolute"><parent link="beam"/>'
                              f'<child link="out"/><origin xyz="{length / 2!r} 0 0"/>'
                              '<axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" '
                              'velocity="1"/></joint>'
                              + flex.replace('link="beam"', 'link="out"') + "</robot>"))
    dyn = ErlsDynamics(FlexibleModel(split, planar=True))
    for gamma in (4, 10, 50):
        f1 = spinning(dyn, gamma / T, 1)[0]
        assert table_close(2 * math.pi * f1 * T, CHORDWISE[gamma])


class HeldCut(SpinUp):
    """Kane's hub motion with a second joint held at zero (columns: hub, cut)."""

    def __init__(self, omega_s):
        super().__init__(omega_s)
        tr = self.trajectory
        tr.q = np.hstack([tr.q, np.zeros_like(tr.q)])
        self.q_start, self.q_end = np.zeros(2), np.array([self.q_end[0], 0.0])

    def __call__(self, t):
        return tuple(np.array([v[0], 0.0]) for v in super().__call__(t))

    def sample(self, times):
        return tuple(np.hstack([v, np.zeros_like(v)]) for v in super().sample(times))


def test_spin_up_of_the_split_beam_is_the_rotating_frame_fe(tmp_path):
    """Kane's spin-up at Ωs = 6 rad/s (Ωs/ω₁ = 1.58) with the beam cut at 0.5 and held there:
    the prescribed drive with terms='full' gives the FE's tip deflection to 1e-4 of its peak."""
    dyn = ErlsDynamics(split_model(tmp_path, (0.5,), condition='locked="true"'))
    motion = HeldCut(6.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ModelValidityWarning)
        sim = simulate_prescribed(dyn, motion, after_s=0.01, sample_hz=20.0, terms="full",
                                  start="rest", grid_per_interval=4, tol=1e-6)
    during = sim.times_s <= SPIN_UP_S
    M, G, K, KN1, fu, fv = beam_fe(10, spin_n(1.0))  # K_N per unit Ω²
    Mi = np.linalg.inv(M)
    m = M.shape[0]

    def rhs(t, y):
        _, thd, thdd = (float(v[0]) for v in SpinUp.__call__(motion, t))
        Kt = K - thd**2 * M + thdd * G + thd**2 * KN1
        return np.concatenate([y[m:], Mi @ (thd**2 * fu - thdd * fv - 2.0 * thd * G @ y[m:]
                                            - Kt @ y[:m])])

    sol = scipy.integrate.solve_ivp(rhs, (0.0, SPIN_UP_S), np.zeros(2 * m), method="Radau",
                                    rtol=1e-7, atol=1e-10, dense_output=True)
    ref = sol.sol(sim.times_s[during])[m - 2]
    # the outer link turns by its joint's elastic offset (the ERLS angle q = q_phys + A x):
    # its tip's deflection off the hub axis is 5 m times that angle plus its own v
    tip = 5.0 * sim.q[during, 1] + sim.x[during, -2]
    peak = np.abs(ref).max()
    assert np.abs(tip - ref).max() <= 1e-4 * peak



def held_mass(kind, link, tip, offset, mass, izz):
    """A mass ``mass`` [kg] (inertia ``izz`` [kg m²] about z) held rigidly at ``offset`` (x, y)
    from the point ``tip`` of ``link``, as a point mass, a body, a rigid link fixed at the tip,
    or a rigid link fixed at the mass (its joint off the beam's axis)."""
    rx, ry = offset
    at = f"{tip + rx!r} {ry!r} 0"
    inertia = f'ixx="{izz / 2}" iyy="{izz / 2}" izz="{izz}"'
    if kind == "point":
        return f'<pinflex:point_mass name="m" link="{link}" xyz="{at}" mass="{mass}"/>'
    if kind == "body":
        return f'<pinflex:body name="m" link="{link}" xyz="{at}" mass="{mass}" {inertia}/>'
    joint, com = (f"{tip!r} 0 0", f"{rx!r} {ry!r} 0") if kind == "rigid" else (at, "0 0 0")
    return (f'<link name="tool"><inertial><origin xyz="{com}"/><mass value="{mass}"/>'
            f'<inertia {inertia} ixy="0" ixz="0" iyz="0"/></inertial></link>'
            f'<joint name="fix" type="fixed"><parent link="{link}"/><child link="tool"/>'
            f'<origin xyz="{joint}"/></joint>')


def lever_case(tmp_path, offset, mass, omega, *, cut, kind="point", izz=0.0):
    """``(pinflex, FE)`` lowest four frequencies [Hz] of Kane's beam spinning at ``omega`` with
    a mass ``mass`` [kg] (``izz`` [kg m²]) held at ``offset`` (x, y) [m] from the tip
    (:func:`held_mass`), the beam whole or cut at 0.5. The FE carries the mass on a rigid
    lever: at ``tip + R(θ) r``, to second order in the tip rotation θ (the lever term
    θ×(θ×r)/2), its inertia on θ."""
    rx, ry = offset
    pm = held_mass(kind, "part1" if cut else "beam", L / 2 if cut else L, offset, mass, izz)
    path = tmp_path / "lever.urdf"
    path.write_text((split_urdf((0.5,)) if cut else KANE_URDF).replace("</robot>",
                                                                      pm + "</robot>"))
    P0 = np.array([L + rx, ry])  # the mass in the hub frame
    M, G, K, KN, _, _ = beam_fe(10, lambda s: spin_n(omega)(s) + mass * omega**2 * P0[0])
    Jp = np.zeros((2, M.shape[0]))  # the mass's displacement from the tip's (u, v, θ)
    Jp[0, -3], Jp[1, -2] = 1.0, 1.0
    Jp[:, -1] = [-ry, rx]
    turn = np.array([[0.0, -1.0], [1.0, 0.0]])  # z ×
    M = M + mass * Jp.T @ Jp
    G = G + mass * Jp.T @ turn @ Jp
    K = K - omega**2 * M  # −½ m Ω² |P|² with P = P0 + Jp x − r θ²/2: its Hessian
    M[-1, -1] += izz
    K[-1, -1] += mass * omega**2 * (P0 @ np.array([rx, ry]))
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelValidityWarning)
        got = spinning(ErlsDynamics(FlexibleModel(path, planar=True)), omega, 4)
    return got, lowest_hz(M, 2.0 * omega * G, K + KN, 4)


@pytest.mark.filterwarnings("ignore::pinflex.exceptions.PlausibilityWarning")  # the lever
@pytest.mark.parametrize("offset", [(0.0, 0.4), (0.5, 0.0), (0.3, -0.6)])
def test_point_mass_on_a_rigid_lever_spinning_is_the_rotating_frame_fe(tmp_path, offset):
    """A 3 kg point mass held off the tip of Kane's beam (beside the axis, beyond the tip,
    both) at Ω = 2 and 6 rad/s: the four lowest modes equal the FE's with the rigid lever to
    1e-9 (without the lever term 0.2 % to 7 % off at 6 rad/s). Cut at 0.5 with the mass on the
    outer link: the same to 1e-9 for the mass on the axis; beside it the mass's load across
    the beam makes
    the cut beam differ at second order in that load (3 kg: 2e-7; 0.3 kg: 100 times less)."""
    for omega in (2.0, 6.0):
        got, ref = lever_case(tmp_path, offset, 3.0, omega, cut=False)
        assert got == pytest.approx(ref, rel=1e-9)
    got, ref = lever_case(tmp_path, offset, 3.0, 2.0, cut=True)
    if offset[1] == 0.0:
        assert got == pytest.approx(ref, rel=1e-9)
        return
    big = np.abs(got / ref - 1.0).max()
    got, ref = lever_case(tmp_path, offset, 0.3, 2.0, cut=True)
    small = np.abs(got / ref - 1.0).max()
    assert big <= 1e-6 and small <= big / 50.0


@pytest.mark.filterwarnings("ignore::pinflex.exceptions.PlausibilityWarning")  # the lever
@pytest.mark.parametrize("kind", ["body", "rigid", "joint"])
def test_a_held_mass_is_the_same_lever_in_every_description(tmp_path, kind):
    """The 3 kg mass (0.03 kg m² about z) held beyond and beside the tip of Kane's spinning
    beam as a body on the beam, a rigid link fixed at the tip, or a rigid link fixed at the
    mass (a joint off the beam's axis): the four lowest modes equal the rigid-lever FE's to
    1e-9 at Ω = 2 and 6 rad/s (each takes another route to the lever term)."""
    for offset in ((0.5, 0.0), (0.3, -0.6)):
        for omega in (2.0, 6.0):
            got, ref = lever_case(tmp_path, offset, 3.0, omega, cut=False, kind=kind, izz=0.03)
            assert got == pytest.approx(ref, rel=1e-9)
