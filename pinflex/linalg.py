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
