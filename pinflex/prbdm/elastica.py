r"""Geometrically exact planar elastica of a beam under dead end loads (the deflection truth).

Equations along the arc length s (x along the undeformed beam, z transverse, :math:`\phi` the
section rotation about +Y, so that :math:`z' = -\sin\phi`):

.. math::

    x' = \cos\phi,\quad z' = -\sin\phi,\quad \phi' = M / EI(s),\quad
    M' = F_x \sin\phi + F_z \cos\phi,

with the beam clamped at s = 0 (:math:`\phi(0) = 0`) and, at the end s = L, a dead force
:math:`(F_x, F_z)` (its direction kept as the beam deflects) and

* **cantilever**: an applied end moment :math:`M(L) = M_L` (positive turns +X towards -Z;
  zero for a tip force alone); the unknown is the end rotation :math:`\phi_L`;
* **fixed-guided**: the end rotation held, :math:`\phi(L) = 0`, the end free to translate; the
  unknown is the end's reaction moment :math:`M(L)`.

Both are solved by shooting from the end to the root, piecewise between planform vertices,
with Newton's method on :math:`\phi(0) = 0` using the exact variational derivative, and by
continuation in the load from zero along the stable branch (:func:`end_load_equilibrium`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

from ..exceptions import InvalidBeam, TruthNotConverged
from .beams import Planform, equivalent_bending_stiffness

#: End conditions of the deflection truth and of the chain statics.
BOUNDARIES = ("cantilever", "fixed-guided")


@dataclass(frozen=True)
class ElasticaSolution:
    """Large-deflection equilibrium of the beam under dead end loads.

    Attributes:
        force_n: End force (Fx, Fz) in the bending plane [N].
        tip_m: Deformed end position (x, z) [m]; the undeformed end is (L, 0).
        tip_rotation_rad: End section rotation about +Y [rad] (positive turns x towards -z;
            zero for a fixed-guided end).
        root_moment_nm: Bending moment about +Y at the root [N m].
        length_m: Beam length L [m].
        moment_nm: Applied end moment [N m] (cantilever; 0 for a fixed-guided end).
        boundary: ``"cantilever"`` or ``"fixed-guided"``.
        end_moment_nm: Bending moment at the end [N m]: the applied moment of a cantilever,
            the guide's reaction moment of a fixed-guided beam.
    """

    force_n: np.ndarray
    tip_m: np.ndarray
    tip_rotation_rad: float
    root_moment_nm: float
    length_m: float
    moment_nm: float = 0.0
    boundary: str = "cantilever"
    end_moment_nm: float = 0.0

    @property
    def tip_displacement_m(self) -> np.ndarray:
        """Tip displacement from the undeformed tip (dx, dz) [m]."""
        return self.tip_m - np.array([self.length_m, 0.0])


def _integrate_elastica(planform: Planform, force: np.ndarray, end_state: tuple[float, float],
                        variation: tuple[float, float], rtol: float
                        ) -> tuple[np.ndarray, np.ndarray]:
    r"""Shoot from the end to the root for a trial end state.

    Integrates :math:`(x, z, \phi, M)` from :math:`(0, 0, \phi_L, M_L)` and the variational
    pair :math:`(h, \mu)` from ``variation`` (``(1, 0)``: the derivative by :math:`\phi_L`;
    ``(0, 1)``: by :math:`M_L`) backwards from the end; positions are relative to the end.

    Returns:
        The root state (x, z, phi, M, h, mu) and (min phi, max phi, min h, max h) over the
        beam, the extremes of h taken without the end point itself.
    """
    fx, fz = float(force[0]), float(force[1])
    e = planform.material.youngs_modulus_pa
    x_v = planform.x_m
    # EI is linear in s between vertices when the thickness is uniform: EI = ei_b + k (s - b).
    ei_v = e * planform.area_moment_m4(x_v)
    linear = planform.thickness_profile_m is None
    cos, sin = math.cos, math.sin

    def piece_rhs(b: float, ei_b: float, k: float):
        def rhs(s, y):
            c, sn = cos(y[2]), sin(y[2])
            ei = ei_b + k * (s - b)
            return [c, -sn, y[3] / ei, sn * fx + c * fz, y[5] / ei, (c * fx - sn * fz) * y[4]]
        return rhs

    def rhs_general(s, y):
        c, sn = np.cos(y[2]), np.sin(y[2])
        ei = e * planform.area_moment_m4(s)
        return [c, -sn, y[3] / ei, sn * fx + c * fz, y[5] / ei, (c * fx - sn * fz) * y[4]]

    state = np.array([0.0, 0.0, end_state[0], end_state[1], variation[0], variation[1]])
    low, high = end_state[0], end_state[0]
    h_min, h_max = np.inf, -np.inf
    for j in range(x_v.size - 1, 0, -1):
        a, b = float(x_v[j]), float(x_v[j - 1])
        rhs = piece_rhs(b, float(ei_v[j - 1]), float((ei_v[j] - ei_v[j - 1]) / (a - b))) \
            if linear else rhs_general
        sol = solve_ivp(rhs, (a, b), state, method="DOP853", rtol=rtol, atol=rtol * 1e-3)
        if not sol.success:
            raise TruthNotConverged(f"elastica integration failed on [{b:g}, {a:g}] m: "
                                    f"{sol.message}")
        state = sol.y[:, -1]
        low, high = min(low, float(sol.y[2].min())), max(high, float(sol.y[2].max()))
        h_piece = sol.y[4, 1:]
        h_min = min(h_min, float(h_piece.min()))
        h_max = max(h_max, float(h_piece.max()))
    return state, np.array([low, high, h_min, h_max])


def check_end_loads(force_n, moment_nm, boundary: str,
                    error: type[Exception]) -> tuple[np.ndarray, float]:
    """The end force (2,) [N] and moment [N m], checked; ``error`` names what is wrong.

    Raises:
        error: If the force is not a finite (Fx, Fz) pair, the moment not finite, the boundary
            unknown, or a moment applied to a fixed-guided end (the guide takes it).
    """
    force = np.asarray(force_n, dtype=float)
    if force.shape != (2,) or not np.all(np.isfinite(force)):
        raise error(f"force_n must be a finite (Fx, Fz) pair [N], got {force_n!r}")
    moment = float(moment_nm)
    if not np.isfinite(moment):
        raise error(f"moment_nm = {moment_nm!r} must be a finite end moment [N m]")
    if boundary not in BOUNDARIES:
        raise error(f"boundary = {boundary!r}; expected one of {BOUNDARIES}")
    if boundary == "fixed-guided" and moment != 0.0:
        raise error("a fixed-guided end holds its rotation and takes no applied moment (the "
                    f"guide's moment is a reaction): got moment_nm = {moment:g}")
    return force, moment


class _Shooting:
    """The end-load shooting problem in one unknown u (nondimensional end state)."""

    def __init__(self, planform: Planform, force: np.ndarray, moment: float, boundary: str,
                 rtol: float):
        self.planform, self.force, self.moment = planform, force, moment
        self.guided = boundary == "fixed-guided"
        self.rtol = rtol
        # The guided unknown is the end moment, scaled to M L / EI_eq (about the end rotation).
        self.scale = equivalent_bending_stiffness(planform) / planform.length_m

    def integrate(self, u: float, fraction: float):
        force = fraction * self.force
        if self.guided:
            return _integrate_elastica(self.planform, force, (0.0, u * self.scale), (0.0, 1.0),
                                       self.rtol)
        return _integrate_elastica(self.planform, force, (u, fraction * self.moment),
                                   (1.0, 0.0), self.rtol)

    def newton(self, u: float, fraction: float, max_iter: int = 12):
        """Newton on the clamp condition phi(0) = 0 from u; None if it fails.

        Converged when the step is below 1e-12, or below 1e-9 (1 + |u|) and no longer
        shrinking (the integration's round-off floor: large rotations carry rtol |u|).
        """
        previous = np.inf
        for _ in range(max_iter):
            state, extremes = self.integrate(u, fraction)
            slope = state[4] * (self.scale if self.guided else 1.0)
            if not np.all(np.isfinite(state)) or slope == 0.0 or \
                    (not self.guided and state[4] <= 0.0):
                return None
            step = state[2] / slope
            size = abs(step)
            if size <= 1e-12 or (size <= 1e-9 * (1.0 + abs(u)) and size > 0.25 * previous):
                # Converged: the state belongs to this u (clamp residual <= step x slope).
                return u, state, extremes
            previous = size
            u = u - step
        return None

    def linear_guess(self, fraction: float) -> float:
        """Linear theory of a uniform beam for the unknown at this load fraction."""
        length = self.planform.length_m
        ei = self.scale * length
        fz = fraction * float(self.force[1])
        if self.guided:
            # M(s) = M_L + Fz (s - L) and phi(L) = 0 give M_L = Fz L / 2.
            return 0.5 * fz * length / self.scale
        return (-0.5 * fz * length**2 + fraction * self.moment * length) / ei

    def stable(self, extremes: np.ndarray) -> bool:
        """No conjugate point: the Jacobi field of the end variation keeps its sign."""
        if self.guided:
            # h(L) = 0, h' > 0 there: h < 0 on [0, L) (backwards from the end).
            return bool(extremes[3] < 0.0)
        return bool(extremes[2] > 0.0)


def end_load_equilibrium(planform: Planform, force_n: np.ndarray, moment_nm: float = 0.0,
                         boundary: str = "cantilever", rtol: float = 1e-11,
                         max_load_step: float = 2.0) -> ElasticaSolution:
    r"""Planar elastica of the clamped beam under a dead end force and end moment.

    Large loads admit several equilibria. The stable branch is followed by continuation in the
    load from zero: the load (force and moment together) grows in steps of at most
    ``max_load_step`` in :math:`\sqrt{\lambda}` (:math:`\lambda = \max(\alpha, |\beta|)` with
    :math:`\alpha = |F| L^2 / EI_{eq}` and :math:`\beta = M L / EI_{eq}`), each step predicted
    by extrapolating the unknown (end rotation, or the guided end's moment); a step whose
    Newton fails or lands far from the prediction is halved. The answer must be stable: the
    Jacobi field of the end variation (:math:`h = \partial\phi/\partial\phi_L`, or
    :math:`\partial\phi/\partial M_L` for a guided end) has no zero on the beam (no conjugate
    point). Under a force alone (no moment) it must also lie on the physical branch: every
    section rotation between the undeformed axis and the force direction. Otherwise
    TruthNotConverged is raised.

    Args:
        planform: The beam.
        force_n: End force (Fx, Fz) [N]; it keeps its direction as the beam deflects.
        moment_nm: End moment [N m] (positive turns +X towards -Z); cantilever only.
        boundary: ``"cantilever"`` (free end) or ``"fixed-guided"`` (end rotation held zero,
            end free to translate).
        rtol: Relative tolerance of the ODE integration.
        max_load_step: Largest continuation step in :math:`\sqrt{\lambda}`.

    Returns:
        The equilibrium.

    Raises:
        InvalidBeam: If the loads are not finite, the boundary is unknown, or a moment is
            applied to a guided end (the guide takes it).
        TruthNotConverged: If continuation stalls or ends off the stable (physical) branch.
    """
    force, moment = check_end_loads(force_n, moment_nm, boundary, InvalidBeam)
    if not np.isfinite(max_load_step) or max_load_step <= 0.0:
        raise InvalidBeam(f"max_load_step = {max_load_step!r} must be positive")
    length = planform.length_m
    ei_eq = equivalent_bending_stiffness(planform)
    magnitude = float(np.hypot(*force))
    if magnitude == 0.0 and moment == 0.0:
        return ElasticaSolution(force, np.array([length, 0.0]), 0.0, 0.0, length, 0.0, boundary)
    shooting = _Shooting(planform, force, moment, boundary, rtol)
    if magnitude == 0.0:
        # A pure end moment: phi' = M / EI is linear and its equilibrium unique (the energy
        # is convex in phi), so one Newton solve from linear theory is the answer.
        solved = shooting.newton(shooting.linear_guess(1.0), 1.0)
        if solved is None:
            raise TruthNotConverged(f"elastica under the end moment {moment:g} N m did not "
                                    "converge")
        return _solution(shooting, solved, boundary)
    level = max(magnitude * length**2 / ei_eq, abs(moment) * length / ei_eq)
    root_level = math.sqrt(level)
    first = min(max_load_step, root_level)
    if moment != 0.0 or boundary == "fixed-guided":
        # The unknown of these loads can turn back as the load grows (a moment against the
        # force): start small so that the predictions follow it.
        first = min(first, 0.25 * max_load_step)
    result, stalled = _continuation(shooting, root_level, first, max_load_step)
    if result is None:
        # A stiffening or softening response (a nearly compressive force) can defeat the
        # predictions from the unloaded state: start again with a small first step.
        result, stalled = _continuation(shooting, root_level, first / 16.0, max_load_step)
    if result is None:
        raise TruthNotConverged(
            f"elastica continuation stalled at {stalled:.4g} of end force {force} N, end "
            f"moment {moment:g} N m ({boundary}, load level {level:.4g})")
    _check_physical(force, moment, boundary, result[2], shooting.stable(result[2]))
    return _solution(shooting, result, boundary)


def _continuation(shooting: _Shooting, root_level: float, first_step: float,
                  max_load_step: float):
    """Continue from zero load to the full load; (answer, None) or (None, stalled fraction).

    The parameter is t in [0, sqrt(level)], the load fraction (t / sqrt(level))^2.
    """
    history: list[tuple[float, float]] = [(0.0, 0.0)]
    t, step = 0.0, first_step
    result = None
    while t < root_level * (1.0 - 1e-14):
        t_new = min(root_level, t + step)
        frac = (t_new / root_level) ** 2
        solved = _continuation_step(shooting, history, t_new, frac)
        if solved is None:
            step *= 0.5
            if step < 1e-6 * max(root_level, 1.0):
                return None, frac
            continue
        history.append((t_new, solved[0]))
        result = solved
        t = t_new
        step = min(max_load_step, 1.5 * step)
    return result, None


def _continuation_step(shooting: _Shooting, history: list[tuple[float, float]], t_new: float,
                       frac: float):
    """Newton at load parameter t_new from a prediction; None unless it lands near one.

    The prediction extrapolates the last two points linearly in t. From the unloaded state
    that chord has half the slope of an unknown growing like the load (t^2: a pure moment,
    a guided end at moderate loads), so there the quadratic extrapolation is tried too. An
    answer farther from its prediction than half the predicted change (plus 0.02 per unit
    of t under a moment or at a guided end) is refused: the step is halved.
    """
    if len(history) < 2:
        solved = shooting.newton(shooting.linear_guess(frac), frac)
        return solved
    (t1, p1), (t2, p2) = history[-2], history[-1]
    turn = 0.02 if shooting.moment != 0.0 or shooting.guided else 0.0
    predictions = [p2 + (p2 - p1) * (t_new - t2) / (t2 - t1)]
    if t1 == 0.0:
        predictions.append(p2 * (t_new / t2) ** 2)
    for predicted in predictions:
        solved = shooting.newton(predicted, frac)
        # Half the predicted change; with a moment or a guided end, whose unknown can turn
        # back (its change vanishes there), plus 0.02 per unit of t.
        allowed = 0.5 * abs(predicted - p2) + turn * (t_new - t2) + 1e-9
        if solved is not None and abs(solved[0] - predicted) <= allowed:
            return solved
    if turn and solved is not None and abs(solved[0] - p2) <= 0.25:
        # Where the unknown turns, the extrapolations miss by their first order: accept a
        # small change that Newton also reaches from the last answer (the same basin).
        again = shooting.newton(p2, frac)
        if again is not None and abs(again[0] - solved[0]) <= 1e-8 * (1.0 + abs(p2)):
            return solved
    return None


def _solution(shooting: _Shooting, solved, boundary: str) -> ElasticaSolution:
    """The equilibrium of a converged shooting unknown."""
    unknown, state, _ = solved
    moment = shooting.moment
    if boundary == "fixed-guided":
        tip_rotation, end_moment = 0.0, unknown * shooting.scale
    else:
        tip_rotation, end_moment = unknown, moment
    return ElasticaSolution(shooting.force, -state[:2], float(tip_rotation), float(state[3]),
                            shooting.planform.length_m, moment, boundary, float(end_moment))


def _check_physical(force: np.ndarray, moment: float, boundary: str, extremes: np.ndarray,
                    stable: bool) -> None:
    """Raise TruthNotConverged unless the answer is stable (and, force alone, in the sector)."""
    slack = 1e-8
    inside = True
    if moment == 0.0:
        force_angle = float(np.arctan2(-force[1], force[0]))
        low, high = min(0.0, force_angle), max(0.0, force_angle)
        inside = bool(extremes[0] >= low - slack and extremes[1] <= high + slack)
    else:
        low, high = -np.inf, np.inf
    if not (inside and stable):
        raise TruthNotConverged(
            f"elastica for end force {force} N, end moment {moment:g} N m ({boundary}) ended "
            f"off the stable branch: section rotations in [{extremes[0]:.4f}, "
            f"{extremes[1]:.4f}] rad against the sector [{low:.4f}, {high:.4f}], Jacobi field "
            f"in [{extremes[2]:.3g}, {extremes[3]:.3g}]")


def elastica_tip(planform: Planform, force_n: np.ndarray, rtol: float = 1e-11,
                 max_load_step: float = 2.0) -> ElasticaSolution:
    r"""Geometrically exact planar elastica of the cantilever under a dead tip force.

    The cantilever case of :func:`end_load_equilibrium` without an end moment: shooting from
    the free tip (:math:`M = 0`) on the unknown tip rotation, Newton on :math:`\phi(0) = 0`
    with the exact variational derivative. (Shooting on the root moment instead is
    ill-conditioned at large loads: its sensitivity grows by orders of magnitude, and a pinched
    planform amplifies it further.) The stable branch is followed by continuation in the load
    from zero (steps of at most ``max_load_step`` in :math:`\sqrt{\alpha}`,
    :math:`\alpha = |F| L^2 / EI_{eq}`); the answer must be on the physical branch (every
    section rotation between the undeformed axis and the force direction) and stable (no
    conjugate point), otherwise TruthNotConverged is raised.

    Args:
        planform: The beam.
        force_n: Tip force (Fx, Fz) [N]; it keeps its direction as the beam deflects.
        rtol: Relative tolerance of the ODE integration.
        max_load_step: Largest continuation step in :math:`\sqrt{\alpha}`.

    Returns:
        The equilibrium.

    Raises:
        InvalidBeam: If the force is not a finite 2-vector.
        TruthNotConverged: If continuation stalls or ends off the stable physical branch.
    """
    return end_load_equilibrium(planform, force_n, 0.0, "cantilever", rtol, max_load_step)
