"""Eigenfrequency assignment along a trajectory (paper 000 Sec. 2.4), verified exactly.

:func:`build_assignment` expands the chosen modes at ``(q0, y0)`` (:mod:`pinflex.parametric`),
samples the partially linear polynomials ``l_{i,0}(q(t))``, ``l_{i,j}(q(t))`` on the
trajectory and returns the QP (12)–(14) with the trapezoidal rule on the trajectory grid
(:mod:`pinflex.assignment.problem`). :func:`assign_frequencies` solves it with ProxQP, then checks
every answer with the exact ERLS model along the whole trajectory; errors reported before and
after always come from the exact model.

Quantity: targets are frequencies [Hz] and, by default, the polynomial expanded for the cost is
the frequency ``f = √λ / 2π`` (``quantity="freq_hz"``). On benchmark A it is about twice as
linear in the added masses as the eigenvalue ``λ = ω²`` (partial-linearization error 1.30 %
vs 2.69 % over y ∈ [0, 0.25]², ``benchmarks/bench_taylor.py``); ``quantity="eigval"`` targets
``λ = (2π f_d)²`` instead, as eq. (10) is written.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pinflex.assignment.problem import AssignmentQP, QPSolution, build_assignment_qp
from pinflex.assignment.solve import solve_assignment_qp
from pinflex.erls import FlexibleModel
from pinflex.exceptions import AssignmentWarning, ConfigurationError
from pinflex.parametric import TaylorModel, expand
from pinflex.trajectory import Trajectory


@dataclass(frozen=True)
class Target:
    """A desired frequency history of one mode.

    Attributes:
        mode: Non-rigid mode number (1 = lowest).
        freq_hz: Desired frequency [Hz]: a constant or one value per trajectory sample.
        weight: Weight of the mode in the cost.
    """

    mode: int
    freq_hz: float | np.ndarray
    weight: float = 1.0


@dataclass(frozen=True)
class AssignmentResult:
    """Answer of an assignment, with its exact verification.

    Attributes:
        found: Whether the QP was solved.
        design: Final design values by name [kg].
        y: Final design vector [kg], (ny,).
        y_before: Design before assignment [kg], (ny,).
        modes: Modes reported in the frequency arrays (targets first, then others).
        targets_hz: Target histories (n_targets, ns) [Hz].
        freq_before_hz: Exact frequencies before, (ns, len(modes)) [Hz].
        freq_after_hz: Exact frequencies after, (ns, len(modes)) [Hz].
        max_error_before: Largest relative target error before (exact model), fraction.
        max_error_after: Largest relative target error after (exact model), fraction.
        predicted_max_error_after: The same, predicted by the partially linear polynomial.
        problem: The last QP solved.
        solution: Its ProxQP answer.
        taylor: The Taylor model the last QP was built from.
        refinements: Re-expansions accepted by the sequential refinement.
        timings_s: Compute time of each stage [s].
        settings: The constraints the problem was built with: ``mass_budget_kg``,
            ``floors`` ``[(mode, f_min_hz)]``, ``bands`` ``[(mode, a_hz, b_hz)]``,
            ``quantity`` (see :mod:`pinflex.assignment.report`).
    """

    found: bool
    design: dict[str, float]
    y: np.ndarray
    y_before: np.ndarray
    modes: tuple[int, ...]
    targets_hz: np.ndarray
    freq_before_hz: np.ndarray
    freq_after_hz: np.ndarray
    max_error_before: float
    max_error_after: float
    predicted_max_error_after: float
    problem: AssignmentQP
    solution: QPSolution
    taylor: TaylorModel
    refinements: int = 0
    timings_s: dict[str, float] = field(default_factory=dict)
    settings: dict = field(default_factory=dict)


def target_matrix(targets: Sequence[Target], ns: int) -> np.ndarray:
    """Target frequencies (n_targets, ns) [Hz] of ``targets`` on ``ns`` samples (checked)."""
    out = np.empty((len(targets), ns))
    for i, t in enumerate(targets):
        f = np.broadcast_to(np.asarray(t.freq_hz, dtype=float), (ns,))
        if np.any(~np.isfinite(f)) or np.any(f <= 0):
            raise ConfigurationError(f"target of mode {t.mode} must be positive frequencies [Hz]")
        out[i] = f
    return out


def check_trajectory_limits(model: FlexibleModel, trajectory: Trajectory) -> None:
    """Warn (TrajectoryWarning) when a trajectory leaves the URDF joint limits.

    The samples are converted to Pinocchio's joint values, which the limits refer to, and
    checked with :meth:`Trajectory.check_limits` (1e-9 of slack for round-off).
    """
    joints = [model.description.joints[name] for name in model.joint_names]
    in_pin = Trajectory(trajectory.times_s, trajectory.q @ model.coord_map.T, model.joint_names)
    in_pin.check_limits([j.lower - 1e-9 for j in joints], [j.upper + 1e-9 for j in joints])


def build_assignment(
    model: FlexibleModel,
    trajectory: Trajectory,
    targets: Sequence[Target],
    *,
    q0=None,
    y0=None,
    order: int = 4,
    quantity: str = "freq_hz",
    design: Sequence[str] | None = None,
    mass_budget_kg: float | None = None,
    A_ineq=None,
    b_ineq=None,
    floors: Sequence[tuple[int, float]] = (),
    bands: Sequence[tuple[int, float, float]] = (),
    taylor: TaylorModel | None = None,
) -> tuple[AssignmentQP, TaylorModel]:
    """Build the assignment QP of ``targets`` along ``trajectory`` (not solved).

    Args:
        model: The flexible model.
        trajectory: Joint samples in the model's user coordinates.
        targets: Desired frequency histories.
        q0: Expansion pose (default: the sample in the middle of the trajectory).
        y0: Expansion design [kg] (default: the URDF's nominal values).
        order: Taylor order p.
        quantity: 'freq_hz' (expand f [Hz]) or 'eigval' (expand λ [rad²/s²]).
        design: Design variables to choose (default all).
        mass_budget_kg: Upper bound of the sum of the chosen design masses [kg].
        A_ineq: Extra rows ``A_ineq (y − y0) <= b_ineq`` on the chosen variables.
        b_ineq: Right-hand side of ``A_ineq``.
        floors: ``(mode, f_min_hz)``: the mode's predicted frequency stays above f_min.
        bands: ``(mode, a_hz, b_hz)``: forbidden band of a mode (see
            :func:`pinflex.assignment.problem.build_assignment_qp`).
        taylor: Reuse this Taylor model instead of expanding.

    Returns:
        ``(problem, taylor_model)``; the QP's variables are ``δy = y − y0`` of ``design``.
    """
    if not targets:
        raise ConfigurationError("give at least one target")
    if quantity not in ("freq_hz", "eigval"):
        raise ConfigurationError(f"quantity='{quantity}': expected 'freq_hz' or 'eigval'")
    Q = model.check_q(trajectory.q)
    if Q.ndim != 2:
        raise ConfigurationError("the trajectory needs joint samples of shape (ns, nv)")
    ns = Q.shape[0]
    if q0 is None:
        q0 = Q[ns // 2]
    y0 = model.check_y(y0)
    modes = []
    for m in [t.mode for t in targets] + [f[0] for f in floors] + [b[0] for b in bands]:
        if m not in modes:
            modes.append(int(m))
    if taylor is None:
        taylor = expand(model, q0, y0, order=order, modes=modes, design=design)
    else:
        missing = set(modes) - set(taylor.modes)
        if missing:
            raise ConfigurationError(f"the given Taylor model lacks modes {sorted(missing)}")
    pos = [taylor.modes.index(m) for m in modes]
    l0, L = taylor.linear_parts(Q, quantity=quantity)
    l0, L = l0[:, pos].T, np.transpose(L[:, pos, :], (1, 0, 2))
    tgt = target_matrix(targets, ns)
    full_targets = np.zeros((len(modes), ns))
    weights = np.zeros(len(modes))
    for t, row in zip(targets, tgt):
        k = modes.index(t.mode)
        full_targets[k] = row
        weights[k] = t.weight
    floor_arr = None
    if floors:
        floor_arr = np.full((len(modes), ns), -np.inf)
        for m, f in floors:
            floor_arr[modes.index(m)] = np.maximum(floor_arr[modes.index(m)], f)
    band_list = [(modes.index(m), a, b) for m, a, b in bands]

    def conv(v):
        return (2 * np.pi * np.asarray(v, dtype=float)) ** 2 if quantity == "eigval" else v

    if quantity == "eigval":
        full_targets = conv(full_targets)
        floor_arr = None if floor_arr is None else np.where(np.isfinite(floor_arr),
                                                             conv(floor_arr), -np.inf)
        band_list = [(k, float(conv(a)), float(conv(b))) for k, a, b in band_list]
    didx = list(taylor.design_idx)
    y0v = taylor.y0
    lower = np.array([model.design[j].lower for j in didx]) - y0v[didx]
    upper = np.array([model.design[j].upper for j in didx]) - y0v[didx]
    A_rows, b_rows = [], []
    if mass_budget_kg is not None:
        A_rows.append(np.ones(len(didx)))
        b_rows.append(float(mass_budget_kg) - float(np.sum(y0v[didx])))
    if A_ineq is not None:
        A_rows.extend(np.atleast_2d(np.asarray(A_ineq, dtype=float)))
        b_rows.extend(np.atleast_1d(np.asarray(b_ineq, dtype=float)))
    problem = build_assignment_qp(
        l0, L, full_targets, trajectory.trapezoid_weights(),
        lower=lower, upper=upper,
        A_ineq=np.array(A_rows) if A_rows else None,
        b_ineq=np.array(b_rows) if b_rows else None,
        floors=floor_arr, bands=band_list or None, mode_weights=weights,
        names=[model.design[j].name for j in didx],
    )
    return problem, taylor


def exact_errors(model: FlexibleModel, Q: np.ndarray, y: np.ndarray,
                 targets: Sequence[Target], modes: Sequence[int]):
    """Exact frequencies (ns, len(modes)) [Hz] and the largest relative target error."""
    f = model.frequencies(Q, y, n_modes=max(modes))[:, [m - 1 for m in modes]]
    tgt = target_matrix(targets, Q.shape[0])
    cols = [list(modes).index(t.mode) for t in targets]
    err = np.abs(f[:, cols].T / tgt - 1.0)
    return f, float(err.max())


def assign_frequencies(
    model: FlexibleModel,
    trajectory: Trajectory,
    targets: Sequence[Target],
    *,
    y_before=None,
    refine: bool = False,
    max_refinements: int = 5,
    report_modes: Sequence[int] = (),
    freq_before_hz: np.ndarray | None = None,
    **build_kwargs,
) -> AssignmentResult:
    """Solve the assignment QP with ProxQP and verify it with the exact model.

    Args:
        model: The flexible model.
        trajectory: Joint samples in the model's user coordinates.
        targets: Desired frequency histories.
        y_before: Design the errors "before" refer to (default: lower bounds, i.e. no added
            mass).
        refine: Re-expand at each new design and re-solve while the exact error improves.
        max_refinements: Most re-expansions.
        report_modes: Extra modes whose frequencies are reported (e.g. 2, 3, 4).
        freq_before_hz: Exact frequencies of ``y_before`` along the trajectory, (ns, modes)
            with the modes in the result's order (targets, then ``report_modes``), when the
            caller already has them (sweeps share them between cases).
        **build_kwargs: Passed to :func:`build_assignment`.

    Raises:
        AssignmentInfeasible: the constraints admit no design.
    """
    t_start = time.perf_counter()
    timings: dict[str, float] = {}
    Q = model.check_q(trajectory.q)
    check_trajectory_limits(model, trajectory)
    if y_before is None:
        y_before = np.array([d.lower for d in model.design])
    y_before = model.check_y(y_before)
    modes = []
    for m in [t.mode for t in targets] + list(report_modes):
        if m not in modes:
            modes.append(int(m))
    t0 = time.perf_counter()
    if freq_before_hz is None:
        f_before, err_before = exact_errors(model, Q, y_before, targets, modes)
    else:
        f_before = np.asarray(freq_before_hz, dtype=float)
        if f_before.shape != (Q.shape[0], len(modes)):
            raise ConfigurationError(
                f"freq_before_hz has shape {f_before.shape}; expected {(Q.shape[0], len(modes))}"
            )
        cols = [modes.index(t.mode) for t in targets]
        err_before = float(np.abs(f_before[:, cols].T / target_matrix(targets, Q.shape[0])
                                  - 1.0).max())
    timings["exact_before"] = time.perf_counter() - t0

    t0 = time.perf_counter()
    problem, taylor = build_assignment(model, trajectory, targets, **build_kwargs)
    timings["expansion_and_build"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    solution = solve_assignment_qp(problem)
    timings["qp"] = time.perf_counter() - t0
    y = _design_from(model, taylor, solution.dy)
    t0 = time.perf_counter()
    f_after, err_after = exact_errors(model, Q, y, targets, modes)
    timings["exact_verification"] = time.perf_counter() - t0
    predicted = _predicted_error(problem, taylor, trajectory, targets, solution, build_kwargs)
    refinements = 0
    while refine and refinements < max_refinements:
        kwargs = dict(build_kwargs, y0=y, q0=taylor.q0, taylor=None)
        t0 = time.perf_counter()
        p2, tm2 = build_assignment(model, trajectory, targets, **kwargs)
        s2 = solve_assignment_qp(p2)
        y2 = _design_from(model, tm2, s2.dy)
        f2, e2 = exact_errors(model, Q, y2, targets, modes)
        timings["refinement"] = timings.get("refinement", 0.0) + time.perf_counter() - t0
        if e2 >= err_after * (1 - 1e-9):
            break
        problem, taylor, solution, y, f_after, err_after = p2, tm2, s2, y2, f2, e2
        predicted = _predicted_error(problem, taylor, trajectory, targets, solution, kwargs)
        refinements += 1
    timings["total"] = time.perf_counter() - t_start
    at_bound = [d.name for d, v in zip(model.design, y)
                if v <= d.lower + 1e-9 or v >= d.upper - 1e-9]
    if err_after > 0.05 and at_bound:
        warnings.warn(
            f"the best design leaves a {100 * err_after:.2f} % target error and sits on the "
            f"bounds of {', '.join(at_bound)}: the target is out of reach of these design "
            "variables; widen the bounds, add design variables or change the target",
            AssignmentWarning,
            stacklevel=2,
        )
    return AssignmentResult(
        found=bool(solution.found),
        design={d.name: float(v) for d, v in zip(model.design, y)},
        y=y,
        y_before=y_before,
        modes=tuple(modes),
        targets_hz=target_matrix(targets, Q.shape[0]),
        freq_before_hz=f_before,
        freq_after_hz=f_after,
        max_error_before=err_before,
        max_error_after=err_after,
        predicted_max_error_after=predicted,
        problem=problem,
        solution=solution,
        taylor=taylor,
        refinements=refinements,
        timings_s=timings,
        settings={
            "mass_budget_kg": build_kwargs.get("mass_budget_kg"),
            "floors": [(int(m), float(f)) for m, f in build_kwargs.get("floors", ())],
            "bands": [(int(m), float(a), float(b)) for m, a, b in build_kwargs.get("bands", ())],
            "quantity": build_kwargs.get("quantity", "freq_hz"),
        },
    )


def _design_from(model: FlexibleModel, taylor: TaylorModel, dy: np.ndarray) -> np.ndarray:
    y = taylor.y0.copy()
    y[list(taylor.design_idx)] += dy
    lo = np.array([d.lower for d in model.design])
    hi = np.array([d.upper for d in model.design])
    return np.clip(y, lo, hi)  # the QP keeps the box to 1e-10; clip round-off only


def _predicted_error(problem, taylor, trajectory, targets, solution, kwargs) -> float:
    quantity = kwargs.get("quantity", "freq_hz")
    Q = trajectory.q
    l0, L = taylor.linear_parts(Q, quantity=quantity)
    tgt = target_matrix(targets, Q.shape[0])
    worst = 0.0
    for t, row in zip(targets, tgt):
        k = taylor.modes.index(t.mode)
        pred = l0[:, k] + L[:, k, :] @ solution.dy
        f = pred if quantity == "freq_hz" else np.sqrt(np.maximum(pred, 0)) / (2 * np.pi)
        worst = max(worst, float(np.max(np.abs(f / row - 1))))
    return worst
