"""The terms of the moving arm that eq. (1) leaves out (``terms="full"``).

Eq. (1) takes the acceleration of a material point as ``S q̈ + Ṡ q̇ + E ẍ + 2 G ẋ``: the rigid
(ERLS) acceleration, the elastic one and the Coriolis term of the elastic motion. Linearised
consistently about a rigid motion ``(q, q̇, q̈)``, the point's acceleration (link axes) has two
more terms of first order in the elastic displacement ``u = E x``,

    α × u + ω × (ω × u)              (Euler and centrifugal terms; ``ω, α`` of the link),

and a beam carries the axial force ``N(s)`` of the inertial and gravity loads outboard of its
section ``s``, whose second-order strain energy ``½ ∫ N (v'² + w'²) ds`` is the geometric
stiffness ``K_G`` (tension stiffens, compression softens; :func:`pinflex.beam.
element_geometric_stiffness`, :func:`pinflex.erls.preload.geometric_stiffness`). The centrifugal term softens what ``K_G`` stiffens: on a spinning
beam the chordwise modes keep ``ω² = ω²_flap − Ω²``; the two are added together or not at all.

The virtual work of the inertial forces on the displaced point adds, in the joint rows, the
moment of ``f_i = m_i (a_i − g)`` about the displacement: the point's Jacobian is ``X(c + u) J =
S − [u]× J_ang``. Altogether the linearised equations gain ``K_s(q, q̇, q̈) x`` with

    K_s[x rows] = Σ m Eᵀ A E + K_G,   K_s[q rows] = Σ m Sᵀ A E − Σ J_angᵀ [f_i]× E,
    A = [α]× + [ω]×[ω]×,

all evaluated on the rigid motion (``x = 0``). ``N(s)`` is exact for the beam's own line mass
(its rigid acceleration field is affine along the beam) and sums the point loads outboard of
``s``: point masses and rigid bodies on the link at their axial position, every child
subtree at its joint. Left out: prestress from torsion and shear, the terms of the torsional
rotary inertia ``ρIp``, and products of two elastic quantities.

:func:`validity` measures how far eq. (1) holds: ``|ω_L|² / ω_i²`` and ``|α_L| / ω_i²`` (the
relative size of the terms above) per sample and mode.
"""

from __future__ import annotations

import numpy as np

from pinflex.erls.preload import geometric_stiffness
from pinflex.linalg import skew

TERMS = ("eq1", "full")


def check_terms(terms: str) -> str:
    """Return ``terms`` if it is ``"eq1"`` or ``"full"``; raise ConfigurationError otherwise."""
    from pinflex.exceptions import ConfigurationError

    if terms not in TERMS:
        raise ConfigurationError(
            f"terms = {terms!r}: choose 'eq1' (paper 000 eq. 1, the default) or 'full' (adds "
            "the centrifugal and Euler terms of the elastic displacement and the geometric "
            "stiffness of the axial loads)")
    return terms


def link_motion(J: np.ndarray, Jd: np.ndarray, qd: np.ndarray, qdd: np.ndarray):
    """``(a0, ω, α)`` of a link frame (link axes) from its LOCAL Jacobian and its rates.

    Args:
        J: Frame Jacobian (6, nv) in the user convention.
        Jd: Its rates per unit joint velocity (nv, 6, nv).
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).

    Returns:
        The classical acceleration of the frame origin (3,), the angular velocity (3,) and
        the angular acceleration (3,), all in link axes.
    """
    v = J @ qd
    acc = J @ qdd + np.einsum("k,kaj,j->a", qd, Jd, qd)
    return acc[:3] + np.cross(v[3:], v[:3]), v[3:], acc[3:]


def speed_stiffness(dyn, q, qd, qdd) -> np.ndarray:
    """``K_s`` (ndof, ndof) of the module doc at the rigid state ``(q, q̇, q̈)``.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics` (its gravity is included).
        q: Joint coordinates (nv,) [rad or m] (user convention).
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).

    Returns:
        ``K_s`` with non-zero columns on the elastic coordinates only.
    """
    q, qd, qdd = (np.asarray(v, dtype=float) for v in (q, qd, qdd))
    J, Jd, R, e, ed = dyn._kinematics(q)
    nx, nd = dyn.nx, dyn.ndof
    Ks = np.zeros((nd, nd))
    g = dyn.gravity
    force: dict[str, list] = {}  # link -> [(positions c (n, 3), forces f (n, 3) link axes)]
    for p in dyn._points:
        W, _, Sdk, S, _ = dyn._maps(p, J, Jd, e, ed)
        E = W[..., :nx]
        _, w, al = link_motion(J[p.link], Jd[p.link], qd, qdd)
        A = skew(al) + skew(w) @ skew(w)
        mW = p.mass[:, None, None] * W
        Ks[:, :nx] += np.einsum("nai,ab,nbx->ix", mW, A, E)
        acc = S @ qdd + np.einsum("k,knaj,j->na", qd, Sdk, qd)
        f = p.mass[:, None] * (acc - R[p.link].T @ g)
        Ks[nx:, :nx] -= J[p.link][3:].T @ np.einsum("nab,nbx->ax", skew(f), E)
        force[p.link] = [(p.c[p.n_beam:], f[p.n_beam:])]
    _add_geometric(dyn, Ks, J, Jd, R, e, qd, qdd, force)
    return Ks


def _add_geometric(dyn, Ks, J, Jd, R, e, qd, qdd, force) -> None:
    """Add every beam's ``K_G`` of the axial force of the rigid motion's loads to ``Ks``.

    The axial force and ``K_G`` are :func:`pinflex.erls.preload.geometric_stiffness`'s (the
    same rule as the static preload of the modal analysis); here a beam's load per unit mass
    is ``a₀ − Rᵀg + A (s eₓ)`` of its link's rigid motion.
    """
    plan = dyn.model.plan
    line = {}
    for link in plan.beams:
        a0, w, al = link_motion(J[link], Jd[link], qd, qdd)
        line[link] = (a0 - R[link].T @ dyn.gravity, skew(al) + skew(w) @ skew(w))
    Ks[:dyn.nx, :dyn.nx] += geometric_stiffness(plan, R, line, force, e, dyn.nx)
