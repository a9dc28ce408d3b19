"""Joint springs and locked joints against independent global FE models and closed forms."""

import math

import numpy as np
import pytest
from arms import spatial_reference, spatial_urdf
from conftest import TWO_LINK
from reference_fe import cantilever_hz, planar_two_link_frequencies, torsion_fixed_free_hz

import pinflex
from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.erls.joints import joint_transform
from pinflex.exceptions import (
    ConfigurationError,
    InvalidBeamProperty,
    InvalidDescription,
    JointNotFound,
)

Q0 = np.array([1.817, 5.312])
# springs of the order of the links' own bending stiffness EI/L (2.74e3/0.6 and /0.45 N m)
K1, K2 = 4.0e3, 1.5e3


def _bench(joints, planar=True):
    return FlexibleModel(TWO_LINK, planar=planar, joints=joints)


@pytest.mark.parametrize(
    ("ours", "ref", "rigid"),
    [
        ({"q1": K1, "q2": K2}, [K1, K2], 0),
        ({"q2": K2}, [None, K2], 1),
        ({"q1": K1}, [K1, None], 1),
        ("locked", ["clamped", "clamped"], 0),
        ({"q2": "locked"}, [None, "clamped"], 1),
        ({"q1": "locked", "q2": K2}, ["clamped", K2], 0),
    ],
)
def test_benchmark_a_joint_conditions_match_global_frame(ours, ref, rigid):
    """Springs on the physical relative rotation and clamped hinges equal the global FE."""
    model = _bench(ours)
    assert model.n_rigid == rigid
    rng = np.random.default_rng(7)
    for _ in range(6):
        q_abs = rng.uniform(-np.pi, 2 * np.pi, size=2)
        y = rng.uniform(0.0, 0.25, size=2)
        _, f_ref = planar_two_link_frequencies(q_abs, y[0], y[1], joints=ref)
        f = model.frequencies(q_abs, y)
        assert f.shape == f_ref.shape
        np.testing.assert_allclose(f, f_ref, rtol=1e-9)
    res = model.modes(Q0, n_modes=3)
    assert res.rigid_modes == rigid
    _, f_ref = planar_two_link_frequencies(Q0, 0.125, 0.125, joints=ref)
    np.testing.assert_allclose(res.freq_hz, f_ref[:3], rtol=1e-9)


def test_annotations_are_the_default_and_free_or_locked_override_them():
    """A file's <pinflex:joint> springs and locks apply unless 'free' or 'locked' is asked."""
    text = TWO_LINK.read_text().replace(
        "<pinflex:coordinates", f'<pinflex:joint name="q1" stiffness="{K1}"/>'
        '<pinflex:joint name="q2" locked="true"/><pinflex:coordinates'
    )
    desc = parse(text)
    ann = FlexibleModel(desc, planar=True)
    assert ann.n_rigid == 0 and ann.ndof == 22 and ann.joint_switch == "annotated"
    assert ann.joint_labels() == {"q1": "k=4e+03", "q2": "locked"}
    _, f_ref = planar_two_link_frequencies(Q0, 0.125, 0.125, joints=[K1, "clamped"])
    np.testing.assert_allclose(ann.frequencies(Q0), f_ref, rtol=1e-9)
    np.testing.assert_allclose(ann.modes(Q0).freq_hz, f_ref, rtol=1e-9)
    same = FlexibleModel(desc, planar=True, joints="annotated")  # the accepted synonym
    np.testing.assert_array_equal(same.frequencies(Q0), ann.frequencies(Q0))
    free = FlexibleModel(desc, planar=True, joints="free")
    assert free.n_rigid == 2 and free.ndof == 23 and free.joint_switch == "free"
    _, f_free = planar_two_link_frequencies(Q0, 0.125, 0.125)
    np.testing.assert_allclose(free.frequencies(Q0), f_free, rtol=1e-9)
    locked = FlexibleModel(desc, planar=True, joints="locked")
    _, f_locked = planar_two_link_frequencies(Q0, 0.125, 0.125, joints=["clamped", "clamped"])
    np.testing.assert_allclose(locked.frequencies(Q0), f_locked, rtol=1e-9)
    # a file without annotations stays free (benchmark A)
    plain = FlexibleModel(TWO_LINK, planar=True)
    assert plain.n_rigid == 2 and plain.joint_switch == "free"


def test_stiff_spring_tends_to_the_locked_joint():
    """|f(k) − f(locked)| falls like 1/k: ten times per decade of stiffness."""
    locked = _bench("locked").frequencies(Q0)[:4]
    errs = []
    for k in (1e5, 1e6, 1e7, 1e8):
        f = _bench({"q1": k, "q2": k}).frequencies(Q0)[:4]
        assert np.all(f < locked)  # a spring is softer than a lock
        errs.append(np.max(np.abs(f / locked - 1)))
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 8.0) & (ratios < 12.0)), ratios
    assert errs[-1] < 2e-4  # at k = 1e8 N m/rad, about 3e4 times the links' EI/L


@pytest.mark.parametrize("seed", [0, 1])
def test_spatial_springs_and_locks_match_global_frame(seed):
    """A skewed spatial arm: springs on both revolute joints, then a locked elbow."""
    rng = np.random.default_rng(seed)
    m1, m2 = rng.uniform(0, 0.5, size=2)
    desc = parse(spatial_urdf(m1, m2))
    k1, k2 = rng.uniform(50.0, 500.0, size=2)
    sprung = FlexibleModel(desc, joints={"j1": k1, "j2": k2})
    elbow_locked = FlexibleModel(desc, joints={"j2": "locked"})
    for q in rng.uniform(-np.pi, np.pi, size=(2, 2)):
        _, ref = spatial_reference(q, m1, m2, springs={0: k1, 1: k2})
        np.testing.assert_allclose(sprung.frequencies(q), ref, rtol=1e-8)
        _, ref = spatial_reference(q, m1, m2, elbow="fixed")
        # the top modes of the inverse form carry ~n ε λ_k/λ_1 (1.2e-9 at mode 52 of 54)
        np.testing.assert_allclose(elbow_locked.frequencies(q), ref, rtol=3e-9)


def _straight_arm(e1, e2, joints):
    """Two equal steel beams in line along x on joints about z and y: one uniform beam."""
    sec = dict(E=2.1e11, G=8.1e10, density=7850.0, A=2e-4, Iy=1.5e-9, Iz=4e-9, J=3e-9)

    def flex(link, n, L):
        return (f'<pinflex:flexible link="{link}" elements="{n}" tip="{L} 0 0" normal="0 0 1">'
                f'<pinflex:material E="{sec["E"]}" G="{sec["G"]}" density="{sec["density"]}"/>'
                f'<pinflex:section A="{sec["A"]}" Iy="{sec["Iy"]}" Iz="{sec["Iz"]}" '
                f'J="{sec["J"]}"/></pinflex:flexible>')

    urdf = f"""<robot name="straight" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="a"/><link name="b"/>
  <joint name="ja" type="revolute"><parent link="base"/><child link="a"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="jb" type="revolute"><parent link="a"/><child link="b"/>
    <origin xyz="0.6 0 0"/><axis xyz="0 1 0"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  {flex("a", e1, 0.6)}{flex("b", e2, 0.6)}
</robot>"""
    return FlexibleModel(parse(urdf), joints=joints), sec


def test_fully_locked_straight_arm_is_a_clamped_cantilever():
    """Both joints locked: bending in both planes and torsion of a 1.2 m clamped beam."""
    model, sec = _straight_arm(30, 30, "locked")
    assert model.n_rigid == 0 and model.ndof == model.nx
    f = model.frequencies(np.zeros(2))
    L, rhoA = 1.2, sec["density"] * sec["A"]
    expected = np.concatenate([
        cantilever_hz(L, sec["E"] * sec["Iz"], rhoA, 3),
        cantilever_hz(L, sec["E"] * sec["Iy"], rhoA, 3),
        torsion_fixed_free_hz(L, sec["G"], sec["J"], sec["density"], sec["Iy"] + sec["Iz"], 1),
    ])
    for target in expected:
        nearest = f[np.argmin(np.abs(f - target))]
        # 60 elements: torsion (linear elements) converged to ~1e-4
        assert abs(nearest / target - 1) < 2e-4
    bending = np.sort(expected[:6])
    got = np.array([f[np.argmin(np.abs(f - t))] for t in bending])
    # cubic bending elements at 60 elements: mesh error 2e-7 at mode 3; mode 1 is limited by
    # round-off of the direct solve (a few 1e-8, SPEC §7)
    np.testing.assert_allclose(got[:2], bending[:2], rtol=1e-7)
    np.testing.assert_allclose(got, bending, rtol=5e-7)


def test_locked_pose_does_not_change_a_straight_cantilever_base_rotation():
    """Locked at the base, the base angle only turns the beam: same frequencies."""
    model, _ = _straight_arm(6, 6, "locked")
    np.testing.assert_allclose(model.frequencies([0.7, 0.0]), model.frequencies([0.0, 0.0]),
                               rtol=1e-10)


def _slider(k, n=60):
    urdf = f"""<robot name="slider" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="bar"/>
  <joint name="s" type="prismatic"><parent link="base"/><child link="bar"/>
    <axis xyz="1 0 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="bar" elements="{n}" tip="1.0 0 0" normal="0 0 1">
    <pinflex:material E="7e10" density="2700"/>
    <pinflex:section A="1e-4" Iy="1e-9" Iz="1e-9" J="2e-9"/>
  </pinflex:flexible>
  <pinflex:joint name="s" stiffness="{k}"/>
</robot>"""
    return FlexibleModel(parse(urdf), planar=True, joints="annotated")


def test_prismatic_spring_gives_the_rod_on_an_axial_spring():
    """Axial modes of a rod on an end spring: EA β tan(βL) = k (closed form)."""
    EA, rhoA, L, k = 7e10 * 1e-4, 2700 * 1e-4, 1.0, 3e6
    model = _slider(k)
    assert model.n_rigid == 0
    f = model.frequencies([0.0])
    from scipy.optimize import brentq

    def root(n):  # n-th root of EA x tan(x) / L = k in x = βL
        return brentq(lambda x: EA * x / L * math.sin(x) - k * math.cos(x),
                      (n - 1) * math.pi + 1e-12, (n - 0.5) * math.pi - 1e-12)

    for n in (1, 2):
        target = root(n) / L * math.sqrt(EA / rhoA) / (2 * math.pi)
        nearest = f[np.argmin(np.abs(f - target))]
        assert abs(nearest / target - 1) < 2e-4  # 60 linear axial elements


def test_taylor_model_of_locked_and_sprung_arms_is_exact():
    """The jets of M, K carry the joint terms: order-4 error falls like h⁵ towards q0."""
    for joints in ({"q2": "locked"}, {"q1": K1, "q2": K2}):
        model = _bench(joints)
        tm = pinflex.expand(model, Q0, order=4, modes=(1, 2))
        errs = []
        for h in (0.08, 0.04):
            q = Q0 + h * np.array([0.6, -1.0])
            exact = model.frequencies(q)[:2] ** 2 * (2 * np.pi) ** 2
            errs.append(np.max(np.abs(tm.evaluate(q[None])[0] / exact - 1)))
        assert errs[0] < 1e-4
        assert 20 < errs[0] / errs[1] < 45, errs


def test_locked_mode_shapes_satisfy_the_eigenproblem_on_full_coordinates():
    """Shapes solve the locked pencil; mapped back, the locked joint has no relative motion."""
    model = _bench({"q2": "locked"})
    res = model.modes(Q0, n_modes=3)
    M, K = model.matrices(Q0)
    phi = res.shapes
    np.testing.assert_allclose(K @ phi, M @ phi * res.eigvals, rtol=1e-8, atol=1e-6)
    T = joint_transform(model, Q0)
    G = model.relative_motion_rows(Q0)
    assert T.shape == (model.nx + model.nv, model.ndof)
    r = G @ T @ phi
    assert np.max(np.abs(r[1])) < 1e-12 * np.max(np.abs(phi))  # the elbow does not move
    assert np.max(np.abs(r[0])) > 1e-3  # the base does
    assert set(res.node_motion) == {"link1", "link2"}


def test_bad_joint_conditions_are_named_errors():
    """Unknown switches, joints and non-positive stiffnesses raise PinflexError subclasses."""
    with pytest.raises(ConfigurationError, match="joints='stiff'"):
        _bench("stiff")
    with pytest.raises(JointNotFound):
        _bench({"elbow": "locked"})
    with pytest.raises(InvalidBeamProperty, match="stiffness"):
        _bench({"q1": -5.0})
    base = TWO_LINK.read_text()
    with pytest.raises(JointNotFound):
        parse(base.replace("<pinflex:coordinates", '<pinflex:joint name="tool_joint" '
                           'locked="true"/><pinflex:coordinates'))
    with pytest.raises(InvalidDescription, match="not both"):
        parse(base.replace("<pinflex:coordinates", '<pinflex:joint name="q1" locked="true" '
                           'stiffness="3"/><pinflex:coordinates'))
    with pytest.raises(InvalidBeamProperty, match="positive"):
        parse(base.replace("<pinflex:coordinates", '<pinflex:joint name="q1" stiffness="0"/>'
                           '<pinflex:coordinates'))


def test_command_line_switch_and_json_carry_the_joint_condition(capsys):
    """``pinflex modes --joints locked --json`` reports the locked model and its labels."""
    import json

    from pinflex.cli import main

    assert main(["modes", str(TWO_LINK), "--planar", "--q", "1.817", "5.312", "--modes", "2",
                 "--joints", "locked", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["rigid_modes"] == 0 and out["ndof"] == 21
    assert out["joint_condition"] == "locked"
    assert out["joints"] == {"q1": "locked", "q2": "locked"}
    _, f_ref = planar_two_link_frequencies(Q0, 0.125, 0.125, joints=["clamped", "clamped"])
    np.testing.assert_allclose(out["frequencies_hz"], f_ref[:2], rtol=1e-9)
    tm = pinflex.expand(_bench({"q1": K1}), Q0, order=2)
    assert tm.joints == {"q1": "k=4e+03", "q2": "free"}


def test_linear_model_export_of_a_locked_elbow():
    """The exported state-space model of a locked elbow has the locked frequencies."""
    from pinflex.native.export import linear_model

    model = _bench({"q2": "locked"})
    data = linear_model(model, Q0)
    assert data["A"].shape == (2 * model.ndof, 2 * model.ndof)
    assert list(data["coordinates"][-1:]) == ["q1"]
    w = np.sort(np.abs(np.linalg.eigvals(data["A"]).imag))[::2]  # ±iω pairs, rigid zeros
    _, f_ref = planar_two_link_frequencies(Q0, 0.125, 0.125, joints=[None, "clamped"])
    np.testing.assert_allclose(w[1:4] / (2 * np.pi), f_ref[:3], rtol=1e-7)


def test_modes_along_a_motion_on_a_locked_arm_are_the_locked_frequencies():
    """Mode tracking works on the modal coordinates of a locked arm."""
    from pinflex.erls.tracking import track_modes

    model = _bench("locked")
    Q = Q0 + np.linspace(0.0, 0.3, 5)[:, None] * np.array([0.0, 1.0])
    tr = track_modes(model, Q, modes=(1, 2))
    for q, lam in zip(Q, np.asarray(tr.eigvals)):
        _, f_ref = planar_two_link_frequencies(q, 0.125, 0.125, joints=["clamped"] * 2)
        np.testing.assert_allclose(np.sqrt(lam) / (2 * np.pi), f_ref[:2], rtol=1e-9)


def test_locked_mode_preview_names_the_joint_condition():
    """The preview of a locked arm's mode says so and draws the locked frequency."""
    pytest.importorskip("meshcat")
    from pinflex.visualization import mode_preview

    model = _bench("locked")
    preview = mode_preview(model, Q0, 1)
    assert "joints locked" in preview.caption
    _, f_ref = planar_two_link_frequencies(Q0, 0.125, 0.125, joints=["clamped"] * 2)
    assert preview.info["freq_hz"] == pytest.approx(f_ref[0], rel=1e-9)


def test_a_spring_too_stiff_for_the_eigensolver_warns():
    """1e12 N m/rad on benchmark A loses digits: a warning points to the lock; 1e8 does not."""
    import warnings

    from pinflex.exceptions import PinflexWarning

    with pytest.warns(PinflexWarning, match="locked"):
        _bench({"q2": 1e12})
    with warnings.catch_warnings():
        warnings.simplefilter("error", PinflexWarning)
        _bench({"q2": 1e8})
