"""Inverse kinematics: Pinocchio damped Gauss–Newton, and the planar 2R closed form."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from pinflex.exceptions import (
    IKNotConverged,
    InvalidPath,
)
from pinflex.linalg import readonly as _readonly
from pinflex.progress import ProgressBar


@dataclass(frozen=True)
class IKSolution:
    """Result of :func:`solve_ik` along a sequence of points.

    Attributes:
        q: Configurations, shape (ns, nq) (Pinocchio configuration vectors).
        residual_m: Position error at each sample, shape (ns,) [m].
        iterations: Gauss–Newton iterations spent at each sample, shape (ns,).
    """

    q: np.ndarray
    residual_m: np.ndarray
    iterations: np.ndarray


def solve_ik(
    model,
    data,
    frame_id: int,
    points: np.ndarray,
    q_init: np.ndarray,
    *,
    tol_m: float = 1e-10,
    max_iter: int = 100,
    damping: float = 1e-3,
    progress: ProgressBar | None = None,
) -> IKSolution:
    """Position-only inverse kinematics of one frame, warm-started along the points.

    Levenberg–Marquardt (damped Gauss–Newton) on ``e(q) = p* − p(q)``: with ``J`` the linear
    rows of the frame Jacobian in LOCAL_WORLD_ALIGNED axes (only the x–y rows if ``points``
    are 2-D), the step ``Δq = Jᵀ (J Jᵀ + μ I)⁻¹ e`` is applied with ``pin.integrate``. A step
    that reduces ``|e|`` is kept and ``μ`` shrinks by 10 (down to ``1e-14``); otherwise ``μ``
    grows by 10. ``μ`` starts at ``damping · |e|²``. Each sample starts from the previous
    solution (the first from ``q_init``), so the IK follows one branch along a continuous path.

    Args:
        model: Pinocchio model.
        data: Its data.
        frame_id: Frame whose origin follows the points.
        points: Targets in the world frame, shape (ns, 3), or (ns, 2) for an x–y task [m].
        q_init: Configuration to start the first sample from, shape (nq,).
        tol_m: Accept a sample when ``|e| <= tol_m`` [m].
        max_iter: Iteration limit per sample.
        damping: Initial damping factor (relative to ``|e|²``).
        progress: A progress bar advanced by one per sample solved (optional).

    Returns:
        The :class:`IKSolution`.

    Raises:
        IKNotConverged: A point was not reached to ``tol_m`` (out of reach, or the iteration
            stalled); carries the sample index, the target, the residual and the last q.
    """
    import pinocchio as pin

    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise InvalidPath(f"points must have shape (ns, 2) or (ns, 3), got {pts.shape}")
    rows = slice(0, pts.shape[1])
    q = np.array(q_init, dtype=float)
    if q.shape != (model.nq,):
        raise InvalidPath(f"q_init must have shape ({model.nq},), got {q.shape}")

    def error(qv):
        pin.framesForwardKinematics(model, data, qv)
        return pts_k - data.oMf[frame_id].translation[rows]

    out_q = np.empty((pts.shape[0], model.nq))
    residual = np.empty(pts.shape[0])
    iterations = np.zeros(pts.shape[0], dtype=int)
    for k, pts_k in enumerate(pts):
        e = error(q)
        norm = float(np.linalg.norm(e))
        mu = damping * norm**2
        it = 0
        while norm > tol_m and it < max_iter:
            it += 1
            J = pin.computeFrameJacobian(model, data, q, frame_id, pin.LOCAL_WORLD_ALIGNED)[rows]
            while True:
                dq = J.T @ np.linalg.solve(J @ J.T + (mu + 1e-14) * np.eye(J.shape[0]), e)
                q_new = pin.integrate(model, q, dq)
                e_new = error(q_new)
                norm_new = float(np.linalg.norm(e_new))
                if norm_new < norm:
                    q, e, norm = q_new, e_new, norm_new
                    mu = max(mu / 10.0, 1e-14)
                    break
                mu = 10.0 * mu + 1e-12
                if mu > 1e12:
                    break
            if mu > 1e12:
                break
        if norm > tol_m:
            raise IKNotConverged(k, pts_k, norm, q, tol_m)
        out_q[k], residual[k], iterations[k] = q, norm, it
        if progress is not None:
            progress.update()
    return IKSolution(_readonly(out_q), _readonly(residual), iterations)


# --------------------------------------------------------------------------- planar 2R arm


def absolute_to_relative(q_abs: ArrayLike) -> np.ndarray:
    """Absolute link angles (paper 000) → relative joint angles (Pinocchio), planar chain.

    ``q_rel[..., 0] = q_abs[..., 0]`` and ``q_rel[..., j] = q_abs[..., j] − q_abs[..., j−1]``
    [rad]; works on a single configuration (n,) or on samples (ns, n).
    """
    q_abs = np.asarray(q_abs, dtype=float)
    return np.concatenate([q_abs[..., :1], np.diff(q_abs, axis=-1)], axis=-1)


def relative_to_absolute(q_rel: np.ndarray) -> np.ndarray:
    """Relative joint angles (Pinocchio) → absolute link angles (paper 000): cumulative sum."""
    return np.cumsum(np.asarray(q_rel, dtype=float), axis=-1)


def planar_2r_fk(q_rel: np.ndarray, l1_m: float, l2_m: float) -> np.ndarray:
    """End-effector position of a planar 2R arm, shape (..., 2) [m].

    Joint 1 turns about z at the origin, joint 2 about z at the tip of link 1 (``l1_m``),
    the end effector is at ``l2_m`` along link 2; ``q_rel`` (..., 2) are relative angles [rad].
    """
    q = np.asarray(q_rel, dtype=float)
    a1, a2 = q[..., 0], q[..., 0] + q[..., 1]
    return np.stack(
        [l1_m * np.cos(a1) + l2_m * np.cos(a2), l1_m * np.sin(a1) + l2_m * np.sin(a2)], axis=-1
    )


def planar_2r_ik(
    points: np.ndarray,
    l1_m: float,
    l2_m: float,
    elbow_sign: int,
    *,
    q_ref: ArrayLike | None = None,
) -> np.ndarray:
    """Closed-form inverse kinematics of a planar 2R arm (same geometry as :func:`planar_2r_fk`).

    ``cos θ2 = (r² − l1² − l2²) / (2 l1 l2)``, ``θ2 = elbow_sign · arccos(...)``,
    ``θ1 = atan2(y, x) − atan2(l2 sin θ2, l1 + l2 cos θ2)``. The angles are then unwrapped
    along the samples (continuous in time) and, if ``q_ref`` is given, shifted by a multiple
    of 2π per joint so that the first sample is nearest to ``q_ref``.

    Args:
        points: Positions, shape (ns, 2) [m].
        l1_m: Length of link 1 [m].
        l2_m: Length of link 2 [m].
        elbow_sign: +1 for ``sin θ2 >= 0``, −1 for ``sin θ2 <= 0``.
        q_ref: Relative angles selecting the 2π branch, shape (2,) [rad].

    Returns:
        Relative joint angles (θ1, θ2), shape (ns, 2) [rad].

    Raises:
        IKNotConverged: A point lies outside the annulus ``|l1 − l2| <= r <= l1 + l2``.
    """
    pts = np.atleast_2d(np.asarray(points, dtype=float))
    if elbow_sign not in (1, -1):
        raise InvalidPath(f"elbow_sign must be +1 or -1, got {elbow_sign!r}")
    r2 = np.sum(pts**2, axis=1)
    c2 = (r2 - l1_m**2 - l2_m**2) / (2.0 * l1_m * l2_m)
    tol = 1e-12
    outside = np.abs(c2) > 1.0 + tol
    if np.any(outside):
        k = int(np.flatnonzero(outside)[0])
        reach = abs(np.sqrt(r2[k]) - np.clip(np.sqrt(r2[k]), abs(l1_m - l2_m), l1_m + l2_m))
        raise IKNotConverged(k, pts[k], float(reach), None, 0.0)
    th2 = elbow_sign * np.arccos(np.clip(c2, -1.0, 1.0))
    th1 = np.arctan2(pts[:, 1], pts[:, 0]) - np.arctan2(
        l2_m * np.sin(th2), l1_m + l2_m * np.cos(th2)
    )
    q = np.unwrap(np.column_stack([th1, th2]), axis=0)
    if q_ref is not None:
        turns = np.round((np.asarray(q_ref, dtype=float) - q[0]) / (2.0 * np.pi))
        q = q + 2.0 * np.pi * turns
    return q
