"""The arm at speed in the outputs: export about a moving state, modes at speed along a
trajectory file, and the validity indicator drawn on the charts.

References written here with no pinflex code: the published frequencies of a rotating
cantilever (Hamza-Cherif and Houmat, 2004, Table 2; ``tests/arms.py``) and the joint rates of
motions quadratic in time. The export about a moving state is also checked against the
prescribed simulation's own linear system at the same instant (the same model by two routes).
"""

from __future__ import annotations

import csv
import json
import math
import warnings

import numpy as np
import pytest
import scipy.linalg
from arms import CHORDWISE, FLAPWISE, rotating_cantilever, table_close

from pinflex import FlexibleModel
from pinflex.cases.spin_up import KANE_URDF, SpinUp
from pinflex.cli import main
from pinflex.dynamics import Damping, ErlsDynamics
from pinflex.dynamics.export import linear_model_at_state
from pinflex.dynamics.modes import modes_at_speed, modes_at_speed_along
from pinflex.dynamics.prescribed import PrescribedSystem
from pinflex.exceptions import ConfigurationError, ModelValidityWarning
from pinflex.native.export import linear_model
from pinflex.trajectory import Trajectory


@pytest.fixture(scope="module")
def kane_path(tmp_path_factory):
    path = tmp_path_factory.mktemp("kane") / "kane.urdf"
    path.write_text(KANE_URDF)
    return path


def _write_csv(path, t, theta):
    path.write_text("t,hub\n" + "".join(f"{float(a)!r},{float(b)!r}\n"
                                         for a, b in zip(t, theta)))
    return path


def _frequencies(A):
    """|Im λ| / 2π of the eigenvalues of A with Im λ > 0, ascending, and their vectors."""
    lam, V = scipy.linalg.eig(A)
    keep = lam.imag > 0
    order = np.argsort(lam.imag[keep])
    return lam.imag[keep][order] / (2 * math.pi), V[:, keep][:, order]


def test_export_about_a_moving_state_is_the_prescribed_drives_system(kane_path):
    """Kane's spin-up at t = 5 s (Ωs = 6 rad/s: q̇ and q̈ both non-zero), terms='full'.

    The exported A and drive equal the prescribed simulation's state equation at that instant
    (Rayleigh damping included) to round-off, and the undamped A's eigenvalues are
    ``modes_at_speed``'s frequencies.
    """
    arm = FlexibleModel(kane_path, planar=True, joints="locked")
    dyn = ErlsDynamics(arm)
    motion = SpinUp(6.0)
    system = PrescribedSystem(dyn, motion, Damping("rayleigh", 0.3, 1e-3), terms="full")
    t = 5.0
    Abar, bbar = system.state_matrix(system.coefficients(t))
    q, qd, qdd = motion(t)
    assert qd[0] > 1.0 and qdd[0] > 0.1
    data = linear_model_at_state(arm, q, qd, qdd, terms="full", rayleigh=(0.3, 1e-3))
    assert np.abs(data["A"] - Abar).max() <= 1e-12 * np.abs(Abar).max()
    assert np.abs(data["drive"] - bbar).max() <= 1e-12 * np.abs(bbar).max()
    undamped = linear_model_at_state(arm, q, qd, qdd, terms="full")
    ref = modes_at_speed(dyn, q, qd, qdd).freq_hz
    assert undamped["freq_hz"] == pytest.approx(ref, rel=1e-12)
    got, _ = _frequencies(undamped["A"])
    assert got[:5] == pytest.approx(ref[:5], rel=1e-9)
    assert str(undamped["terms"]) == "full" and undamped["qd"] == pytest.approx(qd)
    # along several states: one leading axis, each equal to the single-state export
    many = linear_model_at_state(arm, np.stack([q, q]), np.stack([qd, 0 * qd]),
                                 np.stack([qdd, qdd]), terms="full")
    assert many["A"].shape == (2, 2 * arm.nx, 2 * arm.nx)
    assert np.array_equal(many["A"][0], undamped["A"])


@pytest.mark.parametrize("gamma", [4, 10])
def test_exported_model_of_a_rotating_cantilever_gives_the_published_frequencies(
        tmp_path, gamma):
    """The exported A at Ω = γ / T: chordwise and flapwise frequencies of the table.

    Two speeds, both models built with every joint locked; terms='full'. With eq. (1)'s terms
    the flapwise frequency at γ = 10 is far below the table's.
    """
    chord_path, flap_path, T = rotating_cantilever(tmp_path, KANE_URDF)
    chord = FlexibleModel(chord_path, planar=True, joints="locked")
    f, _ = _frequencies(linear_model_at_state(chord, [0.0], [gamma / T], terms="full")["A"])
    assert table_close(2 * math.pi * f[0] * T, CHORDWISE[gamma])
    spatial = FlexibleModel(flap_path, joints="locked")
    out_of_plane = [i for i, n in enumerate(spatial.x_names) if n.endswith(("uz", "ry"))]
    in_plane = [i for i, n in enumerate(spatial.x_names) if n.endswith(("uy", "rz"))]

    def lowest_flapwise(terms):
        A = linear_model_at_state(spatial, [0.0], [gamma / T], terms=terms)["A"]
        f, V = _frequencies(A)
        share = np.abs(V[:spatial.nx])
        is_flap = share[out_of_plane].sum(0) > share[in_plane].sum(0)
        return 2 * math.pi * f[is_flap][0] * T

    assert table_close(lowest_flapwise("full"), FLAPWISE[gamma])
    if gamma == 10:
        assert lowest_flapwise("eq1") < 0.5 * FLAPWISE[10]


def test_export_at_rest_is_todays_export_and_a_moving_free_arm_is_refused(kane_path,
                                                                           tmp_path):
    """At rest the export is the one at a pose, bit for bit (also through the command line
    with --terms full); a moving state needs every joint locked (named remedy)."""
    arm = FlexibleModel(kane_path, planar=True, joints="locked")
    rest = linear_model(arm, [0.3], zeta=0.02)
    for terms in ("eq1", "full"):
        same = linear_model_at_state(arm, [0.3], [0.0], [0.0], terms=terms, zeta=0.02)
        assert same.keys() == rest.keys()
        for key in rest:
            assert np.array_equal(same[key], rest[key]), key
    common = [str(kane_path), "--planar", "--q", "0.3", "--joints", "locked"]
    assert main(["export", *common, "--out", str(tmp_path / "a.npz")]) == 0
    assert main(["export", *common, "--terms", "full", "--out", str(tmp_path / "b.npz")]) == 0
    a, b = np.load(tmp_path / "a.npz"), np.load(tmp_path / "b.npz")
    assert sorted(a.files) == sorted(b.files)
    for key in a.files:
        assert np.array_equal(a[key], b[key]), key
    # a moving state from the command line equals the Python export
    assert main(["export", *common, "--qd", "6", "--qdd", "0.5", "--terms", "full", "--out",
                 str(tmp_path / "c.npz")]) == 0
    c = np.load(tmp_path / "c.npz")
    ref = linear_model_at_state(arm, [0.3], [6.0], [0.5], terms="full")
    assert np.array_equal(c["A"], ref["A"]) and np.array_equal(c["drive"], ref["drive"])
    free = FlexibleModel(kane_path, planar=True)
    with pytest.raises(ConfigurationError, match="joints='locked'"):
        linear_model_at_state(free, [0.3], [6.0])
    with pytest.raises(ConfigurationError, match="shape of q"):
        linear_model_at_state(arm, [0.3], [6.0, 1.0])


@pytest.mark.parametrize("gamma", [4, 10])
def test_modes_cli_at_constant_speed_gives_the_published_chordwise_frequency(tmp_path, gamma):
    """`pinflex modes --trajectory --at-speed` along θ = Ω t, Ω = γ / T: every sample's mode 1
    is the table's chordwise frequency; the rates are Ω and 0 (finite differences exact)."""
    chord_path, _, T = rotating_cantilever(tmp_path, KANE_URDF)
    omega = gamma / T
    t = np.linspace(0.0, 0.2, 3)
    traj = _write_csv(tmp_path / "spin.csv", t, omega * t)
    out = tmp_path / "modes.csv"
    assert main(["modes", str(chord_path), "--planar", "--trajectory", str(traj), "--at-speed",
                 "--modes", "2", "--csv", str(out)]) == 0
    rows = list(csv.DictReader(out.open()))
    assert len(rows) == t.size
    for row in rows:
        assert float(row["d(hub)/dt"]) == pytest.approx(omega, rel=1e-12)
        assert abs(float(row["d2(hub)/dt2"])) <= 1e-9 * omega
        assert table_close(2 * math.pi * float(row["mode1_hz"]) * T, CHORDWISE[gamma])


def test_modes_cli_along_an_accelerating_trajectory_equals_modes_at_speed(kane_path, tmp_path,
                                                                          capsys):
    """θ = Ω₀ t + a t²/2 (rates exact by second-order differences): the command's JSON and
    CSV frequencies equal modes_at_speed at the exact state, for both terms; the JSON, CSV and
    chart carry the same validity ratios."""
    w0, a = 1.5, 0.8
    t = np.linspace(0.0, 2.0, 9)
    traj = _write_csv(tmp_path / "acc.csv", t, w0 * t + 0.5 * a * t * t)
    dyn = ErlsDynamics(FlexibleModel(kane_path, planar=True))
    for terms in ("full", "eq1"):
        out = tmp_path / f"{terms}.csv"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ModelValidityWarning)
            assert main(["modes", str(kane_path), "--planar", "--trajectory", str(traj),
                         "--terms", terms, "--json", "--csv", str(out)]) == 0
        js = json.loads(capsys.readouterr().out)
        assert js["terms"] == terms and js["rates"] == "samples"
        rows = list(csv.DictReader(out.open()))
        for i in (0, 4, 8):
            ref = modes_at_speed(dyn, [w0 * t[i] + 0.5 * a * t[i] ** 2], [w0 + a * t[i]], [a],
                                 terms=terms, n_modes=3).freq_hz
            assert js["frequencies_hz"][i] == pytest.approx(ref, rel=1e-9)
            assert [float(rows[i][f"mode{k}_hz"]) for k in (1, 2, 3)] == pytest.approx(
                ref, rel=1e-9)
        assert [float(r["speed_ratio"]) for r in rows] == js["validity"]["speed_ratio"]
        assert [float(r["accel_ratio"]) for r in rows] == js["validity"]["accel_ratio"]
    # the chart's indicator panel draws exactly these ratios, with the threshold
    res = modes_at_speed_along(dyn, Trajectory(t, (w0 * t + 0.5 * a * t * t)[:, None],
                                               ("hub",)), rates="samples")
    low = res.figure().axes[1]
    speed, accel, threshold = low.get_lines()[:3]
    assert np.array_equal(speed.get_xdata(), t)
    assert np.array_equal(speed.get_ydata(), np.maximum(res.validity.speed_ratio[:, 0], 1e-12))
    assert np.array_equal(accel.get_ydata(), np.maximum(res.validity.accel_ratio[:, 0], 1e-12))
    assert list(threshold.get_ydata()) == [0.1, 0.1]
    # the ratios are those of the exact rates: |θ̇|²/ω₁² and |θ̈|/ω₁² at the frequencies found
    w1 = 2 * math.pi * res.freq_hz[:, 0]
    assert res.validity.speed_ratio[:, 0] == pytest.approx((w0 + a * t) ** 2 / w1**2,
                                                           rel=1e-9)
    assert res.validity.accel_ratio[:, 0] == pytest.approx(a / w1**2, rel=1e-9)
    assert main(["modes", str(kane_path), "--planar", "--terms", "full"]) == 2
    assert "go with --trajectory" in capsys.readouterr().err


def test_modes_along_chart_draws_the_validity_of_its_csv(kane_path, tmp_path):
    """`modes --trajectory --png`'s chart: the lower panel's lines are the CSV's ratios."""
    from pinflex.erls.along import modes_along

    model = FlexibleModel(kane_path, planar=True)
    t = np.linspace(0.0, 2.0, 11)
    traj = Trajectory(t, (0.4 * t + 0.3 * t * t)[:, None], ("hub",))
    res = modes_along(model, traj, modes=2)
    res.to_csv(tmp_path / "m.csv")
    rows = list(csv.DictReader((tmp_path / "m.csv").open()))
    fig = res.figure()
    assert len(fig.axes) == 2
    speed, accel, threshold = fig.axes[1].get_lines()[:3]
    assert list(speed.get_ydata()) == [max(float(r["speed_ratio"]), 1e-12) for r in rows]
    assert list(accel.get_ydata()) == [max(float(r["accel_ratio"]), 1e-12) for r in rows]
    assert list(threshold.get_ydata()) == [0.1, 0.1]
    assert json.loads(res.to_json())["validity"]["speed_ratio"] == [
        float(r["speed_ratio"]) for r in rows]
    assert res.plot(tmp_path / "m.png").read_bytes()[:4] == b"\x89PNG"


def test_assignment_charts_draw_the_validity_of_the_assignment_csv(tmp_path):
    """Benchmark A's assignment: every chart's indicator panel draws the CSV's ratios."""
    from conftest import TWO_LINK

    from pinflex.assignment import Target, assign_frequencies
    from pinflex.assignment.charts import assignment_charts, assignment_figures
    from pinflex.assignment.report import assignment_data
    from pinflex.assignment.study import user_trajectory

    model = FlexibleModel(TWO_LINK, planar=True)
    traj = user_trajectory(model, "benchmark_a")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = assign_frequencies(model, traj, [Target(1, 190.0)], q0=np.array([1.817, 5.312]),
                                 y_before=np.zeros(2), report_modes=(2,))
    data = assignment_data(model, traj, res)
    data.to_csv(tmp_path / "a.csv")
    rows = [r for r in csv.DictReader((tmp_path / "a.csv").open()) if r["mode"] == "1"]
    speed = [float(r["speed_ratio"]) for r in rows]
    accel = [float(r["accel_ratio"]) for r in rows]
    assert 0.0 < max(speed) < 0.1 and len(speed) == traj.n_samples
    assert data.to_dict()["validity"]["speed_ratio"] == speed
    figures = assignment_figures(res, traj.times_s, data)
    assert sorted(figures) == ["mode1_assignment.png", "other_modes.png"]
    for fig in figures.values():
        lines = fig.axes[-1].get_lines()
        assert list(lines[0].get_ydata()) == [max(v, 1e-12) for v in speed]
        assert list(lines[1].get_ydata()) == [max(v, 1e-12) for v in accel]
        assert list(lines[2].get_ydata()) == [0.1, 0.1]
    paths = assignment_charts(res, traj.times_s, tmp_path / "charts", data)
    assert [p.name for p in paths] == ["mode1_assignment.png", "other_modes.png"]


def test_export_along_a_trajectory_with_the_motions_rates_is_the_prescribed_simulations(
        kane_path, tmp_path, capsys):
    """`export --trajectory --terms full --rates motion`: at every sample the exported A and
    drive are the prescribed simulation's state equation (the same rest-to-rest spline) to
    1e-12; `modes --rates motion` gives modes_at_speed_along's frequencies; --rates alone is
    refused."""
    from pinflex.dynamics.motion import JointMotion

    t = np.linspace(0.0, 2.0, 17)
    s = t / 2.0
    traj = _write_csv(tmp_path / "move.csv", t, 1.2 * s**3 * (10 - 15 * s + 6 * s * s))
    arm = FlexibleModel(kane_path, planar=True, joints="locked")
    common = [str(kane_path), "--planar", "--joints", "locked", "--trajectory", str(traj)]
    assert main(["export", *common, "--terms", "full", "--rates", "motion", "--out",
                 str(tmp_path / "m.npz")]) == 0
    data = np.load(tmp_path / "m.npz")
    assert data["A"].shape == (t.size, 2 * arm.nx, 2 * arm.nx)
    trajectory = Trajectory.from_csv(traj, joint_names=arm.joint_names)
    system = PrescribedSystem(ErlsDynamics(arm), JointMotion(trajectory), terms="full")
    for i in (1, 8, 13):
        Abar, bbar = system.state_matrix(system.coefficients(t[i]))
        assert np.abs(data["A"][i] - Abar).max() <= 1e-12 * np.abs(Abar).max()
        assert np.abs(data["drive"][i] - bbar).max() <= 1e-12 * np.abs(bbar).max()
    capsys.readouterr()
    assert main(["modes", *common, "--at-speed", "--rates", "motion", "--json"]) == 0
    js = json.loads(capsys.readouterr().out)
    ref = modes_at_speed_along(ErlsDynamics(arm), trajectory)
    assert js["rates"] == "motion"
    assert np.array_equal(np.array(js["frequencies_hz"]), ref.freq_hz)
    assert main(["modes", *common, "--rates", "motion"]) == 2
    assert main(["export", *common, "--rates", "motion", "--out", str(tmp_path / "x.npz")]) == 2
    assert "--rates" in capsys.readouterr().err


def test_modes_at_speed_along_matches_trajectory_columns_by_name():
    """A trajectory whose columns are in another order than the arm's joints gives the same
    modes at speed (columns matched by name, both rate schemes)."""
    from conftest import TWO_LINK

    arm = FlexibleModel(TWO_LINK, planar=True)
    dyn = ErlsDynamics(arm)
    t = np.linspace(0.0, 1.0, 7)
    q = np.stack([0.3 + 0.5 * t**3 * (10 - 15 * t + 6 * t * t), 2.0 - 0.8 * t * t], axis=1)
    names = tuple(arm.joint_names)
    ordered = Trajectory(t, q, names)
    swapped = Trajectory(t, q[:, ::-1], names[::-1])
    for rates in ("motion", "samples"):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            a = modes_at_speed_along(dyn, ordered, rates=rates, n_modes=2, terms="eq1")
            b = modes_at_speed_along(dyn, swapped, rates=rates, n_modes=2, terms="eq1")
        assert np.array_equal(a.qd, b.qd)  # the frequencies to round-off (the order of
        assert a.freq_hz == pytest.approx(b.freq_hz, rel=1e-12)  # BLAS sums varies)
        assert not np.allclose(a.freq_hz[3], a.freq_hz[0])


def test_coarse_samples_for_the_speed_terms_are_warned_and_reported(kane_path, tmp_path,
                                                                     capsys):
    """θ = 0.5 sin(πt) on Kane's beam (|θ̇|²/ω₁² ≈ 0.12, |θ̈|/ω₁² ≈ 0.23): with 17 samples the
    finite-difference rates change the speed terms by several % of the elastic forces (warned,
    with the remedy); with 257 samples by less than 1 % (silent). The estimates are reported
    and bound the actual error of the rates against the exact ones."""
    from pinflex.exceptions import TrajectoryWarning

    dyn = ErlsDynamics(FlexibleModel(kane_path, planar=True))
    for n, warns in ((17, True), (257, False)):
        t = np.linspace(0.0, 2.0, n)
        traj = Trajectory(t, (0.5 * np.sin(np.pi * t))[:, None], ("hub",))
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = modes_at_speed_along(dyn, traj, rates="samples", n_modes=1)
        got = [w for w in caught if issubclass(w.category, TrajectoryWarning)
               and "too coarsely" in str(w.message)]
        assert bool(got) is warns, n
        err = res.to_dict()["rates_error"]
        assert (err["terms"] > 1e-2) is warns
        exact_qd = 0.5 * np.pi * np.cos(np.pi * t)
        exact_qdd = -0.5 * np.pi**2 * np.sin(np.pi * t)
        assert np.abs(res.qd[:, 0] - exact_qd).max() / np.abs(exact_qd).max() <= err["velocity"]
        assert np.abs(res.qdd[:, 0] - exact_qdd).max() / np.abs(exact_qdd).max() <= \
            err["acceleration"]
    # the export along the same coarse samples says so too (on stderr, the command's warnings)
    t = np.linspace(0.0, 2.0, 17)
    coarse = _write_csv(tmp_path / "coarse.csv", t, 0.5 * np.sin(np.pi * t))
    capsys.readouterr()
    assert main(["export", str(kane_path), "--planar", "--joints", "locked", "--trajectory",
                 str(coarse), "--terms", "full", "--out", str(tmp_path / "c.npz")]) == 0
    assert "too coarsely" in capsys.readouterr().err


def _split_beam(folder):
    """Kane's beam in two links of 5 m joined by a revolute elbow (every joint is held)."""
    half = KANE_URDF.replace('elements="10" normal="0 0 1" tip="10 0 0"',
                             'elements="5" normal="0 0 1" tip="5 0 0"')
    beam = half[half.index("<pinflex:flexible"):half.index("</pinflex:flexible>")]
    beam += "</pinflex:flexible>"
    text = half.replace('<link name="beam"/>', '<link name="beam"/><link name="outer"/>').replace(
        "</robot>",
        '<joint name="elbow" type="revolute"><parent link="beam"/><child link="outer"/>'
        '<origin xyz="5 0 0"/><axis xyz="0 0 1"/>'
        '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        + beam.replace('link="beam"', 'link="outer"') + "</robot>")
    path = folder / "split.urdf"
    path.write_text(text)
    return path


def test_full_terms_on_a_deforming_link(kane_path, tmp_path, capsys):
    """terms='full' with a joint on a deforming link: Kane's beam split at a held elbow is the
    one beam at speed (it was 79 % off the table at γ = 10 before the joints' terms, and then
    refused), in Python and through the export command (the exported A's frequencies); eq.
    (1)'s terms are served too."""
    split = FlexibleModel(_split_beam(tmp_path), planar=True)
    one = ErlsDynamics(FlexibleModel(kane_path, planar=True))
    two = ErlsDynamics(split)
    for qd in (0.0, 1.0, 6.0):
        ref = modes_at_speed(one, [0.0], [qd], n_modes=3).freq_hz
        assert modes_at_speed(two, [0.0, 0.0], [qd, 0.0], n_modes=3).freq_hz == pytest.approx(
            ref, rel=1e-9)
    with warnings.catch_warnings():
        warnings.simplefilter("error", ModelValidityWarning)
        modes_at_speed(two, [0.0, 0.0], [1.0, 0.0], terms="eq1")
    locked = FlexibleModel(_split_beam(tmp_path), planar=True, joints="locked")
    assert main(["export", str(tmp_path / "split.urdf"), "--planar", "--joints", "locked",
                 "--qd", "6", "0", "--terms", "full", "--out", str(tmp_path / "s.npz")]) == 0
    exported = np.load(tmp_path / "s.npz")
    assert _frequencies(exported["A"])[0][:3] == pytest.approx(
        modes_at_speed(one, [0.0], [6.0], n_modes=3).freq_hz, rel=1e-8)
    assert linear_model_at_state(locked, [0.0, 0.0], [1.0, 0.0], terms="eq1")["A"].shape == (
        2 * locked.nx, 2 * locked.nx)
