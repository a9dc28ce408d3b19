"""Small array helpers: read-only copies, and the rigid-body algebra of the ERLS layers.

The rigid-body helpers are batched over leading axes.
"""

from __future__ import annotations

import numpy as np


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices of vectors (..., 3) -> (..., 3, 3)."""
    v = np.asarray(v, dtype=float)
    out = np.zeros(v.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


def translate_twist(p: np.ndarray) -> np.ndarray:
    """6×6 map of a small motion (δo, θ) at a frame origin to (δp, θ) at point ``p``.

    ``δp = δo + θ × p``; the same matrix moves a velocity twist (v, ω) to a point.
    """
    out = np.eye(6)
    out[:3, 3:] = -skew(p)
    return out


def rotate_twist(R: np.ndarray) -> np.ndarray:
    """Block-diagonal 6×6 rotation ``diag(R, R)`` (batched over leading axes)."""
    R = np.asarray(R)
    out = np.zeros(R.shape[:-2] + (6, 6))
    out[..., :3, :3] = R
    out[..., 3:, 3:] = R
    return out


def axis_rotation(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotations about a unit axis by angles (n,) [rad] -> (n, 3, 3) (Rodrigues)."""
    angle = np.asarray(angle, dtype=float)
    k = skew(axis)
    k2 = k @ k
    s, c = np.sin(angle), np.cos(angle)
    return np.eye(3) + s[..., None, None] * k + (1.0 - c)[..., None, None] * k2


def readonly(values) -> np.ndarray:
    """A read-only float copy of ``values`` (fields of frozen dataclasses)."""
    array = np.array(values, dtype=float)
    array.setflags(write=False)
    return array


def held_rayleigh(M: np.ndarray, K: np.ndarray, G: np.ndarray, nx: int, alpha: float,
                  beta: float) -> np.ndarray:
    """Rayleigh damping of the deformation: ``α M_H + β K_H`` on the elastic coordinates.

    The one meaning of Rayleigh ``(α, β)`` in pinflex (simulation, FRF, export): the damping
    forces act on the deformation rate ``ẋ`` only (rigid motion is not damped), with the mass
    and stiffness of the arm whose motors are held, ``M_H = Zᵀ M Z``, ``K_H = Zᵀ K Z``, where
    ``Z = [I; −G_q⁻¹ G_x]`` spans the motions with no relative joint motion ``G z = 0``. Every
    locked-joint mode ``i`` then decays at ``α/2 + β ω_i²/2`` (damping ratio
    ``α/(2ω_i) + β ω_i/2``).

    Args:
        M: Mass matrix (n, n) over ``z = [x; q]`` (the first ``nx`` elastic).
        K: Stiffness matrix (n, n).
        G: Relative joint motion rows (m, n) ``r = G z`` of the joints not locked, ``G_q``
            (m, n − nx) invertible; ``m = 0`` when every joint is locked.
        nx: Number of elastic coordinates.
        alpha: Mass coefficient α [1/s].
        beta: Stiffness coefficient β [s].

    Returns:
        ``C`` (n, n), zero outside the ``x`` block.
    """
    n = M.shape[0]
    Z = np.eye(n)[:, :nx]
    if n > nx:
        Z[nx:] = -np.linalg.solve(G[:, nx:], G[:, :nx])
    C = np.zeros((n, n))
    C[:nx, :nx] = Z.T @ (alpha * M + beta * K) @ Z
    return C
