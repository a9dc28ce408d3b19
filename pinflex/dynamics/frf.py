"""Frequency responses (receptances) of a flexible arm at a pose or a moving state.

At a pose with ``q̇ = 0`` eq. (1) is linear: ``M z̈ + C ż + K z = B u``. The receptance between
inputs ``u`` and outputs ``y = Y z`` is ``H(ω) = Y (K − ω² M + iω C)⁻¹ B``. At a moving state
``(q, q̇, q̈)`` held by the motors (``joints="locked"``), the small elastic motion is the
prescribed drive's locked system (:func:`pinflex.dynamics.prescribed.locked_coefficients`):
``C`` holds the gyroscopic terms and, with ``terms="full"``, ``K`` the centrifugal, Euler and
geometric-stiffness terms (:mod:`pinflex.dynamics.speed`) — the linearised model about a
moving state.

* Inputs: a motor torque at a joint (``("torque", joint)``, acting on the physical joint angle,
  generalized force ``Gᵀ e_j`` with the stator reaction on the parent) or a force at a point of
  a link along a world direction (``("force", link, xyz, direction)``).
* Outputs: the world displacement of a point of a link along a direction
  (``("displacement", link, xyz, direction)``), total (rigid and elastic).
* Joint conditions: ``"free"`` (paper 000: the free joints give rigid modes, ``1/(−ω²)`` terms)
  or ``"locked"`` (motors holding the joints: the projection ``Z = [I; A]`` of the prescribed
  drive; torque inputs are then reactions and not allowed).
* Damping: modal ratios ``ζ_i`` of the analysed system's elastic modes
  (``C = M Φ diag(2ζω) Φᵀ M``; rigid modes undamped) or Rayleigh ``(α, β)`` of the deformation
  (:mod:`pinflex.dynamics.damping`: ``α M_H + β K_H`` with the motors held; the rigid motion is
  not damped).

:func:`frf` sums the modes (``eigh(K, M)``) when they decouple the damping and solves directly
otherwise (gyroscopic terms, Rayleigh with free joints); :func:`frf_direct` always solves the
complex system at each frequency.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

from pinflex.checks import check_q
from pinflex.dynamics.damping import Damping
from pinflex.exceptions import ConfigurationError
from pinflex.linalg import held_rayleigh


@dataclass(frozen=True)
class LinearPose:
    """``M``, ``K``, ``C``, input ``B`` and output ``Y`` matrices at a pose."""

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    B: np.ndarray
    Y: np.ndarray
    joints: str


def _direction(d) -> np.ndarray:
    d = np.asarray(d, dtype=float)
    if d.shape != (3,) or not np.all(np.isfinite(d)) or np.linalg.norm(d) == 0.0:
        raise ConfigurationError(f"a direction must be 3 finite numbers, not all zero: {d!r}")
    return d / np.linalg.norm(d)


def linear_pose(dyn, q, inputs, outputs, *, damping: Damping | None = None,
                joints: str = "free", qd=None, qdd=None, terms: str = "eq1") -> LinearPose:
    """The matrices of the receptance at pose ``q`` or a moving state (see the module doc).

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics`.
        q: Joint coordinates (nv,) [rad or m].
        inputs: ``("torque", joint)`` or ``("force", link, xyz, direction)`` entries.
        outputs: ``("displacement", link, xyz, direction)`` entries.
        damping: :class:`~pinflex.dynamics.Damping` (default none).
        joints: ``"free"`` or ``"locked"``.
        qd: Joint velocities (nv,) of a moving state (``joints="locked"``; default zero).
        qdd: Joint accelerations (nv,) of a moving state (default zero).
        terms: ``"eq1"`` or ``"full"`` (``joints="locked"``).
    """
    from pinflex.dynamics.speed import check_terms

    if joints not in ("free", "locked"):
        raise ConfigurationError(f"joints = {joints!r} must be 'free' or 'locked'")
    moving = (qd is not None and np.any(qd)) or (qdd is not None and np.any(qdd))
    if (moving or check_terms(terms) == "full") and joints != "locked":
        raise ConfigurationError(
            "a moving state (qd, qdd) or terms='full' is linearised with the motors holding "
            "the joints: use joints='locked'")
    if joints == "free" and dyn.locked:
        raise ConfigurationError(
            f"joints {[n for n, _ in dyn.locked]} are locked in this model; joints='free' "
            "would free them: use joints='locked' (every joint held) or build the model with "
            "springs")
    q = check_q(dyn.model, q).astype(float)
    M, _, K, _ = dyn.linear_terms(q)
    nx, nd = dyn.nx, dyn.ndof
    A = dyn.joint_offsets(q)[0]
    Cm = dyn.model.coord_map
    G = np.hstack([-(Cm @ A), Cm])
    cols = []
    for u in inputs:
        if u[0] == "torque":
            if joints == "locked":
                raise ConfigurationError("a joint torque is a reaction when the joints are "
                                         "locked; use joints='free' or a force input")
            cols.append(G[dyn.model.joint_index(u[1])])
        elif u[0] == "force":
            _, link, xyz, d = u
            Tw, Sw = dyn.frame_map(link, xyz)(q)
            cols.append(np.concatenate([Tw[:3].T, Sw[:3].T]) @ _direction(d))
        else:
            raise ConfigurationError(f"unknown input {u!r}: use ('torque', joint) or "
                                     "('force', link, xyz, direction)")
    rows = []
    for o in outputs:
        if o[0] != "displacement":
            raise ConfigurationError(f"unknown output {o!r}: use ('displacement', link, xyz, "
                                     "direction)")
        _, link, xyz, d = o
        Tw, Sw = dyn.frame_map(link, xyz)(q)
        rows.append(_direction(d) @ np.hstack([Tw[:3], Sw[:3]]))
    B = np.array(cols).T.reshape(nd, len(cols))
    Y = np.array(rows).reshape(len(rows), nd)
    C0 = None
    K_damp = K
    if joints == "locked":
        Z = np.vstack([np.eye(nx), A])
        B, Y = Z.T @ B, Y @ Z
        if moving or terms == "full":
            from pinflex.dynamics.prescribed import locked_coefficients

            zero = np.zeros(dyn.nv)
            c = locked_coefficients(dyn, q, zero if qd is None else np.asarray(qd, float),
                                    zero if qdd is None else np.asarray(qdd, float),
                                    terms=terms)
            M, K, C0 = c.M, c.K, c.C
            K_damp = c.K_eq1
        else:
            M, K = Z.T @ M @ Z, Z.T @ K @ Z
            K_damp = K
    damping = damping or Damping()
    if damping.kind == "rayleigh" and joints == "locked":
        C = damping.alpha * M + damping.beta * K_damp
    elif damping.kind == "rayleigh":  # the deformation's, motors held (linalg.held_rayleigh)
        C = held_rayleigh(M, K, G, nx, damping.alpha, damping.beta)
    elif damping.kind == "modal":
        lam, phi = scipy.linalg.eigh(K_damp, M)
        w = np.sqrt(np.clip(lam, 0.0, None))
        z = np.asarray(damping.ratios, dtype=float)
        rigid = lam <= 1e-9 * max(lam.max(), 1.0)
        k = np.maximum(np.cumsum(~rigid) - 1, 0)  # elastic modes take the ratios in order
        zeta = np.where(rigid, 0.0, np.concatenate([z, np.full(w.size, z[-1])])[k])
        Bm = M @ phi
        C = (Bm * (2.0 * zeta * w)) @ Bm.T
    else:
        C = np.zeros_like(M)
    if C0 is not None:
        C = C + C0
    if joints != "locked":  # joint dampers (zero on the motors-held motions)
        C = C + dyn.joint_damping(q)
    return LinearPose(M, K, C, B, Y, joints)


def frf(lp: LinearPose, freqs_hz) -> np.ndarray:
    """Receptance ``H`` (nf, n_out, n_in) [m/N or m/(N m)] by modal superposition."""
    if np.abs(lp.K - lp.K.T).max() > 1e-12 * np.abs(lp.K).max():
        return frf_direct(lp, freqs_hz)  # speed terms (Euler) make K unsymmetric
    w = 2.0 * np.pi * np.asarray(freqs_hz, dtype=float)
    lam, phi = scipy.linalg.eigh(lp.K, lp.M)
    lam = np.where(lam < 1e-9 * max(lam.max(), 1.0), 0.0, lam)
    cd = phi.T @ lp.C @ phi
    off = np.abs(cd - np.diag(np.diag(cd))).max()
    if off > 1e-8 * max(np.abs(cd).max(), 1e-300):
        # not classical (the deformation's Rayleigh damping with free joints, or modal ratios
        # that the modes do not decouple): the direct solve is exact
        return frf_direct(lp, freqs_hz)
    c = np.diag(cd)
    left = lp.Y @ phi
    right = phi.T @ lp.B
    den = lam[None, :] - w[:, None] ** 2 + 1j * w[:, None] * c[None, :]
    return np.einsum("om,fm,mi->foi", left, 1.0 / den, right)


def frf_direct(lp: LinearPose, freqs_hz) -> np.ndarray:
    """Receptance by a direct complex solve of ``(K − ω² M + iω C) Z = B`` at each ω."""
    w = 2.0 * np.pi * np.asarray(freqs_hz, dtype=float)
    return np.array([lp.Y @ np.linalg.solve(lp.K - wk**2 * lp.M + 1j * wk * lp.C, lp.B)
                     for wk in w])
