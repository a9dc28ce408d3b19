"""The terms of the moving arm that eq. (1) leaves out (``terms="full"``).

Eq. (1) takes the acceleration of a material point as ``S q̈ + Ṡ q̇ + E ẍ + 2 G ẋ``: the rigid
(ERLS) acceleration, the elastic one and the Coriolis term of the elastic motion. Linearised
consistently about a rigid motion ``(q, q̇, q̈)``, the point's acceleration (link axes) has two
more terms of first order in the elastic displacement ``u = E x``,

    α × u + ω × (ω × u)              (Euler and centrifugal terms; ``ω, α`` of the link),

and a beam carries the axial force ``N(s)`` of the inertial and gravity loads outboard of its
section ``s``, whose second-order strain energy ``½ ∫ N (v'² + w'²) ds`` is the geometric
stiffness ``K_G`` (tension stiffens, compression softens; :func:`pinflex.beam.
element_geometric_stiffness`, :func:`pinflex.erls.preload.geometric_stiffness`). The
centrifugal term softens what ``K_G`` stiffens: on a spinning beam the chordwise modes keep
``ω² = ω²_flap − Ω²``; the two are added together or not at all.

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

For a moving joint on a deforming link (an elastic offset ``A x`` of the held joint) these
terms are not the whole second variation: the joint's subtree turns by ``A x`` and its child's
root copy turns with it; and a load held off a beam's axis rises by ``θ × (θ × r) / 2`` as the
section turns (the lever term). :func:`locked_speed_stiffness` then gives the locked system's
stiffness from the material points' positions to second order (its docstring; levers in
:func:`lever_terms`); :func:`speed_stiffness` stays the route of arms whose moving joints sit
on rigid links with their loads on the beam axes, where both agree to 1e-9. A beam cut into
links at held joints is the one beam it is, spinning or under its weight, to 1e-12; a mass
held off the axis as a point mass, a body, a rigid link or through a joint off the axis is a
rotating-frame FE with a rigid lever to 1e-12 (``tests/test_speed_joints.py``).

Left out, as in the beams' ``K_G``: bending-moment and torsion prestress, and what the
static deflection does to the stiffness. A beam cut at a joint and loaded across its axis (an
angular acceleration, gravity across the beam, a mass held beside it) differs from the one
beam at second order in that load (2e-7 relative at 2 rad/s² on Kane's beam): both leave those
terms out, in different places. Spatial arms: the levers and the joints' terms are checked
with the joint axes across the beams; where a joint's axis rotation and the root copy's
rotation across it combine (a lever off a joint turning about the beam's axis), the order of
the two small rotations is ERLS's (axis rotation exact, the other linear).

:mod:`pinflex.erls.validity` measures how far eq. (1) holds: ``|ω_L|² / ω_i²`` and
``|α_L| / ω_i²`` (the relative size of the terms above) per sample and mode.
"""

from __future__ import annotations

import numpy as np

from pinflex.erls.preload import geometric_stiffness, lever_offset, lever_stiffness
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


#: Step of the central differences of the locked system's load terms, as a rotation [rad]
#: (fourth-order stencil of exact first-order quantities: error about 1e-12 relative).
STEP = 1e-3


def _world_maps(dyn, q, qd):
    """Per translational carrier group: ``(m, P1, Ṗ1, S̃, Ẽ)`` in world axes at ``(q, q̇)``.

    ``P1 = R (E + S A)`` maps the elastic coordinates to the point displacements of the locked
    system (the joints held at ``q_phys``, so ``q = q_phys + A x``); ``Ṗ1`` is its rate along
    the motion ``q̇``; ``S̃ = R S`` and ``Ẽ = R E`` are the points' Jacobians over ``q`` and ``x``.
    """
    J, Jd, R, e, ed = dyn._kinematics(q)
    A, Adk = dyn.joint_offsets(q)
    Ad = np.tensordot(qd, Adk, axes=(0, 0))
    out = []
    for p in dyn._points:
        W, Gk, Sdk, S, _ = dyn._maps(p, J, Jd, e, ed)
        E = W[..., :dyn.nx]
        V = E + S @ A
        Vd = (np.tensordot(qd, Gk, axes=(0, 0)) + np.tensordot(qd, Sdk, axes=(0, 0)) @ A
              + S @ Ad)
        Rl = R[p.link]
        out.append((p.mass, Rl @ V, Rl @ Vd, Rl @ S, Rl @ E))
    return out, A


def locked_speed_stiffness(dyn, q, qd, qdd, statics=None) -> np.ndarray:
    """The locked system's stiffness of the rigid motion's loads (nx, nx), beyond ``Zᵀ K Z``.

    With the joints held (``q = q_phys(t) + A x``) a material point sits at
    ``P(t, x) = P0 + P1 x + ½ P2[x, x] + …`` and the second variation of the action gives
    ``M_L ẍ + 2 Σ m P1ᵀ Ṗ1 ẋ + (Zᵀ K Z + K_L) x = f`` with

        K_L = Σ m P1ᵀ P̈1 + Σ f0 · P2 + K_G,      f0 = m (P̈0 − g),

    ``P̈1`` the second time derivative of ``P1`` along the rigid motion and ``P2`` the Hessian
    of the point's position over ``x`` through ``q = q_phys + A(q) x`` (the joints' subtrees
    turn by ``A x``, the root copies of the elastic twists turn with them). ``P̈1`` is the
    fourth-order central difference of the exact ``Ṗ1`` along the motion ``q + q̇ τ +
    q̈ τ²/2``; the ``q`` derivatives of ``Σ W̃ᵀ f0`` and ``A`` (only along the joints with an
    elastic offset) are fourth-order central differences of exact first derivatives.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics` (its gravity is a load).
        q: Physical joint coordinates (nv,) [rad or m] (user convention).
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).
        statics: The locked system's static state ``x_s`` (nx,) under the same loads, for
            the forces the joints pass on (:func:`_root_copy_turn`); None leaves them out.

    Returns:
        ``K_L`` (nx, nx) [N/m, N, N m], to be added to ``Zᵀ K Z``.
    """
    q, qd, qdd = (np.asarray(v, dtype=float) for v in (q, qd, qdd))
    nx, nv = dyn.nx, dyn.nv
    K = np.zeros((nx, nx))
    base, A = _world_maps(dyn, q, qd)
    # rigid accelerations and loads f0 (world) at the state
    J, Jd, R, e, ed = dyn._kinematics(q)
    loads = []
    for p in dyn._points:
        _, _, Sdk, S, _ = dyn._maps(p, J, Jd, e, ed)
        acc = S @ qdd + np.einsum("k,knaj,j->na", qd, Sdk, qd)
        loads.append(p.mass[:, None] * (acc @ R[p.link].T - dyn.gravity[None, :]))
    # Σ m P1ᵀ P̈1 along the motion
    scale = max(float(np.abs(qd).max(initial=0.0)), float(np.sqrt(np.abs(qdd).max(initial=0.0))))
    if scale > 0.0:
        h = STEP / scale
        w = {-2: 1.0, -1: -8.0, 1: 8.0, 2: -1.0}
        acc1 = [np.zeros_like(b[1]) for b in base]
        for k, c in w.items():
            tau = k * h
            side, _ = _world_maps(dyn, q + qd * tau + 0.5 * qdd * tau * tau, qd + qdd * tau)
            for i, s in enumerate(side):
                acc1[i] += c / (12.0 * h) * s[2]
        for (m, P1, _, _, _), Pdd in zip(base, acc1):
            K += np.einsum("n,nax,nay->xy", m, P1, Pdd)
    # Σ f0 · P2: the Hessian of the loads' work Σ f0 · P(q_phys + A(q) x, x)
    offset = [k for k in range(nv) if np.any(A[k])]
    if offset and any(np.any(f) for f in loads):
        def gen(qq):
            maps, AA = _world_maps(dyn, qq, np.zeros(nv))
            gx = sum(np.einsum("nax,na->x", Et, f) for (_, _, _, _, Et), f in zip(maps, loads))
            gq = sum(np.einsum("naj,na->j", St, f) for (_, _, _, St, _), f in zip(maps, loads))
            return gx, gq, AA

        g0x, g0q, _ = gen(q)
        dgx = np.zeros((nx, nv))
        dgq = np.zeros((nv, nv))
        dA = np.zeros((nv, nv, nx))  # dA[l] = ∂A/∂q_l
        for j in offset:
            for k, c in {-2: 1.0, -1: -8.0, 1: 8.0, 2: -1.0}.items():
                dq = np.zeros(nv)
                dq[j] = k * STEP
                gx, gq, AA = gen(q + dq)
                dgx[:, j] += c / (12.0 * STEP) * gx
                dgq[:, j] += c / (12.0 * STEP) * gq
                dA[j] += c / (12.0 * STEP) * AA
        H = dgx @ A + (dgx @ A).T + A.T @ (0.5 * (dgq + dgq.T)) @ A
        # the held angle q − A(q) x is linear in x only at fixed q: q's curvature in x
        D = np.einsum("k,lka,lb->ab", g0q, dA, A)
        K += H + D + D.T
        K += _root_copy_turn(dyn, q, offset, A, statics)
    _add_geometric_locked(dyn, K, J, Jd, R, e, qd, qdd, loads)
    K += lever_terms(dyn, J, Jd, R, e, qd, qdd, loads)
    return K


def lever_terms(dyn, J, Jd, R, e, qd, qdd, loads) -> np.ndarray:
    """The lever terms of loads held off the beam axes (nx, nx).

    A load ``F`` held at the offset ``r`` from the section it rides on (the axis point at its
    clipped station, or a rigid link's origin) sits, to second order in the section's elastic
    rotation ``θ``, at ``… + θ × r + ½ θ × (θ × r)``, which adds ``θᵀ ((F·r) 𝟙 − sym(F rᵀ)) θ``
    (:func:`pinflex.erls.preload.lever_stiffness`; a hanging mass stiffens, a standing one
    softens). Here ``F = −m (a − g)`` of every point mass on a beam, of the points of a body on
    a beam (their offsets from the body's section), of the points on rigid links that move
    elastically (``θ`` their root twist's rotation), and the loads of every subtree carried at
    a joint off its parent's axis. The links' own frame rotations are exact in the positions.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics`.
        J: Link Jacobians (``dyn._kinematics``).
        Jd: Their rates per unit joint velocity.
        R: Link rotations in the world frame.
        e: Root twists of the links (or None).
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).
        loads: ``m (a − g)`` (n, 3) world, per carrier group of ``dyn._points``.

    Returns:
        The lever terms (nx, nx) [N m].
    """
    from pinflex.dynamics.carriers import _equivalent_points

    model = dyn.model
    plan = model.plan
    K = np.zeros((dyn.nx, dyn.nx))

    def applied(link, c, m):  # −m (a − g) of points c (n, 3) of a link, link axes
        a0, w, al = link_motion(J[link], Jd[link], qd, qdd)
        acc = a0 + np.cross(al, c) + np.cross(w, np.cross(w, c))
        return -m[:, None] * (acc - R[link].T @ dyn.gravity)

    def rotation(att, link):  # (3, nx) elastic rotation of an attachment, or None
        el = e.get(link)
        out = None if att.const is None else att.const[3:].copy()
        if att.lin is not None and el is not None:
            out = att.lin[3:] @ el if out is None else out + att.lin[3:] @ el
        return out

    for pm in plan.point_masses:
        theta = rotation(pm.attach, pm.link)
        c = np.asarray(pm.xyz, dtype=float)[None]
        r = lever_offset(plan, pm.link, c)
        if pm.link not in plan.beams or theta is None or not np.any(r):
            continue  # on rigid links: with the link's points below
        d = plan.design.mass_index.get(pm.name, -1)
        m = float(dyn.y[d]) if d >= 0 else float(model.point_mass_values[pm.name])
        K += theta.T @ lever_stiffness(applied(pm.link, c, np.array([m])), r) @ theta
    for body in plan.bodies:
        theta = rotation(body.attach, body.link)
        if theta is None:
            continue
        mass = float(body.inertia[0, 0])
        com = np.asarray(body.xyz, dtype=float)
        c, m = _equivalent_points(mass, com, body.inertia[3:, 3:])  # as the carriers
        r = c - (com - lever_offset(plan, body.link, com[None])[0])
        K += theta.T @ lever_stiffness(applied(body.link, c, m), r) @ theta
    for p in dyn._points:
        el = e.get(p.link)
        if p.link in plan.beams or el is None:
            continue
        theta = el[3:]
        K += theta.T @ lever_stiffness(applied(p.link, p.c, p.mass), p.c) @ theta
    # subtrees carried at joints off their parent's axis
    total = {p.link: -f.sum(axis=0) for p, f in zip(dyn._points, loads)}  # world
    sub: dict = {}
    for j in reversed(plan.joints):  # children before parents
        sub[j.child] = sub.get(j.child, np.zeros(3)) + total.get(j.child, np.zeros(3))
        sub[j.parent] = sub.get(j.parent, np.zeros(3)) + sub[j.child]
    for j in plan.joints:
        theta = rotation(j.attach, j.parent)
        r = lever_offset(plan, j.parent, np.asarray(j.xyz, dtype=float)[None])
        if theta is None or not np.any(r):
            continue
        F = (R[j.parent].T @ sub[j.child])[None]
        K += theta.T @ lever_stiffness(F, r) @ theta
    return K


def has_levers(dyn) -> bool:
    """Whether a load is held off the axis of a link that moves elastically (cached)."""
    hit = getattr(dyn, "_has_levers", None)
    if hit is None:
        plan = dyn.model.plan
        e, _ = dyn._root_twists(np.zeros(dyn.nv))

        def moves(att, link):
            return att.const is not None or (att.lin is not None and e.get(link) is not None)

        def off(link, c):
            return bool(np.any(lever_offset(plan, link, np.asarray(c, dtype=float)[None])))

        hit = (any(moves(pm.attach, pm.link) and off(pm.link, pm.xyz)
                   for pm in plan.point_masses)
               or any(moves(b.attach, b.link) for b in plan.bodies)
               or any(p.link not in plan.beams and e.get(p.link) is not None
                      for p in dyn._points)
               or any(moves(j.attach, j.parent) and off(j.parent, j.xyz) for j in plan.joints))
        dyn._has_levers = hit
    return hit


def _add_geometric_locked(dyn, K, J, Jd, R, e, qd, qdd, loads) -> None:
    """Add ``K_G`` of the beams' axial force (:func:`_add_geometric`'s rule) to ``K``."""
    force = {}
    for p, f in zip(dyn._points, loads):
        force[p.link] = [(p.c[p.n_beam:], f[p.n_beam:] @ R[p.link])]
    plan = dyn.model.plan
    line = {}
    for link in plan.beams:
        a0, w, al = link_motion(J[link], Jd[link], qd, qdd)
        line[link] = (a0 - R[link].T @ dyn.gravity, skew(al) + skew(w) @ skew(w))
    K += geometric_stiffness(plan, R, line, force, e, dyn.nx)


def _root_copy_turn(dyn, q, offset, A, xs) -> np.ndarray:
    """The force a joint passes on times the turn of its child's root copy (nx, nx).

    A child beam's root copy is the parent's attachment twist in the child's axes, which turn
    with the joint (``q = q_phys + A x``), while the child's other nodes keep their
    coordinates (their share of the joint point's translation ``t`` turns with the child): the
    strain energy ``½ (b(q) x)ᵀ K (b(q) x)`` (``b = sel + root e(q)``) has, at the loads'
    static state ``x_s``, the Hessian term ``2 sym(Σ_l ∂bᵀ/∂q_l F A_l)`` with the root node's
    force ``F = (K b x_s)[root translation]``: the joint turns about its displaced point. The
    root node's moment is left out, as the beams' ``K_G`` leaves out bending-moment prestress
    (with it a beam split at a joint and bent across the joint's axis by its weight was 1.6e-3
    off the one beam it is).
    """
    nx, nv = dyn.nx, dyn.nv
    if xs is None or not np.any(xs):
        return np.zeros((nx, nx))
    plan = dyn.model.plan
    e0, _ = dyn._root_twists(q)
    forces = {}
    for link, bp in plan.beams.items():
        sel, root, _, _, stiffness = bp.kept
        el = e0.get(link)
        if el is not None:
            force = np.asarray(bp.rows) < 3  # the root node's translation rows
            forces[link] = np.where(force, stiffness @ ((sel + root @ el) @ xs), 0.0)
    if not forces:
        return np.zeros((nx, nx))
    dg = np.zeros((nx, nv))
    for j in offset:
        for k, c in {-2: 1.0, -1: -8.0, 1: 8.0, 2: -1.0}.items():
            dq = np.zeros(nv)
            dq[j] = k * STEP
            e, _ = dyn._root_twists(q + dq)
            for link, F in forces.items():
                bp = plan.beams[link]
                dg[:, j] += c / (12.0 * STEP) * ((bp.kept[1] @ e[link]).T @ F)
    out = dg @ A
    return out + out.T
