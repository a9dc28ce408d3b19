"""Mode shapes of a lumped arm beside the ERLS model's: are the matched modes the same modes?

The fit pairs the lumped arm's k lowest frequencies with the ERLS model's k lowest, in order.
Equal frequencies do not make equal modes: a lumped arm could put a bending mode where the
ERLS model has a torsion or axial one. This module compares the shapes themselves, on the
one quantity both models define: the world translation of the points of every flexible link
where the ERLS beam has its nodes (the ERLS model's ``node_motion``; on the lumped arm, the
rigid segment holding that point, by its Pinocchio joint Jacobian), and the modal assurance
criterion ``MAC_ij = |a_i . b_j|^2 / (|a_i|^2 |b_j|^2)`` between ERLS mode i and lumped mode j.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
from scipy.optimize import linear_sum_assignment

from pinflex.lumped.model import LumpedArm, segment_of

#: A matched pair whose MAC falls below this is reported as a different shape.
MIN_MAC = 0.8

#: Pairing by shape replaces pairing by order only when it raises the summed MAC of the
#: pairs by more than this (a clear swap, not the noise of near-equal shapes).
PAIR_MARGIN = 0.2

#: ERLS frequencies closer than this (relative) are one repeated frequency: any basis of
#: their shapes is valid, so a pair inside it is not a mismatch.
REPEATED = 1e-6


def node_translations(lumped: LumpedArm, q, shapes: np.ndarray,
                      node_positions) -> np.ndarray:
    """World translations (3 per point, stacked over links) of lumped modes at given points.

    Args:
        lumped: The lumped arm.
        q: Arm pose (user convention).
        shapes: Lumped mode shapes (nv, k).
        node_positions: ``{flexible link: (P, 3) world points on its undeformed beam}``, the
            first one the beam's root (as the ERLS nodes): a point's station is its distance
            from the first.

    Returns:
        (3 P_total, k) translations.
    """
    model = lumped.model
    data = model.createData()
    pin.computeJointJacobians(model, data, lumped.configuration(q))
    rows = []
    for link, pts in node_positions.items():
        seg = lumped.segments[link]
        stations = np.linalg.norm(pts - pts[0], axis=1)
        for p, s in zip(pts, stations):
            jid = lumped.segment_ids[(link, segment_of(seg.bounds_m, min(s, seg.length_m)))]
            J = pin.getJointJacobian(model, data, jid, pin.LOCAL_WORLD_ALIGNED)
            r = p - data.oMi[jid].translation
            rows.append((J[:3] - pin.skew(r) @ J[3:]) @ shapes)
    return np.concatenate(rows, axis=0)


def erls_translations(result) -> tuple[dict, np.ndarray]:
    """Node positions and the stacked world translations (3 P_total, k) of an ERLS result."""
    pos = result.node_positions
    mot = [result.node_motion[link][:, :, :3].reshape(result.node_motion[link].shape[0], -1)
           for link in pos]
    return pos, np.concatenate(mot, axis=1).T


def mac_matrix(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``MAC_ij`` between the columns of ``a`` (n, k) and ``b`` (n, m)."""
    num = np.abs(a.T @ b) ** 2
    den = np.outer((a * a).sum(axis=0), (b * b).sum(axis=0))
    return num / np.where(den > 0.0, den, np.inf)


def pairing(erls_result, lumped: LumpedArm, q, condition: str, k: int) -> np.ndarray:
    """MAC (k, k) between the ERLS modes and the lumped arm's, at one pose and condition."""
    pos, ue = erls_translations(erls_result)
    shapes = lumped.modes(q, condition)[1][:, :k]
    return mac_matrix(ue[:, :k], node_translations(lumped, q, shapes, pos))


def mismatches(mac: np.ndarray) -> list[tuple[int, int, float, float]]:
    """Matched pairs that are not the same mode.

    A pair (i, i) is a mismatch when its MAC is below :data:`MIN_MAC`, or when ERLS mode i
    resembles another lumped mode j more (or lumped mode i another ERLS mode).

    Returns:
        ``[(i, j, MAC_ii, MAC_ij), ...]`` with j the closest other mode (or i).
    """
    out = []
    for i in range(mac.shape[0]):
        row = mac[i].copy()
        col = mac[:, i].copy()
        row[i] = col[i] = -1.0
        j_row, j_col = int(np.argmax(row)), int(np.argmax(col))
        j = j_row if row[j_row] >= col[j_col] else j_col
        other = max(row[j_row], col[j_col]) if mac.shape[0] > 1 else -1.0
        if mac[i, i] < MIN_MAC or other > mac[i, i]:
            out.append((i, j if other > mac[i, i] else i, float(mac[i, i]), float(other)))
    return out


class ErlsShapes:
    """The ERLS modes of one pose and condition as :func:`shape_order` reads them.

    Attributes:
        positions: ``{flexible link: (P, 3)}`` undeformed node positions (root first) [m].
        translations: (3 P_total, k) world node translations of the k lowest modes.
        freq_hz: (k,) their frequencies [Hz].
    """

    def __init__(self, result, k: int):
        self.positions, ue = erls_translations(result)
        self.translations = ue[:, :k]
        self.freq_hz = np.asarray(result.freq_hz[:k])


def shape_order(lumped: LumpedArm, q, shapes: np.ndarray, erls: ErlsShapes) -> np.ndarray:
    """Which of the k lowest lumped modes is each ERLS mode (order (k,) of lumped indices).

    The assignment maximising the summed MAC, used only when it beats the plain order by
    more than :data:`PAIR_MARGIN` and swaps no modes of a repeated ERLS frequency; else the
    plain order.
    """
    k = erls.translations.shape[1]
    mac = mac_matrix(erls.translations,
                     node_translations(lumped, q, shapes[:, :k], erls.positions))
    rows, cols = linear_sum_assignment(-mac)
    order = cols[np.argsort(rows)]
    plain = np.arange(k)
    if mac[plain, order].sum() <= np.trace(mac) + PAIR_MARGIN:
        return plain
    f = erls.freq_hz
    if any(abs(f[m] - f[order[m]]) <= REPEATED * f[m] for m in plain if order[m] != m):
        return plain
    return order
