"""Matched modes are the same modes: shapes of the lumped arm beside the ERLS model's."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pinocchio as pin
import pytest
from conftest import TWO_LINK

from pinflex.erls import FlexibleModel
from pinflex.lumped import build, fit_lumped
from pinflex.lumped.fit import locked_twin
from pinflex.lumped.shapes import mac_matrix, mismatches, node_translations, pairing

Q = np.array([0.4, 1.9])


@pytest.fixture(scope="module")
def arm():
    """Benchmark A, planar."""
    return FlexibleModel(TWO_LINK, planar=True)


@pytest.fixture(scope="module")
def fit(arm):
    """Benchmark A fitted with 4 segments per link at Q."""
    return fit_lumped(arm, 4, poses=Q, max_evaluations=60)


def test_point_translations_equal_finite_differences_of_the_placements(fit):
    """J-based translations of points on the segments = d/de of the moved points (Pinocchio)."""
    lumped = fit.lumped
    model, data = lumped.model, lumped.model.createData()
    x0 = lumped.configuration(Q)
    shapes = lumped.modes(Q, "own")[1][:, :2]
    pts = {link: np.array([[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [0.41, 0.0, 0.0]])
           for link in lumped.segments}
    # the points in world at the pose: on each link's beam axis (link frame x), root first
    pin.forwardKinematics(model, data, x0)
    world = {}
    for link, local in pts.items():
        jid, placement = lumped.frames[link]
        frame = data.oMi[jid] * placement
        world[link] = np.array([frame.act(p) for p in local])
    u = node_translations(lumped, Q, shapes, world)
    eps = 1e-7
    for m in range(2):
        cols = []
        for sign in (1.0, -1.0):
            pin.forwardKinematics(model, data, x0)
            fixed = []
            for link, pw in world.items():
                seg = lumped.segments[link]
                for p in pw:
                    s = np.linalg.norm(p - pw[0])
                    j = int(np.searchsorted(seg.bounds_m, s, side="right") - 1)
                    jid = lumped.segment_ids[(link, min(j, seg.n_segments - 1))]
                    fixed.append((jid, data.oMi[jid].actInv(p)))
            pin.forwardKinematics(model, data, x0 + sign * eps * shapes[:, m])
            cols.append(np.concatenate([data.oMi[jid].act(p) for jid, p in fixed]))
        np.testing.assert_allclose(u[:, m], (cols[0] - cols[1]) / (2 * eps),
                                   atol=1e-6 * np.abs(u[:, m]).max())


def test_a_good_fit_pairs_every_mode_with_its_own_shape(fit):
    """4 segments per link: every matched pair has MAC > 0.98, no mismatch."""
    assert fit.shape_mismatches == ()
    for c in fit.conditions:
        assert np.all(fit.mode_mac[c] > 0.98), (c, fit.mode_mac[c])


def test_swapped_modes_are_found(arm, fit):
    """Link 1's hinges 100 times stiffer: the lumped locked mode 1 becomes link 2's mode.

    Its frequency is paired with ERLS mode 1 (link 1's) but the shapes say otherwise.
    """
    erls = locked_twin(arm).modes(Q, n_modes=2)
    good = pairing(erls, fit.lumped, Q, "locked", 2)
    assert mismatches(good) == []
    segs = dict(fit.lumped.segments)
    segs["link1"] = replace(segs["link1"], stiffness=100.0 * segs["link1"].stiffness)
    stiff = build(fit.lumped.layout, segs)
    mac = pairing(erls, stiff, Q, "locked", 2)
    found = mismatches(mac)
    assert found and found[0][:2] == (0, 1), (mac, found)


def test_mac_of_hand_made_vectors():
    """MAC is 1 for parallel, 0 for orthogonal, scale-free; a swap is reported both ways."""
    a = np.array([[1.0, 0.0], [0.0, 1.0], [0.0, 0.0]])
    b = np.array([[0.0, -3.0], [2.0, 0.0], [0.0, 0.0]])
    mac = mac_matrix(a, b)
    np.testing.assert_allclose(mac, [[0.0, 1.0], [1.0, 0.0]])
    assert [m[:2] for m in mismatches(mac)] == [(0, 1), (1, 0)]
    assert mismatches(mac_matrix(a, a)) == []


def test_close_bending_planes_on_the_z1_pair_by_shape():
    """Z1 tubes (zero pose): each ERLS mode is paired with the lumped mode of its own shape.

    The test pairs the modes itself from the MAC of the two models' node translations. Paired
    by order (``pair_by_shape=False``), the fit names a pair that is not the same mode exactly
    when the test's pairing finds one (with the tubes alone: locked modes 3 and 4, 203.4
    and 206.6 Hz, one link's two bending planes, crosswise). Paired by shape (the default),
    every pair is its own mode and the frequencies are within the fit's stated error.
    """
    import warnings

    from conftest import ROOT

    from pinflex.lumped.shapes import erls_translations

    z1 = FlexibleModel(ROOT / "urdf" / "z1_tubes.xml")
    q = np.zeros(z1.nv)
    models = {"own": z1, "locked": locked_twin(z1)}
    erls = {c: m.modes(q, n_modes=4) for c, m in models.items()}

    def own_mac(lumped, c):
        pos, ue = erls_translations(erls[c])
        return mac_matrix(ue, node_translations(lumped, q, lumped.modes(q, c)[1][:, :4], pos))

    def crosswise(mac):
        return [(i, int(np.argmax(mac[i]))) for i in range(4) if np.argmax(mac[i]) != i]

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        by_order = fit_lumped(z1, 3, poses=q, axial=True, max_evaluations=60,
                              pair_by_shape=False)
    found = {(c, i, j) for c in models for i, j in crosswise(own_mac(by_order.lumped, c))}
    named = {(m[0], m[2], m[3]) for m in by_order.shape_mismatches if m[3] != m[2]}
    assert named == found
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        fit = fit_lumped(z1, 3, poses=q, axial=True, max_evaluations=60)
    assert fit.shape_mismatches == ()
    for c in models:
        mac = own_mac(fit.lumped, c)
        f = fit.lumped.frequencies(q, c)[:4][np.argmax(mac, axis=1)]
        assert np.all(np.abs(f / erls[c].freq_hz - 1.0) <= fit.worst_error + 1e-12), c
