"""Eigenfrequency assignment along a trajectory (paper 000 Sec. 2.4), verified exactly.

:func:`build_assignment` expands the chosen modes at ``(q0, y0)`` (:mod:`pinflex.parametric`),
samples the partially linear polynomials ``l_{i,0}(q(t))``, ``l_{i,j}(q(t))`` on the
trajectory and returns the QP (12)–(14) with the trapezoidal rule on the trajectory grid
(:mod:`pinflex.assignment.problem`). :func:`assign_frequencies` solves it with ProxQP, then checks
every answer with the exact ERLS model along the whole trajectory; errors reported before and
after always come from the exact model.

Mode identity: a target "mode i" is mode i at the expansion point, followed by shape along the
design change and the trajectory (:mod:`pinflex.assignment.verify`, :mod:`pinflex.tracking`);
``max_error_*`` are the errors of those tracked modes, ``max_error_*_sorted`` those of the
sorted mode numbers. When a target mode crosses or veers with another one along the trajectory
the two differ and :class:`~pinflex.exceptions.ModeCrossingWarning` is issued. A design whose
tracked exact error is larger than before is never reported as an improvement: ``improved``
is False and :class:`~pinflex.exceptions.AssignmentNotImproved` is issued (the design is still
returned, for inspection; nothing is refused). Floors that the polynomial declares infeasible
are checked on the exact model before refusing (see :mod:`pinflex.assignment.verify`).

Quantity: targets are frequencies [Hz] and, by default, the polynomial expanded for the cost is
the frequency ``f = √λ / 2π`` (``quantity="freq_hz"``). On benchmark A it is about twice as
linear in the added masses as the eigenvalue ``λ = ω²`` (partial-linearization error 1.30 %
vs 2.69 % over y ∈ [0, 0.25]², ``benchmarks/bench_taylor.py``); ``quantity="eigval"`` targets
``λ = (2π f_d)²`` instead, as eq. (10) is written.
"""

from __future__ import annotations

import itertools
import time
import warnings
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pinflex.assignment.points import PiecewiseTaylor
from pinflex.assignment.problem import AssignmentQP, QPSolution, build_assignment_qp
from pinflex.assignment.solve import solve_assignment_qp
from pinflex.assignment.verify import (
    Verification,
    exact_floor_candidates,
    floor_margins,
    verify_tracked,
)
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    AssignmentInfeasible,
    AssignmentNotImproved,
    AssignmentWarning,
    ConfigurationError,
    InvalidTrajectory,
    ModeCrossingWarning,
)
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
        timings_s: Compute time of each stage [s] (wall clock).
        cpu_timings_s: The same stages in CPU time of the calling thread [s] (with
            single-thread BLAS all of the work; a loaded machine does not inflate it).
        settings: The constraints the problem was built with: ``mass_budget_kg``,
            ``floors`` ``[(mode, f_min_hz)]``, ``bands`` ``[(mode, a_hz, b_hz)]``,
            ``quantity`` (see :mod:`pinflex.assignment.report`).
        freq_before_sorted_hz: Exact frequencies before of the sorted mode numbers.
        freq_after_sorted_hz: The same after.
        max_error_before_sorted: Largest target error before on the sorted mode numbers.
        max_error_after_sorted: The same after.
        improved: Whether the tracked exact error went down (never True when it went up).
        events: Crossings, veering and ambiguous steps of the target modes along the
            trajectory, before and after (:class:`pinflex.tracking.ModeEvent`).
        floors_model: Which model the floors were enforced on: ``""`` (no floors),
            ``"taylor"`` (the partially linear polynomial) or ``"taylor+exact"`` (corrected by
            the exact model after the polynomial alone refused them).
        floor_margin_hz: Smallest exact margin of the floors after (tracked modes) [Hz];
            negative when a floor is violated on the exact model.
        joints: The joint conditions the assignment was made under (``{joint: label}``).
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
    taylor: TaylorModel | PiecewiseTaylor
    refinements: int = 0
    timings_s: dict[str, float] = field(default_factory=dict)
    settings: dict = field(default_factory=dict)
    freq_before_sorted_hz: np.ndarray | None = None
    freq_after_sorted_hz: np.ndarray | None = None
    max_error_before_sorted: float = float("nan")
    max_error_after_sorted: float = float("nan")
    improved: bool = True
    events: tuple = ()
    floors_model: str = ""
    floor_margin_hz: float | None = None
    joints: dict[str, str] = field(default_factory=dict)
    cpu_timings_s: dict[str, float] = field(default_factory=dict)


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

    Args:
        model: The flexible model whose URDF holds the limits [rad or m].
        trajectory: Joint samples (ns, nv) in the model's user coordinates, one value per
            moving joint.

    Raises:
        InvalidTrajectory: If the samples do not have one column per joint of the model.
    """
    q = np.asarray(trajectory.q)
    if q.ndim != 2 or q.shape[1] != len(model.joint_names):
        raise InvalidTrajectory(
            f"the trajectory has samples of shape {q.shape}; the model needs (n_samples, "
            f"{len(model.joint_names)}): one column per joint {list(model.joint_names)}")
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
    taylor: TaylorModel | PiecewiseTaylor | None = None,
    taylor_tol: float | None = None,
    points_tol: float | None = None,
) -> tuple[AssignmentQP, TaylorModel | PiecewiseTaylor]:
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
        mass_budget_kg: Upper bound of the design mass of the chosen variables [kg]: their
            point masses plus the beam mass of links whose section or material they set
            (:func:`pinflex.erls.design.design_mass`, linearised at ``y0``).
        A_ineq: Extra rows ``A_ineq (y − y0) <= b_ineq`` on the chosen variables.
        b_ineq: Right-hand side of ``A_ineq``.
        floors: ``(mode, f_min_hz)``: the mode's predicted frequency stays above f_min
            (a constant or one value per sample).
        bands: ``(mode, a_hz, b_hz)``: forbidden band of a mode (see
            :func:`pinflex.assignment.problem.build_assignment_qp`).
        taylor: Reuse this Taylor model instead of expanding.
        taylor_tol: Pick the Taylor order (1–8, ``order`` is then ignored): the lowest whose
            two-term estimate (the larger of the next two orders' terms) of the relative
            error of ``quantity`` meets it along the trajectory at ``y0`` and at the corners
            of the design box
            (:func:`pinflex.parametric.fidelity.order_for_tolerance`); the model's
            ``order_choice`` reports it.
        points_tol: Cover the trajectory with the fewest Taylor expansion points (then the
            lowest order) whose two-term estimate meets it at every sample at ``y0``
            (:func:`pinflex.assignment.points.points_for_tolerance`); each sample's QP rows
            come from its segment's model, ``q0`` and ``order`` are then ignored and the
            model's ``points_choice`` reports the choice.

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
    if taylor_tol is not None and points_tol is not None:
        raise ConfigurationError("give taylor_tol (one point, order by tolerance) or "
                                 "points_tol (expansion points by tolerance), not both")
    if taylor is None and points_tol is not None:
        from pinflex.assignment.points import points_for_tolerance

        taylor = points_for_tolerance(model, Q, y0, tol=points_tol, modes=modes, design=design,
                                      quantity=quantity)
    elif taylor is None and taylor_tol is not None:
        over = design_region(model, Q, y0, design)
        taylor = expand(model, q0, y0, order=8, modes=modes, design=design, tol=taylor_tol,
                        over=over)
    elif taylor is None:
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
        # the design mass: design point masses plus the beams of designed links (exactly the
        # sum of the masses when only point masses are designed; linearised at y0 otherwise)
        from pinflex.erls.design import design_mass

        m0, grad = design_mass(model, y0v, order=1)
        others = [j for j in range(model.ny) if j not in didx]
        fixed = float(np.sum(y0v[others])) if all(
            model.design[j].kind == "mass" for j in others) else 0.0
        A_rows.append(grad[didx])
        b_rows.append(float(mass_budget_kg) - (m0 - fixed))
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


def design_region(model: FlexibleModel, Q: np.ndarray, y0: np.ndarray,
                  design: Sequence[str] | None) -> tuple[np.ndarray, np.ndarray]:
    """Samples ``(Q, Y)`` where an assignment's Taylor model is used.

    The trajectory at ``y0`` and at every corner of the box of the chosen design variables
    (≤ 6 of them; at each bound along each axis otherwise); infinite bounds are left out.
    """
    names = model.design_names if design is None else tuple(design)
    didx = [model.design_names.index(n) for n in names]
    designs = [np.asarray(y0, dtype=float)]
    bounds = [[b for b in (model.design[j].lower, model.design[j].upper) if np.isfinite(b)]
              for j in didx]
    if len(didx) <= 6:
        for corner in itertools.product(*bounds):
            y = designs[0].copy()
            y[didx] = corner
            designs.append(y)
    else:
        for j, bj in zip(didx, bounds):
            for b in bj:
                y = designs[0].copy()
                y[j] = b
                designs.append(y)
    ns = Q.shape[0]
    return np.tile(Q, (len(designs), 1)), np.repeat(np.array(designs), ns, axis=0)


def exact_errors(model: FlexibleModel, Q: np.ndarray, y: np.ndarray,
                 targets: Sequence[Target], modes: Sequence[int]):
    """Exact frequencies (ns, len(modes)) [Hz] and the largest relative target error.

    Args:
        model: The flexible model.
        Q: Joint samples (ns, nv), user convention [rad or m].
        y: Design values (ny,) [kg].
        targets: Desired frequency histories; each target's ``mode`` must be in ``modes``.
        modes: 1-based mode numbers to compute.

    Returns:
        ``(f, error)``: frequencies (ns, len(modes)) [Hz] and
        ``max |f/f* − 1|`` over targets and samples (dimensionless).

    Raises:
        ConfigurationError: Invalid ``Q`` or ``y``, or a target that is not positive
            frequencies.
        DesignVariableOutOfBounds: ``y`` leaves its bounds.
    """
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
    progress: bool = False,
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
        progress: Show a progress bar of the stages (expansion, exact model before, QP,
            exact verification, refinements) on stderr.
        **build_kwargs: Passed to :func:`build_assignment`.

    Raises:
        AssignmentInfeasible: the constraints admit no design.
    """
    try:
        from pinflex.progress import ProgressBar
    except ImportError:  # the batch runner's bar, before the shared module exists
        from pinflex.batch.runner import ProgressBar
    bar = ProgressBar(4 + (max_refinements if refine else 0), "assignment stages",
                      bool(progress))
    t_start, c_start = time.perf_counter(), time.thread_time()
    timings: dict[str, float] = {}
    cpu: dict[str, float] = {}

    def stage(key: str, since: tuple[float, float]) -> None:  # add a stage's wall and CPU
        timings[key] = timings.get(key, 0.0) + time.perf_counter() - since[0]
        cpu[key] = cpu.get(key, 0.0) + time.thread_time() - since[1]

    def now() -> tuple[float, float]:
        return time.perf_counter(), time.thread_time()
    Q = model.check_q(trajectory.q)
    check_trajectory_limits(model, trajectory)
    if y_before is None:
        y_before = np.array([d.lower for d in model.design])
    y_before = model.check_y(y_before)
    modes = []
    for m in [t.mode for t in targets] + list(report_modes):
        if m not in modes:
            modes.append(int(m))
    tgt = target_matrix(targets, Q.shape[0])
    tmodes = [t.mode for t in targets]
    if freq_before_hz is not None:
        f_before = np.asarray(freq_before_hz, dtype=float)
        if f_before.shape != (Q.shape[0], len(modes)):
            raise ConfigurationError(
                f"freq_before_hz has shape {f_before.shape}; expected {(Q.shape[0], len(modes))}"
            )

    t0 = now()
    problem, taylor = build_assignment(model, trajectory, targets, **build_kwargs)
    stage("expansion_and_build", t0)
    bar.update()
    reference = (taylor.q0, taylor.y0)
    t0 = now()
    if freq_before_hz is None:
        before = verify_tracked(model, Q, y_before, tgt, tmodes, modes, reference)
    else:  # given by the caller (a sweep shares them): taken as the tracked frequencies
        cols = [modes.index(m) for m in tmodes]
        err = float(np.abs(f_before[:, cols].T / tgt - 1.0).max())
        before = Verification(None, f_before, f_before, err, err)
    stage("exact_before", t0)
    bar.update()
    floors = list(build_kwargs.get("floors", ()))
    t0 = now()
    floors_model = "taylor" if floors else ""
    try:
        solution = solve_assignment_qp(problem)
    except AssignmentInfeasible as exc:
        if not floors or exc.result is not None:
            raise _refusal(exc, problem) from None
        problem, taylor, solution = _floors_on_exact(
            model, trajectory, targets, build_kwargs, problem, taylor, y_before, exc)
        floors_model = "taylor+exact"
    stage("qp", t0)
    bar.update()
    y = _design_from(model, taylor, solution.dy)
    t0 = now()
    after = verify_tracked(model, Q, y, tgt, tmodes, modes, reference)
    stage("exact_verification", t0)
    bar.update()
    predicted = _predicted_error(problem, taylor, trajectory, targets, solution, build_kwargs)
    refinements = 0
    while refine and refinements < max_refinements:
        kwargs = dict(build_kwargs, y0=y, q0=taylor.q0, taylor=None)
        t0 = now()
        p2, tm2 = build_assignment(model, trajectory, targets, **kwargs)
        try:
            s2 = solve_assignment_qp(p2)
        except AssignmentInfeasible:
            break
        y2 = _design_from(model, tm2, s2.dy)
        v2 = verify_tracked(model, Q, y2, tgt, tmodes, modes, reference)
        stage("refinement", t0)
        bar.update()
        if v2.max_error >= after.max_error * (1 - 1e-9):
            break
        problem, taylor, solution, y, after = p2, tm2, s2, y2, v2
        predicted = _predicted_error(problem, taylor, trajectory, targets, solution, kwargs)
        refinements += 1
    if floors:
        problem, taylor, solution, y, after, corrected_exact = _floors_kept_exactly(
            model, trajectory, targets, build_kwargs, problem, taylor, solution, y, after,
            (tgt, tmodes, modes, reference))
        if corrected_exact:
            floors_model = "taylor+exact"
    margin = floor_margins(model, Q, y, floors, reference) if floors else None
    bar.total = bar.done
    bar.close()
    timings["total"] = time.perf_counter() - t_start
    cpu["total"] = time.thread_time() - c_start
    err_before, err_after = before.max_error, after.max_error
    events = _target_events(before, after, tmodes)
    _warn_outcome(model, y, before, after, events, tmodes, predicted, margin)
    return AssignmentResult(
        found=bool(solution.found),
        design={d.name: float(v) for d, v in zip(model.design, y)},
        y=y,
        y_before=y_before,
        modes=tuple(modes),
        targets_hz=tgt,
        freq_before_hz=before.freq_hz,
        freq_after_hz=after.freq_hz,
        max_error_before=err_before,
        max_error_after=err_after,
        predicted_max_error_after=predicted,
        problem=problem,
        solution=solution,
        taylor=taylor,
        refinements=refinements,
        timings_s=timings,
        cpu_timings_s=cpu,
        settings={
            "mass_budget_kg": build_kwargs.get("mass_budget_kg"),
            "floors": [(int(m), float(f) if np.ndim(f) == 0 else
                        np.asarray(f, dtype=float).tolist())
                       for m, f in build_kwargs.get("floors", ())],
            "bands": [(int(m), float(a), float(b)) for m, a, b in build_kwargs.get("bands", ())],
            "quantity": build_kwargs.get("quantity", "freq_hz"),
        },
        freq_before_sorted_hz=before.sorted_hz,
        freq_after_sorted_hz=after.sorted_hz,
        max_error_before_sorted=before.max_error_sorted,
        max_error_after_sorted=after.max_error_sorted,
        improved=bool(err_after < err_before),
        events=events,
        floors_model=floors_model,
        floor_margin_hz=margin,
        joints=model.joint_labels(),
    )


def _refusal(exc: AssignmentInfeasible, problem) -> AssignmentInfeasible:
    """The QP's refusal, saying which model refused it."""
    groups = set(problem.constraint_groups)
    model_based = bool(groups & {"floor", "band"})
    who = "taylor" if model_based else "constraints"
    text = ("refused by the partially linear Taylor model (floors/bands on the polynomial)"
            if model_based else "refused by the box and linear constraints (exact)")
    return AssignmentInfeasible(f"{exc} [{text}]", exc.problem, exc.result, refused_by=who)


def _floors_on_exact(model, trajectory, targets, build_kwargs, problem, taylor, y_before, exc):
    """Re-solve a QP whose polynomial floors were infeasible with exact-corrected floors."""
    Q = model.check_q(trajectory.q)
    reference = (taylor.q0, taylor.y0)
    floors = list(build_kwargs["floors"])
    best = None
    for y in exact_floor_candidates(model, problem, taylor, y_before):
        m = floor_margins(model, Q, y, floors, reference)
        if best is None or m > best[1]:
            best = (y, m)
    if best is None or best[1] < 0:
        detail = ("no design meets the box and linear constraints" if best is None else
                  f"the best of the checked designs (y0, the design before and the box "
                  f"corners), y = {np.round(best[0], 6).tolist()}, misses a floor by "
                  f"{-best[1]:.4g} Hz")
        raise AssignmentInfeasible(
            f"{exc} [refused by the partially linear Taylor model and confirmed on the exact "
            f"model: {detail}]", problem, None, refused_by="exact") from None
    quantity = build_kwargs.get("quantity", "freq_hz")
    y_star = best[0]
    solution = None
    for _ in range(4):
        corrected = _corrected_floors(model, Q, taylor, y_star, floors, quantity, reference)
        kwargs = dict(build_kwargs, floors=corrected, taylor=taylor)
        problem, taylor = build_assignment(model, trajectory, targets, **kwargs)
        solution = solve_assignment_qp(problem)
        y = _design_from(model, taylor, solution.dy)
        if floor_margins(model, Q, y, floors, reference) >= -1e-9 * max(
                float(np.max(np.abs(np.asarray(f, dtype=float)))) for _, f in floors):
            break
        y_star = y
    warnings.warn(
        "the partially linear Taylor model declared the frequency floors infeasible, but the "
        f"exact model meets them at y = {np.round(best[0], 6).tolist()} (margin "
        f"{best[1]:.4g} Hz); the floors were corrected by the exact-minus-predicted offsets "
        "and the QP solved again (floors_model = 'taylor+exact')",
        AssignmentWarning,
        stacklevel=3,
    )
    return problem, taylor, solution


def _floors_kept_exactly(model, trajectory, targets, build_kwargs, problem, taylor, solution,
                         y, after, verify_args):
    """Re-solve with exact-corrected floors when only the polynomial meets them.

    Section variables are where the partially linear model is least accurate: the floors are
    shifted by the exact-minus-predicted offsets at the answer and the QP solved again.
    """
    Q = model.check_q(trajectory.q)
    tgt, tmodes, modes, reference = verify_args
    floors = list(build_kwargs["floors"])
    quantity = build_kwargs.get("quantity", "freq_hz")
    tol = 1e-9 * max(float(np.max(np.abs(np.asarray(f, dtype=float)))) for _, f in floors)
    if floor_margins(model, Q, y, floors, reference) >= -tol:
        return problem, taylor, solution, y, after, False
    y_star, changed = y, False
    for _ in range(6):
        corrected = [(m, np.asarray(f) + 1e-6 * np.abs(np.asarray(f)))  # a hair of margin
                     for m, f in _corrected_floors(model, Q, taylor, y_star, floors, quantity,
                                                   reference)]
        kwargs = dict(build_kwargs, floors=corrected, taylor=taylor)
        p3, tm3 = build_assignment(model, trajectory, targets, **kwargs)
        try:
            s3 = solve_assignment_qp(p3)
        except AssignmentInfeasible:
            break
        problem, taylor, solution, y = p3, tm3, s3, _design_from(model, tm3, s3.dy)
        changed = True
        if floor_margins(model, Q, y, floors, reference) >= -tol:
            break
        y_star = y
    if changed:
        after = verify_tracked(model, Q, y, tgt, tmodes, modes, reference)
    return problem, taylor, solution, y, after, changed


def _corrected_floors(model, Q, taylor, y_star, floors, quantity, reference):
    """Floors shifted so that the polynomial equals the exact tracked model at ``y_star``."""
    modes = tuple(sorted({int(m) for m, _ in floors}))
    tr = verify_tracked(model, Q, y_star, np.ones((1, Q.shape[0])), [modes[0]], modes,
                        reference).tracking
    l0, L = taylor.linear_parts(Q, quantity=quantity)
    didx = list(taylor.design_idx)
    dy = y_star[didx] - taylor.y0[didx]
    out = []
    for m, fmin in floors:
        k = taylor.modes.index(int(m))
        pred = l0[:, k] + L[:, k, :] @ dy
        exact_f = tr.freq_hz[:, modes.index(int(m))]
        fmin = np.broadcast_to(np.asarray(fmin, dtype=float), exact_f.shape)
        if quantity == "eigval":
            lam = (2 * np.pi * fmin) ** 2 - ((2 * np.pi * exact_f) ** 2 - pred)
            out.append((int(m), np.sqrt(np.maximum(lam, 0.0)) / (2 * np.pi)))
        else:
            out.append((int(m), fmin - (exact_f - pred)))
    return out


def _target_events(before: Verification, after: Verification, target_modes) -> tuple:
    """Crossing/veering/ambiguous events of target modes, before and after."""
    seen, out = set(), []
    for v in (before, after):
        if v.tracking is None:
            continue
        for e in v.tracking.events:
            if any(m in e.modes for m in target_modes):
                key = (e.kind, e.sample, e.modes)
                if key not in seen:
                    seen.add(key)
                    out.append(e)
    return tuple(out)


def _warn_outcome(model, y, before, after, events, target_modes, predicted, margin) -> None:
    err_before, err_after = before.max_error, after.max_error
    changed = [m for m in target_modes
               if any(v.tracking is not None and v.tracking.changes_identity(m)
                      for v in (before, after))]
    if events or changed:
        kinds = sorted({f"{e.kind} of modes {'/'.join(map(str, e.modes))} at sample {e.sample}"
                        for e in events})[:4]
        warnings.warn(
            "target modes change their sorted number along the trajectory "
            f"({'; '.join(kinds) or 'modes ' + str(changed)}): errors and frequencies refer "
            "to the modes tracked by shape from the expansion point "
            f"({100 * err_before:.2f} % -> {100 * err_after:.2f} %); the sorted mode numbers "
            f"give {100 * before.max_error_sorted:.2f} % -> "
            f"{100 * after.max_error_sorted:.2f} %",
            ModeCrossingWarning,
            stacklevel=3,
        )
    if err_after > err_before * (1 + 1e-9):
        warnings.warn(
            f"the assigned design is not an improvement: the exact error of the tracked target "
            f"modes goes from {100 * err_before:.2f} % to {100 * err_after:.2f} % (the "
            f"polynomial predicted {100 * predicted:.2f} %); keep the design before, expand "
            "closer to the trajectory or at a higher order, or refine",
            AssignmentNotImproved,
            stacklevel=3,
        )
    if margin is not None and margin < 0:
        warnings.warn(
            f"a frequency floor is violated on the exact model by {-margin:.4g} Hz (tracked "
            "modes) although the polynomial meets it",
            AssignmentWarning,
            stacklevel=3,
        )
    at_bound = [d.name for d, v in zip(model.design, y)
                if v <= d.lower + 1e-9 or v >= d.upper - 1e-9]
    if err_after > 0.05 and at_bound:
        warnings.warn(
            f"the best design leaves a {100 * err_after:.2f} % target error and sits on the "
            f"bounds of {', '.join(at_bound)}: the target is out of reach of these design "
            "variables; widen the bounds, add design variables or change the target",
            AssignmentWarning,
            stacklevel=3,
        )


def _design_from(model: FlexibleModel, taylor: TaylorModel | PiecewiseTaylor, dy: np.ndarray
                 ) -> np.ndarray:
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
