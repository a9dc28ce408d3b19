r"""Modes along a motion: follow each mode by its shape, report crossings and veering.

Sorting eigenfrequencies is not tracking. Along a trajectory two modes can *cross* (their
frequencies pass through each other, e.g. an in-plane and an out-of-plane mode of an arm that
moves in a plane, which do not interact) or *veer* (coupled modes approach, exchange their
shapes and move apart again without crossing). "Mode 2" of a sorted list then names different
physical modes at different samples, and a Taylor series of an eigenvalue, which follows its
analytic branch, stops describing the sorted mode it was expanded for.

This module follows every mode by shape. The similarity of two shapes is the mass-weighted
modal assurance criterion

.. math:: \mathrm{MAC}(\phi_a, \phi_b) = \frac{(\phi_a^T M \phi_b)^2}
          {(\phi_a^T M \phi_a)(\phi_b^T M \phi_b)} \in [0, 1],

with ``M`` the mass matrix of the later of the two samples compared. Each sample is matched to
its neighbour towards the reference (a chain, robust to slow drift of the shapes) by the
one-to-one assignment that maximises the summed MAC (the plain best match when it is one to
one, else ``scipy.optimize.linear_sum_assignment``); the MAC against the reference sample's
shapes is kept as data too. All MAC matrices are computed in one batched product.

Public API:

* :func:`track_modes` ``(model, Q, y=None, *, modes=(1,), reference=None, extra=3, ...)``:
  eigenpairs of a :class:`~pinflex.erls.FlexibleModel` along joint samples ``Q`` (and
  designs ``y``: one, or one per sample) and their tracking. ``reference`` is a sample index
  or a point ``(q0, y0)`` off the trajectory (e.g. a Taylor expansion point): mode numbers
  are the sorted numbers **at the reference**, and the path from the reference to the nearest
  sample is walked in small steps so the identity carries over.
* :func:`track` ``(eigvals, shapes, mass=None, *, modes, start=0, ...)``: the same on plain
  arrays (any symmetric generalized eigenproblem sampled along a path), for callers that have
  their own eigenpairs.
* :func:`mac_matrix` ``(phi_a, phi_b, mass=None)``: MAC of every column pair.
* :func:`solver_eigenpairs` and :class:`PoseMap`: the solver-coordinate eigenpairs and the
  map between the coordinates of two samples (``track(..., pose_map=)``).

Both trackers return a :class:`ModeTracking`:

* ``freq_hz`` (ns, k): the tracked frequencies of ``modes`` [Hz] (column c follows mode
  ``modes[c]`` of the reference); ``eigvals`` the same in λ = ω² [rad²/s²];
* ``order`` (ns, k): the sorted (1-based) mode number the tracked mode has at each sample,
  so ``sorted_hz[s, order[s, c] - 1] == freq_hz[s, c]``; ``permutation`` (ns, n) the same
  for every tracked mode (a permutation of ``0..n-1`` per sample);
* ``mac_step`` (ns, k): MAC of each tracked mode with itself at the previous sample of the
  walk (1 at the reference); ``mac_reference`` (ns, k): MAC against the reference shapes;
* ``events``: :class:`ModeEvent` records, ``kind`` one of

  - ``"crossing"``: two tracked modes exchange their sorted positions between samples
    ``sample - 1`` and ``sample`` (a MAC swap);
  - ``"veering"``: two modes that are neighbours in frequency come within ``veer_rtol``
    (relative) of each other at ``sample`` without swapping, and their shapes rotate: the
    MAC of a mode's shape before and after the approach (where the gap has doubled, or the
    ends of the trajectory) is below ``veer_mac``;
  - ``"ambiguous"``: a step's best match has ``MAC < mac_min``: the sampling is too coarse
    to follow that mode (refine the trajectory near ``sample``);

* ``crossings(mode)`` / ``veerings(mode)``: the events that involve a mode;
  ``changes_identity(mode)``: whether the sorted number of a mode differs from its
  reference number anywhere (then sorted and tracked results differ).

Mode numbers are non-rigid modes, 1 = lowest. Shapes of a :class:`FlexibleModel` are the
elastic coordinates (beam axes of each link, so they change smoothly with the pose) with the
rigid coordinates condensed out, mass-normalised with the condensed mass matrix — the same
reduced problem as :meth:`~pinflex.erls.FlexibleModel.frequencies`.

Where the conditioned solve (:mod:`pinflex.erls.solve`) covers the model, the eigenpairs come
from it (:func:`solver_eigenpairs`: one batched symmetric eigensolve of the condensed
solver-coordinate mass per sample, no nodal matrices): its coordinates ``w`` map to the nodal
ones by ``x = T(q) w`` with ``T`` depending on the pose, so a shape is compared with another
sample's only after :class:`PoseMap` has expressed it in that sample's coordinates
(``T(q_t)⁻¹ T(q_s) φ``, per link with a constant 6-column map). The MACs are then the nodal
ones (equal to round-off), so crossings, veering and ambiguous steps are decided exactly as
on the nodal pencil; comparing the unmoved solver vectors instead would not be (benchmark A:
0.990 between neighbouring samples where the shapes agree to 0.99999).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from pinflex.checks import check_q, check_y
from pinflex.erls.eigenpairs import PoseMap, eigenpairs, solver_eigenpairs
from pinflex.exceptions import ConfigurationError
from pinflex.progress import ProgressBar
from pinflex.resources import check_poses

__all__ = [
    "ModeEvent",
    "ModeTracking",
    "PoseMap",
    "eigenpairs",
    "mac_matrix",
    "solver_eigenpairs",
    "track",
    "track_modes",
]


@dataclass(frozen=True)
class ModeEvent:
    """One event along a tracked motion.

    Attributes:
        kind: ``"crossing"``, ``"veering"`` or ``"ambiguous"`` (see :mod:`pinflex.erls.tracking`).
        sample: Trajectory sample of the event (for a crossing, the first sample after it).
        modes: Reference mode numbers involved (1 = lowest at the reference); one number for
            ``"ambiguous"``.
        freq_hz: Their tracked frequencies at ``sample`` [Hz].
        gap: Smallest relative frequency gap of the pair near the event (0 for ambiguous).
        mac: For a crossing or ambiguous step, the MAC of the chosen match; for veering, the
            MAC of the shape before and after the approach.
    """

    kind: str
    sample: int
    modes: tuple[int, ...]
    freq_hz: tuple[float, ...]
    gap: float
    mac: float


@dataclass(frozen=True)
class ModeTracking:
    """Modes followed by shape along a motion (see :mod:`pinflex.erls.tracking`).

    Attributes:
        modes: Reference mode numbers reported in ``freq_hz`` (1 = lowest at the reference).
        eigvals: Tracked eigenvalues λ [rad²/s²], (ns, len(modes)).
        order: Sorted mode number (1-based) of each tracked mode at each sample, (ns, k).
        sorted_eigvals: Sorted eigenvalues of every tracked mode slot, (ns, n).
        permutation: ``permutation[s, r]`` = sorted index (0-based) at sample s of the mode
            that has sorted index r at the reference, (ns, n).
        mac_step: MAC with the previous sample of the walk, (ns, k).
        mac_reference: MAC against the reference shapes, (ns, k).
        events: Crossings, veering and ambiguous steps, sorted by sample.
        reference: Sample index the walk started from (the nearest sample to an off-trajectory
            reference point).
    """

    modes: tuple[int, ...]
    eigvals: np.ndarray
    order: np.ndarray
    sorted_eigvals: np.ndarray
    permutation: np.ndarray
    mac_step: np.ndarray
    mac_reference: np.ndarray
    events: tuple[ModeEvent, ...] = field(default=())
    reference: int = 0

    @property
    def freq_hz(self) -> np.ndarray:
        """Tracked frequencies [Hz], (ns, len(modes))."""
        return np.sqrt(np.maximum(self.eigvals, 0.0)) / (2.0 * np.pi)

    @property
    def sorted_hz(self) -> np.ndarray:
        """Sorted frequencies [Hz] of all tracked slots, (ns, n)."""
        return np.sqrt(np.maximum(self.sorted_eigvals, 0.0)) / (2.0 * np.pi)

    def _involving(self, kind: str, mode: int | None) -> list[ModeEvent]:
        return [e for e in self.events if e.kind == kind and (mode is None or mode in e.modes)]

    def crossings(self, mode: int | None = None) -> list[ModeEvent]:
        """Crossing events, all or those involving reference mode ``mode``."""
        return self._involving("crossing", mode)

    def veerings(self, mode: int | None = None) -> list[ModeEvent]:
        """Veering events, all or those involving reference mode ``mode``."""
        return self._involving("veering", mode)

    def ambiguous(self, mode: int | None = None) -> list[ModeEvent]:
        """Steps where a mode could not be matched with confidence."""
        return self._involving("ambiguous", mode)

    def changes_identity(self, mode: int) -> bool:
        """Whether reference mode ``mode`` has another sorted number at some sample."""
        return bool(np.any(self.permutation[:, mode - 1] != mode - 1))


def mac_matrix(phi_a: np.ndarray, phi_b: np.ndarray, mass: np.ndarray | None = None
               ) -> np.ndarray:
    """Mass-weighted MAC of every column of ``phi_a`` (n, ka) with every column of ``phi_b``.

    Args:
        phi_a: Shapes (n, ka).
        phi_b: Shapes (n, kb).
        mass: Symmetric positive definite weight (n, n); identity when omitted.

    Returns:
        (ka, kb) values in [0, 1].
    """
    phi_a = np.asarray(phi_a, dtype=float)
    phi_b = np.asarray(phi_b, dtype=float)
    ma = phi_a if mass is None else mass @ phi_a
    mb = phi_b if mass is None else mass @ phi_b
    cross = phi_a.T @ mb
    na = np.einsum("ik,ik->k", phi_a, ma)
    nb = np.einsum("ik,ik->k", phi_b, mb)
    return cross**2 / np.outer(na, nb)


def track(
    eigvals: np.ndarray,
    shapes: np.ndarray,
    mass: np.ndarray | None = None,
    *,
    modes: Sequence[int] = (1,),
    start: int = 0,
    start_shapes: np.ndarray | None = None,
    mac_min: float = 0.5,
    veer_rtol: float = 0.05,
    veer_mac: float = 0.5,
    pose_map: PoseMap | None = None,
) -> ModeTracking:
    """Follow modes by shape through sampled eigenpairs.

    Args:
        eigvals: Sorted eigenvalues (ns, n) [rad²/s²] (any monotone quantity works).
        shapes: Shapes (ns, ndof, n), columns in the order of ``eigvals``.
        mass: Mass matrices (ns, ndof, ndof) for the MAC weight; identity when omitted.
        modes: Mode numbers (1-based, at sample ``start``) to report; every one of the n
            slots is tracked, so keep a few modes above the highest requested one.
        start: Sample where the numbering is defined.
        start_shapes: Shapes (ndof, n) that define the numbering instead of those of
            ``start`` (e.g. from an off-trajectory reference point); sample ``start`` is
            then matched to them first.
        mac_min: A match below this MAC is reported as ``"ambiguous"``.
        veer_rtol: Relative gap under which neighbouring modes count as approaching.
        veer_mac: Shape-rotation threshold of a veering (MAC before vs after).
        pose_map: When the shapes of each sample are in coordinates of their own (solver
            coordinates, see :class:`PoseMap`), the map that expresses a shape of one sample
            in the coordinates of another; every MAC then compares the shapes in the
            coordinates of the sample whose mass weights it. ``start_shapes`` must be in the
            coordinates of sample ``start``.

    Returns:
        A :class:`ModeTracking`.
    """
    lam, phi, modes, mass = _track_inputs(eigvals, shapes, mass, modes, start)
    ns, n = lam.shape

    def weight(s):
        return None if mass is None else mass[s]

    def moved(x, src, dst):  # shapes of samples src in the coordinates of samples dst
        return x if pose_map is None else pose_map.move(x, src, dst)

    perm, mac_step = _walk(phi, mass, start, start_shapes, pose_map)
    ambiguous: list[tuple[int, int, float]] = []
    for r in range(n):
        bad = np.flatnonzero(mac_step[:, r] < mac_min)
        ambiguous.extend((int(s), r, float(mac_step[s, r])) for s in bad)
    mac_ref = _reference_macs(phi, mass, perm, start, pose_map)
    tracked = np.take_along_axis(lam, perm, axis=1)  # (ns, n) by slot
    events = _events(lam, phi, weight, perm, tracked, start, ambiguous, veer_rtol, veer_mac,
                     mac_step, moved)
    cols = [m - 1 for m in modes]
    return ModeTracking(
        modes=tuple(modes),
        eigvals=tracked[:, cols],
        order=perm[:, cols] + 1,
        sorted_eigvals=lam,
        permutation=perm,
        mac_step=mac_step[:, cols],
        mac_reference=mac_ref[:, cols],
        events=tuple(sorted(events, key=lambda e: (e.sample, e.kind, e.modes))),
        reference=int(start),
    )


def _track_inputs(eigvals, shapes, mass, modes, start):
    """:func:`track`'s inputs checked: eigenvalues, shapes, mode numbers, masses."""
    lam = np.asarray(eigvals, dtype=float)
    phi = np.asarray(shapes, dtype=float)
    if lam.ndim != 2 or phi.ndim != 3 or phi.shape[0] != lam.shape[0] or \
            phi.shape[2] != lam.shape[1]:
        raise ConfigurationError(
            f"eigvals (ns, n) and shapes (ns, ndof, n) do not match: {lam.shape}, {phi.shape}"
        )
    ns, n = lam.shape
    modes = tuple(int(m) for m in np.atleast_1d(modes))
    if not modes or min(modes) < 1 or max(modes) > n:
        raise ConfigurationError(f"modes {modes} must lie in 1..{n} (the tracked modes)")
    if not 0 <= start < ns:
        raise ConfigurationError(f"start sample {start} is not in 0..{ns - 1}")
    if mass is not None:
        mass = np.asarray(mass, dtype=float)
        if mass.shape != (ns, phi.shape[1], phi.shape[1]):
            raise ConfigurationError(
                f"mass has shape {mass.shape}; expected {(ns, phi.shape[1], phi.shape[1])}"
            )
    return lam, phi, modes, mass


def _walk(phi, mass, start, start_shapes, pose_map):
    """Slot permutation (ns, n) from sample ``start`` both ways, and the MAC of each step.

    Slot r is the reference sorted index r; ``perm[s, r]`` its sorted index at sample s.
    """
    ns, _, n = phi.shape
    perm = np.full((ns, n), -1, dtype=int)
    mac_step = np.ones((ns, n))
    if start_shapes is None:
        perm[start] = np.arange(n)
    else:
        C0 = mac_matrix(np.asarray(start_shapes, dtype=float), phi[start],
                        None if mass is None else mass[start])
        rows, cols = linear_sum_assignment(-C0)
        perm[start, rows] = cols
        mac_step[start, rows] = C0[rows, cols]
    # MAC of sorted modes between consecutive samples, all steps at once: C[s] pairs the
    # sorted modes of sample s (rows) with those of s + 1 (columns), weighted with M[s + 1].
    C = _step_macs(phi, mass, None if pose_map is None else
                   pose_map.move(phi[:-1], np.arange(ns - 1), np.arange(1, ns)))
    fwd, bwd = _step_maps(C)  # sorted index at s -> at s + 1, and back
    ident = np.all(fwd == np.arange(n), axis=1)  # steps that keep every sorted index
    perm[start:] = perm[start]
    for s in np.flatnonzero(~ident[start:]) + start:  # forward: s -> s + 1
        perm[s + 1:] = fwd[s][perm[s]]
    perm[:start] = perm[start]
    for s in np.flatnonzero(~ident[:start])[::-1]:  # backward: s + 1 -> s
        perm[: s + 1] = bwd[s][perm[s + 1]]
    if ns > 1:
        steps = np.arange(ns - 1)[:, None]
        macs = C[steps, perm[:-1], perm[1:]]  # step s -> s + 1, (ns - 1, n)
        mac_step[start + 1:] = macs[start:]
        mac_step[:start] = macs[:start]
    return perm, mac_step


def _reference_macs(phi, mass, perm, start, pose_map):
    """MAC (ns, n) of each slot's tracked shape with its reference shape at ``start``."""
    ns, _, n = phi.shape
    ref_shapes = phi[start][:, perm[start]]  # reference shape of each slot, at `start`
    if pose_map is not None:  # shapes in coordinates of their own sample: move the reference
        ref_at = pose_map.move(np.broadcast_to(ref_shapes, (ns,) + ref_shapes.shape), start,
                               np.arange(ns))  # (ns, ndof, n)
        Mref = ref_at if mass is None else mass @ ref_at
        cross = np.swapaxes(Mref, 1, 2) @ phi
        nref = np.einsum("sir,sir->sr", Mref, ref_at)
    elif mass is None:
        cross = np.einsum("ir,sik->srk", ref_shapes, phi)
        nref = np.einsum("ir,ir->r", ref_shapes, ref_shapes)[None, :]
        nref = np.broadcast_to(nref, (ns, n))
    else:
        Mref = mass @ ref_shapes  # (ns, ndof, n)
        cross = np.einsum("sir,sik->srk", Mref, phi)
        nref = np.einsum("sir,ir->sr", Mref, ref_shapes)
    nphi = np.einsum("sik,sik->sk", phi, phi if mass is None else mass @ phi)
    idx = np.arange(ns)[:, None], np.arange(n)[None, :], perm
    return cross[idx] ** 2 / (nref * np.take_along_axis(nphi, perm, axis=1))


def _step_macs(phi: np.ndarray, mass: np.ndarray | None, a: np.ndarray | None = None
               ) -> np.ndarray:
    """MAC matrices (ns − 1, n, n) between the sorted shapes of samples s and s + 1.

    ``a``: the shapes of samples 0..ns−2 in the coordinates of samples 1..ns−1 (default: the
    shapes themselves, one set of coordinates for all samples).
    """
    a = phi[:-1] if a is None else a
    b = phi[1:]
    mb = b if mass is None else mass[1:] @ b
    ma = a if mass is None else mass[1:] @ a
    cross = np.swapaxes(a, 1, 2) @ mb
    na = np.einsum("sik,sik->sk", a, ma)
    nb = np.einsum("sik,sik->sk", b, mb)
    return cross**2 / (na[:, :, None] * nb[:, None, :])


def _step_maps(C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Best one-to-one maps of sorted indices across each step, forward and backward.

    Where each row's best MAC is also its column's best (the usual case) that is the map;
    otherwise the assignment maximising the summed MAC (Hungarian algorithm).
    """
    nstep, n, _ = C.shape
    fwd = np.argmax(C, axis=2)
    clean = np.all(np.sort(fwd, axis=1) == np.arange(n), axis=1)
    clean &= np.all(np.argmax(C, axis=1) == np.argsort(fwd, axis=1), axis=1)
    for s in np.flatnonzero(~clean):
        rows, cols = linear_sum_assignment(-C[s])
        fwd[s, rows] = cols
    bwd = np.argsort(fwd, axis=1)
    return fwd, bwd


def _events(lam, phi, weight, perm, tracked, start, ambiguous, veer_rtol, veer_mac, mac_step,
            moved):
    ns, n = lam.shape
    events: list[ModeEvent] = []
    f = np.sqrt(np.maximum(tracked, 0.0)) / (2.0 * np.pi)
    for s, r, mac in ambiguous:
        events.append(ModeEvent("ambiguous", s, (r + 1,), (float(f[s, r]),), 0.0, mac))
    # crossings: the sorted order of two slots flips between consecutive samples
    above = perm[:, :, None] > perm[:, None, :]  # (ns, n, n): slot a sorted above slot b
    flips = np.triu(above[1:] != above[:-1], k=1)
    for s, a, b in zip(*np.nonzero(flips)):
        s, a, b = int(s) + 1, int(a), int(b)
        gap = min(abs(f[t, a] - f[t, b]) / max(f[t, a], f[t, b]) for t in (s - 1, s))
        events.append(ModeEvent(
            "crossing", s, (a + 1, b + 1), (float(f[s, a]), float(f[s, b])),
            float(gap), float(min(mac_step[s, a], mac_step[s, b])),
        ))
    # veering: sorted neighbours approach within veer_rtol and exchange shape character
    if ns >= 3:
        fs = np.sqrt(np.maximum(lam, 0.0))
        gaps = (fs[:, 1:] - fs[:, :-1]) / fs[:, :-1]  # relative frequency gap of sorted i, i+1
        inv = np.argsort(perm, axis=1)  # sorted index -> slot
        close = (gaps[1:-1] <= gaps[:-2]) & (gaps[1:-1] < gaps[2:]) & (gaps[1:-1] < veer_rtol)
        for s, i in zip(*(np.nonzero(close))):  # local minima of a neighbour gap
            s, i = int(s) + 1, int(i)
            g = gaps[:, i]
            a, b = sorted((int(inv[s, i]), int(inv[s, i + 1])))
            left, right = s, s
            while left > 0 and g[left - 1] < 2 * g[s] and g[left - 1] >= g[left]:
                left -= 1
            while right < ns - 1 and g[right + 1] < 2 * g[s] and g[right + 1] >= g[right]:
                right += 1
            left, right = max(left - 1, 0), min(right + 1, ns - 1)
            if np.any(np.sign(perm[left:right + 1, a] - perm[left:right + 1, b])
                      != np.sign(perm[s, a] - perm[s, b])):
                continue  # the pair swaps here: a crossing, reported above
            # the mode's own shape before and after the approach
            C = mac_matrix(moved(phi[left][:, [perm[left, a]]], left, right),
                           phi[right][:, [perm[right, a]]], weight(right))
            mac = float(C[0, 0])
            if mac < veer_mac:
                events.append(ModeEvent(
                    "veering", int(s), (a + 1, b + 1),
                    (float(f[s, a]), float(f[s, b])), float(g[s]), mac,
                ))
    return events


def track_modes(
    model,
    Q,
    y=None,
    *,
    modes: Sequence[int] = (1,),
    reference=None,
    extra: int = 3,
    mac_min: float = 0.5,
    veer_rtol: float = 0.05,
    veer_mac: float = 0.5,
    check_bounds: bool = True,
    coordinates: str = "auto",
    progress: ProgressBar | None = None,
) -> ModeTracking:
    """Track modes of a FlexibleModel by shape along joint samples.

    Args:
        model: A :class:`~pinflex.erls.FlexibleModel`.
        Q: Joint samples (ns, nv), user coordinates, in the order of the motion.
        y: Design values (ny,) or one per sample (ns, ny) [kg] (default nominal).
        modes: Non-rigid mode numbers to report (1 = lowest at the reference).
        reference: Where mode numbers are defined: ``None`` (sample 0), a sample index, or a
            point ``(q0, y0)`` (``y0`` may be ``None``: the design ``y`` of the nearest
            sample), e.g. a Taylor model's expansion point. From a point the walk goes in
            straight steps (in joints and design) to the nearest sample, as fine as the
            trajectory's own median step, then along the trajectory both ways.
        extra: Modes tracked above the highest requested one (a mode can leave the lowest
            ones only if its partner is tracked).
        mac_min: See :func:`track`.
        veer_rtol: See :func:`track`.
        veer_mac: See :func:`track`.
        check_bounds: Refuse design values outside their bounds.
        coordinates: ``"solver"``: eigenpairs of the conditioned solve (the one
            :meth:`~pinflex.erls.FlexibleModel.frequencies` uses), shapes compared through
            :class:`PoseMap` (the same MACs as in nodal coordinates); ``"nodal"``: eigenpairs
            of the nodal-coordinate pencil (:func:`eigenpairs`); ``"auto"`` (default): solver
            where the conditioned solve covers the model and resolves the modes, else nodal.
        progress: A progress bar advanced by one per sample solved (optional; its total
            should be the number of samples). The samples are solved in chunks of
            ``_CHUNK``; when the solver coordinates give way to nodal ones the bar starts
            again.

    Returns:
        A :class:`ModeTracking`; ``sorted_eigvals`` holds the lowest ``max(modes) + extra``
        modes.
    """
    Q = np.atleast_2d(check_q(model, Q))
    ns = Q.shape[0]
    Y = check_y(model, y, bounds=check_bounds)
    Yb = np.broadcast_to(Y, (ns, model.ny)) if Y.ndim == 1 else Y
    if Yb.shape[0] != ns:
        raise ConfigurationError(f"got {Yb.shape[0]} design vectors for {ns} samples")
    modes = tuple(int(m) for m in np.atleast_1d(modes))
    if not modes or min(modes) < 1 or max(modes) > model.n_elastic:
        raise ConfigurationError(f"modes {modes} must lie in 1..{model.n_elastic}")
    n = min(model.n_elastic, max(modes) + max(int(extra), 0))
    if coordinates not in ("auto", "solver", "nodal"):
        raise ConfigurationError(f"coordinates = {coordinates!r}: use 'auto', 'solver' or "
                                 "'nodal'")
    solver = coordinates != "nodal"
    pairs = _pairs(model, Q, Y if Y.ndim == 1 else Yb, n, check_bounds, solver,
                   progress=progress)
    if pairs is None:
        if coordinates == "solver":
            raise ConfigurationError("the conditioned solve does not cover this model or "
                                     "does not resolve the tracked modes: use "
                                     "coordinates='nodal' or 'auto'")
        solver = False
        _restart(progress)
        pairs = _pairs(model, Q, Yb, n, check_bounds, False, progress=progress)
    assert pairs is not None
    lam, phi, mass, pose_map = pairs
    start, start_shapes = 0, None
    if reference is not None and not isinstance(reference, tuple) and np.ndim(reference) == 0:
        start = int(reference)
        if not 0 <= start < ns:
            raise ConfigurationError(f"reference sample {start} is not in 0..{ns - 1}")
    elif reference is not None:
        q0, y0 = reference
        q0 = check_q(model, q0)
        start = int(np.argmin(np.linalg.norm(Q - q0, axis=1)))
        y0 = Yb[start] if y0 is None else check_y(model, y0, bounds=check_bounds)
        start_shapes = _lead_in(model, Q, Yb, start, q0, y0, n, mac_min, check_bounds, solver)
        if start_shapes is None:  # the lead-in left the conditioned solve: all nodal
            if coordinates == "solver":
                raise ConfigurationError("the conditioned solve does not resolve the tracked "
                                         "modes on the way from the reference point: use "
                                         "coordinates='nodal' or 'auto'")
            _restart(progress)
            return track_modes(model, Q, y, modes=modes, reference=reference, extra=extra,
                               mac_min=mac_min, veer_rtol=veer_rtol, veer_mac=veer_mac,
                               check_bounds=check_bounds, coordinates="nodal",
                               progress=progress)
    return track(lam, phi, mass, modes=modes, start=start, start_shapes=start_shapes,
                 mac_min=mac_min, veer_rtol=veer_rtol, veer_mac=veer_mac, pose_map=pose_map)


_CHUNK = 128  # samples per batched eigensolve (paces the progress bar, bounds temporaries)


def _restart(progress: ProgressBar | None) -> None:
    if progress is not None:
        progress.done = 0


def _pairs(model, Q, Y, n, check_bounds, solver, one_pose=False, progress=None):
    """``(eigvals, shapes, mass, pose_map)`` of the samples; None if solver coordinates fail.

    Solved in chunks of ``_CHUNK`` samples (each sample's eigenproblem is its own, so the
    result is the one batched solve's); ``progress`` advances by the samples of each chunk.
    """
    ns = Q.shape[0]
    if one_pose or ns <= _CHUNK:
        parts = [_pairs_once(model, Q, Y, n, check_bounds, solver, one_pose)]
        if progress is not None:
            progress.update(ns)
    else:
        parts = []
        for a in range(0, ns, _CHUNK):
            b = min(a + _CHUNK, ns)
            part = _pairs_once(model, Q[a:b], Y if Y.ndim == 1 else Y[a:b], n, check_bounds,
                               solver, False)
            if progress is not None:
                progress.update(b - a)
            parts.append(part)
            if part is None:
                break
    if any(p is None for p in parts):
        return None
    if len(parts) == 1:
        return parts[0]
    lam, phi, mass = (np.concatenate([p[i] for p in parts]) for i in range(3))
    maps = [p[3] for p in parts]
    return lam, phi, mass, None if maps[0] is None else PoseMap.joined(maps)


def _pairs_once(model, Q, Y, n, check_bounds, solver, one_pose):
    if solver:
        return solver_eigenpairs(model, Q, Y, n_modes=n, one_pose=one_pose)
    return (*eigenpairs(model, Q, Y, n_modes=n, check_bounds=check_bounds), None)


def _lead_in(model, Q, Y, start, q0, y0, n, mac_min, check_bounds, solver):
    """Shapes at ``Q[start]`` numbered as at the point (q0, y0), walked in small steps.

    In solver coordinates (``solver``) the last walk point is the pose of ``Q[start]``, so its
    shapes are in that sample's coordinates; None when the walk leaves the conditioned solve.
    """
    qs, ys = Q[start], Y[start]
    if Q.shape[0] > 1:
        step = float(np.median(np.linalg.norm(np.diff(Q, axis=0), axis=1)))
    else:
        step = 0.0
    dq = float(np.linalg.norm(qs - q0))
    # design moves are walked in 20 steps per full span of the bounds
    span = np.array([max(d.upper - d.lower, 1e-12) if np.isfinite(d.upper - d.lower) else
                     max(abs(d.nominal), 1.0) for d in model.design])
    dy = float(np.max(np.abs(ys - y0) / span)) if model.ny else 0.0
    nsteps = float(np.ceil(max(dq / step if step > 0 else 0.0, 20.0 * dy, 1.0)))
    nsteps = check_poses(nsteps, model.ndof, f"the walk of {dq:.3g} from the expansion point "
                         "to the trajectory's first sample (in steps of the trajectory's)",
                         "expand at a point nearer the trajectory (q0)", maximum=20_000)
    t = np.linspace(0.0, 1.0, nsteps + 1)[:, None]
    Qp = q0 + t * (qs - q0)
    Yp = y0 + t * (ys - y0)
    Qp[-1] = qs  # the sample's own pose (its solver coordinates)
    one_pose = dq <= 1e-12 * (1.0 + float(np.linalg.norm(qs)))  # a walk in the design only
    if one_pose:
        Qp[:] = qs
    if solver:
        Yp = check_y(model, Yp, bounds=check_bounds)
    pairs = _pairs(model, Qp, Yp, n, check_bounds, solver, one_pose)
    if pairs is None:
        return None
    lam, phi, mass, pose_map = pairs
    walk = track(lam, phi, mass, modes=tuple(range(1, n + 1)), start=0, mac_min=mac_min,
                 pose_map=pose_map)
    # shapes of the last lead-in point, ordered by the reference's numbering
    return phi[-1][:, walk.permutation[-1]]
