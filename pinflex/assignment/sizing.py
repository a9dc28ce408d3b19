"""Least added mass under frequency floors along a motion (section design variables).

The alternative objective to the target cost of paper 000: choose the design variables
(tube diameters, wall thicknesses, widths, point masses, joint stiffnesses) that keep each
floored mode above its floor at every sample of a trajectory, with the least design mass
(:func:`pinflex.erls.design.design_mass`: design point masses plus the beams of designed
links).

Method (sequential steps on exact Taylor models, verified exactly):

1. Expand the floored modes' frequencies [Hz] at ``(q0, y_k)`` (joints and design variables,
   order ``p``, full Taylor in both) and sample the polynomial on the trajectory.
2. Step: minimise the design mass (exact, through the section formulas) subject to the
   polynomial staying above ``floor + c`` at every sample, the parameters' bounds and a trust
   region (``step_fraction`` times the estimated radius along each design axis, halved after
   a rejected step), solved by SLSQP on the polynomial (microseconds per evaluation). ``c``
   corrects the floors by the polynomial's error at the current design (predicted minus
   exact, worst sample), so the step answers for the exact model.
3. Exact verification along the whole trajectory; a step is accepted if it keeps the floors
   (or reduces their violation) without adding mass, and the model is re-expanded at the
   accepted design (the re-expansion step).

It stops when the step is below ``xtol`` (relative to the bounds) and every floor holds on the
exact model within ``tol_hz``. Mode numbers are the sorted non-rigid modes at every sample (a
floor on "mode 1" is a floor on the lowest frequency, which is what a floor means); the joint
conditions of the model apply (:mod:`pinflex.erls.joints`).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pinflex.checks import check_q, check_y
from pinflex.erls.design import design_mass
from pinflex.exceptions import AssignmentWarning, ConfigurationError
from pinflex.parametric import expand
from pinflex.summaries import dataclass_summary


@dataclass(frozen=True)
class SizingResult:
    """Answer of :func:`size_for_floors`, verified on the exact model.

    Attributes:
        design: Final design values by name.
        y: Final design vector, (ny,).
        y_start: Starting design, (ny,).
        mass_kg: Design mass at ``y`` [kg].
        mass_start_kg: Design mass at ``y_start`` [kg].
        floors: The floors ``[(mode, f_min_hz)]``.
        freq_hz: Exact frequencies of the floored modes along the trajectory, (ns, k) [Hz].
        freq_start_hz: The same at the start design.
        margin_hz: Smallest exact margin ``f − f_min`` over samples and floors [Hz].
        feasible: Whether every floor holds on the exact model (within ``tol_hz``).
        expansions: Taylor expansions made.
        history: Per iteration ``(y, mass_kg, exact margin_hz)``.
        timings_s: Compute time of expansions, steps and exact verification [s].
        joints: Joint conditions of the model.
        status: ``"met"`` when every floor (and the budget) holds on the exact model, else
            ``"floors_unmet"`` (the command line then exits with 3).
    """

    __repr__ = dataclass_summary  # fields summarised: no array dumps

    design: dict[str, float]
    y: np.ndarray
    y_start: np.ndarray
    mass_kg: float
    mass_start_kg: float
    floors: tuple[tuple[int, float], ...]
    freq_hz: np.ndarray
    freq_start_hz: np.ndarray
    margin_hz: float
    feasible: bool
    expansions: int
    history: tuple = ()
    timings_s: dict[str, float] = field(default_factory=dict)
    joints: dict[str, str] = field(default_factory=dict)
    status: str = "met"

    @property
    def ok(self) -> bool:
        """Whether every floor holds on the exact model (``status == "met"``)."""
        return self.status == "met"

    @property
    def added_mass_kg(self) -> float:
        """Mass added by the sizing [kg] (negative when mass was removed)."""
        return self.mass_kg - self.mass_start_kg


def _solve_step(model, y, didx, predict, floor, lo_b, hi_b, rho, span, budget):
    """Least design mass on the Taylor polynomial inside the trust region (SLSQP)."""
    from scipy.optimize import minimize

    n = len(didx)
    lower = np.maximum(lo_b - y[didx], -rho) / span
    upper = np.minimum(hi_b - y[didx], rho) / span

    def full(x):
        out = y.copy()
        out[didx] += x * span
        return out

    m_ref = max(design_mass(model, y), 1e-12)
    f_ref = max(float(np.max(np.abs(floor))), 1e-12)
    cons = [{"type": "ineq",
             "fun": lambda x: ((predict(x * span) - floor[None, :]) / f_ref).ravel()}]
    if budget is not None:
        cons.append({"type": "ineq", "fun": lambda x: (budget - design_mass(model, full(x)))
                     / m_ref})
    limits = _section_limit_functions(model, full)
    if limits is not None:
        cons.append({"type": "ineq", "fun": limits})
    res = minimize(lambda x: design_mass(model, full(x)) / m_ref, np.zeros(n),
                   bounds=list(zip(lower, upper)), constraints=cons, method="SLSQP",
                   options={"ftol": 1e-13, "maxiter": 200})
    x = np.clip(res.x, lower, upper)
    return x * span


def _section_limit_functions(model, full):
    """Constraint values (≥ 0) that keep every designed section valid, or None."""
    from pinflex.sections import section_limits

    names = list(model.design_names)
    links = [model.plan.beams[link].spec.inputs for link in model.plan.design.links]
    if not any(inp.shape == "hollow_circle" for inp in links):
        return None

    def fun(x):
        yv = full(x)
        out = []
        for inp in links:
            lim = section_limits(inp, lambda n: yv[names.index(n)])
            scale = max(abs(v) for v in lim.values()) or 1.0
            out.extend(float(v) / scale for v in lim.values())
        return np.array(out) if out else np.zeros(1)

    return fun


def _exact(model, Q, y, modes):
    f = model.frequencies(Q, y, n_modes=max(modes))
    return f[:, [m - 1 for m in modes]]


def size_for_floors(
    model,
    trajectory,
    floors: Sequence[tuple[int, float]],
    *,
    design: Sequence[str] | None = None,
    y_start=None,
    q0=None,
    order: int = 4,
    step_fraction: float = 0.5,
    max_expansions: int = 30,
    xtol: float = 1e-6,
    tol_hz: float = 1e-6,
    mass_budget_kg: float | None = None,
    safety: float = 1e-5,
    progress: bool = False,
) -> SizingResult:
    """Least design mass with every floored mode above its floor along a trajectory.

    Args:
        model: A :class:`~pinflex.FlexibleModel` with design variables.
        trajectory: Joint samples (``q`` (ns, nv) in user coordinates, ``times_s``).
        floors: ``[(mode, f_min_hz)]``: mode ``mode`` (1 = lowest non-rigid) stays at or
            above ``f_min_hz`` at every sample.
        design: Design variables to choose (default all).
        y_start: Starting design (default nominal); also the mass reference.
        q0: Expansion pose (default the middle sample).
        order: Taylor order.
        step_fraction: Trust region as a fraction of the estimated radius along each axis.
        max_expansions: Re-expansion limit.
        xtol: Stop when every step is below ``xtol`` times the variable's bound range.
        tol_hz: Floor tolerance of the exact verification [Hz].
        mass_budget_kg: Optional upper bound of the design mass [kg].
        safety: Relative margin added to the floors in each step (the polynomial's error
            grows away from its expansion point; the exact check decides).
        progress: Show a progress bar of the steps on stderr.

    Raises:
        ConfigurationError: No floor, no design variable, or a setting out of range.
        InvalidTrajectory: The trajectory does not have one column per joint.
    """
    from pinflex.assignment.targets import check_trajectory_limits
    from pinflex.progress import ProgressBar

    for name, value, low in (("step_fraction", step_fraction, 0.0), ("xtol", xtol, 0.0),
                             ("tol_hz", tol_hz, 0.0), ("safety", safety, -1.0)):
        if not (isinstance(value, int | float) and np.isfinite(value) and value > low):
            raise ConfigurationError(f"{name} = {value!r}: give a number above {low:g}")
    if isinstance(max_expansions, bool) or not isinstance(max_expansions, int) or \
            max_expansions < 1:
        raise ConfigurationError(f"max_expansions = {max_expansions!r}: give a whole number >= 1")
    t_all = time.perf_counter()
    check_trajectory_limits(model, trajectory)
    Q = np.atleast_2d(check_q(model, trajectory.in_order(model.joint_names)))
    floors = tuple((int(m), float(f)) for m, f in floors)
    if not floors:
        raise ConfigurationError("give at least one floor (mode, f_min_hz)")
    modes = tuple(sorted({m for m, _ in floors}))
    fmin = np.full(len(modes), -np.inf)
    for m, f in floors:
        fmin[modes.index(m)] = max(fmin[modes.index(m)], f)
    names = list(model.design_names if design is None else design)
    didx = [model.design_names.index(n) for n in names]
    if not didx:
        raise ConfigurationError("the model has no design variable to size")
    y = check_y(model, y_start).astype(float).copy()
    y_start = y.copy()
    q0 = Q[len(Q) // 2] if q0 is None else np.asarray(q0, dtype=float)
    moving = [model.joint_names[j] for j in range(model.nv)
              if np.ptp(Q[:, j]) > 0 or abs(Q[0, j] - q0[j]) > 0]
    lo_b = np.array([model.design[j].lower for j in didx])
    hi_b = np.array([model.design[j].upper for j in didx])
    span = np.where(np.isfinite(hi_b - lo_b), hi_b - lo_b, np.maximum(np.abs(y[didx]), 1.0))
    t = {"expansion": 0.0, "step_solve": 0.0, "exact_verification": 0.0}
    t0 = time.perf_counter()
    f_start = _exact(model, Q, y, modes)
    t["exact_verification"] += time.perf_counter() - t0
    f_now = f_start
    history = []
    expansions = 0
    rho = None  # trust radius per variable (absolute units)
    tm = None
    solves = 0
    stalls = 0
    bar = ProgressBar(4 * max_expansions, "sizing steps", bool(progress))
    while expansions < max_expansions and solves < 4 * max_expansions:
        if tm is None:
            t0 = time.perf_counter()
            tm = expand(model, q0, y, order=order, modes=modes, joints=moving, design=names)
            expansions += 1
            t["expansion"] += time.perf_counter() - t0
            nj = len(tm.joint_idx)
            if rho is None:
                rho = np.minimum(step_fraction * np.min(tm.radius[nj:], axis=1), 0.25 * span)
            y_base = y.copy()

            def predict(dy, tm=tm, y_base=y_base):
                Y = y_base.copy()
                Y[didx] += dy
                return tm.evaluate(Q, Y, quantity="freq_hz", warn=False)

            correction = np.max(predict(np.zeros(len(names))) - f_now, axis=0)
        t0 = time.perf_counter()
        dy = _solve_step(model, y, didx, predict, fmin * (1.0 + safety) + correction, lo_b,
                         hi_b, rho, span, mass_budget_kg)
        solves += 1
        bar.update()
        t["step_solve"] = t.get("step_solve", 0.0) + time.perf_counter() - t0
        y_new = y.copy()
        y_new[didx] = np.clip(y[didx] + dy, lo_b, hi_b)
        t0 = time.perf_counter()
        f_new = _exact(model, Q, y_new, modes)
        t["exact_verification"] += time.perf_counter() - t0
        margin_old = float(np.min(f_now - fmin[None, :]))
        margin = float(np.min(f_new - fmin[None, :]))
        mass_new, mass_old = design_mass(model, y_new), design_mass(model, y)
        if margin_old >= -tol_hz:
            accept = margin >= -tol_hz and mass_new <= mass_old + 1e-12 * max(1.0, mass_old)
        else:
            accept = margin > margin_old
        moved = float(np.max(np.abs(y_new[didx] - y[didx]) / span))
        assert rho is not None  # set at the first expansion, before any step
        # out of reach: a step that gains less than 0.1 % of the shortfall is a stall
        stalls = (stalls + 1 if accept and margin_old < -tol_hz
                  and margin - margin_old < 1e-3 * -margin_old else 0)
        if accept:
            history.append((y_new.copy(), mass_new, margin))
            y, f_now, tm = y_new, f_new, None  # re-expand at the new design
            rho = np.minimum(rho * 2.0, span)
        else:
            rho = rho * 0.5
        if (accept and moved < xtol) or np.all(rho < xtol * span) or stalls >= 2:
            break  # converged, or no step left that changes anything
    bar.total = bar.done
    bar.close()
    margin = float(np.min(f_now - fmin[None, :]))
    over_budget = mass_budget_kg is not None and design_mass(model, y) > mass_budget_kg * (
        1 + 1e-9)
    if margin < -tol_hz:
        import warnings

        warnings.warn(
            f"sizing ended with a floor violated by {-margin:.3g} Hz on the exact model: the "
            "floors may be out of reach within the bounds (widen them or lower the floors)",
            AssignmentWarning, stacklevel=2,
        )
    t["total"] = time.perf_counter() - t_all
    return SizingResult(
        design={d.name: float(v) for d, v in zip(model.design, y)},
        y=y, y_start=y_start, mass_kg=design_mass(model, y),
        mass_start_kg=design_mass(model, y_start), floors=floors, freq_hz=f_now,
        freq_start_hz=f_start, margin_hz=margin, feasible=bool(margin >= -tol_hz),
        expansions=expansions, history=tuple(history), timings_s=t,
        joints=model.joint_labels(),
        status="met" if margin >= -tol_hz and not over_budget else "floors_unmet",
    )
