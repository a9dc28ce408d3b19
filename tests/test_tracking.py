"""Modes followed by shape: closed-form pencils and an arm whose modes really cross."""

import crossing_arm as arm_ref
import numpy as np
import pytest

from pinflex.description import parse
from pinflex.erls import FlexibleModel
from pinflex.erls.tracking import mac_matrix, track, track_modes
from pinflex.exceptions import ConfigurationError


def _family(t, c):
    """Eigenpairs of K(t) = [[1 + t, c], [c, 2 - t]], M = I, sorted, at each t."""
    lam, vec = [], []
    for ti in t:
        w, v = np.linalg.eigh(np.array([[1 + ti, c], [c, 2 - ti]]))
        lam.append(w)
        vec.append(v)
    return np.array(lam), np.array(vec)


def test_mac_is_one_for_equal_shapes_and_zero_for_mass_orthogonal_ones():
    """MAC is scale-free, 1 on equal shapes and 0 on M-orthogonal ones."""
    M = np.array([[2.0, 0.5], [0.5, 1.0]])
    _, V = np.linalg.eigh(M)  # eigenvectors of M are orthogonal in M as well
    assert mac_matrix(V, V, M)[0, 1] == pytest.approx(0.0, abs=1e-15)
    assert mac_matrix(V, V)[1, 0] == pytest.approx(0.0, abs=1e-15)
    phi = np.linalg.solve(np.linalg.cholesky(M).T, np.eye(2))  # M-orthonormal columns
    assert mac_matrix(phi, phi, M)[0, 1] == pytest.approx(0.0, abs=1e-15)
    assert mac_matrix(phi, 3 * phi, M)[1, 1] == pytest.approx(1.0)


def test_uncoupled_branches_are_followed_through_their_crossing():
    """diag(1 + t, 2 − t) crosses at t = 1/2: tracked values are the two lines exactly."""
    t = np.linspace(0.0, 1.0, 40)  # no sample at the double eigenvalue itself
    lam, vec = _family(t, 0.0)
    tr = track(lam, vec, modes=(1, 2))
    np.testing.assert_allclose(tr.eigvals[:, 0], 1 + t, rtol=1e-14)
    np.testing.assert_allclose(tr.eigvals[:, 1], 2 - t, rtol=1e-14)
    (ev,) = tr.crossings()
    assert ev.modes == (1, 2) and t[ev.sample - 1] < 0.5 <= t[ev.sample]
    assert tr.veerings() == []
    assert tr.order[0].tolist() == [1, 2] and tr.order[-1].tolist() == [2, 1]


def test_coupled_branches_veer_and_are_not_called_a_crossing():
    """With coupling 0.02 the pencil veers (gap 0.04 at t = 1/2, shapes turn by 90°)."""
    t = np.linspace(0.0, 1.0, 201)
    lam, vec = _family(t, 0.02)
    tr = track(lam, vec, modes=(1, 2))
    assert tr.crossings() == []
    (ev,) = tr.veerings()
    assert ev.modes == (1, 2) and abs(t[ev.sample] - 0.5) < 0.01
    assert ev.gap == pytest.approx(np.sqrt(1.5 + 0.02) / np.sqrt(1.5 - 0.02) - 1, rel=0.05)
    np.testing.assert_array_equal(tr.eigvals, lam)  # tracking follows the sorted branches


@pytest.fixture(scope="module")
def crossing_arm():
    """The edge-bar arm of ``crossing_arm`` with its nominal masses."""
    return FlexibleModel(parse(arm_ref.urdf()))


def _elbow_sweep(n=31):
    el = np.linspace(0.0, 0.6, n)
    return np.column_stack([np.full_like(el, 0.3), el])


def test_tracked_modes_of_a_crossing_arm_equal_the_global_fe_families(crossing_arm):
    """Tracked modes 2 and 3 are the FE's 2nd out-of-plane and 1st in-plane branches."""
    Q = _elbow_sweep()
    tr = track_modes(crossing_arm, Q, modes=(1, 2, 3, 4), reference=15)
    ref = [arm_ref.reference_families(q, 0.125, 0.125) for q in Q]
    inp = np.array([r[0] for r in ref])
    out = np.array([r[1] for r in ref])
    # numbering at the reference sample: 1 out-of-plane, 2 out-of-plane, 3 in-plane, 4 in-plane
    np.testing.assert_allclose(tr.freq_hz[:, 0], out[:, 0], rtol=1e-9)
    np.testing.assert_allclose(tr.freq_hz[:, 1], out[:, 1], rtol=1e-9)
    np.testing.assert_allclose(tr.freq_hz[:, 2], inp[:, 0], rtol=1e-9)
    np.testing.assert_allclose(tr.freq_hz[:, 3], inp[:, 1], rtol=1e-9)
    # the FE branches swap order exactly where the crossing is reported
    swap = np.flatnonzero(np.diff(np.sign(out[:, 1] - inp[:, 0])))
    assert swap.size == 1
    crossings = tr.crossings(2)
    assert [(e.sample, e.modes) for e in crossings] == [(int(swap[0]) + 1, (2, 3))]
    assert tr.changes_identity(2) and tr.changes_identity(3) and not tr.changes_identity(1)
    # the sorted frequencies are what frequencies() returns; tracked ones differ before the swap
    np.testing.assert_allclose(tr.sorted_hz[:, :4], crossing_arm.frequencies(Q, n_modes=4),
                               rtol=1e-9)
    assert tr.order[0, 1:3].tolist() == [3, 2]


def test_reference_point_off_the_trajectory_keeps_its_numbering(crossing_arm):
    """Numbered at (elbow 0.3, other masses) off the samples: same identities as above."""
    Q = _elbow_sweep(16)[:6]  # elbow 0 .. 0.2 only: the reference pose is beyond the samples
    tr = track_modes(crossing_arm, Q, [0.0, 0.25], modes=(2, 3),
                     reference=(np.array([0.3, 0.3]), np.array([0.125, 0.125])))
    out = np.array([arm_ref.reference_families(q, 0.0, 0.25)[1][1] for q in Q])
    inp = np.array([arm_ref.reference_families(q, 0.0, 0.25)[0][0] for q in Q])
    np.testing.assert_allclose(tr.freq_hz[:, 0], out, rtol=1e-9)
    np.testing.assert_allclose(tr.freq_hz[:, 1], inp, rtol=1e-9)


def test_a_leaning_elbow_axis_turns_the_crossing_into_a_veering():
    """Tilting the elbow axis by 0.1 rad couples the families: veering, no crossing."""
    model = FlexibleModel(parse(arm_ref.urdf(tilt=0.1)))
    tr = track_modes(model, _elbow_sweep(61), modes=(1, 2, 3, 4))
    assert tr.crossings(2) == [] and tr.crossings(3) == []
    (ev,) = tr.veerings(2)
    assert ev.modes == (2, 3) and ev.gap < 0.05 and ev.mac < 0.5
    assert not tr.changes_identity(2)


def test_bad_tracking_requests_are_named_errors(crossing_arm):
    """Mode numbers, reference samples and array shapes are checked."""
    Q = _elbow_sweep(5)
    with pytest.raises(ConfigurationError):
        track_modes(crossing_arm, Q, modes=(0,))
    with pytest.raises(ConfigurationError):
        track_modes(crossing_arm, Q, modes=(1,), reference=9)
    with pytest.raises(ConfigurationError):
        track(np.ones((3, 2)), np.ones((3, 4, 3)), modes=(1,))
