"""ERLS (equivalent rigid-link system) model of a flexible-link arm on Pinocchio.

Generalized coordinates are ``[x; q]``: ``x`` the independent elastic nodal coordinates of
all flexible links, ``q`` the ERLS joint coordinates (one value per moving joint, in the
model's user convention, see :class:`FlexibleModel`). With ``q̇ = 0`` the modal problem is
``K(q, y) φ = λ M(q, y) φ`` with ``K = blkdiag(Kₓₓ, 0)``.

Formulation (equivalent to the world-axes form of paper 000 eq. 1 by an orthogonal change of
elastic coordinates at each pose, hence the same eigenvalues):

* The elastic dofs of a beam node are a small translation and rotation in the *beam* axes of
  its link. Nodes 1..N of every flexible link are independent. Node 0 (the root, at the link
  origin) copies the elastic motion of the point it is attached to on the parent link, rotated
  into the child frame by the joint, **minus the joint's motion subspace** (a revolute joint's
  rotation about its axis, a prismatic joint's translation along it): this is the unique-ERLS
  rule. The root link of the URDF is clamped to the ground.
* A point on a flexible link moves with the beam's shape functions at its axial station plus a
  rigid offset; a rigid link moves rigidly with the elastic motion of its root. A prismatic
  joint's guide is attached at the joint origin.
* The ERLS velocity of each node is Pinocchio's LOCAL frame Jacobian of the link, moved to the
  node: ``S``. Kinetic energy uses the consistent beam mass, the URDF inertia of rigid links and
  the point masses; strain energy the beam stiffness.

Non-rigid eigenvalues are computed from the reduced problem
``Kₓₓ φₓ = λ (Mₓₓ − Mₓq Mqq⁻¹ Mqx) φₓ``, which has exactly the non-zero eigenvalues of the full
pair and no spurious near-zero ones; the ``nv`` rigid modes are counted, not computed.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import replace
from pathlib import Path
from types import MappingProxyType

import numpy as np
import pinocchio as pin

from pinflex.checks import check_n_modes, check_q, check_y
from pinflex.description import RobotDescription, load
from pinflex.description.crosscheck import (
    check_pinocchio_reading,
    native_stderr,
    urdfdom_message,
)
from pinflex.erls import design as design_channels
from pinflex.erls import joints as joint_conditions
from pinflex.erls import kinematics, modal
from pinflex.erls.assembly import matrices_from_terms
from pinflex.erls.kinematics import NodePlacement
from pinflex.erls.plan import build_plan, coordinate_map
from pinflex.erls.preload import Preload, make_preload
from pinflex.erls.terms import (
    DesignVariable,
    ModelPlan,
)
from pinflex.erls.workspace import FlexibleData, ThreadWorkspaces, check_data
from pinflex.exceptions import (
    ConfigurationError,
    DesignVariableNotFound,
    DesignVariableOutOfBounds,
    ImmutableModelError,
    InvalidDescription,
)
from pinflex.linalg import skew
from pinflex.resources import check_modal, check_model_size
from pinflex.validation import require_array


def _read_only(a: np.ndarray) -> np.ndarray:
    a = np.array(a)
    a.setflags(write=False)
    return a


def _checked_mass(description: RobotDescription, design: tuple, name: str, value) -> float:
    """A point mass's new value [kg], checked (one finite number, within bounds, >= 0)."""
    arr = require_array(value, f"the value of '{name}'")
    if isinstance(value, bool) or arr.shape != ():
        raise ConfigurationError(f"the value of '{name}' must be one number [kg]")
    v = float(arr)
    for d in design:
        if d.name == name and not d.lower <= v <= d.upper:
            raise DesignVariableOutOfBounds(name, v, d.lower, d.upper)
    if v < 0.0:
        raise DesignVariableOutOfBounds(name, v, 0.0, np.inf)
    return v


def _rodrigues_constants(model) -> tuple:
    """Constants of :func:`pinflex.erls.kinematics.pose_terms`.

    The revolute joints' names, user columns and ``R_o``, ``R_o K``, ``R_o K^2`` (K the axis'
    cross-product matrix) stacked (nj, 3, 3), and whether the coordinate map is the identity.
    """
    rev = [j for j in model.plan.joints if j.motion.rotates]
    K = [skew(j.axis) for j in rev]
    A0 = np.array([j.R_o for j in rev]).reshape(-1, 3, 3)
    A1 = np.array([j.R_o @ k for j, k in zip(rev, K)]).reshape(-1, 3, 3)
    A2 = np.array([j.R_o @ k @ k for j, k in zip(rev, K)]).reshape(-1, 3, 3)
    for a in (A0, A1, A2):
        a.setflags(write=False)
    plain = bool(np.array_equal(model.coord_map, np.eye(model.nv)))
    return (tuple(j.name for j in rev), _read_only(np.array([j.user_col for j in rev], dtype=int)),
            A0, A1, A2, plain)


def _pin_order(pmodel) -> np.ndarray | None:
    """``idx_v`` per configuration slot when it is not the identity (nq = nv), else None."""
    order = np.zeros(pmodel.nq, dtype=int)
    for j in range(1, pmodel.njoints):
        jm = pmodel.joints[j]
        order[jm.idx_q : jm.idx_q + jm.nq] = np.arange(jm.idx_v, jm.idx_v + jm.nv)
    return None if np.array_equal(order, np.arange(order.size)) else _read_only(order)


def _placement_constants(plan: ModelPlan) -> tuple:
    """Per beam: its link, nodes with a column of ones (N+1, 4) and the beam axes (3, 3)."""
    rows = []
    for link, bp in plan.beams.items():
        nodes_h = _read_only(np.hstack([bp.nodes, np.ones((bp.nodes.shape[0], 1))]))
        rows.append((link, nodes_h, bp.spec.rotation))
    return tuple(rows)


#: The public surface of :class:`FlexibleModel`, all of it (tests/test_api_surface.py):
#: the model's data (as ``pinocchio.Model``'s attributes), construction and the queries the
#: documentation describes. What pinflex's own layers run on a model lives, as Pinocchio's
#: algorithms, in free functions of the module that owns it: :mod:`pinflex.checks`
#: (``check_q``, ``check_y``, ``check_n_modes``), :mod:`pinflex.erls.kinematics`
#: (``pose_terms``, ``pose_terms_one``, ``pose_terms_and_placements``, ``root_twists``),
#: :mod:`pinflex.erls.assembly` (``assemble``, ``matrices_from_terms``) and
#: :mod:`pinflex.erls.joints` (``full_shapes``).
PUBLIC = (
    "model", "description", "plan", "nv", "nx", "ny", "ndof", "n_elastic", "n_rigid", "planar",
    "plane_normal", "coordinates", "coord_map", "joint_names", "joint_index", "x_names",
    "joint_conditions", "joint_switch", "joint_labels", "kept_joints", "design", "design_names",
    "y0", "point_mass_values", "frequencies", "modes", "matrices", "joint_damping",
    "relative_motion_rows", "joint_transform", "eigvals_from", "node_placements",
    "effective_inertias", "effective_model", "pin_configuration", "from_configuration",
    "from_pinocchio", "with_values", "create_data", "workspace",
)

#: Former methods of :class:`FlexibleModel` and where they live now (named in the
#: AttributeError an old call raises).
MOVED = {
    "check_q": "pinflex.checks.check_q(model, q)",
    "check_y": "pinflex.checks.check_y(model, y, bounds=...)",
    "check_n_modes": "pinflex.checks.check_n_modes(model, n_modes)",
    "pose_terms": "pinflex.erls.kinematics.pose_terms(model, Q, data)",
    "pose_terms_one": "pinflex.erls.kinematics.pose_terms_one(model, q, data)",
    "pose_terms_and_placements":
        "pinflex.erls.kinematics.pose_terms_and_placements(model, q, data)",
    "root_twists": "pinflex.erls.kinematics.root_twists(model, terms, alg)",
    "assemble": "pinflex.erls.assembly.assemble(model, terms, alg)",
    "matrices_from_terms": "pinflex.erls.assembly.matrices_from_terms(model, terms, y, n)",
    "full_shapes": "pinflex.erls.joints.full_shapes(model, q, shapes)",
    "pin_q": "model.coord_map @ q",
    "design_channels": "model.plan.design.channels",
    "design_links": "model.plan.design.links",
    "set_value": "model = model.with_values(name=value)",
}


class FlexibleModel:
    """A URDF arm whose annotated links are finite-element beams (ERLS).

    Joint coordinates given by users are one value per moving joint in Pinocchio's velocity
    order (``joint_names``). By default they are Pinocchio's own (relative) joint values; a
    description with ``<pinflex:coordinates convention="absolute"/>`` uses absolute link
    angles ``q_abs`` of a planar serial arm instead, with ``q_rel = C q_abs`` (``C`` has ones on
    the diagonal and minus ones below it). A Pinocchio configuration vector (length ``nq``,
    continuous joints as cos/sin) is accepted wherever joint values are, see
    :meth:`from_configuration`. Models in memory: :meth:`from_pinocchio`,
    :func:`pinflex.example_robot`.

    ``self.model`` is Pinocchio's model of the URDF: it keeps the URDF inertias of every link,
    also of the links that the modal model replaces by beams (UR5 upper arm: 8.39 kg there,
    1.53 kg for the tube of ``urdf/ur5_flexible.xml``); :meth:`effective_inertias` and
    :meth:`effective_model` give what the modal model uses.

    Args:
        description: A parsed description or the path of an annotated URDF.
        planar: Keep only in-plane elastic dofs (all revolute axes parallel to one normal,
            beams normal to it).
        values: Values of parameters and point masses ``{name: value}`` (checked against
            their bounds); unknown names raise :class:`DesignVariableNotFound`.
        coordinates: 'relative' or 'absolute' to override the description's convention.
        joints: Joint conditions: by default (None or 'annotated') the file's
            ``<pinflex:joint>`` springs and locks, other joints free (a file without them,
            as paper 000's benchmark, has every joint free); 'free' (no joint stiffness, one
            rigid mode per joint) or 'locked' (every joint held rigidly) override them, as
            does a mapping ``{joint: 'free' | 'locked' | stiffness}``. See
            :mod:`pinflex.erls.joints`: matrices are over the modal coordinates
            ``[x; q_kept]`` (locked joints' coordinates eliminated) and ``n_rigid`` counts the
            free joints.

    The model is constant once built (as ``pinocchio.Model``): attributes cannot be set and its
    arrays are read-only. Other values give another model, :meth:`with_values`. What a
    computation writes lives in a workspace (:class:`~pinflex.erls.workspace.FlexibleData`, as
    ``pinocchio.Data``): every computing method takes ``data=None``, by default the calling
    thread's own workspace (:meth:`workspace`), so threads may share one model.
    """

    def __init__(
        self,
        description: RobotDescription | str | Path,
        *,
        planar: bool = False,
        values: dict[str, float] | None = None,
        coordinates: str | None = None,
        joints=None,
        _reuse: FlexibleModel | None = None,
    ):
        """Build the ERLS model of a description (arguments as in the class docstring).

        Args:
            description: A :class:`RobotDescription` or the path of an annotated URDF.
            planar: Keep only in-plane elastic dofs (a bool).
            values: ``{name: value}`` of parameters [their units] and point masses [kg].
            coordinates: ``'relative'``, ``'absolute'`` or None (the description's choice).
            joints: Joint conditions: None or ``'annotated'`` (the file's), ``'free'``,
                ``'locked'`` or ``{joint: 'free' | 'locked' | stiffness}``.
            _reuse: A model of the same description and options whose Pinocchio model and
                plan this one shares (internal, :meth:`with_values`).

        Raises:
            DesignVariableNotFound: A name in ``values`` is neither a parameter nor a point
                mass.
            DesignVariableOutOfBounds: A value in ``values`` leaves its bounds.
            ConfigurationError: ``planar`` is not a bool, or ``coordinates`` is unknown.
            InvalidDescription: Pinocchio cannot load the URDF, or a joint has more than one
                degree of freedom.
        """
        if not isinstance(description, RobotDescription):
            description = load(description)
        values = dict(values or {})
        known = set(description.parameters) | {p.name for p in description.point_masses}
        for name in values:
            if name not in known:
                raise DesignVariableNotFound(name, sorted(known))
        params = {k: v for k, v in values.items() if k in description.parameters}
        if params:
            description = description.with_values(params)
            _reuse = None
        self.description = description
        if not isinstance(planar, bool | np.bool_):
            raise ConfigurationError(f"planar must be True or False, got {planar!r}")
        self.planar = bool(planar)
        #: Pinocchio's model of the URDF (constant; shared by models of the same URDF).
        self.model: pin.Model
        if _reuse is not None:
            self.model = _reuse.model  # the same URDF: Pinocchio's model is shared, unchanged
        else:
            native: list[str] = []
            try:
                with native_stderr() as native:  # urdfdom's messages go into the error
                    self.model = pin.buildModelFromXML(description.urdf_xml)
            except Exception as exc:  # Pinocchio raises plain RuntimeError/ValueError
                said = urdfdom_message(native)
                raise InvalidDescription(f"Pinocchio could not load the URDF: {exc}"
                                         + (f" (urdfdom: {said})" if said else "")) from None
            check_pinocchio_reading(description, self.model, native)
        self.joint_names = tuple(self.model.names[1:])
        self.nv = self.model.nv
        if self.nv != len(self.joint_names):
            raise InvalidDescription("only joints with one degree of freedom are supported")
        if coordinates is not None and not isinstance(coordinates, str):
            raise ConfigurationError(f"coordinates={coordinates!r}: expected 'relative' or "
                                     "'absolute'")
        absolute = description.absolute_coordinates if coordinates is None else (
            coordinates == "absolute"
        )
        if coordinates not in (None, "relative", "absolute"):
            raise ConfigurationError(
                f"coordinates='{coordinates}': expected 'relative' or 'absolute'"
            )
        self.coordinates = "absolute" if absolute else "relative"
        self.coord_map = _read_only(coordinate_map(self, absolute))
        pm_values = {p.name: p.mass for p in description.point_masses}
        design = tuple(
            DesignVariable(p.name, p.lower, p.upper, p.mass)
            for p in description.point_masses
            if p.design
        ) + tuple(
            DesignVariable(p.name, p.lower, p.upper, p.value, "parameter", p.unit)
            for p in description.parameters.values()
            if p.design
        )
        masses = {}
        for name, value in values.items():
            if name not in params:
                masses[name] = value = _checked_mass(description, design, name, value)
                pm_values[name] = value
                design = tuple(DesignVariable(name, d.lower, d.upper, value)
                               if d.name == name else d for d in design)
        self.design = design
        self._pm_values = MappingProxyType(pm_values)
        self._masses_set = MappingProxyType(masses)
        self._joints_arg = MappingProxyType(dict(joints)) if isinstance(joints, Mapping) else (
            joints)
        if _reuse is not None:
            plan = _reuse.plan
        else:
            check_model_size([f.elements for f in description.flexible.values()], self.nv,
                             self.planar, f"the model of robot '{description.name}'")
            plan = build_plan(self)
            conditions = joint_conditions.layout(self, plan, joints)
            plan = replace(plan, conditions=conditions,
                           design=design_channels.layout(self, plan, conditions))
        #: The fixed, read-only layout (links, beams, joints, carriers, joint conditions and
        #: design channels; see ModelPlan).
        self.plan: ModelPlan = plan
        self.nx = plan.nx
        self.ndof = plan.conditions.ndof
        self.x_names = plan.x_names
        self._mass_design_index = plan.design.mass_index
        # constants of the kinematics passes (computed here: the model never changes)
        self._rodrigues = _rodrigues_constants(self)
        self._revolute_ids = tuple((name, self.model.getJointId(name))
                                   for name in self._rodrigues[0])
        self._pin_order = _pin_order(self.model)
        self._placement_constants = _placement_constants(plan)
        self._workspaces = ThreadWorkspaces()
        check_modal(self.ndof, 1, f"the model of robot '{description.name}'")
        self.__dict__["_built"] = True

    def __setattr__(self, name: str, value) -> None:
        """Refused once the model is built: other values give another model."""
        if self.__dict__.get("_built"):
            raise ImmutableModelError(
                f"FlexibleModel is constant once built: cannot set '{name}'; build another "
                "model, e.g. model.with_values(NAME=VALUE) for new parameter or mass values"
            )
        object.__setattr__(self, name, value)

    def __delattr__(self, name: str) -> None:
        """Refused: the model is constant."""
        raise ImmutableModelError(f"FlexibleModel is constant once built: cannot delete '{name}'")

    def __getattr__(self, name: str):
        """Only reached for a missing attribute: name where a former method lives now."""
        if name == "set_value":  # ImmutableModelError is an AttributeError
            raise ImmutableModelError(f"FlexibleModel is constant once built: set_value is gone; "
                                      f"use {MOVED[name]}, which returns a new model")
        if name in MOVED:
            raise AttributeError(f"FlexibleModel has no attribute '{name}': use {MOVED[name]}",
                                 name=name, obj=self)
        raise AttributeError(f"'FlexibleModel' object has no attribute '{name}'", name=name,
                             obj=self)

    def __repr__(self) -> str:
        """Robot, dof, flexible links, joint conditions and design, in a few lines."""
        from pinflex.summaries import model_summary

        return model_summary(self)

    def __getstate__(self) -> dict:
        """State for pickling (the per-thread workspaces stay behind)."""
        state = dict(self.__dict__)
        del state["_workspaces"]
        return state

    def __setstate__(self, state: dict) -> None:
        """Restore a pickled model, with fresh per-thread workspaces."""
        self.__dict__.update(state)
        self.__dict__["_workspaces"] = ThreadWorkspaces()

    # ------------------------------------------------------------------ values and workspaces
    def with_values(self, values: Mapping[str, float] | None = None, /,
                    **kwargs: float) -> FlexibleModel:
        """A new model with some parameter or point-mass values changed; this one is unchanged.

        Values given before (``values=`` when this model was built, or an earlier
        ``with_values``) are kept unless overridden. When only point masses change, the new
        model shares this one's Pinocchio model and plan (both constant).

        Args:
            values: ``{name: value}`` of parameters [their units] and point masses [kg].
            **kwargs: The same as keywords, ``model.with_values(tip=1.0)``.

        Returns:
            A new :class:`FlexibleModel` (its own workspaces).

        Raises:
            DesignVariableNotFound: A name is neither a parameter nor a point mass.
            DesignVariableOutOfBounds: A value leaves its bounds (or a mass is negative).
            ConfigurationError: A value is not one finite number.
        """
        new = {**dict(values or {}), **kwargs}
        known = set(self.description.parameters) | set(self._pm_values)
        for name in new:
            if name not in known:
                raise DesignVariableNotFound(name, sorted(known))
        params = {k: v for k, v in new.items() if k in self.description.parameters}
        masses = {**self._masses_set, **{k: v for k, v in new.items() if k not in params}}
        description = self.description.with_values(params) if params else self.description
        return FlexibleModel(description, planar=self.planar, values=masses,
                             coordinates=self.coordinates, joints=self._joints_arg,
                             _reuse=None if params else self)

    def create_data(self) -> FlexibleData:
        """A new workspace of this model (for ``data=``), as ``pinocchio.Model.createData``."""
        return FlexibleData(self)

    def workspace(self, data: FlexibleData | None = None) -> FlexibleData:
        """``data`` checked, or the calling thread's own workspace of this model.

        Args:
            data: A workspace from :meth:`create_data`, or None.

        Returns:
            ``data``, or this thread's default workspace (created on first use).

        Raises:
            ConfigurationError: ``data`` belongs to another model.
        """
        if data is None:
            return self._workspaces.get(self)
        return check_data(self, data)

    @classmethod
    def from_pinocchio(
        cls,
        model_or_robot,
        flexible: dict | None = None,
        masses: dict | None = None,
        joints=None,
        **kwargs,
    ) -> FlexibleModel:
        """A flexible model of a Pinocchio ``Model`` or ``RobotWrapper`` kept in memory.

        The model's tree and inertias are written out as URDF (see
        :func:`pinflex.native.urdf.urdf_from_model`) and annotated from the Python
        specifications, so the result equals the overlay route on the same arm to round-off.

        Args:
            model_or_robot: A fixed-base ``pinocchio.Model`` or ``RobotWrapper`` with revolute,
                continuous or prismatic joints.
            flexible: ``{link or joint name: pinflex.Beam}``; a joint name stands for the link
                it carries.
            masses: ``{name: pinflex.Mass}`` point masses [kg, m].
            joints: Joint conditions of the modal model, as for the constructor
                (``"free"``, ``"locked"``, ``"annotated"`` or ``{joint: ...}``); by default
                the annotations, and Python specifications carry none: every joint free.
            **kwargs: ``planar``, ``values``, ``coordinates`` as for the constructor.

        Example::

            arm = FlexibleModel.from_pinocchio(robot, flexible={"upper_arm_link": Beam(...)})
        """
        from pinflex.native.robots import describe_pinocchio

        return cls(describe_pinocchio(model_or_robot, flexible, masses), joints=joints, **kwargs)

    def effective_inertias(self) -> dict:
        """Rigid-body inertia of every flexible link as the modal model sees it.

        ``self.model`` (the Pinocchio model) keeps the URDF inertias of all links, also of the
        links the modal model replaces by beams; this gives the beams' own inertias instead.

        Returns:
            ``{link: pinocchio.Inertia}`` at the link frame origin in link axes [kg, m, kg m²].
        """
        from pinflex.erls.effective import effective_inertias

        return effective_inertias(self)

    def effective_model(self, y=None, *, point_masses: bool = True):
        """Copy of ``self.model`` whose flexible links carry their beams' inertias.

        Use it for rigid-body dynamics consistent with the modal model: ``pin.crba`` of it
        equals the rigid block ``M[nx:, nx:]`` of :meth:`matrices` (relative coordinates).

        Args:
            y: Design values [kg] of design point masses (default: nominal).
            point_masses: Add the point masses to the links carrying them.
        """
        from pinflex.erls.effective import effective_model

        return effective_model(self, y, point_masses=point_masses)

    @property
    def point_mass_values(self) -> Mapping[str, float]:
        """Current values of every point mass ``{name: kg}`` (read-only view)."""
        return MappingProxyType(self._pm_values)

    @property
    def plane_normal(self) -> np.ndarray | None:
        """World normal (3,) of the plane of a planar model, None otherwise."""
        return self.plan.plane_normal

    def node_placements(self, q, *, data: FlexibleData | None = None
                        ) -> dict[str, NodePlacement]:
        """World placement of every beam's nodes at one pose.

        Args:
            q: Joint coordinates (nv,) in the user convention [rad or m].
            data: Workspace (default: this thread's).

        Returns:
            ``{link: NodePlacement}`` for every flexible link, in plan order: node positions
            (N+1, 3) [m] and the rotation (3, 3) of the beam axes, both in the world frame.
        """
        q = check_q(self, q)
        pdata = self.workspace(data).pin
        pin.framesForwardKinematics(self.model, pdata, self.pin_configuration(q))
        return kinematics.placements(self, pdata)

    @property
    def design_names(self) -> tuple[str, ...]:
        """Names of the design variables in order."""
        return tuple(d.name for d in self.design)

    @property
    def y0(self) -> np.ndarray:
        """Nominal design values [kg], (ny,)."""
        return np.array([d.nominal for d in self.design])

    @property
    def ny(self) -> int:
        """Number of design variables."""
        return len(self.design)

    def from_configuration(self, qpin) -> np.ndarray:
        """User coordinates (nv,) or (n, nv) of Pinocchio configuration vectors (nq,) or (n, nq).

        A continuous joint's ``(cos θ, sin θ)`` pair becomes ``θ = atan2(sin θ, cos θ)`` in
        (-π, π]; other joints copy their value. The relative joint values are then mapped to
        the model's user convention (``q_user = C⁻¹ q_rel``, the identity for relative
        coordinates). Inverse of :meth:`pin_configuration` up to multiples of 2π.

        Args:
            qpin: Pinocchio configuration vectors, (nq,) or (n, nq) [rad, m, or cos/sin].

        Returns:
            User coordinates (nv,) or (n, nv) [rad or m].

        Raises:
            ConfigurationError: Wrong length, non-finite values, or a (cos, sin) pair whose
                norm is not 1 (to 1e-6).
        """
        qpin = require_array(qpin, "Pinocchio configuration")
        if qpin.shape[-1:] != (self.model.nq,) or qpin.ndim not in (1, 2):
            raise ConfigurationError(
                f"expected Pinocchio configurations of length nq = {self.model.nq}, got shape "
                f"{qpin.shape}"
            )
        if not np.all(np.isfinite(qpin)):
            raise ConfigurationError("joint values must be finite")
        qrel = np.zeros(qpin.shape[:-1] + (self.nv,))
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            if jm.nq == 2:
                c, s = qpin[..., jm.idx_q], qpin[..., jm.idx_q + 1]
                if np.any(np.abs(np.hypot(c, s) - 1.0) > 1e-6):
                    raise ConfigurationError(
                        f"continuous joint '{self.model.names[j]}': (cos, sin) = "
                        f"({np.ravel(c)[0]!r}, {np.ravel(s)[0]!r}) is not a unit vector"
                    )
                qrel[..., jm.idx_v] = np.arctan2(s, c)
            else:
                qrel[..., jm.idx_v] = qpin[..., jm.idx_q]
        return np.linalg.solve(self.coord_map, qrel[..., None])[..., 0]

    def joint_index(self, name: str) -> int:
        """Index of a moving joint in the coordinate vector.

        Args:
            name: Name of a moving joint (one of :attr:`joint_names`).

        Returns:
            Its column in the user coordinates (nv,), Pinocchio's velocity order.

        Raises:
            JointNotFound: No moving joint has this name.
        """
        if name not in self.joint_names:
            from pinflex.exceptions import JointNotFound

            raise JointNotFound(name, self.joint_names)
        return self.joint_names.index(name)

    def pin_configuration(self, q: np.ndarray) -> np.ndarray:
        """Pinocchio configuration vector (nq,) of user coordinates.

        Args:
            q: User coordinates (nv,) of one pose [rad or m]; not validated.

        Returns:
            Configuration (nq,) in Pinocchio's order, continuous joints as ``(cos θ, sin θ)``.
        """
        return self._configuration_of(self.coord_map @ np.asarray(q, dtype=float))

    def _configuration_of(self, qv: np.ndarray) -> np.ndarray:
        """Pinocchio configuration vector (nq,) of Pinocchio joint values (nv,)."""
        if self.model.nq == self.nv:  # no continuous joint: the values in Pinocchio's order
            return qv[self._pin_order] if self._pin_order is not None else qv
        out = np.zeros(self.model.nq)
        for j in range(1, self.model.njoints):
            jm = self.model.joints[j]
            v = qv[jm.idx_v]
            if jm.nq == 2:
                out[jm.idx_q : jm.idx_q + 2] = np.cos(v), np.sin(v)
            else:
                out[jm.idx_q] = v
        return out

    # ------------------------------------------------------------------ matrices
    def matrices(self, Q, y=None, *, check_bounds: bool = True,
                 data: FlexibleData | None = None):
        """Mass and stiffness matrices at one pose (nv,) or many (n, nv).

        Args:
            Q: Joint coordinates (user convention) [rad or m].
            y: Design values [kg] (default: nominal).
            check_bounds: Raise when a design value leaves its bounds.
            data: Workspace (default: this thread's).

        Returns:
            ``(M, K)``, each (ndof, ndof) for one pose or (n, ndof, ndof).
        """
        Q = check_q(self, Q)
        y = check_y(self, y, bounds=check_bounds)
        single = Q.ndim == 1
        Qb = Q[None] if single else Q
        if y.ndim == 2 and y.shape[0] != Qb.shape[0]:
            raise ConfigurationError(
                f"got {y.shape[0]} design vectors for {Qb.shape[0]} poses; give one or one per pose"
            )
        M, K = matrices_from_terms(self, kinematics.pose_terms(self, Qb, data), y, Qb.shape[0])
        return (M[0], K[0]) if single else (M, K)

    def joint_damping(self, Q, *, data: FlexibleData | None = None) -> np.ndarray:
        """The joints' dampers as a damping matrix over the modal coordinates.

        ``C = Σ c gᵀg`` with ``g`` each joint's physical relative motion (zero without
        ``<pinflex:joint damping=...>``); :func:`pinflex.erls.joints.damping_matrices`.

        Args:
            Q: Joint coordinates (user convention), one pose (nv,) or many (n, nv).
            data: Workspace (default: this thread's).

        Returns:
            ``C`` (ndof, ndof) or (n, ndof, ndof) [N m s/rad, N s/m and the coupled units].
        """
        return joint_conditions.damping_matrices(self, Q, data=data)

    # ------------------------------------------------------------------ joint conditions
    @property
    def joint_conditions(self) -> tuple:
        """Per moving joint its :class:`~pinflex.erls.joints.JointCondition` (velocity order)."""
        return self.plan.conditions.conditions

    @property
    def kept_joints(self) -> tuple[str, ...]:
        """Joints that are not locked: their coordinates are modal coordinates."""
        return self.plan.conditions.kept_joints

    @property
    def n_rigid(self) -> int:
        """Number of rigid (zero-frequency) modes: the free joints."""
        return self.plan.conditions.n_rigid

    @property
    def n_elastic(self) -> int:
        """Number of non-rigid modes: elastic coordinates plus spring-held joints."""
        return self.ndof - self.n_rigid

    @property
    def joint_switch(self) -> str:
        """The joint conditions in one word: 'free', 'locked', or 'annotated' when mixed."""
        kinds = {c.kind for c in self.joint_conditions}
        if kinds <= {"free"}:
            return "free"
        if kinds == {"locked"}:
            return "locked"
        return "annotated"

    def joint_labels(self) -> dict[str, str]:
        """``{joint: 'free' | 'locked' | 'k=...'}`` for reports and JSON outputs."""
        return {c.name: c.label() for c in self.joint_conditions}

    def joint_transform(self, q) -> np.ndarray:
        """``T`` (nx + nv, ndof): ``[x; q_all] = T [x; q_kept]`` at pose ``q``.

        The identity when no joint is locked; the rows of a locked joint give its coordinate
        as the parent attachment's elastic motion along the joint axis
        (:func:`pinflex.erls.joints.joint_transform`).

        Args:
            q: Joint coordinates (nv,) of one pose in the user convention [rad or m].

        Returns:
            ``T`` (nx + nv, ndof), dimensionless.

        Raises:
            ConfigurationError: Invalid ``q`` or more than one pose.
        """
        return joint_conditions.joint_transform(self, q)

    def relative_motion_rows(self, q) -> np.ndarray:
        """``G`` (nv, nx + nv): the joints' physical relative motion ``r = G [x; q_all]``.

        ``r_j = (C q)_j − aᵀθ_parent``: the motion between the parent's deformed attachment
        and the child along the joint axis [rad or m] (see :mod:`pinflex.erls.joints`).

        Args:
            q: Joint coordinates (nv,) of one pose in the user convention [rad or m].

        Returns:
            ``G`` (nv, nx + nv), rows in :attr:`joint_names` order.

        Raises:
            ConfigurationError: Invalid ``q`` or more than one pose.
        """
        return joint_conditions.relative_motion_rows(
            self, *joint_conditions.one_pose_twists(self, q, "relative_motion_rows()"))[0]

    # ------------------------------------------------------------------ modal analysis
    def frequencies(self, Q, y=None, *, n_modes: int | None = None, check_bounds=True,
                    data: FlexibleData | None = None, gravity=None, loads=None,
                    preload: Preload | None = None):
        """Non-rigid eigenfrequencies [Hz] at one pose (k,) or many (n, k), ascending.

        Batched: all poses are assembled and solved together. Frequencies are sorted at each
        pose, so mode ``i`` is the ``i``-th lowest, not a mode followed by its shape (for that,
        see :mod:`pinflex.erls.tracking` where available).

        Args:
            Q: Joint coordinates, one pose (nv,) or many (n, nv), in the user convention
                [rad or m]; Pinocchio configurations (nq,) are accepted and converted
                (:meth:`from_configuration`).
            y: Design values [kg], (ny,), per pose (n, ny), a ``{name: kg}`` dict, or ``None``
                for the nominal ones.
            n_modes: Keep the lowest ``n_modes`` (default: all ``nx``).
            check_bounds: Raise :class:`DesignVariableOutOfBounds` outside the bounds.
            data: Workspace (default: this thread's, see :meth:`workspace`).
            gravity: Gravity preload (3,) in world axes [m/s²], e.g. ``(0, 0, -9.81)``: the
                stiffness of the static loads enters ``K`` (:mod:`pinflex.erls.preload`);
                default None, no preload (paper 000).
            loads: Dead point forces of the preload (:class:`~pinflex.PointForce`: link,
                point [m], world force [N]), e.g. a payload's weight.
            preload: A :class:`~pinflex.Preload` instead of ``gravity`` and ``loads``.

        Returns:
            Frequencies [Hz], (k,) or (n, k).

        Raises:
            PreloadNotInEquilibrium: A preload loads a free joint (lock it or spring it).
            PreloadBuckles: The preload makes the arm unstable.
        """
        n_modes = check_n_modes(self, n_modes)
        Q = check_q(self, Q)
        check_modal(self.ndof, 1 if Q.ndim == 1 else Q.shape[0], "frequencies()")
        return modal.frequencies(self, Q, y, n_modes=n_modes, check_bounds=check_bounds,
                                 data=self.workspace(data),
                                 preload=make_preload(self, gravity, loads, preload))

    def eigvals_from(self, M: np.ndarray, K: np.ndarray) -> np.ndarray:
        """Non-rigid eigenvalues λ [rad²/s²] of stacked matrix pairs (..., ndof, ndof).

        Args:
            M: Mass matrices (..., ndof, ndof) over the modal coordinates, e.g. from
                :meth:`matrices`.
            K: Stiffness matrices of the same shape.

        Returns:
            Eigenvalues (..., n_elastic) ascending [rad²/s²]; ``f = √λ / 2π`` [Hz].

        Raises:
            EigenSolverError: A singular mass matrix or a non-positive elastic eigenvalue
                (an unrestrained structure).
        """
        return modal.eigvals_from(self, M, K)

    def modes(self, q, y=None, *, n_modes: int | None = None, check_bounds=True,
              data: FlexibleData | None = None, gravity=None, loads=None,
              preload: Preload | None = None):
        """Eigenfrequencies, mass-normalised mode shapes and nodal motion at one pose.

        Solves ``K φ = λ M φ`` with the free joints' coordinates condensed out, in the
        conditioned coordinates of :mod:`pinflex.erls.solve` (free joints) or
        :mod:`pinflex.erls.solve_conditions` (springs, locks, section or material design), the
        same solve as :meth:`frequencies`, and returns the shapes over ``[x; q_kept]``.

        Args:
            q: Joint coordinates (nv,) in the user convention [rad or m], or a Pinocchio
                configuration (nq,) (continuous joints as cos/sin, converted by
                :meth:`from_configuration`).
            y: Design values [kg] (default: nominal); ``{name: kg}`` accepted.
            n_modes: Number of lowest modes to compute (default: all ``nx``).
            check_bounds: Raise when a design value leaves its bounds.
            data: Workspace (default: this thread's, see :meth:`workspace`).
            gravity: Gravity preload (3,) [m/s²] (see :meth:`frequencies`).
            loads: Dead point forces of the preload (see :meth:`frequencies`).
            preload: A :class:`~pinflex.Preload` instead of ``gravity`` and ``loads``.

        Returns:
            :class:`ModalResult`: ``freq_hz`` [Hz], ``eigvals`` [rad²/s²], ``shapes`` over
            ``[x; q]`` (ndof, k) normalised to ``φᵀ M φ = 1``, nodal positions [m] and motion,
            ``preload`` (None without one). ``print(result)`` shows a short table.

        Raises:
            ConfigurationError: Wrong number of joint values or several poses.
            EigenSolverError: Singular mass matrix or an unrestrained structure.
            PreloadNotInEquilibrium: A preload loads a free joint (lock it or spring it).
            PreloadBuckles: The preload makes the arm unstable.
        """
        n_modes = check_n_modes(self, n_modes)
        if y is not None and not isinstance(y, dict):
            y = require_array(y, "design values y")
            if y.ndim == 2 and y.shape[0] == 1:
                y = y[0]
            elif y.ndim != 1:
                raise ConfigurationError(
                    f"modes() takes one design vector of {self.ny} values "
                    f"({', '.join(self.design_names)}), got an array of shape {y.shape}"
                )
        return modal.modes(self, q, y, n_modes=n_modes, check_bounds=check_bounds,
                           data=self.workspace(data),
                           preload=make_preload(self, gravity, loads, preload))
