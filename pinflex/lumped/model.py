r"""Lumped pseudo-rigid model of a whole flexible arm: rigid segments joined by spring hinges.

Every flexible link of length L becomes N rigid segments ``[s_j, s_{j+1}]`` (``s_0 = 0``,
``s_N = L``) joined at the stations ``s_1 .. s_{N-1}`` by spring hinges: one about the beam
normal z in a planar model; in 3-D three hinges in series at the same point, bending about z,
bending about y and torsion about the beam axis x (order z, y, x; at rest they are the three
orthogonal beam axes). The first segment rides on the link's own frame, so a link's root is
where the arm's joint (or the parent) holds it, as in paper 001's nR chains.

* **Segments** carry the beam's mass ``m = ρA l`` with its centre at mid-length. Planar: the
  rotational inertia about the plane normal is ``ρA l³/12``, as the arm's Euler–Bernoulli
  beam has (no rotary inertia of the section in bending); the inertias about the other axes
  never enter a planar motion and are set equal to it. 3-D: the rigid-body inertia of the
  stretch, ``ρA l³/12 + ρI_y l`` and ``ρA l³/12 + ρI_z l`` about the bending axes and
  ``ρI_p l`` about the beam axis. (Without the section's rotary inertia in bending a rigid
  body with torsional inertia breaks the triangle inequality of inertias once it is shorter
  than about 2.5 section radii, which MuJoCo refuses; the difference from the Euler–Bernoulli
  beam is of order (r/L)² and the fit absorbs it.)
* **Point masses** and **rigid bodies** on a flexible link ride on the segment that contains
  their axial station (a point on a hinge station rides on the outer segment); child joints
  likewise, with the link's rigid offset from the beam axis.
* **The arm's joints** keep their condition: free (no stiffness, one rigid mode each), spring
  (its stiffness on the joint, which here is the physical relative motion between the parent's
  deformed end and the child), or locked (its coordinate removed from the modal problem; a
  fixed joint in the exports).
* **Stiffness law** (as ``pinflex.prbdm``'s ``segment`` law): hinge j of axis a has
  :math:`k_{j,a} = c_{j,a} R_a / w_j` with :math:`R_a` the rigidity (EI_z, EI_y, GJ) and
  :math:`w_j` the stretch of beam the hinge stands for, from the middle of segment j−1 (the
  root for j = 1) to the middle of segment j (the tip for j = N−1). With every
  :math:`c = 1` the hinges' rotational compliances add up to the beam's, L / R.

The model is a Pinocchio model built in code with one-dof joints only (``nq == nv``); the
hinge angles are zero at rest (``springref`` 0). Modal problems are solved at a pose of the
arm's joints with every hinge at rest: ``K φ = λ M φ`` with ``M`` from CRBA (plus armature)
and the diagonal ``K``; free joints' coordinates are condensed out as in the ERLS model.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from types import MappingProxyType

import numpy as np
import pinocchio as pin
import scipy.linalg as sla

from pinflex.exceptions import ConfigurationError, EigenSolverError
from pinflex.lumped.layout import ArmLayout, BeamData

#: Smallest segment, as a fraction of its link's length (paper 001 eq. 15c uses 0.02).
MIN_FRACTION = 0.02


@dataclass(frozen=True)
class LinkSegments:
    """Segments and hinges of one flexible link.

    Attributes:
        link: Link name.
        length_m: Link (beam) length L [m].
        stations_m: Hinge stations ``s_1 .. s_{N-1}`` from the link root, increasing (N-1,) [m].
        stiffness: Hinge stiffnesses (n_axes, N-1) [N m/rad], rows in the order of ``axes``.
        axes: Hinge axes per station ('bz'; or 'bz', 'by', 'tx').
    """

    link: str
    length_m: float
    stations_m: np.ndarray
    stiffness: np.ndarray
    axes: tuple[str, ...]

    @property
    def n_segments(self) -> int:
        """Number of rigid segments N."""
        return int(self.stations_m.size) + 1

    @property
    def bounds_m(self) -> np.ndarray:
        """Segment ends ``[0, s_1, .., s_{N-1}, L]`` (N+1,) [m]."""
        return np.concatenate([[0.0], self.stations_m, [self.length_m]])


def stretches(bounds: np.ndarray) -> np.ndarray:
    """Beam stretch each hinge stands for, (N-1,) [m]: middle of segment j-1 to middle of j.

    The first stretch starts at the root and the last ends at the tip, so they add up to L.

    Args:
        bounds: Segment ends ``[0, s_1, .., s_{N-1}, L]`` (N+1,) [m].
    """
    mids = 0.5 * (bounds[:-1] + bounds[1:])
    mids[0], mids[-1] = bounds[0], bounds[-1]
    return np.diff(mids)


def law_stiffness(beam: BeamData, axes, bounds: np.ndarray, factors: np.ndarray) -> np.ndarray:
    """Hinge stiffnesses ``c R / w`` (n_axes, N-1) [N m/rad] of the stiffness law."""
    rig = np.array([beam.rigidity[a] for a in axes])[:, None]
    return np.asarray(factors, dtype=float) * rig / stretches(bounds)[None, :]


def equal_segments(beam: BeamData, n_segments: int, axes, *, naive: bool = True
                   ) -> LinkSegments:
    """N equal segments; hinges ``k = R / l`` (``naive``) or the stiffness law with c = 1.

    Args:
        beam: The link's beam.
        n_segments: N >= 1.
        axes: Hinge axes per station.
        naive: ``k = R / l`` with ``l = L / N`` (the textbook equal-segment chain); else the
            stiffness law with every factor 1 (rotational compliance of the beam kept).
    """
    bounds = np.linspace(0.0, beam.length_m, n_segments + 1)
    if naive:
        rig = np.array([beam.rigidity[a] for a in axes])[:, None]
        k = np.repeat(rig * n_segments / beam.length_m, n_segments - 1, axis=1)
    else:
        k = law_stiffness(beam, axes, bounds, np.ones((len(axes), n_segments - 1)))
    return LinkSegments(beam.link, beam.length_m, bounds[1:-1].copy(), k, tuple(axes))


@dataclass(frozen=True)
class LumpedArm:
    """A flexible arm as rigid segments and spring hinges (see the module docstring).

    Attributes:
        layout: The arm it lumps.
        segments: ``{flexible link: LinkSegments}``.
        model: Pinocchio model, one-dof joints only (``nq == nv``): the arm's moving joints
            (named as in the arm, locked ones included) and the hinges
            ``<link>_h<j>_<axis>``.
        stiffness: Diagonal joint stiffness (nv,) [N m/rad or N/m]: hinge springs and the
            arm's joint springs (0 for free and locked joints).
        damping: Joint damping (nv,) [N m s/rad]: the arm's joint damping; hinges 0 unless
            set by :meth:`with_damping`.
        armature: Armature (nv,) [kg m^2] added to M's diagonal (the arm's joints').
        arm_index: Velocity index of each arm joint, in ``layout.arm_joints`` order (nv_arm,).
        hinge_index: Velocity indices of the hinges (n_hinges,).
        hinge_ids: ``{(link, j): joint ids of station j}`` (j = 1..N-1), in axis order.
        segment_ids: ``{(link, j): joint id segment j rides on}`` (j = 0..N-1).
        frames: ``{link: (joint id, placement of the link frame in that joint's frame)}``
            (a flexible link: on its first segment).
    """

    layout: ArmLayout
    segments: Mapping[str, LinkSegments]
    model: pin.Model
    stiffness: np.ndarray
    damping: np.ndarray
    armature: np.ndarray
    arm_index: np.ndarray
    hinge_index: np.ndarray
    hinge_ids: Mapping[tuple[str, int], tuple[int, ...]]
    segment_ids: Mapping[tuple[str, int], int]
    frames: Mapping[str, tuple[int, pin.SE3]]
    _data: list = field(default_factory=list, repr=False, compare=False)

    @property
    def nv(self) -> int:
        """Number of joint coordinates (arm joints + hinges)."""
        return int(self.model.nv)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names in velocity order."""
        return tuple(self.model.names[1:])

    @property
    def n_hinges(self) -> int:
        """Number of spring hinges."""
        return int(self.hinge_index.size)

    def configuration(self, q) -> np.ndarray:
        """Lumped configuration (nv,) at arm pose ``q`` (user convention), hinges at rest."""
        q = np.asarray(q, dtype=float)
        nv_arm = len(self.layout.arm_joints)
        if q.shape != (nv_arm,) or not np.all(np.isfinite(q)):
            raise ConfigurationError(
                f"the arm pose must be {nv_arm} finite joint values "
                f"({', '.join(j.name for j in self.layout.arm_joints)}), got {q.tolist()}")
        out = np.zeros(self.nv)
        out[self.arm_index] = self.layout.coord_map @ q
        return out

    def _pin_data(self) -> pin.Data:
        if not self._data:
            self._data.append(self.model.createData())
        return self._data[0]

    def mass_matrix(self, q) -> np.ndarray:
        """Joint-space mass matrix (nv, nv) at arm pose ``q`` (user convention), armature in."""
        m = pin.crba(self.model, self._pin_data(), self.configuration(q))
        m = np.triu(m) + np.triu(m, 1).T
        m[np.diag_indices_from(m)] += self.armature
        return m

    def kept(self, condition: str = "own") -> tuple[np.ndarray, np.ndarray]:
        """Velocity indices kept in a modal problem, and which of them are rigid.

        Args:
            condition: 'own' (the arm's joint conditions) or 'locked' (every arm joint held).

        Returns:
            ``(kept, rigid)``: kept indices (n,) and a boolean mask (n,) of free joints.
        """
        if condition not in ("own", "locked"):
            raise ConfigurationError(f"condition '{condition}': expected 'own' or 'locked'")
        drop: set[int] = set()
        free: set[int] = set()
        for joint, idx in zip(self.layout.arm_joints, self.arm_index):
            if condition == "locked" or joint.condition == "locked":
                drop.add(int(idx))
            elif joint.condition == "free":
                free.add(int(idx))
        kept = np.array([i for i in range(self.nv) if i not in drop], dtype=int)
        return kept, np.array([i in free for i in kept], dtype=bool)

    def modes(self, q, condition: str = "own", mass: np.ndarray | None = None):
        """Non-rigid eigenvalues and mass-normalised shapes at arm pose ``q``.

        Solves ``K_ee φ_e = λ (M_ee − M_er M_rr⁻¹ M_re) φ_e`` over the kept coordinates
        (rigid = free arm joints) and recovers ``φ_r = −M_rr⁻¹ M_re φ_e``.

        Args:
            q: Arm pose (user convention) [rad or m].
            condition: 'own' or 'locked' (see :meth:`kept`).
            mass: The mass matrix at ``q`` if already computed.

        Returns:
            ``(eigvals (n_el,) [rad^2/s^2], shapes (nv, n_el))``: shapes over all coordinates
            (zero rows for dropped ones), ``φᵀ M φ = 1``.

        Raises:
            EigenSolverError: No elastic coordinate, or a singular condensed mass matrix.
        """
        M = self.mass_matrix(q) if mass is None else mass
        kept, rigid = self.kept(condition)
        Mk = M[np.ix_(kept, kept)]
        Kk = np.diag(self.stiffness[kept])
        e, r = ~rigid, rigid
        if not e.any():
            raise EigenSolverError("the lumped model has no elastic coordinate")
        if r.any():
            Mrr = Mk[np.ix_(r, r)]
            Mre = Mk[np.ix_(r, e)]
            G = np.linalg.solve(Mrr, Mre)
            Mc = Mk[np.ix_(e, e)] - Mre.T @ G
        else:
            G = np.zeros((0, int(e.sum())))
            Mc = Mk[np.ix_(e, e)]
        try:
            lam, phi = sla.eigh(Kk[np.ix_(e, e)], 0.5 * (Mc + Mc.T))
        except np.linalg.LinAlgError as exc:
            raise EigenSolverError(f"lumped modal problem failed: {exc}") from exc
        shapes = np.zeros((self.nv, lam.size))
        idx_e, idx_r = kept[e], kept[r]
        shapes[idx_e] = phi
        shapes[idx_r] = -G @ phi
        return lam, shapes

    def frequencies(self, q, condition: str = "own", n_modes: int | None = None) -> np.ndarray:
        """Non-rigid eigenfrequencies [Hz] at arm pose ``q`` (user convention), ascending."""
        lam = self.modes(q, condition)[0]
        f = np.sqrt(np.clip(lam, 0.0, None)) / (2.0 * np.pi)
        return f if n_modes is None else f[:n_modes]

    def n_elastic(self, condition: str = "own") -> int:
        """Number of non-rigid modes under a condition."""
        kept, rigid = self.kept(condition)
        return int((~rigid).sum())

    def locked(self) -> LumpedArm:
        """The same segments with every arm joint locked (welded in the exports)."""
        joints = tuple(replace(j, condition="locked", stiffness=np.inf)
                       for j in self.layout.arm_joints)
        return build(replace(self.layout, arm_joints=joints), self.segments)

    def with_damping(self, hinge_damping: np.ndarray) -> LumpedArm:
        """The same arm with hinge damping (n_hinges,) [N m s/rad] (arm joints' kept)."""
        d = np.array(self.damping, dtype=float)
        d[self.hinge_index] = np.asarray(hinge_damping, dtype=float)
        d.setflags(write=False)
        return LumpedArm(self.layout, self.segments, self.model, self.stiffness, d,
                         self.armature, self.arm_index, self.hinge_index, self.hinge_ids,
                         self.segment_ids, self.frames)


def _frozen(a) -> np.ndarray:
    arr = np.array(a)
    arr.setflags(write=False)
    return arr


def _arm_joint_model(kind: str, axis: np.ndarray):
    if kind == "prismatic":
        return pin.JointModelPrismaticUnaligned(np.asarray(axis, dtype=float))
    return pin.JointModelRevoluteUnaligned(np.asarray(axis, dtype=float))


_HINGE_MODELS = {"bz": pin.JointModelRZ, "by": pin.JointModelRY, "tx": pin.JointModelRX,
                 "ax": pin.JointModelPX}


def segment_of(bounds: np.ndarray, station: float) -> int:
    """Index of the segment holding an axial station (a station on a boundary: the outer one)."""
    n = bounds.size - 1
    found = int(np.searchsorted(bounds, station, side="right")) - 1
    return min(max(found, 0), n - 1)


def build(layout: ArmLayout, segments: Mapping[str, LinkSegments]) -> LumpedArm:
    """Build the lumped arm of a layout with given segments.

    Args:
        layout: The arm.
        segments: ``{flexible link: LinkSegments}`` for every flexible link of the layout.

    Returns:
        The :class:`LumpedArm`.

    Raises:
        ConfigurationError: A flexible link without segments, or stations that are not
            increasing inside the link.
    """
    for link in layout.beams:
        if link not in segments:
            raise ConfigurationError(f"no segments given for flexible link '{link}'")
        seg = segments[link]
        b = seg.bounds_m
        if np.any(np.diff(b) <= 0.0) or not np.all(np.isfinite(b)):
            raise ConfigurationError(
                f"hinge stations of '{link}' must increase strictly inside (0, {seg.length_m}) "
                f"m, got {np.round(seg.stations_m, 9).tolist()}")
    model = pin.Model()
    model.name = layout.name
    frames: dict[str, tuple[int, pin.SE3]] = {layout.links[0]: (0, pin.SE3.Identity())}
    hinge_ids: dict[tuple[str, int], tuple[int, ...]] = {}
    segment_ids: dict[tuple[str, int], int] = {}
    # per flexible link: (joint id, link frame in that joint's frame) of every segment
    rides: dict[str, list[tuple[int, pin.SE3]]] = {}
    stiffness: dict[str, float] = {}
    arm_by_name = {j.name: j for j in layout.arm_joints}

    def ride(link: str, point: np.ndarray) -> tuple[int, pin.SE3]:
        """Joint carrying a point of a link, and the link frame's placement in that joint."""
        if link not in rides:
            return frames[link]
        beam = layout.beams[link]
        station = float(point @ beam.rotation[:, 0])
        j = segment_of(segments[link].bounds_m, station)
        return rides[link][j]

    def add_flexible(link: str) -> None:
        beam = layout.beams[link]
        seg = segments[link]
        jid, link_in_joint = frames[link]
        rb = pin.SE3(beam.rotation, np.zeros(3))
        b = seg.bounds_m
        out = [(jid, link_in_joint)]
        segment_ids[(link, 0)] = jid
        parent, placement = jid, link_in_joint * rb  # segment-0 frame in the joint frame
        for j in range(1, seg.n_segments):
            place = placement * pin.SE3(np.eye(3), np.array([b[j] - b[j - 1], 0.0, 0.0]))
            ids = []
            for a_i, axis in enumerate(seg.axes):
                name = f"{link}_h{j}_{axis}"
                parent = model.addJoint(parent, _HINGE_MODELS[axis](), place, name)
                stiffness[name] = float(seg.stiffness[a_i, j - 1])
                ids.append(parent)
                place = pin.SE3.Identity()
            hinge_ids[(link, j)] = tuple(ids)
            segment_ids[(link, j)] = parent
            placement = pin.SE3.Identity()
            # link frame in the hinge frame: the inverse of (beam axes, station)
            out.append((parent, (pin.SE3(beam.rotation, b[j] * beam.rotation[:, 0])).inverse()))
        rides[link] = out
        for j in range(seg.n_segments):
            l_j = b[j + 1] - b[j]
            m = beam.rhoA * l_j
            if layout.planar:  # only the inertia about z enters a planar arm's motion
                rot = np.diag([1.0, 1.0, 1.0]) * (m * l_j**2 / 12.0)
            else:
                rot = np.diag([beam.rhoIp * l_j, m * l_j**2 / 12.0 + beam.rhoI[0] * l_j,
                               m * l_j**2 / 12.0 + beam.rhoI[1] * l_j])
            inertia = pin.Inertia(m, np.array([b[j] + 0.5 * l_j, 0.0, 0.0]), rot)
            jid_j, frame_j = out[j]
            # segment inertia given in beam axes at the link origin
            model.appendBodyToJoint(jid_j, inertia, frame_j * rb)

    for link in layout.links:
        if link != layout.links[0]:
            jd = layout.joints[link]
            pj, pframe = ride(jd.parent, jd.placement.translation)
            place = pframe * jd.placement
            if jd.kind == "fixed":
                frames[link] = (pj, place)
            else:
                jid = model.addJoint(pj, _arm_joint_model(jd.kind, jd.axis), place, jd.name)
                frames[link] = (jid, pin.SE3.Identity())
                arm = arm_by_name[jd.name]
                stiffness[jd.name] = arm.stiffness if arm.condition == "spring" else 0.0
        if link in layout.beams:
            add_flexible(link)
        if link in layout.inertias:
            inertia = layout.inertias[link]
            jid, frame = ride(link, inertia.lever)
            model.appendBodyToJoint(jid, inertia, frame)
    for _name, link, xyz, mass in layout.point_masses:
        if mass > 0.0:
            jid, frame = ride(link, xyz)
            model.appendBodyToJoint(jid, pin.Inertia(mass, xyz, np.zeros((3, 3))), frame)
    for _name, link, inertia in layout.bodies:
        jid, frame = ride(link, inertia.lever)
        model.appendBodyToJoint(jid, inertia, frame)
    for link, (jid, frame) in frames.items():
        model.addFrame(pin.Frame(link, jid, frame, pin.FrameType.BODY))
    names = list(model.names[1:])
    nv = model.nv
    k = np.array([stiffness[n] for n in names])
    damping = np.zeros(nv)
    armature = np.zeros(nv)
    arm_index = []
    for joint in layout.arm_joints:
        idx = model.joints[model.getJointId(joint.name)].idx_v
        arm_index.append(idx)
        damping[idx] = joint.damping
        armature[idx] = joint.armature
    hinge_index = sorted(model.joints[jid].idx_v for ids in hinge_ids.values() for jid in ids)
    return LumpedArm(layout, MappingProxyType(dict(segments)), model, _frozen(k),
                     _frozen(damping), _frozen(armature), _frozen(np.array(arm_index, int)),
                     _frozen(np.array(hinge_index, int)), MappingProxyType(hinge_ids),
                     MappingProxyType(segment_ids), MappingProxyType(frames))


def equal_lumped(layout: ArmLayout, n_segments, *, naive: bool = True) -> LumpedArm:
    """The lumped arm with equal segments (see :func:`equal_segments`).

    Args:
        layout: The arm.
        n_segments: Segments per flexible link: one int, or ``{link: int}``.
        naive: ``k = R / l`` hinges (True) or the stiffness law with c = 1.
    """
    counts = n_segments if isinstance(n_segments, Mapping) else {
        link: int(n_segments) for link in layout.beams}
    return build(layout, {link: equal_segments(beam, counts[link], layout.axes, naive=naive)
                          for link, beam in layout.beams.items()})
