"""Linear models about a moving state for control design (``pinflex export --terms``).

:func:`pinflex.native.export.linear_model` linearises the arm at rest (``q̇ = q̈ = 0``, no
gravity): ``M p̈ + Dₚ ṗ + K p = Bᵤ τ`` over ``p = [x; q]``. About a moving state
``(q, q̇, q̈)`` the small motion is linearised with **every joint held by its motor on the
motion** (the prescribed drive's locked joints; a free joint's rows at speed are the torque
drive's): the elastic coordinates obey the locked-joint system of
:func:`pinflex.dynamics.prescribed.locked_coefficients`,

    M_L ẍ + (G_L + D) ẋ + K_L x = f_L,

``G_L`` the velocity (gyroscopic and Coriolis) terms of the elastic motion, ``K_L`` the stiffness
with, for ``terms="full"``, the centrifugal and Euler terms of the elastic displacement and the
geometric stiffness of the inertial and gravity axial loads (:mod:`pinflex.dynamics.speed`),
``f_L`` the elastic load of the rigid motion. The state-space model is the one the prescribed
simulation integrates at that instant and whose eigenvalues :func:`pinflex.dynamics.
modes_at_speed` reads:

    ż = A z + B τ + e,   z = [x; ẋ],   A = [[0, I], [−M_L⁻¹K_L, −M_L⁻¹(G_L + D)]],
    e = [0; M_L⁻¹ f_L]   (``drive``),

the arm's model built with every joint locked (``joints="locked"``: the same coordinates, names
and zero torque columns ``B`` as its export at rest, a held joint's torque being a reaction).
Damping ``D``: Rayleigh ``α M_L + β K_H`` (``K_H`` the held stiffness without the speed terms,
:func:`pinflex.linalg.held_rayleigh`'s meaning) and modal ratios of the modes of
``(K_H, M_L)``, as at rest. A state at rest with no gravity is the export at rest, exactly.
"""

from __future__ import annotations

import numpy as np

from pinflex.exceptions import ConfigurationError


def _moving(qd, qdd) -> bool:
    return bool(np.any(qd) or np.any(qdd))


def _state(values, name: str, shape) -> np.ndarray:
    if values is None:
        return np.zeros(shape)
    v = np.asarray(values, dtype=float)
    if v.shape != shape:
        raise ConfigurationError(f"{name} must have the shape of q {shape} (one rate per "
                                 f"moving joint), got {v.shape}")
    if not np.all(np.isfinite(v)):
        raise ConfigurationError(f"{name} must be finite numbers")
    return v


def linear_model_at_state(arm, q, qd=None, qdd=None, *, y=None, terms: str = "eq1",
                          gravity=None, zeta: float = 0.0, rayleigh=None,
                          torque_input: str = "motor") -> dict:
    """M, K, damping and (A, B, C, D) about a state ``(q, q̇, q̈)``, or along states (module doc).

    At rest (``q̇ = q̈ = 0`` at every state) with no gravity this returns
    :func:`pinflex.native.export.linear_model` itself (the speed terms vanish there).

    Args:
        arm: A :class:`~pinflex.FlexibleModel`; about a moving state (or with gravity and
            ``terms="full"``) every joint must be locked (``joints="locked"``).
        q: Joint coordinates (nv,) or (ns, nv) [rad or m].
        qd: Joint velocities of the same shape (default zero) [rad/s or m/s].
        qdd: Joint accelerations of the same shape (default zero) [rad/s² or m/s²].
        y: Design values (default nominal).
        terms: ``"eq1"`` (paper 000 eq. (1): gyroscopic terms only) or ``"full"``.
        gravity: Gravity acceleration (3,) in world axes [m/s²] (default none); it enters
            ``K_L`` with ``terms="full"`` (axial preload) and ``drive``.
        zeta: Modal damping ratio of every elastic mode (>= 0).
        rayleigh: ``(alpha [1/s], beta [s])`` of the deformation.
        torque_input: As :func:`pinflex.native.export.linear_model` (at rest).

    Returns:
        The dictionary of :func:`pinflex.native.export.linear_model`; about a moving state
        also ``qd``, ``qdd``, ``terms``, ``gravity``, ``velocity`` (``G_L`` (nx, nx)) and
        ``drive`` (``e`` (2 nx,)), each with a leading (ns,) axis for several states;
        ``damping`` is ``D`` (without ``G_L``) and ``freq_hz`` the modes at speed
        (``|Im λ| / 2π`` of the undamped ``A``).

    Raises:
        ConfigurationError: A moving state on a model with joints not locked; bad shapes or
            terms.
    """
    from pinflex.dynamics.speed import check_terms
    from pinflex.native.export import linear_model

    terms = check_terms(terms)
    g = None if gravity is None else np.asarray(gravity, dtype=float)
    if g is not None and (g.shape != (3,) or not np.all(np.isfinite(g))):
        raise ConfigurationError(f"gravity must be 3 finite numbers [m/s^2], got {gravity!r}")
    preload = g is not None and terms == "full" and bool(np.any(g))
    rest = linear_model(arm, q, y, zeta=zeta, rayleigh=rayleigh, torque_input=torque_input)
    Q = np.asarray(rest["q"], dtype=float)  # checked (nv,) or (ns, nv), user convention
    Qd, Qdd = _state(qd, "qd", Q.shape), _state(qdd, "qdd", Q.shape)
    if not _moving(Qd, Qdd) and not preload:
        return rest
    if arm.ndof != arm.nx:
        raise ConfigurationError(
            "a moving state (qd, qdd) or gravity with terms='full' is linearised with every "
            "joint held by its motor on the motion (the free joints' rows at speed are the "
            "torque drive's): build the model with joints='locked' (--joints locked)")
    from pinflex.dynamics.terms import ErlsDynamics

    dyn = ErlsDynamics(arm, y, gravity=g)
    several = Q.ndim == 2
    rows = [_one_state(dyn, qk, qdk, qddk, terms, float(rest["zeta"]),
                       None if rayleigh is None else tuple(rest["rayleigh"]))
            for qk, qdk, qddk in zip(np.atleast_2d(Q), np.atleast_2d(Qd), np.atleast_2d(Qdd))]
    out = dict(rest)
    for key in rows[0]:
        out[key] = np.stack([r[key] for r in rows]) if several else rows[0][key]
    out.update(qd=Qd, qdd=Qdd, terms=np.array(terms),
               gravity=np.zeros(3) if g is None else g)
    return out


def _one_state(dyn, q, qd, qdd, terms: str, zeta: float, rayleigh) -> dict:
    import scipy.linalg

    from pinflex.dynamics.modes import modes_of
    from pinflex.dynamics.prescribed import locked_coefficients

    c = locked_coefficients(dyn, q, qd, qdd, terms=terms)
    nx, nv = dyn.nx, dyn.nv
    K_held = c.K if c.K_eq1 is None else c.K_eq1
    damping = np.zeros((nx, nx))
    if rayleigh is not None:
        damping = rayleigh[0] * c.M + rayleigh[1] * K_held
    if zeta:
        lam, phi = scipy.linalg.eigh(K_held, c.M)
        MP = c.M @ phi
        damping = damping + (MP * (2.0 * zeta * np.sqrt(np.clip(lam, 0.0, None)))) @ MP.T
    sol = np.linalg.solve(c.M, np.hstack([c.K, c.C + damping, c.f[:, None]]))
    A = np.zeros((2 * nx, 2 * nx))
    A[:nx, nx:] = np.eye(nx)
    A[nx:, :nx] = -sol[:, :nx]
    A[nx:, nx:] = -sol[:, nx:2 * nx]
    drive = np.concatenate([np.zeros(nx), sol[:, -1]])
    freq = modes_of(c.M, c.C, c.K, terms).freq_hz
    return {"M": c.M, "K": c.K, "damping": damping, "velocity": c.C, "A": A,
            "B": np.zeros((2 * nx, nv)), "C": np.hstack([np.eye(nx), np.zeros((nx, nx))]),
            "D": np.zeros((nx, nv)), "freq_hz": freq, "drive": drive}
