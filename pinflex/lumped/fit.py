r"""Fit a lumped arm's hinge stations and stiffnesses to the arm's own ERLS modes.

Paper 001's mapping (link lengths on the simplex and stiffness correction factors, fitted by
least squares to the beam's frequencies and statics), applied to every flexible link of an arm
at once, against the arm's ERLS model instead of a lone beam:

* **parameters** per flexible link of N segments: segment fractions
  :math:`\gamma = g + (1 - N g)\,\mathrm{softmax}(0, z_1, .., z_{N-1})` (each at least
  ``g = MIN_FRACTION``, summing to 1) and log stiffness factors :math:`\ell_{j,a}`,
  :math:`k_{j,a} = e^{\ell_{j,a}} R_a / w_j` (:mod:`pinflex.lumped.model`);
* **matched quantities**: the relative errors :math:`f_{lumped}/f_{ERLS} - 1` of the k lowest
  non-rigid frequencies at every fitted pose, under the arm's own joint conditions and with
  every joint locked (a driven arm rings at its locked-joint frequencies after a stop); and
  each flexible link's static tip compliance as a cantilever clamped at its root (tip force
  and moment in each bending plane: three entries, and the torsion compliance), relative to
  the beam's :math:`L^3/3R, L^2/2R, L/R`;
* **prior**: a weak pull (weight ``prior``) of every parameter towards 0 (equal segments,
  factors 1). When the parameters outnumber the matched quantities the match can be exact on
  a whole manifold; the prior picks the point of it nearest the equal-segment chain, so the
  answer is unique. The fit says which case it is (``determinacy``).
* **exact Jacobian**: frequency derivatives
  :math:`\partial\lambda = \phi^T(\partial K - \lambda\,\partial M)\phi` with the exact
  :math:`\partial M/\partial s` of :mod:`pinflex.lumped.sensitivity`; compliance derivatives in
  closed form. Solved by ``scipy.optimize.least_squares`` (trust region).

The fit reports its **worst frequency error** over all the given poses (also those not fitted,
when a trajectory has more samples than ``max_fit_poses``) and both conditions, and its
**worst static compliance error**, beside the same figures of the naive equal-segment chain
(``k = R / l``).
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from pinflex.exceptions import (
    ConfigurationError,
    JointLimitsExceeded,
    LinkTooShort,
    LumpedFitWarning,
    TooManyModes,
)
from pinflex.lumped.layout import ArmLayout, layout_of
from pinflex.lumped.model import (
    MIN_FRACTION,
    LinkSegments,
    LumpedArm,
    build,
    equal_lumped,
    stretches,
)
from pinflex.lumped.sensitivity import mass_from_geometry, pose_geometry, station_derivatives
from pinflex.lumped.shapes import (
    REPEATED,
    ErlsShapes,
    mac_matrix,
    mismatches,
    node_translations,
    shape_order,
)


@dataclass(frozen=True)
class LumpedFit:
    """A fitted lumped arm and how well it matches the arm's ERLS model.

    Attributes:
        lumped: The fitted lumped arm.
        naive: The equal-segment chain with ``k = R / l`` (the reference it must beat).
        poses: Arm poses judged (n, nv) in the arm's user convention [rad or m].
        fit_poses: Indices of the poses the fit used (m,).
        conditions: Joint conditions matched ('own', and 'locked' unless every joint is
            locked already).
        n_modes: Modes matched per pose and condition, k.
        erls_hz: ``{condition: (n, k)}`` ERLS frequencies [Hz].
        lumped_hz: ``{condition: (n, k)}`` fitted lumped frequencies [Hz].
        naive_hz: ``{condition: (n, k)}`` naive chain frequencies [Hz].
        worst_error: Largest ``|f/f_ERLS - 1|`` over poses, modes and conditions [-].
        mode_errors: ``{condition: (k,)}`` largest error per mode over the poses [-].
        compliance_error: Largest relative error of the links' static tip compliances [-].
        naive_worst_error: The naive chain's worst frequency error [-].
        naive_mode_errors: ``{condition: (k,)}`` the naive chain's largest error per mode [-].
        naive_compliance_error: The naive chain's compliance error [-].
        n_parameters: Free parameters.
        n_quantities: Matched quantities (frequencies at fitted poses, compliances).
        determinacy: 'exactly determined' (n_parameters >= n_quantities: the prior picks
            the fit) or 'over-determined'.
        evaluations: Residual evaluations of the search.
        message: The solver's message.
        mode_mac: ``{condition: (k,)}`` smallest MAC over the fitted poses between each
            ERLS mode and the lumped mode its frequency is matched to (1: the same shape;
            :mod:`pinflex.lumped.shapes`); empty when not checked.
        shape_mismatches: ``(condition, pose index, ERLS mode, closest lumped mode, MAC of
            the matched pair, MAC with the closest other)`` for every matched pair that is
            not the same mode (0-based modes).
    """

    lumped: LumpedArm
    naive: LumpedArm
    poses: np.ndarray
    fit_poses: np.ndarray
    conditions: tuple[str, ...]
    n_modes: int
    erls_hz: Mapping[str, np.ndarray]
    lumped_hz: Mapping[str, np.ndarray]
    naive_hz: Mapping[str, np.ndarray]
    worst_error: float
    mode_errors: Mapping[str, np.ndarray]
    compliance_error: float
    naive_worst_error: float
    naive_mode_errors: Mapping[str, np.ndarray]
    naive_compliance_error: float
    n_parameters: int
    n_quantities: int
    determinacy: str
    evaluations: int
    message: str = field(default="")
    mode_mac: Mapping[str, np.ndarray] = field(default_factory=dict)
    shape_mismatches: tuple[tuple[str, int, int, int, float, float], ...] = ()

    def summary(self) -> dict:
        """The fit as plain data (JSON-ready): segments, stiffnesses, errors."""
        links = {}
        for link, seg in self.lumped.segments.items():
            links[link] = {
                "length_m": seg.length_m,
                "segments": seg.n_segments,
                "stations_m": seg.stations_m.tolist(),
                "stiffness_nm_rad": {a: seg.stiffness[i].tolist() for i, a in enumerate(seg.axes)},
            }
        return {
            "robot": self.lumped.layout.name,
            "planar": self.lumped.layout.planar,
            "n_modes": self.n_modes,
            "conditions": list(self.conditions),
            "poses": self.poses.tolist(),
            "fit_poses": self.fit_poses.tolist(),
            "links": links,
            "worst_error": self.worst_error,
            "mode_errors": {c: v.tolist() for c, v in self.mode_errors.items()},
            "compliance_error": self.compliance_error,
            "naive_worst_error": self.naive_worst_error,
            "naive_mode_errors": {c: v.tolist() for c, v in self.naive_mode_errors.items()},
            "naive_compliance_error": self.naive_compliance_error,
            "erls_hz": {c: v.tolist() for c, v in self.erls_hz.items()},
            "lumped_hz": {c: v.tolist() for c, v in self.lumped_hz.items()},
            "naive_hz": {c: v.tolist() for c, v in self.naive_hz.items()},
            "n_parameters": self.n_parameters,
            "n_quantities": self.n_quantities,
            "determinacy": self.determinacy,
            "evaluations": self.evaluations,
            "mode_mac": {c: v.tolist() for c, v in self.mode_mac.items()},
            "shape_mismatches": [list(m) for m in self.shape_mismatches],
        }

    def to_json(self) -> str:
        """:meth:`summary` as JSON text."""
        return json.dumps(self.summary(), indent=2)


# ----------------------------------------------------------------------------- parameters
@dataclass(frozen=True)
class _LinkBlock:
    link: str
    n: int          # segments
    n_axes: int
    start: int      # first parameter index

    @property
    def size(self) -> int:
        return (self.n - 1) * (1 + self.n_axes)


def _blocks(layout: ArmLayout, counts: Mapping[str, int]) -> list[_LinkBlock]:
    out, start = [], 0
    for link in layout.beams:
        b = _LinkBlock(link, counts[link], len(layout.axes), start)
        out.append(b)
        start += b.size
    return out


def _stations(length: float, n: int, z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Stations (n-1,) and their derivative with respect to z (n-1, n-1)."""
    zz = np.concatenate([[0.0], z])
    w = np.exp(zz - zz.max())
    sig = w / w.sum()
    scale = 1.0 - n * MIN_FRACTION
    gamma = MIN_FRACTION + scale * sig
    dgamma = scale * (np.diag(sig) - np.outer(sig, sig))[:, 1:]  # (n, n-1)
    stations = length * np.cumsum(gamma)[:-1]
    dst = length * np.cumsum(dgamma, axis=0)[:-1]
    return stations, dst


def _stretch_jacobian(n: int) -> np.ndarray:
    """``∂w/∂s`` (n-1, n-1) of the hinge stretches (:func:`stretches`)."""
    # mids[i] (i = 0..n-1) of segments; mids[0] = 0, mids[n-1] = L, else (b_i + b_{i+1}) / 2
    dmid = np.zeros((n, n - 1))
    for i in range(1, n - 1):
        dmid[i, i - 1] += 0.5   # b_i = s_i
        dmid[i, i] += 0.5       # b_{i+1} = s_{i+1}
    return np.diff(dmid, axis=0)


def _decode(layout: ArmLayout, blocks, x: np.ndarray):
    segs, extras = {}, {}
    for b in blocks:
        beam = layout.beams[b.link]
        p = x[b.start:b.start + b.size]
        z = p[:b.n - 1]
        ell = p[b.n - 1:].reshape(b.n_axes, b.n - 1)
        stations, dst = _stations(beam.length_m, b.n, z)
        bounds = np.concatenate([[0.0], stations, [beam.length_m]])
        w = stretches(bounds)
        rig = np.array([beam.rigidity[a] for a in layout.axes])[:, None]
        k = np.exp(ell) * rig / w[None, :]
        segs[b.link] = LinkSegments(b.link, beam.length_m, stations, k, layout.axes)
        extras[b.link] = (dst, w, rig)
    return segs, extras


# ----------------------------------------------------------------------------- compliance
def _compliance(seg: LinkSegments, rig: np.ndarray, w: np.ndarray, axes):
    """Relative compliance errors of one link and their derivatives.

    Returns ``(r, dr_ds (m, n-1), dr_dell (m, n_axes, n-1))``.
    """
    L, s, k = seg.length_m, seg.stations_m, seg.stiffness
    arm_ = L - s
    dw = _stretch_jacobian(seg.n_segments)
    res, d_s, d_l = [], [], []
    for a_i, axis in enumerate(axes):
        R = rig[a_i, 0]
        inv = 1.0 / k[a_i]                      # = w / (c R)
        dinv_ds = (inv / w)[:, None] * dw       # (n-1, n-1): d(1/k_j)/d s_m
        entries = [(np.ones_like(s), 0, L / R)]
        if axis in ("bz", "by"):
            entries = [(arm_**2, 2, L**3 / (3 * R)), (arm_, 1, L**2 / (2 * R))] + entries
        for weight, power, target in entries:
            value = weight @ inv
            ds = weight @ dinv_ds
            if power:
                ds = ds - power * arm_ ** (power - 1) * inv
            dl = np.zeros((len(axes), s.size))
            dl[a_i] = -weight * inv
            res.append(value / target - 1.0)
            d_s.append(ds / target)
            d_l.append(dl / target)
    return np.array(res), np.array(d_s), np.array(d_l)


def compliance_errors(lumped: LumpedArm) -> np.ndarray:
    """Relative errors of every flexible link's static tip compliances (cantilever at its root).

    Per link and bending axis: tip deflection under a tip force, tip rotation under a tip force
    (= deflection under a moment), rotation under a moment; torsion: twist under a torque.
    """
    out = []
    for link, seg in lumped.segments.items():
        beam = lumped.layout.beams[link]
        if seg.n_segments < 2:
            continue
        rig = np.array([beam.rigidity[a] for a in seg.axes])[:, None]
        out.append(_compliance(seg, rig, stretches(seg.bounds_m), seg.axes)[0])
    return np.concatenate(out) if out else np.zeros(0)


# ----------------------------------------------------------------------------- fitting
def _relative_errors(lumped: LumpedArm, poses, conditions, n_modes, erls, shapes=None):
    """Lumped frequencies paired with the ERLS modes (by shape when ``shapes`` are given)."""
    out = {}
    for c in conditions:
        rows = []
        for i, q in enumerate(poses):
            lam, phi = lumped.modes(q, c)
            f = np.sqrt(np.clip(lam[:n_modes], 0.0, None)) / (2.0 * np.pi)
            if shapes is not None:
                f = f[shape_order(lumped, q, phi, shapes[c][i])]
            rows.append(f)
        out[c] = np.array(rows)
    err = np.concatenate([(out[c] / erls[c] - 1.0).ravel() for c in conditions])
    return out, err


def locked_twin(arm):
    """The arm's ERLS model with every joint locked (same design values)."""
    from pinflex.erls import FlexibleModel

    values = {k: v for k, v in arm.point_mass_values.items()}
    values.update(arm.description.values)
    return FlexibleModel(arm.description, planar=arm.planar, values=values,
                         coordinates=arm.coordinates, joints="locked")


def check_segments(layout: ArmLayout, counts: Mapping[str, int]) -> None:
    """Refuse segment counts a link cannot hold.

    A segment must be at least ``MIN_FRACTION`` of its link and no shorter than the
    section's diameter (a shorter rigid piece is no longer a slender beam's stretch).

    Raises:
        LinkTooShort: Naming the link, its length, the section and the largest count allowed.
        ConfigurationError: A count that is not a positive integer.
    """
    for link, beam in layout.beams.items():
        n = counts[link]
        if isinstance(n, bool) or int(n) != n or n < 1:
            raise ConfigurationError(f"segments of '{link}' = {n!r}: give an integer >= 1")
        diameter = 2.0 * beam.radius_m
        longest = int(min(np.floor((1.0 - 1e-9) / MIN_FRACTION),
                          np.floor(beam.length_m / diameter)))
        if n > 1 and n > longest:
            raise LinkTooShort(
                f"link '{link}' ({beam.length_m:.4g} m long, section diameter "
                f"{diameter:.4g} m) is too short for {n} segments: a segment must be at least "
                f"{MIN_FRACTION:g} of the link and no shorter than its section; use at most "
                f"{max(longest, 1)} segments")


def check_limits(layout: ArmLayout, poses: np.ndarray) -> None:
    """Refuse poses outside the arm's joint limits (relative joint values).

    Raises:
        JointLimitsExceeded: Naming the samples, joints, values and limits.
    """
    rel = poses @ layout.coord_map.T
    rows = []
    for i, joint in enumerate(layout.arm_joints):
        if joint.continuous:
            continue
        bad = np.flatnonzero((rel[:, i] < joint.lower - 1e-9) | (rel[:, i] > joint.upper + 1e-9))
        rows += [(int(s), joint.name, rel[s, i], joint.lower, joint.upper) for s in bad]
    if rows:
        rows.sort()
        raise JointLimitsExceeded(*zip(*rows))


def default_modes(layout: ArmLayout) -> int:
    """One mode per bending plane of every flexible link (planar: one per link)."""
    return len(layout.beams) * (1 if layout.planar else 2)


def fit_lumped(arm, segments, *, poses=None, n_modes: int | None = None,
               max_fit_poses: int = 8, prior: float = 1e-6, compliance_weight: float = 0.1,
               max_evaluations: int = 400, axial: bool = False, layout: ArmLayout | None = None,
               erls: Mapping[str, np.ndarray] | None = None,
               warn_above: float | None = 0.01, pair_by_shape: bool = True) -> LumpedFit:
    """Fit hinge stations and stiffnesses of a lumped arm to the arm's ERLS frequencies.

    Args:
        arm: The :class:`~pinflex.erls.FlexibleModel`.
        segments: Rigid segments per flexible link: one int or ``{link: int}``.
        poses: Arm poses (n, nv) or one (nv,), user convention; default the zero pose.
        n_modes: Lowest non-rigid modes matched per pose and condition (default: one per
            bending plane of each flexible link).
        max_fit_poses: Poses used by the search (evenly spread over ``poses``); the errors
            are reported over all of them.
        prior: Weight of the pull towards equal segments and unit factors (the search starts
            with a 1000 times stronger pull, then relaxes it to this one).
        compliance_weight: Weight of the static compliance errors beside the frequencies'
            (default 0.1: when the hinges cannot match both, the frequencies come first; on
            benchmark A with 3 segments per link, weight 1 leaves mode 1 0.40 % off and the
            compliance 2.3 %, weight 0.1 0.004 % and 2.5 %).
        max_evaluations: Residual evaluations allowed to each of the two stages of the search.
        axial: Give every station an axial spring too (see
            :func:`~pinflex.lumped.layout.layout_of`); ignored when ``layout`` is given.
        layout: The arm's layout if already read (:func:`~pinflex.lumped.layout.layout_of`).
        erls: Precomputed ERLS frequencies ``{condition: (n, >= k)}`` at ``poses``.
        warn_above: Warn (:class:`~pinflex.exceptions.LumpedFitWarning`) when the worst
            frequency error or the compliance error exceeds this [-] (default 1 %); None: no
            warning (the errors are reported on the fit either way).
        pair_by_shape: Pair the lumped modes with the ERLS modes by shape (MAC of the beams'
            node translations, :mod:`pinflex.lumped.shapes`) in the search and in the
            reported errors, where that clearly beats pairing by order; else by order. Either
            way the pairs are checked at the fitted poses: a pair that is not the same mode
            is reported in ``shape_mismatches`` and warned about.

    Returns:
        The :class:`LumpedFit`.

    Warns:
        LumpedFitWarning: The fit misses by more than ``warn_above``: too few segments for
            the modes and poses asked; the message names the worst mode and condition. Or a
            matched frequency belongs to a different mode shape.

    Raises:
        LinkTooShort: A link cannot hold its segments.
        TooManyModes: ``n_modes`` exceeds what the hinges can carry under a condition.
        JointLimitsExceeded: A pose leaves a joint's limits.
        ConfigurationError: Bad ``poses``, ``n_modes`` or weights.
    """
    layout = layout_of(arm, axial=axial) if layout is None else layout
    counts = dict(segments) if isinstance(segments, Mapping) else {
        link: segments for link in layout.beams}
    for link in layout.beams:
        counts.setdefault(link, 1)
    check_segments(layout, counts)
    counts = {k: int(v) for k, v in counts.items()}
    nv_arm = len(layout.arm_joints)
    P = np.zeros((1, nv_arm)) if poses is None else np.atleast_2d(np.asarray(poses, float))
    if P.shape[1] != nv_arm or not np.all(np.isfinite(P)):
        raise ConfigurationError(f"poses must be (n, {nv_arm}) finite joint values, "
                                 f"got shape {P.shape}")
    check_limits(layout, P)
    k = default_modes(layout) if n_modes is None else n_modes
    if isinstance(k, bool) or int(k) != k or k < 1:
        raise ConfigurationError(f"n_modes = {n_modes!r}: give an integer >= 1")
    k = int(k)
    naive = equal_lumped(layout, counts, naive=True)
    all_locked = all(j.condition == "locked" for j in layout.arm_joints)
    conditions = ("own",) if all_locked else ("own", "locked")
    for c in conditions:
        carried = naive.n_elastic(c)
        if k > carried:
            raise TooManyModes(
                f"{k} modes asked, but {sum(counts.values())} segments on "
                f"{len(layout.beams)} flexible link(s) give the lumped arm only {carried} "
                f"non-rigid modes with {'its own' if c == 'own' else 'locked'} joints: "
                "ask fewer modes (--modes) or more segments (--segments)")
    if erls is None:
        erls = {"own": np.atleast_2d(arm.frequencies(P, n_modes=k))}
        if "locked" in conditions:
            erls["locked"] = np.atleast_2d(locked_twin(arm).frequencies(P, n_modes=k))
    erls = {c: np.asarray(erls[c])[:, :k] for c in conditions}
    if P.shape[0] <= max_fit_poses:
        fit_idx = np.arange(P.shape[0])
    else:
        fit_idx = np.unique(np.round(np.linspace(0, P.shape[0] - 1, max_fit_poses)).astype(int))
    blocks = _blocks(layout, counts)
    n_par = sum(b.size for b in blocks)
    fitted = [link for link in layout.beams if counts[link] > 1]
    n_comp = len(fitted) * sum(3 if a in ("bz", "by") else 1 for a in layout.axes)
    n_q = fit_idx.size * len(conditions) * k + n_comp
    evaluations = [0]
    targets = {c: erls[c][fit_idx] for c in conditions}
    if pair_by_shape:  # ERLS shapes at every pose (the reported errors pair by shape too)
        shapes_all = _erls_shapes(arm, P, conditions, k)
        shapes_fit = {c: [v[i] for i in fit_idx] for c, v in shapes_all.items()}
    else:  # only at the fitted poses, for the check
        shapes_all, shapes_fit = None, _erls_shapes(arm, P[fit_idx], conditions, k)
    pair_fit = shapes_fit if pair_by_shape else None
    fit_P = P[fit_idx]

    def residuals(x: np.ndarray):
        segs, extras = _decode(layout, blocks, x)
        lumped = build(layout, segs)
        evaluations[0] += 1
        rows, jac = [], []
        for i, q in enumerate(fit_P):
            geo = pose_geometry(lumped, q)
            M = mass_from_geometry(geo, lumped.armature)
            dM = None
            for c in conditions:
                lam, phi = lumped.modes(q, c, mass=M)
                lam, phi = lam[:k], phi[:, :k]
                if pair_fit is not None:
                    order = shape_order(lumped, q, phi, pair_fit[c][i])
                    lam, phi = lam[order], phi[:, order]
                f = np.sqrt(np.clip(lam, 1e-300, None)) / (2 * np.pi)
                tgt = targets[c][i]
                rows.append(f / tgt - 1.0)
                dr_dlam = 1.0 / (8 * np.pi**2 * f * tgt)
                if dM is None:
                    dM = station_derivatives(lumped, geo)
                J = np.zeros((k, n_par))
                for b in blocks:
                    if b.n < 2:
                        continue
                    dst, w, rig = extras[b.link]
                    seg = segs[b.link]
                    names = [lumped.hinge_ids[(b.link, h)] for h in range(1, b.n)]
                    vidx = np.array([[lumped.model.joints[jid].idx_v for jid in ids]
                                     for ids in names]).T  # (n_axes, n-1)
                    dw = _stretch_jacobian(b.n)
                    # d lambda / d s_h
                    dl_ds = np.zeros((k, b.n - 1))
                    for h in range(1, b.n):
                        dMh = dM[(b.link, h)]
                        dk = -(seg.stiffness / w[None, :]) * dw[:, h - 1][None, :]
                        quad_k = np.einsum("ah,ahm->m", dk, phi[vidx] ** 2)
                        quad_m = np.einsum("im,ij,jm->m", phi, dMh, phi)
                        dl_ds[:, h - 1] = quad_k - lam * quad_m
                    J[:, b.start:b.start + b.n - 1] = dl_ds @ dst
                    dl_dell = seg.stiffness[..., None] * phi[vidx] ** 2  # (a, n-1, k)
                    J[:, b.start + b.n - 1:b.start + b.size] = dl_dell.reshape(-1, k).T
                jac.append(dr_dlam[:, None] * J)
        for b in blocks:
            if b.n < 2:
                continue
            dst, w, rig = extras[b.link]
            r, d_s, d_l = _compliance(segs[b.link], rig, w, layout.axes)
            J = np.zeros((r.size, n_par))
            J[:, b.start:b.start + b.n - 1] = d_s @ dst
            J[:, b.start + b.n - 1:b.start + b.size] = d_l.reshape(r.size, -1)
            rows.append(compliance_weight * r)
            jac.append(compliance_weight * J)
        rows.append(weight[0] * x)
        jac.append(weight[0] * np.eye(n_par))
        return np.concatenate(rows), np.vstack(jac)

    cache: dict = {}

    def fun(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = residuals(x)
        return cache[key][0]

    def jac(x):
        key = x.tobytes()
        if key not in cache:
            cache.clear()
            cache[key] = residuals(x)
        return cache[key][1]

    message = "no free parameter"
    x = np.zeros(n_par)
    weight = [1e3 * prior]
    for stage in range(2 if n_par else 0):
        cache.clear()
        sol = least_squares(fun, x, jac=jac, method="trf", xtol=1e-15, ftol=1e-15, gtol=1e-15,
                            max_nfev=max_evaluations)
        x, message = sol.x, str(sol.message)
        weight[0] = prior
    segs, _ = _decode(layout, blocks, x)
    lumped = build(layout, segs)
    lumped_hz, err = _relative_errors(lumped, P, conditions, k, erls, shapes_all)
    naive_hz, nerr = _relative_errors(naive, P, conditions, k, erls, shapes_all)

    def per_mode(hz):
        return {c: np.abs(hz[c] / erls[c] - 1.0).max(axis=0) for c in conditions}

    ce, nce = compliance_errors(lumped), compliance_errors(naive)
    mode_mac, mismatched = _shape_check(lumped, P[fit_idx], fit_idx, conditions, shapes_fit,
                                        pair_by_shape)
    fit = LumpedFit(
        lumped=lumped, naive=naive, poses=P, fit_poses=fit_idx, conditions=conditions,
        n_modes=k, erls_hz=erls, lumped_hz=lumped_hz, naive_hz=naive_hz,
        worst_error=float(np.abs(err).max()), mode_errors=per_mode(lumped_hz),
        compliance_error=float(np.abs(ce).max()) if ce.size else 0.0,
        naive_worst_error=float(np.abs(nerr).max()), naive_mode_errors=per_mode(naive_hz),
        naive_compliance_error=float(np.abs(nce).max()) if nce.size else 0.0,
        n_parameters=n_par, n_quantities=n_q,
        determinacy="exactly determined" if n_par >= n_q else "over-determined",
        evaluations=evaluations[0], message=message, mode_mac=mode_mac,
        shape_mismatches=mismatched)
    if mismatched and warn_above is not None:
        c, pose, i, j, own, other = mismatched[0]
        label = "its own" if c == "own" else "locked"
        warnings.warn(LumpedFitWarning(
            f"the lumped mode matched to ERLS mode {i + 1} ({label} joints, pose {pose}) is "
            f"not its shape (MAC {own:.3f}"
            + (f"; it resembles mode {j + 1}: MAC {other:.3f}" if j != i else "")
            + f"); {len(mismatched)} such pair(s): the frequency errors do not describe the "
            "modes; use more segments, fewer modes (--modes)"
            + ("" if layout.axial or layout.planar else ", or axial springs (--axial)")),
            stacklevel=2)
    if warn_above is not None:
        warn_if_off(fit, warn_above, counts)
    return fit


def _erls_shapes(arm, poses, conditions, k: int):
    """``{condition: [ErlsShapes per pose]}``."""
    models = {"own": arm}
    if "locked" in conditions:
        models["locked"] = locked_twin(arm)
    return {c: [ErlsShapes(models[c].modes(q, n_modes=k), k) for q in poses]
            for c in conditions}


def _shape_check(lumped: LumpedArm, poses: np.ndarray, indices, conditions, shapes,
                 by_shape: bool):
    """Smallest matched-pair MAC per mode and condition, and the mismatched pairs."""
    mode_mac, bad = {}, []
    for c in conditions:
        diag = []
        for p, q, erls in zip(indices, poses, shapes[c]):
            k = erls.translations.shape[1]
            phi = lumped.modes(q, c)[1][:, :k]
            if by_shape:
                phi = phi[:, shape_order(lumped, q, phi, erls)]
            mac = mac_matrix(erls.translations,
                             node_translations(lumped, q, phi, erls.positions))
            diag.append(np.diag(mac))
            f = erls.freq_hz
            # within a repeated frequency any basis is a valid set of shapes: no mismatch
            bad += [(c, int(p), *m) for m in mismatches(mac)
                    if abs(f[m[1]] - f[m[0]]) > REPEATED * f[m[0]]]
        mode_mac[c] = np.min(diag, axis=0)
    return mode_mac, tuple(bad)


def warn_if_off(fit: LumpedFit, limit: float, counts: Mapping[str, int]) -> None:
    """Warn (:class:`LumpedFitWarning`) when the fit's errors exceed ``limit``."""
    comp = fit.compliance_error
    if fit.worst_error <= limit and comp <= limit:
        return
    c, mode = max(((c, int(np.argmax(v))) for c, v in fit.mode_errors.items()),
                  key=lambda cm: fit.mode_errors[cm[0]][cm[1]])
    label = "its own" if c == "own" else "locked"
    seg = ", ".join(f"{link}: {n}" for link, n in counts.items())
    worse = (" (worse than the equal-segment chain's "
             f"{100 * fit.naive_worst_error:.3g} %)"
             if fit.worst_error > fit.naive_worst_error else "")
    warnings.warn(LumpedFitWarning(
        f"lumped fit with segments {{{seg}}} misses the ERLS model: worst frequency error "
        f"{100 * fit.worst_error:.3g} % (mode {mode + 1}, {label} joints, over "
        f"{len(fit.poses)} pose(s)){worse}, static compliance error {100 * comp:.3g} %; "
        f"allowed {100 * limit:.3g} %: too few segments for {fit.n_modes} modes; use more "
        "segments (--segments, or --tol to pick them), fewer modes (--modes)"
        + ("" if fit.lumped.layout.axial or fit.lumped.layout.planar
           else ", or axial springs (--axial)")), stacklevel=3)
