"""Terms of the ERLS equations of motion (paper 000 eq. 1) at a pose and velocity.

Generalized coordinates ``z = [x; q]`` (elastic coordinates of :class:`FlexibleModel`, then the
joint coordinates in the model's user convention). The equations are

    M(q) z̈ + C(q, q̇) ż + K z = F(q),

    M = [[Me, Me S], [Sᵀ Me, Sᵀ Me S]],   C = [[2 M_eG, Me Ṡ], [2 Sᵀ M_eG, Sᵀ Me Ṡ]],
    K = blkdiag(Ke, 0),                  F = [Me g + f; Sᵀ (Me g + f)]  (generalized),

written here as sums over *material points* instead of nodal blocks, which makes every term
exact for the consistent beam mass:

* every flexible link is sampled at 4 Gauss points per element (exact for the degree-6
  integrands of the cubic Hermite fields), each a point of mass ``ρA w le``; point masses are
  points; a rigid link's URDF inertia is replaced by 7 points (signed masses allowed) with the
  same mass, centre of mass and inertia tensor, so its kinetic energy is the same;
* point ``i`` on link ``L`` sits at ``c_i`` in the link frame and moves elastically by
  ``u_i = E_i(q) x`` (link axes), ``E_i = C_i + D_i e_L(q)``, where ``e_L`` is the elastic twist of
  the link root (the unique-ERLS copy of the parent attachment, rotated by the joint; constant
  ``C_i`` for the link's own nodes);
* its ERLS velocity in link axes is ``S_i q̇``, ``S_i = X(c_i) J_L`` with ``J_L`` Pinocchio's
  LOCAL frame Jacobian of the link and ``X(c) = [I, −[c]×]``;
* its acceleration (link axes) is taken as ``S_i q̈ + Ṡ_i q̇ + E_i ẍ + 2 G_i ẋ`` with the exact
  ERLS (classical) acceleration ``Ṡ_i q̇ = X J̇_L q̇ + ω × (S_i q̇)`` (``J̇_L`` from
  ``pin.computeJointJacobiansTimeVariation``) and the Coriolis term of the elastic motion in the
  rotating link frame ``G_i = Ė_i + [ω]× E_i`` (``Ė_i`` is the rate of the root copy when the
  child turns against its parent). This is eq. (1): ``Me = Σ m Eᵀ E``, ``Me S = Σ m Eᵀ S``,
  ``M_eG = Σ m Eᵀ G``.
* Terms of eq. (1)'s level of approximation are left out: products of the elastic
  displacement with the rigid accelerations or with two rigid velocities (``α × u``,
  ``ω × (ω × u)``, the shift of the child frames by the elastic joint offset), and any
  prestress (geometric stiffness) from inertial or gravity loads. They are of relative size
  ``|q̈| / ω₁²`` and ``|q̇|² / ω₁²`` (about 1e-5 on benchmark A).
* The torsional rotary inertia ``ρIp`` of spatial beams is a rotational carrier with angular
  acceleration ``J_ang q̈ + J̇_ang q̇ + E_r ẍ + (Ė_r + [ω]× E_r) ẋ`` and the Euler term
  ``ω × (I ω)``.

``M`` equals the assembly of :meth:`FlexibleModel.matrices` to round-off (tested).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from pinflex.checks import check_y
from pinflex.dynamics.carriers import Carriers, build_carriers
from pinflex.erls.design import design_model
from pinflex.erls.plan import attachment
from pinflex.erls.preload import MAX_GRAVITY, check_gravity  # noqa: F401 (re-exported)
from pinflex.erls.terms import joint_step, joint_step_rate
from pinflex.exceptions import ConfigurationError
from pinflex.linalg import rotate_twist, skew, translate_twist
from pinflex.validation import require_array



@dataclass(frozen=True)
class EomTerms:
    """Terms of eq. (1) at one state; see :mod:`pinflex.dynamics.terms`.

    Attributes:
        M: Mass matrix (ndof, ndof).
        C: Velocity matrix (ndof, ndof); the velocity forces are ``C @ ż``.
        K: Stiffness matrix (ndof, ndof) (``Ke`` on the elastic block).
        F: Generalized gravity force (ndof,) [N, N m] (zero without gravity).
    """

    M: np.ndarray
    C: np.ndarray
    K: np.ndarray
    F: np.ndarray


class ErlsDynamics:
    """Equations of motion of paper 000 eq. (1) for a :class:`~pinflex.FlexibleModel`.

    Args:
        model: The flexible model (its current point-mass values are the defaults). Locked
            joints (``joints='locked'`` or per joint) are constraints on the drive: a
            prescribed motion must hold their physical angle; the torque drive refuses them.
        y: Design values [kg] (default: the model's nominal values).
        gravity: Gravity acceleration in world axes [m/s²], (3,) (default zero, as in paper 000's
            benchmark).
    """

    def __init__(self, model, y=None, *, gravity=None):
        """Set up the carriers of ``model`` for design ``y`` (see the class docstring).

        Args:
            model: The :class:`~pinflex.FlexibleModel`.
            y: Design values (ny,) [kg], a ``{name: kg}`` dict, or None for the nominal ones.
            gravity: Gravity acceleration (3,) in world axes [m/s²], or None for zero.

        Raises:
            ConfigurationError: ``y`` is not one design vector, or ``gravity`` is not 3 finite
                numbers.
            DesignVariableNotFound: A dict key of ``y`` is not a design variable.
            DesignVariableOutOfBounds: A design value leaves its bounds.
        """
        y = check_y(model, y)
        if y.ndim != 1:
            raise ConfigurationError("ErlsDynamics takes one design vector (ny,)")
        #: the model at design ``y`` (sections, materials, springs and masses from ``y``)
        self.model = model = design_model(model, y)
        self.y = y
        self.gravity = np.zeros(3) if gravity is None else check_gravity(gravity)
        # eq. (1) is written over every coordinate [x; q_all]; a locked joint is a constraint
        # of the drive on its physical angle (see ``locked``), not a change of the terms
        self.nx, self.nv = model.nx, model.nv
        self.ndof = self.nx + self.nv
        self._pdata = model.model.createData()
        self._points, self._rotors = build_carriers(model, self.y)
        self._links = sorted({c.link for c in self._points} | {c.link for c in self._rotors},
                             key=model.plan.links.index)
        #: whether the joint offsets A(q) change with the pose (a joint on an element-0 point
        #: of a link whose root itself moves elastically)
        self.offsets_vary = any(
            j.attach.lin is not None and j.parent != model.plan.root and j.user_col >= 0
            for j in model.plan.joints)
        conds = getattr(model, "joint_conditions", ())
        #: joint drives ``(user column, armature, damping)`` on the physical relative motion
        #: ``r = G z`` (pinflex.erls.joints): ``M += a GᵀG``, the joints' ``C = Σ c GᵀG``
        self._drives = [(model.joint_index(c.name), float(getattr(c, "armature", 0.0) or 0.0),
                         float(getattr(c, "damping", 0.0) or 0.0)) for c in conds
                        if c.kind != "locked" and (getattr(c, "armature", 0.0)
                                                   or getattr(c, "damping", 0.0))]
        #: locked joints ``(name, user column)``: their physical angle is held constant (the
        #: prescribed drive checks that the trajectory holds them; the torque drive refuses)
        self.locked = tuple((c.name, model.joint_index(c.name)) for c in conds
                            if c.kind == "locked")
        #: joint springs ``(user column, stiffness)`` on the physical relative motion
        self._springs = [(model.joint_index(c.name), float(c.stiffness)) for c in conds
                         if c.kind == "spring"]
        self._K_const = np.zeros((self.ndof, self.ndof))

    # ------------------------------------------------------------------ kinematics
    def _kinematics(self, q: np.ndarray):
        """Link Jacobians, rotations, root twists, and rates per unit joint velocity."""
        model, pm, pd = self.model, self.model.model, self._pdata
        Cm = model.coord_map
        qp = model.pin_configuration(q)
        pin.computeJointJacobians(pm, pd, qp)
        pin.updateFramePlacements(pm, pd)
        J, R = {}, {}
        Jd = {link: np.zeros((self.nv, 6, self.nv)) for link in self._links}
        for link in self._links:
            fid = model.plan.frame_ids[link]
            J[link] = _jac(pin.getFrameJacobian(pm, pd, fid, pin.LOCAL), self.nv) @ Cm
            R[link] = pd.oMf[fid].rotation.copy()
        for k in range(self.nv):
            pin.computeJointJacobiansTimeVariation(pm, pd, qp, Cm[:, k].copy())
            for link in self._links:
                Jd[link][k] = _jac(pin.getFrameJacobianTimeVariation(
                    pm, pd, model.plan.frame_ids[link], pin.LOCAL), self.nv) @ Cm
        e, ed = self._root_twists(q)
        return J, Jd, R, e, ed

    def _root_twists(self, q: np.ndarray):
        """:func:`root_twists` at ``q`` with unit joint rates (the last pose is reused)."""
        key = np.asarray(q, dtype=float).tobytes()
        hit = getattr(self, "_rt_last", None)
        if hit is not None and hit[0] == key:
            return hit[1]
        Cm = self.model.coord_map
        out = root_twists(self.model, Cm @ np.asarray(q, dtype=float), Cm)
        self._rt_last = (key, out)
        return out

    def _maps(self, p: Carriers, J, Jd, e, ed):
        """``W = [E, S]``, and per unit joint velocity ``G_k`` and ``Ṡ_k`` of a carrier group."""
        JL = J[p.link]
        el, edl = e.get(p.link), ed.get(p.link)
        E = p.C if el is None else p.C + p.D @ el
        S = p.X @ JL
        wx = skew(JL[3:].T)  # (nv, 3, 3): [ω]× per unit joint velocity
        Gk = np.einsum("kab,nbx->knax", wx, E)
        if edl is not None and p.D is not None:
            Gk = Gk + np.einsum("nab,kbx->knax", p.D, edl)
        Sdk = np.einsum("nab,kbj->knaj", p.X, Jd[p.link]) + np.einsum("kab,nbj->knaj", wx, S)
        return np.concatenate([E, S], axis=-1), Gk, Sdk, S, wx

    def point_maps(self, q):
        """Per link: ``(W, Sdot_k)`` of the translational material points at a pose.

        ``W = [E, S]`` (n, 3, ndof); ``Sdot_k`` (nv, n, 3, nv) with ``Σ_k q̇_k Sdot_k q̇`` the
        ERLS acceleration at q̈ = 0. Used by the tests to check ``Ṡ`` against finite differences
        of the point positions along a motion.

        Args:
            q: Joint coordinates (nv,) in the user convention [rad or m]; not validated.

        Returns:
            ``{link: (W, Sdot_k, R, c)}`` for every link carrying translational material
            points, ``n`` the number of its points: ``W`` (n, 3, ndof) in link axes [m per
            unit coordinate], ``Sdot_k`` (nv, n, 3, nv), ``R`` (3, 3) the link rotation in the
            world frame and ``c`` (n, 3) the points' positions in the link frame [m].
        """
        J, Jd, R, e, ed = self._kinematics(np.asarray(q, dtype=float))
        out = {}
        for p in self._points:
            W, _, Sdk, _, _ = self._maps(p, J, Jd, e, ed)
            out[p.link] = (W, Sdk, R[p.link], p.c)
        return out

    # ------------------------------------------------------------------ terms
    def linear_terms(self, q):
        """``M(q)``, ``C_k(q)`` (nv, ndof, ndof), ``K(q)``, ``F(q)``; ``C(q, q̇) = Σ q̇_k C_k``.

        Over every coordinate ``[x; q_all]`` (``ndof = nx + nv``).

        Args:
            q: Joint coordinates (nv,) in the user convention [rad or m]; not validated.

        Returns:
            ``(M, Ck, K, F)``: mass matrix (ndof, ndof), velocity matrices per unit joint
            velocity (nv, ndof, ndof), stiffness matrix (ndof, ndof) (beams and joint springs)
            and generalized gravity force (ndof,) [N, N m].
        """
        q = np.asarray(q, dtype=float)
        self._q_last = q
        J, Jd, R, e, ed = self._kinematics(q)
        nd, nx, nv = self.ndof, self.nx, self.nv
        M = np.zeros((nd, nd))
        Ck = np.zeros((nv, nd, nd))
        F = np.zeros(nd)
        gworld = bool(np.any(self.gravity != 0.0))
        for p in self._points:
            W, Gk, Sdk, _, _ = self._maps(p, J, Jd, e, ed)
            n3 = 3 * p.mass.size
            W2 = W.reshape(n3, nd)
            mWt = (np.repeat(p.mass, 3)[:, None] * W2).T
            M += mWt @ W2
            Ck[:, :, :nx] += 2.0 * (mWt @ Gk.reshape(nv, n3, nx))
            Ck[:, :, nx:] += mWt @ Sdk.reshape(nv, n3, nv)
            if gworld:
                F += mWt @ np.tile(R[p.link].T @ self.gravity, p.mass.size)
        for p in self._rotors:
            # rotational carriers (X = [0, I]): torque I Ω̇ + ω × (I ω), Ω̇ = J_ang q̈ + J̇_ang q̇
            # + E_r ẍ + (Ė_r + [ω]× E_r) ẋ; Sdk holds J̇_ang + [ω]× J_ang
            W, Gk, Sdk, S, wx = self._maps(p, J, Jd, e, ed)
            n3 = 3 * p.mass.shape[0]
            IWt = np.einsum("nab,nbi->ina", p.mass, W).reshape(nd, n3)
            Jdang = Sdk - np.einsum("kab,nbj->knaj", wx, S)
            gyro = np.einsum("kab,nbc,ncj->knaj", wx, p.mass, S).reshape(nv, n3, nv)
            M += IWt @ W.reshape(n3, nd)
            Ck[:, :, :nx] += IWt @ Gk.reshape(nv, n3, nx)
            Ck[:, :, nx:] += IWt @ Jdang.reshape(nv, n3, nv) + W.reshape(n3, nd).T @ gyro
        if any(a for _, a, _ in self._drives):
            G = self.model.relative_motion_rows(q)
            for col, a, _ in self._drives:
                M += a * np.outer(G[col], G[col])
        return M, Ck, self._stiffness(e), F

    def joint_damping(self, q) -> np.ndarray:
        """The joint dampers' damping matrix ``Σ c GᵀG`` (ndof, ndof) at ``q`` [N m s/rad].

        ``G`` is the joints' physical relative motion over ``[x; q_all]``
        (:meth:`pinflex.FlexibleModel.relative_motion_rows`), so a damper between a flexible
        parent and its child damps that motion; zero on the motors-held (locked) motions.
        """
        C = np.zeros((self.ndof, self.ndof))
        if any(c for _, _, c in self._drives):
            G = self.model.relative_motion_rows(np.asarray(q, dtype=float))
            for col, _, c in self._drives:
                C += c * np.outer(G[col], G[col])
        return C

    def terms(self, q, qd) -> EomTerms:
        """``M, C, K, F`` of eq. (1) at joint coordinates ``q`` and velocities ``q̇`` (user).

        Args:
            q: Joint coordinates (nv,) in the user convention [rad or m]; not validated.
            qd: Joint velocities (nv,) [rad/s or m/s].

        Returns:
            :class:`EomTerms` with ``M``, ``C = Σ q̇_k C_k``, ``K`` (ndof, ndof) and ``F``
            (ndof,).
        """
        M, Ck, K, F = self.linear_terms(q)
        C = np.tensordot(np.asarray(qd, dtype=float), Ck, axes=(0, 0))
        return EomTerms(M=M, C=C, K=K, F=F)

    def _stiffness(self, e) -> np.ndarray:
        """``K(q) = Σ bxᵀ Ke bx`` with ``bx = sel + root e_L(q)`` (the root copy turns with q)."""
        K = self._K_const.copy()
        if self._springs:
            G = self.model.relative_motion_rows(self._q_last)
            for col, k in self._springs:
                K += k * np.outer(G[col], G[col])
        for link, bp in self.model.plan.beams.items():
            sel, root, _, _, stiffness = bp.kept
            el = e.get(link)
            bx = sel if el is None else sel + root @ el
            K[: self.nx, : self.nx] += bx.T @ stiffness @ bx
        return K

    def joint_offsets(self, q):
        """``A`` (nv, nx) and its rates ``Ȧ_k`` (nv, nv, nx) per unit joint velocity.

        ``A x`` is the elastic offset of the ERLS joint coordinates (user convention) against
        the physical joint motion: a motor turns its joint by ``q_pin,j − aᵀθ_parent`` (the
        joint-axis component of the parent attachment's elastic rotation, or translation for a
        prismatic joint), so ``q_user = C⁻¹ (q_pin,phys + A_pin x)`` and ``A = C⁻¹ A_pin``.

        Args:
            q: Joint coordinates (nv,) in the user convention [rad or m]; not validated.

        Returns:
            ``(A, Adot)``: ``A`` (nv, nx) and ``Adot`` (nv, nv, nx), ``Adot[k]`` the rate of
            ``A`` per unit velocity of joint ``k``.
        """
        model = self.model
        Cm = model.coord_map
        q = np.asarray(q, dtype=float)
        e, ed = self._root_twists(q)
        nv, nx = self.nv, self.nx
        Ap = np.zeros((nv, nx))
        Adp = np.zeros((nv, nv, nx))
        for j in model.plan.joints:
            if j.user_col < 0 or not j.motion.moves:
                continue
            att = j.attach
            ep, edp = e[j.parent], ed[j.parent]
            tau = att.const if (ep is None or att.lin is None) else (
                att.lin @ ep if att.const is None else att.const + att.lin @ ep)
            if tau is None:
                continue
            rows = j.motion.rows  # rotation (revolute) or translation (prismatic)
            a = j.R_o @ j.axis  # joint axis in parent axes (invariant under the joint)
            Ap[j.user_col] = a @ tau[rows]
            if edp is not None and att.lin is not None:
                Adp[:, j.user_col] = np.einsum("a,kax->kx", a, (att.lin @ edp)[:, rows])
        Ci = np.linalg.inv(Cm)
        return Ci @ Ap, np.einsum("ij,kjx->kix", Ci, Adp)

    # ------------------------------------------------------------------ outputs
    def frame_map(self, link: str, xyz=(0.0, 0.0, 0.0)):
        """``(T, S)`` of a point on a link: elastic twist ``T(q) x`` and ERLS twist ``S(q) q̇``.

        Returns a function of ``q`` giving ``(Tw, Sw)``, each with rows (translation, rotation)
        in WORLD axes: ``Tw`` (6, nx), ``Sw`` (6, nv).

        Args:
            link: Name of the link carrying the point.
            xyz: Position (3,) of the point in the link frame [m] (default: the link origin).

        Returns:
            ``at(q)``: a function of joint coordinates (nv,) [rad or m] returning
            ``(Tw, Sw)``, translation rows [m per unit coordinate], rotation rows [rad per
            unit coordinate].

        Raises:
            LinkNotFound: ``link`` is not a link of the description.
        """
        model = self.model
        model.description.require_link(link)
        xyz = np.asarray(xyz, dtype=float)
        att = attachment(model.plan.beams, link, xyz)
        pm, pd = model.model, model.model.createData()
        fid = model.plan.frame_ids[link]
        Xp = translate_twist(xyz)

        def at(q):
            q = np.asarray(q, dtype=float)
            pin.computeJointJacobians(pm, pd, model.pin_configuration(q))
            pin.updateFramePlacements(pm, pd)
            Rw = rotate_twist(pd.oMf[fid].rotation)
            JL = _jac(pin.getFrameJacobian(pm, pd, fid, pin.LOCAL), model.nv) @ model.coord_map
            el = self._root_twists(q)[0].get(link)
            T = np.zeros((6, model.nx)) if att.const is None else att.const.copy()
            if att.lin is not None and el is not None:
                T = T + att.lin @ el
            return Rw @ T, Rw @ (Xp @ JL)

        return at



def root_twists(model, qrel: np.ndarray, vrel: np.ndarray):
    """Elastic twists of the link roots ``e_L`` (6, nx) in link axes and their rates.

    Follows the unique-ERLS rule of the assembly
    (:func:`pinflex.erls.kinematics.root_twists`) at one pose:
    a child root copies its parent attachment's elastic twist rotated into the child axes,
    minus the joint's motion subspace. The rates ``ė_L`` (k, 6, nx) come from the joints
    turning (or sliding) with the Pinocchio velocities in the columns of ``vrel`` (nv, k).
    ``None`` where a root has no elastic motion.
    """
    tw: dict = {model.plan.root: None}
    rate: dict = {model.plan.root: None}
    vrel = np.asarray(vrel, dtype=float).reshape(model.nv, -1)
    nk = vrel.shape[1]
    for j in model.plan.joints:
        att = j.attach
        ep, edp = tw[j.parent], rate[j.parent]
        if ep is None or att.lin is None:
            tau = att.const
            taud = None
        else:
            tau = att.lin @ ep if att.const is None else att.const + att.lin @ ep
            taud = None if edp is None else att.lin @ edp
        if tau is None:
            tw[j.child] = rate[j.child] = None
            continue
        # the one unique-ERLS rule of the assembly (erls.terms.joint_step) and its rate
        rot = j.motion.rotation(j, qrel)
        step = joint_step(j, rot, j.motion.slide(j, qrel))
        dstep = joint_step_rate(j, rot, vrel[j.user_col] if j.user_col >= 0 else np.zeros(nk))
        tw[j.child] = step @ tau
        childd = np.zeros((nk,) + tau.shape) if dstep is None else dstep @ tau
        rate[j.child] = childd if taud is None else childd + step @ taud
    return tw, rate



def _jac(J, nv: int) -> np.ndarray:
    """A Pinocchio frame Jacobian as (6, nv): for one joint Pinocchio returns a (6,) vector."""
    return np.asarray(J).reshape(6, nv)


