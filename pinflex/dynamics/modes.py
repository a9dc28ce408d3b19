"""Modes of the moving arm ("modes at speed"): the locked-joint system on a rigid state.

At a joint state ``(q, q̇, q̈)`` held by the motors (the prescribed drive's locked joints), the
small elastic motion obeys ``M ẍ + C ẋ + K x = f`` (:func:`pinflex.dynamics.prescribed.
locked_coefficients`): ``C`` holds the gyroscopic (Coriolis) terms of the elastic motion and,
with ``terms="full"``, ``K`` holds the centrifugal and Euler terms and the geometric stiffness
of the axial loads (:mod:`pinflex.dynamics.speed`). Its frequencies are the imaginary parts of
the eigenvalues of the first-order form ``[[0, I], [−M⁻¹K, −M⁻¹C]]`` (a gyroscopic system at
constant speed: purely imaginary pairs while it is stable). At ``q̇ = 0`` they are the
locked-joint frequencies of the pose; on a spinning cantilever the flapwise ones rise with the
speed and the chordwise ones much less (checked against a published table in the tests).

A state whose stiffness is no longer positive (a column past buckling, a beam spun into
divergence) gives an eigenvalue with a positive real part: :class:`ModesAtSpeed` reports it in
``unstable`` and its frequency in ``growth_rate_1_s``. With an angular acceleration the frozen
system is not conservative (the Euler term): real parts of order ``|α_L| / ω_i`` of either sign
appear, which are not a growth of the moving arm. :func:`modes_at_speed_along` follows a motion.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg

from pinflex.dynamics.prescribed import locked_coefficients
from pinflex.dynamics.speed import check_terms


@dataclass(frozen=True)
class ModesAtSpeed:
    """Modes of the locked-joint system at one rigid state (module doc).

    Attributes:
        freq_hz: Frequencies (k,) ascending [Hz], ``|Im λ| / 2π`` of the eigenvalue pairs.
        growth_rate_1_s: ``Re λ`` (k,) [1/s] (0 for a conservative stable state).
        shapes: Complex mode shapes (nx, k) over the elastic coordinates (displacement part).
        unstable: Whether an eigenvalue has a positive real part above round-off.
        terms: ``"eq1"`` or ``"full"``.
    """

    freq_hz: np.ndarray
    growth_rate_1_s: np.ndarray
    shapes: np.ndarray = field(repr=False)
    unstable: bool
    terms: str


def modes_at_speed(dyn, q, qd=None, qdd=None, *, terms: str = "full",
                   n_modes: int | None = None) -> ModesAtSpeed:
    """Frequencies of the locked-joint arm moving through ``(q, q̇, q̈)`` (module doc).

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics` (its design and gravity).
        q: Joint coordinates (nv,) [rad or m], user convention.
        qd: Joint velocities (nv,) (default zero).
        qdd: Joint accelerations (nv,) (default zero).
        terms: ``"full"`` (default here: the terms that change the modes at speed) or
            ``"eq1"`` (gyroscopic terms only).
        n_modes: Number of modes (default all ``nx``).

    Returns:
        :class:`ModesAtSpeed`.
    """
    terms = check_terms(terms)
    nv, nx = dyn.nv, dyn.nx
    q = np.asarray(q, dtype=float)
    qd = np.zeros(nv) if qd is None else np.asarray(qd, dtype=float)
    qdd = np.zeros(nv) if qdd is None else np.asarray(qdd, dtype=float)
    c = locked_coefficients(dyn, q, qd, qdd, terms=terms)
    k = nx if n_modes is None else max(1, min(int(n_modes), nx))
    if not np.any(c.C):
        lam, phi = scipy.linalg.eigh(c.K, c.M)
        w = np.sqrt(np.abs(lam))
        growth = np.where(lam < 0.0, w, 0.0)
        freq = np.where(lam < 0.0, 0.0, w) / (2.0 * np.pi)
        order = np.argsort(lam)[:k]
        return ModesAtSpeed(freq[order], growth[order], phi[:, order].astype(complex),
                            bool(np.any(lam < -1e-9 * np.abs(lam).max())), terms)
    Mi = np.linalg.inv(c.M)
    A = np.zeros((2 * nx, 2 * nx))
    A[:nx, nx:] = np.eye(nx)
    A[nx:, :nx] = -Mi @ c.K
    A[nx:, nx:] = -Mi @ c.C
    lam, V = scipy.linalg.eig(A)
    keep = lam.imag >= 0.0  # one of each conjugate pair (real ones: divergence)
    lam, V = lam[keep], V[:, keep]
    order = np.argsort(np.abs(lam.imag))[:k]
    lam, V = lam[order], V[:, order]
    scale = np.abs(lam).max() if lam.size else 1.0
    return ModesAtSpeed(np.abs(lam.imag) / (2.0 * np.pi), lam.real, V[:nx],
                        bool(np.any(lam.real > 1e-7 * scale)), terms)


@dataclass(frozen=True)
class ModesAtSpeedAlong:
    """Modes of the moving arm at the samples of a motion (:func:`modes_at_speed_along`).

    Attributes:
        times_s: Sample times (ns,) [s].
        freq_hz: Lowest frequencies (ns, k) [Hz], sorted at each sample.
        growth_rate_1_s: Real parts (ns, k) [1/s].
        unstable: Per sample, whether an eigenvalue grows (ns,).
        terms: ``"eq1"`` or ``"full"``.
    """

    times_s: np.ndarray
    freq_hz: np.ndarray
    growth_rate_1_s: np.ndarray
    unstable: np.ndarray
    terms: str


def modes_at_speed_along(dyn, trajectory, *, terms: str = "full", n_modes: int = 3,
                         times=None) -> ModesAtSpeedAlong:
    """:func:`modes_at_speed` at every sample of a joint motion (rates of its interpolation).

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics`.
        trajectory: A :class:`~pinflex.Trajectory` or a
            :class:`~pinflex.dynamics.motion.JointMotion` (its exact rates).
        terms: ``"full"`` (default) or ``"eq1"``.
        n_modes: Modes per sample.
        times: Sample times (default the trajectory's).

    Returns:
        :class:`ModesAtSpeedAlong`.
    """
    from pinflex.dynamics.motion import JointMotion

    motion = trajectory if isinstance(trajectory, JointMotion) else JointMotion(trajectory)
    t = np.asarray(motion.trajectory.times_s if times is None else times, dtype=float)
    q, qd, qdd = motion.sample(t)
    k = max(1, min(int(n_modes), dyn.nx))
    freq, growth = np.empty((t.size, k)), np.empty((t.size, k))
    unstable = np.zeros(t.size, dtype=bool)
    for i in range(t.size):
        r = modes_at_speed(dyn, q[i], qd[i], qdd[i], terms=terms, n_modes=k)
        freq[i], growth[i], unstable[i] = r.freq_hz, r.growth_rate_1_s, r.unstable
    return ModesAtSpeedAlong(t, freq, growth, unstable, check_terms(terms))
