"""Joint conditions of an ERLS model: free joints, joint springs and locked joints.

A moving joint is one of

* **free** (paper 000): the joint coordinate has no stiffness; each free joint gives one rigid
  (zero-frequency) mode;
* a **spring** of stiffness ``k`` [N m/rad revolute, N/m prismatic] on the joint's *physical*
  relative motion. A servo or gearbox holding a joint is modelled this way;
* **locked**: the child's root follows the parent's deformed attachment rigidly.

The physical relative motion. With the unique-ERLS rule the child's root drops the elastic
dof along the joint axis, so the ERLS coordinate ``q_j`` is the child's motion relative to the
parent's *undeformed* attachment frame. The parent attachment itself moves elastically by the
twist ``τ`` (in parent link axes); its component along the joint axis ``a`` (the rotation for
a revolute joint, the translation for a prismatic one) is ``aᵀθ_parent``. The relative motion
is therefore, to first order,

    r_j = (C q)_j − aᵀθ_parent(x)

(``C`` maps user coordinates to relative joint values, the identity unless the file uses
absolute angles). ``aᵀθ_parent`` is linear in the elastic coordinates ``x`` and, through the
rotations of the joints between the parent and the last flexible link, may depend on the pose.
It is zero on the ground and on a parent whose attachment does not deform.

* A spring adds ``k r_j²`` to the strain energy: ``K += k gᵀ g`` with ``g = ∂r_j/∂[x; q]``,
  which couples ``x`` and ``q``. No preload: the spring is at rest in the pose analysed.
* A lock imposes ``r_j = 0``: the locked joints' coordinates are eliminated,
  ``[x; q] = T [x; q_kept]`` with ``q_L = C_LL⁻¹ (Gₓ x − C_LK q_kept)``, and ``M``, ``K``
  become ``Tᵀ M T``, ``Tᵀ K T``. It is the limit ``k → ∞`` of the spring.

The assembly works on the *modal coordinates* ``[x; q_kept]``: the elastic coordinates and the
user coordinates of the joints that are not locked (``FlexibleModel.kept_joints``). Springs
turn their joints' coordinates into elastic ones: the modal problem condenses only the free
joints' coordinates out, and the number of rigid modes is the number of free joints. (With
absolute user coordinates it does so in relative joint values, where free joints carry no
stiffness; the shapes are reported in the user coordinates.)
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pinflex.checks import check_q
from pinflex.erls import kinematics
from pinflex.erls.terms import BatchAlgebra, twist_at
from pinflex.exceptions import ConfigurationError, InvalidBeamProperty, JointNotFound

JOINT_SWITCHES = ("free", "locked", "annotated")


@dataclass(frozen=True)
class JointCondition:
    """The condition of one moving joint in a model.

    Attributes:
        name: Joint name.
        kind: 'free', 'spring' or 'locked'.
        stiffness: Spring stiffness [N m/rad or N/m]; 0 when free, ``inf`` when locked.
        damping: Damper on the joint's physical relative motion [N m s/rad or N s/m].
        armature: Reflected rotor inertia on the same motion [kg m² or kg].
    """

    name: str
    kind: str
    stiffness: float
    damping: float = 0.0
    armature: float = 0.0

    def label(self) -> str:
        """Short text: ``free``, ``locked`` or ``k=1.2e+04``, with ``c=`` and ``a=`` if set."""
        text = self.kind if self.kind != "spring" else f"k={self.stiffness:.3g}"
        if self.damping and self.kind != "locked":
            text += f" c={self.damping:.3g}"
        if self.armature and self.kind != "locked":
            text += f" a={self.armature:.3g}"
        return text


def resolve(model, joints) -> tuple[JointCondition, ...]:
    """Conditions of the model's moving joints from the ``joints`` switch.

    Args:
        model: The model (its joint names and description).
        joints: 'annotated' or None (the default: the file's ``<pinflex:joint>``
            elements; unannotated joints are free), 'free', 'locked', or a mapping
            ``{joint: 'free' | 'locked' | stiffness | JointSpec}`` (unnamed joints are free).

    The holding condition (free, spring, lock) and the damper come from the switch; the
    armature is the drive's hardware and stays the file's under every switch (a
    :class:`~pinflex.native.spec.JointSpec` in a mapping may give its own).
    """
    names = model.joint_names
    notes = model.description.joint_annotations
    file_armature = {n: a.armature for n, a in notes.items()}
    if joints is None:
        joints = "annotated"
    if isinstance(joints, str):
        if joints not in JOINT_SWITCHES:
            raise ConfigurationError(
                f"joints='{joints}': expected one of {', '.join(JOINT_SWITCHES)} or a mapping "
                "{joint: 'free' | 'locked' | stiffness | JointSpec}"
            )
        if joints in ("free", "locked"):
            k = 0.0 if joints == "free" else np.inf
            return tuple(JointCondition(n, joints, k, 0.0, file_armature.get(n, 0.0))
                         for n in names)
        spec: dict = {}
        for name, a in notes.items():
            spec[name] = _Held("locked" if a.locked else "spring" if a.stiffness is not None
                               else "free", a.stiffness, a.damping, a.armature)
    elif isinstance(joints, Mapping):
        spec = dict(joints)
    else:
        raise ConfigurationError(
            f"joints={joints!r}: expected 'free', 'locked', 'annotated' or a mapping"
        )
    for name in spec:
        if name not in names:
            raise JointNotFound(name, names)
    return tuple(_condition(n, spec.get(n, "free"), file_armature.get(n, 0.0)) for n in names)


@dataclass(frozen=True)
class _Held:
    kind: str
    stiffness: float | None
    damping: float
    armature: float


def _condition(n: str, v, armature: float) -> JointCondition:
    """One joint's condition from a mapping value (or a parsed annotation)."""
    damping = 0.0
    if isinstance(v, _Held):
        kind, k, damping, armature = v.kind, v.stiffness, v.damping, v.armature
        v = kind if kind != "spring" else k
    elif hasattr(v, "stiffness") and hasattr(v, "armature"):  # a pinflex.JointSpec
        damping = float(v.damping)
        armature = armature if v.armature is None else float(v.armature)
        for what, x in (("damping", damping), ("armature", armature)):
            if not (np.isfinite(x) and x >= 0.0):
                raise InvalidBeamProperty(f"joint '{n}': {what} = {x!r} must be a finite "
                                          "number >= 0")
        v = "locked" if v.locked else ("free" if v.stiffness is None else v.stiffness)
    if isinstance(v, str):
        if v not in ("free", "locked"):
            raise ConfigurationError(
                f"joint '{n}': condition '{v}' must be 'free', 'locked', a stiffness or a "
                "pinflex.JointSpec"
            )
        return JointCondition(n, v, 0.0 if v == "free" else np.inf,
                              0.0 if v == "locked" else damping, armature)
    if isinstance(v, bool | np.bool_) or not isinstance(v, int | float | np.integer | np.floating):
        raise ConfigurationError(
            f"joint '{n}': condition {v!r} must be 'free', 'locked', a stiffness "
            "[N m/rad or N/m] or a pinflex.JointSpec")
    k = float(v)
    if not np.isfinite(k) or k <= 0.0:
        raise InvalidBeamProperty(
            f"joint '{n}': stiffness = {v!r} must be a positive finite number "
            "[N m/rad or N/m]; use 'free' or 'locked' for the limits"
        )
    return JointCondition(n, "spring", k, damping, armature)


@dataclass(frozen=True)
class JointLayout:
    """The modal coordinates of a model's joint conditions (``model.plan.conditions``).

    Computed once when the model is built (:func:`layout`); read-only.

    Attributes:
        conditions: Per moving joint (Pinocchio's velocity order), its :class:`JointCondition`.
        switch: The ``joints`` argument the conditions came from: 'annotated' (the file's
            ``<pinflex:joint>`` elements, the default), 'free', 'locked' or 'mapping'.
        kept_joints: Names of the joints that are not locked (their coordinates stay modal).
        n_rigid: Number of free joints (rigid modes).
        ndof: Number of modal coordinates ``nx + len(kept_joints)``.
        rigid_cols: Modal columns of the free joints.
        elastic_cols: Modal columns of ``x`` and of the spring-held joints.
        spring_joints: ``(JointPlan, stiffness)`` of every spring-held joint.
        spring_refs: ``{joint: parameter}`` of springs whose stiffness is a parameter.
        locked_joints: ``JointPlan`` of every locked joint.
        armatures: ``(JointPlan, armature)`` of every joint that is not locked and has a
            reflected rotor inertia (added to M on its relative motion).
        dampers: ``(JointPlan, damping)`` of every joint that is not locked and has a damper
            (the joint part of the damping matrix, :func:`damping_matrices`).
        lock_T0: Constant part of ``T`` (nx + nv, ndof) when a joint is locked, else None.
        lock_inv: ``C_LL⁻¹`` of the locked joints, else None.
        lock_rows: Rows of ``T`` of the locked joints' coordinates, else None.
        plain: Every joint free (the modal coordinates are ``[x; q]``).
        modal_Winv: ``W⁻¹`` mapping relative to user values of the kept joints when they
            differ (absolute coordinates with springs or locks), else None.
    """

    conditions: tuple[JointCondition, ...]
    switch: str
    kept_joints: tuple[str, ...]
    n_rigid: int
    ndof: int
    rigid_cols: np.ndarray
    elastic_cols: np.ndarray
    spring_joints: tuple
    spring_refs: Mapping[str, str]
    locked_joints: tuple
    lock_T0: np.ndarray | None
    lock_inv: np.ndarray | None
    lock_rows: np.ndarray | None
    plain: bool
    modal_Winv: np.ndarray | None
    armatures: tuple = ()
    dampers: tuple = ()


def _frozen(a):
    if a is None:
        return None
    a = np.array(a)
    a.setflags(write=False)
    return a


def layout(model, plan, joints) -> JointLayout:
    """The modal-coordinate layout of the joint conditions (after the elastic layout).

    Args:
        model: The model being built (its joint names, description and coordinate map).
        plan: Its :class:`~pinflex.erls.terms.ModelPlan` (joints, beams, ``nx``).
        joints: The ``joints`` switch or mapping (see :func:`resolve`).
    """
    from types import MappingProxyType

    conds = resolve(model, joints)
    switch = "annotated" if joints is None else (joints if isinstance(joints, str)
                                                 else "mapping")
    spring_refs: dict[str, str] = {}
    if switch == "annotated":
        spring_refs = {
            a.name: a.stiffness_ref
            for a in model.description.joint_annotations.values()
            if a.stiffness_ref is not None and not a.locked
        }
    conds = _soft_springs_free(plan, conds, spring_refs)
    nv, nx = model.nv, plan.nx
    locked = [i for i, c in enumerate(conds) if c.kind == "locked"]
    kept = [i for i, c in enumerate(conds) if c.kind != "locked"]
    ndof = nx + len(kept)
    modal_col = {j: nx + k for k, j in enumerate(kept)}
    rigid_cols = np.array([modal_col[i] for i, c in enumerate(conds) if c.kind == "free"],
                          dtype=int)
    elastic_cols = np.concatenate(
        [np.arange(nx), [modal_col[i] for i, c in enumerate(conds) if c.kind == "spring"]]
    ).astype(int)
    by_col = {j.user_col: j for j in plan.joints if j.user_col >= 0}
    spring_joints = tuple(
        (by_col[i], c.stiffness) for i, c in enumerate(conds) if c.kind == "spring"
    )
    locked_joints = tuple(by_col[i] for i in locked)
    armatures = tuple((by_col[i], c.armature) for i, c in enumerate(conds)
                      if c.kind != "locked" and c.armature > 0.0)
    dampers = tuple((by_col[i], c.damping) for i, c in enumerate(conds)
                    if c.kind != "locked" and c.damping > 0.0)
    _check_spring_scale(plan, spring_joints)
    C = model.coord_map
    T0 = inv = rows = None
    if locked:
        CLL = C[np.ix_(locked, locked)]
        CLK = C[np.ix_(locked, kept)]
        inv = np.linalg.inv(CLL)  # C is unit lower triangular: the block is invertible
        T0 = np.zeros((nx + nv, ndof))
        T0[:nx, :nx] = np.eye(nx)
        T0[nx + np.array(kept, dtype=int), nx + np.arange(len(kept))] = 1.0
        T0[np.ix_(nx + np.array(locked), nx + np.arange(len(kept)))] = -inv @ CLK
        rows = nx + np.array(locked, dtype=int)
    plain = not spring_joints and not locked and not armatures
    # Free joints carry no stiffness in *relative* joint values; with absolute user
    # coordinates a spring on one joint couples its neighbours' user coordinates. The modal
    # reduction therefore works in [x; r_kept] with r_kept = W q_kept (x = 0 in the locks).
    Winv = None
    if not plain:
        Tq = np.zeros((nv, len(kept)))
        Tq[kept, np.arange(len(kept))] = 1.0
        if inv is not None:
            Tq[locked] = -inv @ C[np.ix_(locked, kept)]
        W = (C @ Tq)[kept]
        if not np.allclose(W, np.eye(len(kept)), rtol=0.0, atol=1e-14):
            Winv = np.linalg.inv(W)
    return JointLayout(
        conditions=conds, switch=switch,
        kept_joints=tuple(model.joint_names[i] for i in kept),
        n_rigid=sum(c.kind == "free" for c in conds), ndof=ndof,
        rigid_cols=_frozen(rigid_cols), elastic_cols=_frozen(elastic_cols),
        spring_joints=spring_joints, spring_refs=MappingProxyType(spring_refs),
        locked_joints=locked_joints, lock_T0=_frozen(T0), lock_inv=_frozen(inv),
        lock_rows=_frozen(rows), plain=plain, modal_Winv=_frozen(Winv),
        armatures=armatures, dampers=dampers,
    )


#: A spring softer than this multiple of the softest beam's own stiffness (``E I_min / L``
#: [N m/rad] for a revolute joint, ``3 E I_min / L³`` [N/m] for a prismatic one) is a free
#: joint: its mode would lie some 1e-8 times below the first elastic frequency and it changes
#: the other modes by less than round-off (relative ``~ k L / EI``). Stiffer springs are
#: resolved exactly, however soft (:mod:`pinflex.erls.solve_conditions`).
SOFT_SPRING_RATIO = 1e-16


def _soft_springs_free(plan, conds, spring_refs) -> tuple:
    """``conds`` with the springs below :data:`SOFT_SPRING_RATIO` made free, with a warning.

    A spring whose stiffness is a design parameter keeps its condition (the design may move it).
    """
    if not plan.beams or not any(c.kind == "spring" for c in conds):
        return conds
    turns = {j.name: j.motion.rotates for j in plan.joints}
    rot = lin = np.inf
    for p in plan.beams.values():
        spec = p.spec
        EI = spec.E * min(spec.section.Iy, spec.section.Iz)
        rot = min(rot, EI / spec.length_m)
        lin = min(lin, 3.0 * EI / spec.length_m**3)
    out = []
    for c in conds:
        ref = rot if turns.get(c.name, True) else lin
        soft = c.kind == "spring" and c.stiffness < SOFT_SPRING_RATIO * ref
        if soft and c.name not in spring_refs:
            import warnings

            from pinflex.exceptions import SoftSpringWarning

            unit = "N m/rad" if turns.get(c.name, True) else "N/m"
            warnings.warn(
                f"joint '{c.name}': stiffness {c.stiffness:.3g} {unit} is below "
                f"{SOFT_SPRING_RATIO:g} times the softest beam's own stiffness ({ref:.3g} {unit}):"
                " treated as a free joint (its mode would lie below 1e-8 times the first "
                "elastic frequency, and it changes the other modes by less than round-off)",
                SoftSpringWarning, stacklevel=6,
            )
            c = JointCondition(c.name, "free", 0.0)
        out.append(c)
    return tuple(out)


#: A spring stiffer than this multiple of the stiffest beam element's own stiffness loses
#: digits in the eigensolution (the pencil's condition number grows with k).
STIFF_SPRING_RATIO = 1e6


def _check_spring_scale(model_plan, spring_joints) -> None:
    """Warn when a spring is so stiff that the eigenvalues lose digits (use a lock)."""
    if not spring_joints or not model_plan.beams:
        return
    scale = 0.0
    for plan in model_plan.beams.values():
        spec = plan.spec
        le = spec.length_m / spec.elements
        sec = spec.section
        rot = spec.E * max(sec.Iy, sec.Iz) / le  # bending [N m/rad]
        ax = spec.E * sec.A / le  # axial [N/m]
        scale = max(scale, rot, ax * 1e-6)
    for j, k in spring_joints:
        ref = scale if j.motion.rotates else scale * 1e6
        if k > STIFF_SPRING_RATIO * ref:
            import warnings

            from pinflex.exceptions import PinflexWarning

            warnings.warn(
                f"joint '{j.name}': stiffness {k:.3g} is {k / ref:.2g} times the stiffest beam "
                "element's; the eigenvalues lose about that many digits of accuracy. For a "
                "rigid joint use locked=\"true\" (joints='locked'), its exact limit",
                PinflexWarning, stacklevel=5,
            )


def parent_rows(model, terms, alg, twist, joints_) -> np.ndarray:
    """``∂(aᵀθ_parent)/∂x`` of the given joints, (b, len(joints_), nx) in the algebra."""
    rows: list[np.ndarray | None] = []
    for j in joints_:
        tau = twist_at(alg, j.attach, twist[j.parent])
        if tau is None:
            rows.append(None)
            continue
        a = j.R_o @ j.axis  # the joint axis in parent link axes (fixed by the joint rotation)
        part = tau[..., j.motion.rows, :]  # rotation (revolute) or translation (prismatic)
        rows.append(np.einsum("i,...ix->...x", a, part))
    ref = next((r for r in rows if r is not None), None)
    if ref is None:
        return alg.const(np.zeros((len(joints_), model.nx)))
    return np.stack([np.zeros_like(ref) if r is None else r for r in rows], axis=-2)


def transform(model, terms, alg, twist):
    """``T`` (b, nx + nv, ndof) from modal coordinates to ``[x; q_all]``, or None if no lock."""
    lay = model.plan.conditions
    if not lay.locked_joints:
        return None
    gx = parent_rows(model, terms, alg, twist, lay.locked_joints)
    T = alg.const(lay.lock_T0).copy()
    T[..., lay.lock_rows, : model.nx] += np.einsum("lm,...mx->...lx", lay.lock_inv, gx)
    return T


def apply(model, terms, alg, twist, M, Mdesign, K):
    """Add the joint springs to ``K`` and eliminate locked joints (see the module docstring).

    ``M``, ``K`` (b, nx + nv, nx + nv) and ``Mdesign`` (ny, b, ...) come from the assembly in
    ``[x; q_all]``; the result is over the modal coordinates ``[x; q_kept]``.
    """
    lay = model.plan.conditions
    if lay.plain:
        return M, Mdesign, K
    if lay.armatures:
        # the rotor turns with the joint's physical relative motion r = g [x; q]: its reflected
        # inertia a adds a gᵀg to M, as Pinocchio's model.armature adds a to the joint's own
        # diagonal when the parent does not deform (there g is the joint's unit row)
        M = M + sum(a * _unit(model, terms, alg, twist, j) for j, a in lay.armatures)
    if lay.spring_joints:
        gx = parent_rows(model, terms, alg, twist, [j for j, _ in lay.spring_joints])
        for s, (j, k) in enumerate(lay.spring_joints):
            g = np.concatenate(
                [-gx[..., s : s + 1, :], alg.const(model.coord_map[j.user_col][None, :])],
                axis=-1,
            )
            K = K + k * alg.mm(np.swapaxes(g, -1, -2), g)
    T = transform(model, terms, alg, twist)
    if T is not None:
        Tt = np.swapaxes(T, -1, -2)
        M = alg.mm(Tt, alg.mm(M, T))
        K = alg.mm(Tt, alg.mm(K, T))
        Mdesign = np.stack([alg.mm(Tt, alg.mm(Md, T)) for Md in Mdesign]) if len(Mdesign) else (
            np.zeros((0,) + M.shape)
        )
    return M, Mdesign, K


def _unit(model, terms, alg, twist, j) -> np.ndarray:
    """``gᵀg`` of one joint's physical relative motion ``r = g [x; q_all]``, (b, nd, nd)."""
    gx = parent_rows(model, terms, alg, twist, [j])
    g = np.concatenate([-gx, alg.const(model.coord_map[j.user_col][None, :])], axis=-1)
    return alg.mm(np.swapaxes(g, -1, -2), g)


def damping_matrices(model, Q, data=None) -> np.ndarray:
    """The joint dampers' damping matrix ``C = Σ c gᵀg`` over the modal coordinates.

    ``g`` is each joint's physical relative motion (as for springs), so a damper between a
    flexible parent and its child damps that motion, not the ERLS coordinate alone. Locked
    joints have none (their relative motion is zero). Beam damping (Rayleigh, modal) is the
    dynamics' own; this is the joints' part of the ``C`` every analysis adds.

    Args:
        model: The flexible model.
        Q: Joint coordinates, one pose (nv,) or many (n, nv), user convention.
        data: Workspace (default: this thread's).

    Returns:
        ``C`` (ndof, ndof) or (n, ndof, ndof) [N m s/rad, N s/m and the coupled units].
    """
    Q = check_q(model, Q)
    single = Q.ndim == 1
    Qb = Q[None] if single else Q
    n = Qb.shape[0]
    lay = model.plan.conditions
    out = np.zeros((n, model.ndof, model.ndof))
    if lay.dampers:
        terms = kinematics.pose_terms(model, Qb, data)
        alg = BatchAlgebra(n)
        twist = kinematics.root_twists(model, terms, alg)
        C = sum(c * _unit(model, terms, alg, twist, j) for j, c in lay.dampers)
        T = transform(model, terms, alg, twist)
        if T is not None:
            C = alg.mm(np.swapaxes(T, -1, -2), alg.mm(C, T))
        out = np.asarray(C)
    return out[0] if single else out


def relative_motion_rows(model, terms, alg, twist) -> np.ndarray:
    """Rows ``G`` (b, nv, nx + nv): physical relative joint motion ``r = G [x; q_all]``."""
    by_col = {j.user_col: j for j in model.plan.joints if j.user_col >= 0}
    ordered = [by_col[i] for i in range(model.nv)]
    gx = parent_rows(model, terms, alg, twist, ordered) if ordered else None
    C = alg.const(model.coord_map)
    if gx is None:
        return C[..., :0, :]
    return np.concatenate([-gx, C], axis=-1)


def joint_transform(model, q) -> np.ndarray:
    """``T`` (nx + nv, ndof): ``[x; q_all] = T [x; q_kept]`` at pose ``q``.

    The identity when no joint is locked; the rows of a locked joint give its coordinate
    as the parent attachment's elastic motion along the joint axis.

    Args:
        model: The flexible model.
        q: Joint coordinates (nv,) of one pose in the user convention [rad or m].

    Returns:
        ``T`` (nx + nv, ndof), dimensionless.

    Raises:
        ConfigurationError: Invalid ``q`` or more than one pose.
    """
    T = transform(model, *one_pose_twists(model, q, "joint_transform()"))
    return np.eye(model.ndof) if T is None else T[0]


def one_pose_twists(model, q, what: str) -> tuple:
    """``(terms, alg, twist)`` of one pose ``q`` (nv,), checked; ``what`` names the caller."""
    q = check_q(model, q)
    if q.ndim != 1:
        raise ConfigurationError(f"{what} takes one pose")
    terms = kinematics.pose_terms(model, q[None])
    alg = BatchAlgebra(1)
    return terms, alg, kinematics.root_twists(model, terms, alg)


def full_shapes(model, q, shapes: np.ndarray) -> np.ndarray:
    """Shapes over the modal coordinates (ndof, k) as ``[x; q_all]`` (nx + nv, k).

    Args:
        model: The flexible model.
        q: Joint coordinates (nv,) of the pose the shapes belong to [rad or m].
        shapes: Mode shapes (ndof, k) over the modal coordinates ``[x; q_kept]``.

    Returns:
        ``T shapes`` (nx + nv, k) (see :func:`joint_transform`); ``shapes`` itself when
        every joint is free.

    Raises:
        ConfigurationError: Invalid ``q`` (only checked when some joint is not free).
    """
    return shapes if model.plan.conditions.plain else joint_transform(model, q) @ shapes
