"""Preload of the modal analysis: the stiffness of static gravity and payload loads.

Under constant loads (gravity ``g`` on every mass, dead point forces ``P`` at points of links)
an arm held by its joint conditions deflects statically, and its small vibrations about that
state feel the second variation of the loads' potential ``V = −Σ fᵢ · pᵢ``. The modal problem
becomes ``(K + K_P) φ = λ M φ`` with ``K_P`` the Hessian of ``V`` over ``[x; q_all]``, mapped to
the modal coordinates ``[x; q_kept]`` like ``K`` (``K_P ← Tᵀ K_P T`` with the locked joints'
map ``T``):

* **Beams: the geometric stiffness of the axial force.** An arm is a tree clamped at its root,
  so linear statics of the restrained system gives each section's axial force ``N(s)`` (tension
  positive) from the loads outboard of it alone, whatever the deflection: the beam's own weight
  exactly (its load is affine along the beam), point loads at their axial station, every child
  subtree at its joint. Its second-order strain energy ``½ ∫ N (v'² + w'²) ds`` is ``K_G``
  (:func:`pinflex.beam.element_geometric_stiffness`; :func:`geometric_stiffness`, shared with
  the moving arm's terms of :mod:`pinflex.dynamics.speed`).
* **Rigid levers.** A load ``f`` carried at a rigid offset ``r`` from the beam section (or link
  root) whose elastic rotation is ``θ`` rises by ``½ θ × (θ × r)``:
  ``½ θᵀ ((f·r) 𝟙 − sym(f rᵀ)) θ`` (a hanging mass below a tip stiffens, a standing one
  softens). Offsets along a beam are the beam's own ``K_G``; the rest (rigid links, point masses
  and bodies off the beam axis or beyond its ends, joints off its axis) is added here.
* **Joints: the loads' stiffness on the rigid motion.** ``V`` over the joint coordinates and
  the cross terms with the elastic ones are exact second derivatives of the ERLS potential:
  ``−∂F/∂q`` of the generalized static load ``F = [Σ Eᵢᵀ Rᵀ fᵢ; Σ Sᵢᵀ Rᵀ fᵢ]``, by
  fourth-order central differences (step :data:`STEP`, error about ``1e-12`` relative). On a
  joint spring ``k`` holding a pendulum this gives ``ω² = (k ± m g l) / I``.
* **Joints turn about their displaced points.** ERLS turns a joint's subtree about the joint's
  undeformed point, and the subtree's nodal coordinates (displacements in the turning link
  axes) carry the joint point's elastic translation ``t`` with them; a real joint turns about
  its displaced point. Per revolute joint the loads' potential gains ``δq (F_w × a) · t``
  (``F_w`` the outboard loads weighted by the share of ``t`` their nodes carry): without it two
  beams on a locked joint are 9 % off the one column they form (tested to 2e-9 with it).

Left out, as in the beam's ``K_G``: torsion, shear and bending-moment prestress, the loads'
moments about a joint across its axis, and what the static deflection does to a link bent
across its axis (its stiffness turned with the deflected shape). The arm stays at its
commanded pose; the loads' second variation is taken at the undeformed state. Exact to first
order where the loads run along the links or act through pendula (columns, payloads along a
link, springs holding a weight). Where the loads bend a link across its axis the left-out
terms are of the same order as the kept ones. On benchmark A's bent arm mode 1's shift is
within 7 % of a geometrically exact tangent and the higher modes' are off by factors
(``benchmarks/bench_preload_frame.py``), so :class:`~pinflex.exceptions.PreloadBendingWarning`
names such links.

A free joint whose coordinate feels a static load is not in equilibrium: there is no static
state to vibrate about, and :class:`~pinflex.exceptions.PreloadNotInEquilibrium` asks to lock
it or give it a spring (a free joint the loads leave neutral, as a vertical axis under
gravity, keeps its rigid mode). A preload that makes ``K + K_P`` indefinite (a column beyond
its buckling load) raises :class:`~pinflex.exceptions.PreloadBuckles`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pinflex import beam
from pinflex.erls import kinematics
from pinflex.erls.plan import attachment
from pinflex.erls.terms import BatchAlgebra, twist_at
from pinflex.exceptions import (
    ConfigurationError,
    PreloadBendingWarning,
    PreloadNotInEquilibrium,
)
from pinflex.linalg import skew
from pinflex.validation import require_array

#: Largest gravity component accepted [m/s^2] (1000 g: beyond any robot's test rig; larger
#: values are unit slips and overflow the equations of motion).
MAX_GRAVITY = 1e4

#: Standard gravity [m/s^2] (the default of ``--gravity`` without values: along −z of the base).
STANDARD_GRAVITY = 9.81

#: Step of the central differences of the generalized static load [rad or m].
STEP = 1e-3

#: Relative size (to the loads' scale) below which a free joint counts as unloaded.
NEUTRAL_RTOL = 1e-9

#: Share of a beam's outboard load across its axis above which the preload warns
#: (:class:`~pinflex.exceptions.PreloadBendingWarning`).
BENDING_SHARE = 1e-6

# two-point Gauss-Legendre on [0, 1]: exact for the beam's weight on the cubic fields
_GXI = 0.5 + np.array([-0.5, 0.5]) / np.sqrt(3.0)
_GWXI = np.array([0.5, 0.5])


@dataclass(frozen=True)
class PointForce:
    """A dead point force on a link (a payload's weight, a test load).

    Attributes:
        link: Link carrying the point.
        xyz: Point (3,) in the link frame [m].
        force: Force (3,) in world axes [N]; it keeps its direction as the arm moves.
    """

    link: str
    xyz: tuple[float, float, float]
    force: tuple[float, float, float]


@dataclass(frozen=True)
class Preload:
    """Static loads whose stiffness enters the modal analysis (module doc).

    Attributes:
        gravity: Gravity acceleration (3,) in world axes [m/s²] acting on every mass.
        forces: Dead point forces.
    """

    gravity: tuple[float, float, float] = (0.0, 0.0, 0.0)
    forces: tuple[PointForce, ...] = ()

    def as_dict(self) -> dict:
        """The preload as JSON-ready data (gravity [m/s²], forces [N] at points [m])."""
        return {"gravity_m_s2": [float(v) for v in self.gravity],
                "forces": [{"link": f.link, "xyz_m": [float(v) for v in f.xyz],
                            "force_n": [float(v) for v in f.force]} for f in self.forces]}

    def __str__(self) -> str:
        """One line: gravity and the point forces."""
        g = ", ".join(f"{v:g}" for v in self.gravity)
        text = f"gravity ({g}) m/s^2"
        for f in self.forces:
            text += (f"; {', '.join(f'{v:g}' for v in f.force)} N on {f.link} at "
                     f"({', '.join(f'{v:g}' for v in f.xyz)}) m")
        return text


def check_gravity(gravity, name: str = "gravity") -> np.ndarray:
    """``gravity`` as 3 finite numbers of at most :data:`MAX_GRAVITY` each [m/s²].

    Raises:
        ConfigurationError: Not 3 numbers, or beyond :data:`MAX_GRAVITY`.
    """
    g = require_array(gravity, name)
    if g.shape != (3,) or not np.all(np.abs(g) <= MAX_GRAVITY):
        raise ConfigurationError(
            f"{name} must be 3 finite numbers of at most {MAX_GRAVITY:g} m/s² each "
            f"({MAX_GRAVITY / 9.81:.0f} g), got {gravity!r}")
    return g


def make_preload(model, gravity=None, loads: Sequence[PointForce] | None = None,
                 preload: Preload | None = None) -> Preload | None:
    """The checked :class:`Preload` of ``gravity=``/``loads=`` or ``preload=`` (None: none).

    Args:
        model: The flexible model (its links name the forces' links).
        gravity: Gravity (3,) in world axes [m/s²], or None.
        loads: Point forces (:class:`PointForce`), or None.
        preload: A :class:`Preload` (instead of ``gravity`` and ``loads``).

    Raises:
        ConfigurationError: Both ``preload`` and ``gravity``/``loads``; gravity or a force not 3
            finite numbers; a load that is not a :class:`PointForce`.
        LinkNotFound: A force on an unknown link.
    """
    if preload is not None:
        if gravity is not None or loads:
            raise ConfigurationError("give either preload= or gravity=/loads=, not both")
        if not isinstance(preload, Preload):
            raise ConfigurationError(f"preload must be a pinflex.Preload, got {preload!r}")
        gravity, loads = preload.gravity, preload.forces
    if gravity is None and not loads:
        return None
    g = np.zeros(3) if gravity is None else check_gravity(gravity)
    forces = []
    for f in loads or ():
        if not isinstance(f, PointForce):
            raise ConfigurationError(f"loads must be pinflex.PointForce items, got {f!r}")
        model.description.require_link(f.link)
        xyz = require_array(f.xyz, f"the point of the force on '{f.link}'")
        force = require_array(f.force, f"the force on '{f.link}'")
        if xyz.shape != (3,) or force.shape != (3,):
            raise ConfigurationError(f"the force on '{f.link}' needs a point xyz (3,) [m] and a "
                                     f"force (3,) [N], got {f.xyz!r} and {f.force!r}")
        forces.append(PointForce(f.link, _vec3(xyz), _vec3(force)))
    return Preload(_vec3(g), tuple(forces))


def _vec3(v: np.ndarray) -> tuple[float, float, float]:
    return float(v[0]), float(v[1]), float(v[2])


# ------------------------------------------------------------------ axial force and K_G


def subtree_resultants(plan, R: Mapping, line: Mapping, force: Mapping) -> dict:
    """Resultant [N] (world axes) of the inertial loads of every link's subtree.

    Args:
        plan: The model's :class:`~pinflex.erls.terms.ModelPlan`.
        R: ``{link: (3, 3)}`` link rotations in the world frame.
        line: ``{beam link: (a (3,), A (3, 3))}``: a beam's load per unit mass at station
            ``s`` is ``a + A (s eₓ)`` (link axes; ``a = a₀ − Rᵀg`` of a moving link).
        force: ``{link: [(c (n, 3), f (n, 3))]}`` point loads in link axes: ``f = m (a − g)``
            minus any applied force (the load the link must give the point).

    Returns:
        ``{link: (3,)}`` for every link of the plan.
    """
    children: dict[str, list] = {}
    for j in plan.joints:
        children.setdefault(j.parent, []).append(j)
    subtree: dict[str, np.ndarray] = {}
    for link in reversed(plan.links):  # children first
        total = np.zeros(3)
        for _, f in force.get(link, ()):
            total += R[link] @ f.sum(axis=0)
        bp = plan.beams.get(link)
        if bp is not None:
            spec = bp.spec
            L = spec.length_m
            a, A = line[link]
            total += R[link] @ (spec.rhoA * (L * a + 0.5 * L * L * (A @ (spec.tip / L))))
        for j in children.get(link, ()):
            total += subtree[j.child]
        subtree[link] = total
    return subtree


def geometric_stiffness(plan, R: Mapping, line: Mapping, force: Mapping, e: Mapping,
                        nx: int, subtree: Mapping | None = None) -> np.ndarray:
    """``K_G`` (nx, nx) of every beam under the axial force of its loads (module doc).

    ``N(s)`` (tension positive) is minus the axial component of the loads outboard of ``s``:
    the line load exactly (affine along the beam), point loads at their axial station
    (clipped to the beam), every child subtree at its joint's station.

    Args:
        plan: The model's plan.
        R: ``{link: (3, 3)}`` link rotations in the world frame.
        line: ``{beam link: (a, A)}`` as :func:`subtree_resultants`.
        force: ``{link: [(c, f)]}`` as :func:`subtree_resultants`.
        e: ``{link: (6, nx) or None}`` elastic root twists (link axes).
        nx: Number of elastic coordinates.
        subtree: The :func:`subtree_resultants` if already computed.

    Returns:
        ``K_G`` over the elastic coordinates [N/m, N, N m].
    """
    if subtree is None:
        subtree = subtree_resultants(plan, R, line, force)
    children: dict[str, list] = {}
    for j in plan.joints:
        children.setdefault(j.parent, []).append(j)
    K = np.zeros((nx, nx))
    for link, bp in plan.beams.items():
        spec = bp.spec
        n, L = spec.elements, spec.length_m
        le = L / n
        ex = spec.tip / L
        a, A = line[link]
        a_x, A_xx = float(ex @ a), float(ex @ A @ ex)
        s = (np.arange(n)[:, None] + beam.GEOMETRIC_POINTS[None, :]) * le  # (n, 5) [m]
        N = -spec.rhoA * ((L - s) * a_x + 0.5 * (L * L - s * s) * A_xx)
        for c, f in force.get(link, ()):
            sp = np.clip(c @ ex, 0.0, L)
            N -= ((sp[None, None, :] > s[:, :, None]) * (f @ ex)[None, None, :]).sum(axis=-1)
        for j in children.get(link, ()):
            sp = float(np.clip(np.asarray(j.xyz) @ ex, 0.0, L))
            N -= (sp > s) * float(ex @ (R[link].T @ subtree[j.child]))
        KG = beam.assemble_line(beam.element_geometric_stiffness(le, N))
        sel, root, _, _, _ = bp.kept
        el = e.get(link)
        bx = sel if el is None else sel + root @ el
        K += bx.T @ KG[np.ix_(bp.rows, bp.rows)] @ bx
    return K


def lever_offset(plan, link: str, c: np.ndarray) -> np.ndarray:
    """Offsets (n, 3) of points ``c`` (n, 3) from where they hang on their link (link axes).

    On a beam: from the axis point at the points' clipped axial station; on a rigid link: from
    the link origin (where its root twist acts).
    """
    bp = plan.beams.get(link)
    if bp is None:
        return c
    L = bp.spec.length_m
    ex = bp.spec.tip / L
    s = np.clip(c @ ex, 0.0, L)
    return c - s[:, None] * ex[None, :]


def lever_stiffness(f: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``(f·r) 𝟙 − sym(f rᵀ)`` summed over loads ``f`` (n, 3) at offsets ``r`` (n, 3) [N m]."""
    fr = np.einsum("na,nb->ab", f, r)
    return np.trace(fr) * np.eye(3) - 0.5 * (fr + fr.T)


# ------------------------------------------------------------------ static loads of a model


@dataclass(frozen=True)
class _Group:
    """The static load points of one link (positions, world forces, attachment maps)."""

    link: str
    c: np.ndarray  # (n, 3) link frame [m]
    f: np.ndarray  # (n, 3) world [N]
    const: np.ndarray  # (n, 6, nx) constant part of the points' elastic twists
    lin: np.ndarray | None  # (n, 6, 6) root-twist part, or None
    on_axis: bool  # the beam's own line load (no lever; its N is exact in K_G)


def _inertia_mass_com(I6: np.ndarray) -> tuple[float, np.ndarray]:
    """Mass and centre of mass of a 6x6 spatial inertia (linear, angular) at the origin."""
    m = float(I6[0, 0])
    if m <= 0.0:
        return 0.0, np.zeros(3)
    mc = I6[3:, :3]  # m [c]x
    return m, np.array([mc[2, 1], mc[0, 2], mc[1, 0]]) / m


def _stack(atts, nx: int):
    const = np.zeros((len(atts), 6, nx))
    lin = None
    for i, att in enumerate(atts):
        if att.const is not None:
            const[i] = att.const
        if att.lin is not None:
            if lin is None:
                lin = np.zeros((len(atts), 6, 6))
            lin[i] = att.lin
    return const, lin


def static_loads(model, preload: Preload, y: np.ndarray) -> list[_Group]:
    """The static load points of ``model`` (at design ``y``) under ``preload``.

    Masses at their values (design masses from ``y``), the beams sampled at two Gauss points
    per element (exact for the cubic fields), rigid inertias and bodies at their centres of
    mass, point forces at their points.
    """
    plan, nx = model.plan, model.nx
    g = np.asarray(preload.gravity, dtype=float)
    groups: list[_Group] = []
    gravity = bool(np.any(g))

    def add(link, c, f, atts, on_axis=False):
        c = np.asarray(c, dtype=float).reshape(-1, 3)
        if not c.shape[0]:
            return
        const, lin = _stack(atts, nx)
        groups.append(_Group(link, c, np.asarray(f, dtype=float).reshape(-1, 3), const, lin,
                             on_axis))

    if gravity:
        for link, bp in plan.beams.items():
            spec = bp.spec
            n = spec.elements
            le = spec.length_m / n
            c = ((np.arange(n)[:, None] + _GXI[None, :]).ravel() / n)[:, None] * spec.tip
            w = np.tile(spec.rhoA * le * _GWXI, n)
            add(link, c, w[:, None] * g, [attachment(plan.beams, link, ci) for ci in c], True)
        for link, I6 in plan.inertias.items():
            mass, com = _inertia_mass_com(np.asarray(I6))
            if mass > 0.0:
                add(link, com, mass * g, [attachment(plan.beams, link, com)])
        for body in plan.bodies:
            mass = float(body.inertia[0, 0])
            if mass > 0.0:
                add(body.link, body.xyz, mass * g, [body.attach])
        values = dict(model.point_mass_values)
        for d, v in zip(model.design, np.atleast_1d(y)):
            if d.kind == "mass":
                values[d.name] = float(v)
        for pm in plan.point_masses:
            m = values[pm.name]
            if m != 0.0:
                add(pm.link, pm.xyz, m * g, [pm.attach])
    for pf in preload.forces:
        xyz = np.asarray(pf.xyz, dtype=float)
        add(pf.link, xyz, np.asarray(pf.force, dtype=float),
            [attachment(plan.beams, pf.link, xyz)])
    return groups


# ------------------------------------------------------------------ the preload stiffness


def _link_frames(model, q: np.ndarray, links, pdata):
    """``{link: (J (6, nv) LOCAL over user coordinates, R (3, 3) world)}`` at one pose."""
    pm = model.model
    pin.computeJointJacobians(pm, pdata, model.pin_configuration(q))
    pin.updateFramePlacements(pm, pdata)
    out = {}
    for link in links:
        fid = model.plan.frame_ids[link]
        J = np.asarray(pin.getFrameJacobian(pm, pdata, fid, pin.LOCAL)).reshape(6, model.nv)
        out[link] = (J @ model.coord_map, pdata.oMf[fid].rotation.copy())
    return out


def _twists(groups, e):
    """Per group the points' elastic twists (n, 6, nx) at root twists ``e`` (one pose)."""
    out = []
    for gr in groups:
        el = e.get(gr.link)
        if el is None or gr.lin is None:
            out.append(gr.const)
        else:
            out.append(gr.const + gr.lin @ el[0])
    return out


def generalized_load(model, groups, q: np.ndarray, data) -> np.ndarray:
    """The generalized static load ``F`` (nx + nv,) over ``[x; q_all]`` at one pose (user q)."""
    nx, nv = model.nx, model.nv
    ws = model.workspace(data)
    frames = _link_frames(model, q, {g.link for g in groups}, ws.pin)
    terms = kinematics.pose_terms(model, q[None], data=ws)
    e = kinematics.root_twists(model, terms, BatchAlgebra(1))
    F = np.zeros(nx + nv)
    for gr, T in zip(groups, _twists(groups, e)):
        J, Rl = frames[gr.link]
        fL = gr.f @ Rl  # link axes
        F[:nx] += np.einsum("nax,na->x", T[:, :3], fL)
        if nv:
            F[nx:] += J[:3].T @ fL.sum(axis=0) + J[3:].T @ np.cross(gr.c, fL).sum(axis=0)
    return F


def _second_order(model, groups, q: np.ndarray, data) -> np.ndarray:
    """``K_G`` plus the rigid levers, (nx, nx), at one pose (module doc)."""
    plan, nx = model.plan, model.nx
    ws = model.workspace(data)
    frames = _link_frames(model, q, plan.links, ws.pin)
    R = {link: fr[1] for link, fr in frames.items()}
    terms = kinematics.pose_terms(model, q[None], data=ws)
    e1 = kinematics.root_twists(model, terms, BatchAlgebra(1))
    e = {link: (None if v is None else v[0]) for link, v in e1.items()}
    line: dict = {}
    force: dict = {}
    for link in plan.beams:
        line[link] = (np.zeros(3), np.zeros((3, 3)))
    K = np.zeros((nx, nx))
    for gr, T in zip(groups, _twists(groups, e1)):
        fL = -(gr.f @ R[gr.link])  # the inertial-load convention: f = m (a − g) − P
        if gr.on_axis:  # the beam's weight: its line load per unit mass is −Rᵀg
            a, _ = line[gr.link]
            spec = plan.beams[gr.link].spec
            line[gr.link] = (a + fL.sum(axis=0) / (spec.rhoA * spec.length_m), np.zeros((3, 3)))
            continue
        force.setdefault(gr.link, []).append((gr.c, fL))
        r = lever_offset(plan, gr.link, gr.c)
        Th = T[:, 3:]  # (n, 3, nx) elastic rotations
        Kl = np.einsum("n,ab->nab", np.einsum("na,na->n", -fL, r), np.eye(3))
        fr = np.einsum("na,nb->nab", -fL, r)
        Kl -= 0.5 * (fr + np.swapaxes(fr, 1, 2))
        K += np.einsum("nax,nab,nby->xy", Th, Kl, Th)
    subtree = subtree_resultants(plan, R, line, force)
    K += geometric_stiffness(plan, R, line, force, e, nx, subtree)
    for j in plan.joints:  # subtree loads carried at a joint off its parent's axis or root
        tau = twist_at(BatchAlgebra(1), j.attach, e1.get(j.parent))
        if tau is None:
            continue
        r = lever_offset(plan, j.parent, np.asarray(j.xyz, dtype=float)[None])
        if not np.any(r):
            continue
        fP = -(R[j.parent].T @ subtree[j.child])  # the applied load, parent axes
        Th = tau[0, 3:]
        K += Th.T @ lever_stiffness(fP[None], r) @ Th
    return K


def preload_hessian(model, groups, q: np.ndarray, data) -> tuple[np.ndarray, np.ndarray]:
    """``(H, F)``: the loads' Hessian (nx + nv, nx + nv) over ``[x; q_all]`` and their
    generalized static load (nx + nv,) at one pose (module doc)."""
    nx, nv = model.nx, model.nv
    H = np.zeros((nx + nv, nx + nv))
    H[:nx, :nx] = _second_order(model, groups, q, data)
    F0 = generalized_load(model, groups, q, data)
    if nv:
        dF = np.zeros((nx + nv, nv))
        for k in range(nv):
            def at(t, k=k):
                qq = q.copy()
                qq[k] += t
                return generalized_load(model, groups, qq, data)
            h = STEP
            dF[:, k] = (8.0 * (at(h) - at(-h)) - (at(2 * h) - at(-2 * h))) / (12.0 * h)
        H[:nx, nx:] = -dF[:nx]
        H[nx:, :nx] = -dF[:nx].T
        H[nx:, nx:] = -dF[nx:]
        _displaced_pivots(model, groups, q, data, H)
    return 0.5 * (H + H.T), F0


def _root_share(plan, link: str, c: np.ndarray) -> np.ndarray:
    """Share (n,) of points' translation that a link's root translation gives them.

    1 on a rigid link; on a beam the root node's Hermite translation weight at the points'
    axial station (``1 − 3ξ² + 2ξ³`` in the first element, 0 beyond).
    """
    bp = plan.beams.get(link)
    if bp is None:
        return np.ones(c.shape[0])
    L, n = bp.spec.length_m, bp.spec.elements
    xi = np.clip(c @ (bp.spec.tip / L), 0.0, L) / (L / n)
    return np.where(xi < 1.0, 1.0 - 3.0 * xi**2 + 2.0 * xi**3, 0.0)


def _displaced_pivots(model, groups, q: np.ndarray, data, H: np.ndarray) -> None:
    """Add the loads' term of joints turning about their displaced points (module doc).

    ERLS turns a joint's subtree about the joint's undeformed point, and the elastic
    coordinates of the subtree's nodes (their displacement in the turning link axes) carry the
    joint point's elastic translation ``t`` with them. A joint turns about its displaced point:
    the part of ``t`` the nodes carry does not turn. Per revolute joint ``j`` this adds
    ``δq_j (F_w × a) · t`` to the potential, ``F_w`` the loads outboard of ``j`` weighted by the
    share of ``t`` their nodes carry (1 minus the root shares along the path, see
    :func:`_root_share`), ``a`` the joint axis.
    """
    plan, nx = model.plan, model.nx
    ws = model.workspace(data)
    frames = _link_frames(model, q, plan.links, ws.pin)
    terms = kinematics.pose_terms(model, q[None], data=ws)
    e1 = kinematics.root_twists(model, terms, BatchAlgebra(1))
    by_link: dict[str, list] = {}
    for gr in groups:
        by_link.setdefault(gr.link, []).append(gr)
    children: dict[str, list] = {}
    for j in plan.joints:
        children.setdefault(j.parent, []).append(j)
    for j in plan.joints:
        if j.kind != "revolute" or j.user_col < 0:
            continue
        tau = twist_at(BatchAlgebra(1), j.attach, e1.get(j.parent))
        if tau is None:
            continue
        RP = frames[j.parent][1]
        t_w = RP @ tau[0, :3]  # (3, nx) world translation of the joint point
        a_w = RP @ (j.R_o @ j.axis)
        Fw = np.zeros(3)
        stack = [(j.child, 1.0)]  # (link, root share of its root)
        while stack:
            link, share = stack.pop()
            for gr in by_link.get(link, ()):
                Fw += ((1.0 - share * _root_share(plan, link, gr.c))[:, None] * gr.f).sum(axis=0)
            for jc in children.get(link, ()):
                xyz = np.asarray(jc.xyz, dtype=float)[None]
                stack.append((jc.child, share * float(_root_share(plan, link, xyz)[0])))
        if np.any(Fw):
            H[nx + j.user_col, :nx] += np.cross(Fw, a_w) @ t_w
            H[:nx, nx + j.user_col] += np.cross(Fw, a_w) @ t_w


def _load_scale(model, groups, q, data) -> float:
    """``Σ |fᵢ| · (|cᵢ| + reach)``: the size of the loads' moments [N m] (for tolerances)."""
    reach = sum(bp.spec.length_m for bp in model.plan.beams.values())
    reach += sum(float(np.linalg.norm(j.xyz)) for j in model.plan.joints)
    return float(sum(np.linalg.norm(gr.f, axis=1).sum() * (reach + np.abs(gr.c).max())
                     for gr in groups)) or 1.0


def preload_stiffness(model, Q: np.ndarray, preload: Preload, y: np.ndarray,
                      data=None) -> np.ndarray:
    """``K_P`` (n, ndof, ndof) over the modal coordinates ``[x; q_kept]`` at poses Q (n, nv).

    Args:
        model: The flexible model (at the design of ``y``: parameters through
            :func:`pinflex.erls.design.design_model`).
        Q: Checked poses (n, nv), user convention [rad or m].
        preload: The loads.
        y: Checked design values (ny,).
        data: Workspace.

    Raises:
        PreloadNotInEquilibrium: A free joint carries a static load (module doc).
    """
    from pinflex.erls import joints as joint_conditions

    groups = static_loads(model, preload, y)
    lay = model.plan.conditions
    nx, nv = model.nx, model.nv
    free = [i for i, c in enumerate(lay.conditions) if c.kind == "free"]
    Ci = np.linalg.inv(model.coord_map)
    out = np.zeros((Q.shape[0], model.ndof, model.ndof))
    bent: dict[str, float] = {}
    for i, q in enumerate(Q):
        for link, share in _bent_beams(model, groups, q, data).items():
            bent[link] = max(share, bent.get(link, 0.0))
        H, F = preload_hessian(model, groups, q, data)
        if free:
            _check_free(model, groups, q, data, H, F, free, Ci)
        terms = kinematics.pose_terms(model, q[None], data=data)
        alg = BatchAlgebra(1)
        T = joint_conditions.transform(model, terms, alg,
                                       kinematics.root_twists(model, terms, alg))
        out[i] = H if T is None else T[0].T @ H @ T[0]
    if bent:
        import warnings

        said = ", ".join(f"'{k}' ({v:.0%})" for k, v in bent.items())
        warnings.warn(
            f"the preload bends link(s) {said} across their axes (share of the outboard load "
            "across the axis): the preload keeps the axial forces' stiffness and the loads' "
            "terms on the joints, not what the static deflection does to a bent link (its "
            "stiffness turned with the deflected shape, the shear prestress). On benchmark "
            "A's bent arm that left mode 1's shift within 7 % of a geometrically exact "
            "tangent and the higher modes' off by factors (benchmarks/bench_preload_frame.py)",
            PreloadBendingWarning, stacklevel=4)
    return out


def _bent_beams(model, groups, q: np.ndarray, data) -> dict[str, float]:
    """``{beam: share}`` of the beams whose outboard load has a share across their axis
    above :data:`BENDING_SHARE` at one pose (share = |transverse| / |total| of the load)."""
    plan = model.plan
    ws = model.workspace(data)
    frames = _link_frames(model, q, plan.links, ws.pin)
    R = {link: fr[1] for link, fr in frames.items()}
    force: dict = {}
    line = {link: (np.zeros(3), np.zeros((3, 3))) for link in plan.beams}
    for gr in groups:
        fL = -(gr.f @ R[gr.link])
        if gr.on_axis:
            spec = plan.beams[gr.link].spec
            line[gr.link] = (line[gr.link][0] + fL.sum(axis=0) / (spec.rhoA * spec.length_m),
                             np.zeros((3, 3)))
        else:
            force.setdefault(gr.link, []).append((gr.c, fL))
    subtree = subtree_resultants(plan, R, line, force)
    out = {}
    for link, bp in plan.beams.items():
        total = R[link].T @ subtree[link]  # link axes
        ex = bp.spec.tip / bp.spec.length_m
        size = float(np.linalg.norm(total))
        across = float(np.linalg.norm(total - (total @ ex) * ex))
        if size > 0.0 and across > BENDING_SHARE * size:
            out[link] = across / size
    return out


def _check_free(model, groups, q, data, H, F, free, Ci) -> None:
    """Raise :class:`PreloadNotInEquilibrium` if a free joint's coordinate feels the loads."""
    nx = model.nx
    scale = _load_scale(model, groups, q, data)
    tau = Ci.T @ F[nx:]  # generalized forces on the relative (Pinocchio) joint values
    P = np.eye(H.shape[0])
    P[nx:, nx:] = Ci
    Hr = P.T @ H @ P
    kinds = {j.user_col: j.kind for j in model.plan.joints}
    bad = []
    for i in free:
        row = np.abs(Hr[nx + i]).max()
        if abs(tau[i]) > NEUTRAL_RTOL * scale or row > 1e3 * NEUTRAL_RTOL * scale:
            bad.append((model.joint_names[i], float(tau[i]), float(Hr[nx + i, nx + i]),
                        kinds.get(i, "revolute")))
    if bad:
        raise PreloadNotInEquilibrium(bad)
