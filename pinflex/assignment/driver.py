"""Eigenfrequency assignment along a trajectory (paper 000 Sec. 2.4), right or refused.

:func:`assign_frequencies` builds the QP (12)–(14) from a Taylor model
(:mod:`pinflex.assignment.build`), solves it with ProxQP and checks every answer with the
exact ERLS model along the whole trajectory; errors reported before and after always come
from the exact model.

Confirmation loop. The QP's model is the partially linear polynomial of eq. (9); with
section or material variables on a real arm it can be far off a few millimetres from its
expansion design (Kinova Jaco2, tube diameters, locked joints: 3.95 % predicted, 42.87 %
exact). An answer counts only when the exact model confirms its prediction: the largest
``|predicted / exact − 1|`` over the samples and the target, floor and band modes must be at
most ``confirm_tol`` (:data:`CONFIRM_TOL`, 0.5 % by default). Until it is, a trust-region
loop runs on the exact model:

1. a candidate whose exact cost (the QP's cost with exact frequencies) is lower than the
   current design's, or whose floor/band/budget violation is smaller, is accepted: the model
   is re-expanded there (floors shifted by the exact-minus-predicted offsets at that design)
   and the QP solved again, inside a trust region twice as large;
2. a candidate that is not better is rejected: the trust region around the current design is
   halved and the QP solved again on the same model.

It stops when a candidate is confirmed and meets its floors (with ``refine=True``, when the
exact cost also stops falling), after ``max_refinements`` re-expansions, or when the trust
region falls below ``1e-6`` of the variables' ranges. The answer is the best confirmed
candidate; if none was confirmed, the best candidate with ``confirmed=False`` and a
:class:`~pinflex.exceptions.PredictionNotConfirmed` warning. ``result.status`` says in one
word whether the exact model meets everything (:mod:`pinflex.assignment.result`); the command
line exits with 3 when it does not.

The loop's pieces (candidates checked on the exact model, trust region, restoration,
floor shifts, re-expansion) are in :mod:`pinflex.assignment.candidates`.

Mode identity: a target "mode i" is mode i at the expansion point, followed by shape along the
design change and the trajectory (:mod:`pinflex.assignment.verify`, :mod:`pinflex.erls.tracking`);
``max_error_*`` are the errors of those tracked modes, ``max_error_*_sorted`` those of the
sorted mode numbers. When a target mode crosses or veers with another one along the trajectory
the two differ and :class:`~pinflex.exceptions.ModeCrossingWarning` is issued. A design whose
tracked exact error is larger than before is never reported as an improvement: ``improved``
is False and :class:`~pinflex.exceptions.AssignmentNotImproved` is issued. Floors that the
polynomial declares infeasible are checked on the exact model before refusing
(:mod:`pinflex.assignment.floors`).

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

import numpy as np

from pinflex.assignment.build import build_assignment, design_region
from pinflex.assignment.candidates import (
    Candidate,
    ExactCheck,
    choose,
    design_from,
    hold_floors,
    reexpand,
    restoration,
    trust_box,
)
from pinflex.assignment.floors import FLOOR_RTOL, floors_on_exact
from pinflex.assignment.result import AssignmentResult, outcome
from pinflex.assignment.solve import solve_assignment_qp
from pinflex.assignment.targets import Target, check_trajectory_limits, target_matrix
from pinflex.assignment.verify import Verification, floor_margins
from pinflex.checks import check_q, check_y
from pinflex.erls import FlexibleModel
from pinflex.exceptions import (
    AssignmentInfeasible,
    AssignmentNotImproved,
    AssignmentWarning,
    ConfigurationError,
    FloorsNotMet,
    ModeCrossingWarning,
    PredictionNotConfirmed,
)
from pinflex.progress import ProgressBar
from pinflex.trajectory import Trajectory
from pinflex.trajectory.samples import in_model_order

__all__ = [
    "CONFIRM_TOL",
    "TARGET_TOL",
    "AssignmentResult",
    "Target",
    "assign_frequencies",
    "build_assignment",
    "check_trajectory_limits",
    "design_region",
    "exact_errors",
    "target_matrix",
]

#: Default ``confirm_tol``: the largest relative difference between an answer's predicted and
#: exact frequencies (target, floor and band modes, every sample) for the answer to count.
CONFIRM_TOL = 5e-3

#: Default ``target_tol``: an exact target error above it (5 %) is "target_missed".
TARGET_TOL = 0.05

#: Trust region below this fraction of every variable's range: the loop stops.
_XTOL = 1e-6


def exact_errors(model: FlexibleModel, Q: np.ndarray, y: np.ndarray,
                 targets: Sequence[Target], modes: Sequence[int]):
    """Exact frequencies (ns, len(modes)) [Hz] and the largest relative target error.

    Args:
        model: The flexible model.
        Q: Joint samples (ns, nv), user convention [rad or m].
        y: Design values (ny,), each in its variable's unit.
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
    max_refinements: int = 8,
    report_modes: Sequence[int] = (),
    freq_before_hz: np.ndarray | None = None,
    progress: bool = False,
    confirm_tol: float = CONFIRM_TOL,
    target_tol: float | None = TARGET_TOL,
    **build_kwargs,
) -> AssignmentResult:
    """Solve the assignment QP, confirm it on the exact model, re-expand until it is.

    Args:
        model: The flexible model.
        trajectory: Joint samples in the model's user coordinates.
        targets: Desired frequency histories.
        y_before: Design the errors "before" refer to (default: lower bounds, i.e. no added
            mass).
        refine: Keep re-expanding while the exact cost falls, also after the answer is
            confirmed (without it the loop stops at the first confirmed answer).
        max_refinements: Most re-expansions.
        report_modes: Extra modes whose frequencies are reported (e.g. 2, 3, 4).
        freq_before_hz: Exact frequencies of ``y_before`` along the trajectory, (ns, modes)
            with the modes in the targets-then-``report_modes`` order, when the caller
            already has them (sweeps share them between cases).
        progress: Show a progress bar of the stages (expansion, exact model before, QPs and
            their exact checks) on stderr.
        confirm_tol: Largest relative difference between the answer's predicted and exact
            frequencies (module docstring); > 0.
        target_tol: The status is ``"target_missed"`` when the exact target error after is
            above it (fraction; default :data:`TARGET_TOL`, 5 %; None: not checked).
        **build_kwargs: Passed to :func:`~pinflex.assignment.build.build_assignment`.

    Raises:
        AssignmentInfeasible: the constraints admit no design (on the exact model too when
            floors are involved).
        ConfigurationError: ``confirm_tol`` or ``target_tol`` not positive.
    """
    if not (isinstance(confirm_tol, int | float) and confirm_tol > 0):
        raise ConfigurationError(f"confirm_tol = {confirm_tol!r}: give a positive fraction")
    if target_tol is not None and not (isinstance(target_tol, int | float) and target_tol > 0):
        raise ConfigurationError(f"target_tol = {target_tol!r}: give a positive fraction")
    bar = ProgressBar(4 + 2 * max_refinements, "assignment stages", bool(progress))
    t_start, c_start = time.perf_counter(), time.thread_time()
    timings: dict[str, float] = {}
    cpu: dict[str, float] = {}

    def stage(key: str, since: tuple[float, float]) -> None:  # add a stage's wall and CPU
        timings[key] = timings.get(key, 0.0) + time.perf_counter() - since[0]
        cpu[key] = cpu.get(key, 0.0) + time.thread_time() - since[1]

    def now() -> tuple[float, float]:
        return time.perf_counter(), time.thread_time()

    if isinstance(targets, str | bytes) or not isinstance(targets, Sequence) or not all(
            isinstance(t, Target) for t in targets):
        raise ConfigurationError(f"targets must be a list of pinflex Target objects (mode, "
                                 f"frequency history), got {targets!r}"[:300])
    trajectory = in_model_order(model, trajectory)  # columns matched by joint name
    Q = check_q(model, trajectory.q)
    check_trajectory_limits(model, trajectory)
    if y_before is None:
        y_before = np.array([d.lower for d in model.design])
    y_before = check_y(model, y_before)
    modes: list[int] = []
    for m in [t.mode for t in targets] + list(report_modes):
        if m not in modes:
            modes.append(int(m))
    floors = list(build_kwargs.get("floors", ()))
    bands = list(build_kwargs.get("bands", ()))
    vmodes = modes + sorted(({int(f[0]) for f in floors} | {int(b[0]) for b in bands})
                            - set(modes))
    tgt = target_matrix(targets, Q.shape[0])
    tmodes = [t.mode for t in targets]
    if freq_before_hz is not None:
        f_before = np.asarray(freq_before_hz, dtype=float)
        if f_before.shape != (Q.shape[0], len(modes)):
            raise ConfigurationError(
                f"freq_before_hz has shape {f_before.shape}; expected {(Q.shape[0], len(modes))}"
            )
    quantity = build_kwargs.get("quantity", "freq_hz")

    t0 = now()
    problem, taylor = build_assignment(model, trajectory, targets, **build_kwargs)
    stage("expansion_and_build", t0)
    bar.update()
    reference = (taylor.q0, taylor.y0)
    check = ExactCheck(model, Q, trajectory, targets, vmodes, reference, build_kwargs)
    check.didx = list(taylor.design_idx)
    t0 = now()
    if freq_before_hz is None:
        before = check.verify(y_before)
    else:  # given by the caller (a sweep shares them): taken as the tracked frequencies
        extra = vmodes[len(modes):]
        if extra:
            fe = model.frequencies(Q, y_before, n_modes=max(extra))[:, [m - 1 for m in extra]]
            f_before = np.hstack([f_before, fe])
        cols = [vmodes.index(m) for m in tmodes]
        err = float(np.abs(f_before[:, cols].T / tgt - 1.0).max())
        before = Verification(None, f_before, f_before, err, err)
    stage("exact_before", t0)
    bar.update()

    def rebuild(floor_rows, tm, **kw):
        kwargs = dict(build_kwargs, taylor=tm, **kw)
        if floors:
            kwargs["floors"] = floor_rows
        return build_assignment(model, trajectory, targets, **kwargs)

    # the first QP, on the whole design box
    t0 = now()
    floors_model = "taylor" if floors else ""
    try:
        solution = solve_assignment_qp(problem)
    except AssignmentInfeasible as exc:
        if not floors or exc.result is not None:
            raise _refusal(exc, problem) from None
        problem, taylor, solution = floors_on_exact(
            model, Q, lambda rows, tm: rebuild(rows, tm), problem, taylor, y_before, exc,
            floors, quantity)
        floors_model = "taylor+exact"
    stage("qp", t0)
    bar.update()
    t0 = now()
    cand = check.evaluate(design_from(model, taylor, solution.dy), taylor, problem, solution,
                          floors_model)
    cand = hold_floors(check, cand, rebuild)
    stage("exact_verification", t0)
    bar.update()

    # the design the model was expanded at: the loop's current point
    didx = list(taylor.design_idx)
    lo = np.array([model.design[j].lower for j in didx])
    hi = np.array([model.design[j].upper for j in didx])
    span = np.where(np.isfinite(hi - lo), hi - lo, np.maximum(np.abs(taylor.y0[didx]), 1.0))
    current: Candidate | None = None  # checked on the exact model only when needed
    history: list[dict] = []
    seen: list[Candidate] = []
    radius = None  # trust radius as a fraction of each variable's range; None: the whole box
    refinements = 0
    solves_left = 3 * (max_refinements + 1) + 10  # accepted steps plus trust-region halvings
    while True:
        seen.append(cand)
        solves_left -= 1
        ok = cand.gap <= confirm_tol and cand.viol <= FLOOR_RTOL
        entry = {"y": cand.y.tolist(), "gap": cand.gap, "cost": cand.cost,
                 "violation": cand.viol, "accepted": True,
                 "radius": None if radius is None else float(radius)}
        history.append(entry)
        if ok and not refine:
            break
        if current is None:
            t0 = now()
            y_exp = taylor.y0  # the first expansion design (no re-expansion yet)
            current = check.evaluate(y_exp, None, None, None, exact=before if (
                np.array_equal(y_exp, y_before) and freq_before_hz is None) else None)
            stage("exact_verification", t0)
        accept = cand.better_than(current)
        entry["accepted"] = bool(accept)
        step = float(np.max(np.abs(cand.y[didx] - current.y[didx]) / span))
        if accept:
            confirmed = cand.gap <= confirm_tol
            stalled = (current.viol - cand.viol <= 0.01 * current.viol if cand.viol > FLOOR_RTOL
                       else current.cost - cand.cost <= 1e-6 * abs(cand.cost))
            current = cand
            if confirmed and stalled and (refine or cand.viol > FLOOR_RTOL):
                break
            if refinements >= max_refinements:
                break
            t0 = now()
            problem, taylor = reexpand(model, trajectory, targets, build_kwargs, check,
                                        current, taylor.q0, rebuild)
            stage("refinement", t0)
            refinements += 1
            radius = None if radius is None else min(2.0 * radius, 1.0)
        else:
            radius = 0.5 * (step if radius is None else min(radius, step))
            if radius < _XTOL or ok:
                break
        if solves_left <= 0:
            break
        t0 = now()
        box = problem if radius is None else trust_box(problem, radius * span)
        try:
            solution = solve_assignment_qp(box)
        except AssignmentInfeasible:
            restored = restoration(box)  # floors out of reach here: the closest approach
            if restored is None:
                break
            box = restored
            try:
                solution = solve_assignment_qp(box)
            except AssignmentInfeasible:
                break
        cand = check.evaluate(design_from(model, taylor, solution.dy), taylor, box, solution,
                              "taylor+exact" if floors and refinements else floors_model)
        cand = hold_floors(check, cand, rebuild, trust=None if radius is None else
                            radius * span)
        stage("refinement", t0)
        bar.update()
    answer = choose(seen, confirm_tol)
    margin = (floor_margins(model, Q, answer.y, floors, reference) if floors else None)
    bar.total = bar.done
    bar.close()
    timings["total"] = time.perf_counter() - t_start
    cpu["total"] = time.thread_time() - c_start
    after = answer.exact
    err_before, err_after = before.max_error, after.max_error
    confirmed = answer.gap <= confirm_tol
    constraints_met = answer.viol <= FLOOR_RTOL
    worse = err_after > err_before * (1 + 1e-9)
    status = outcome(confirmed=confirmed, constraints_met=constraints_met, improved=not worse,
                     error_after=err_after, target_tol=target_tol)
    pred = answer.predicted
    assert pred is not None and answer.problem is not None and answer.solution is not None
    cols = [vmodes.index(m) for m in tmodes]
    predicted_err = float(np.max(np.abs(pred[:, cols].T / tgt - 1.0)))
    events = _target_events(before, after, tmodes)
    _warn_outcome(model, answer.y, before, after, events, tmodes, predicted_err, margin)
    if not confirmed:
        warnings.warn(
            f"the exact model does not confirm the answer: its frequencies are up to "
            f"{100 * answer.gap:.3g} % off the Taylor model's prediction (confirm_tol "
            f"{100 * confirm_tol:.3g} %) after {refinements} re-expansions; the design is the "
            "best one checked. Raise the order, give fewer or narrower design variables, or "
            "start closer (expansion y0)",
            PredictionNotConfirmed, stacklevel=2)
    elif not constraints_met:
        floors_hz = f"; the floors' exact margin is {margin:.4g} Hz" if margin is not None else ""
        warnings.warn(
            f"a floor, band or the mass budget is violated on the exact model by "
            f"{100 * answer.viol:.3g} % of its limit at the closest design the confirmed "
            f"Taylor steps reached{floors_hz}: out of reach of these design variables within "
            "their bounds (widen them, add variables or lower the floors)",
            FloorsNotMet, stacklevel=2)
    indicator = _motion_validity(model, trajectory, Q, after)
    return AssignmentResult(
        found=bool(answer.solution.found),
        design={d.name: float(v) for d, v in zip(model.design, answer.y)},
        y=answer.y,
        y_before=y_before,
        modes=tuple(vmodes),
        targets_hz=tgt,
        freq_before_hz=before.freq_hz,
        freq_after_hz=after.freq_hz,
        max_error_before=err_before,
        max_error_after=err_after,
        predicted_max_error_after=predicted_err,
        problem=answer.problem,
        solution=answer.solution,
        taylor=answer.taylor,
        refinements=refinements,
        timings_s=timings,
        cpu_timings_s=cpu,
        settings={
            "mass_budget_kg": build_kwargs.get("mass_budget_kg"),
            "floors": [(int(m), float(f) if np.ndim(f) == 0 else
                        np.asarray(f, dtype=float).tolist()) for m, f in floors],
            "bands": [(int(m), float(a), float(b)) for m, a, b in bands],
            "quantity": quantity,
            "confirm_tol": float(confirm_tol),
            "target_tol": None if target_tol is None else float(target_tol),
        },
        freq_before_sorted_hz=before.sorted_hz,
        freq_after_sorted_hz=after.sorted_hz,
        max_error_before_sorted=before.max_error_sorted,
        max_error_after_sorted=after.max_error_sorted,
        improved=bool(err_after < err_before),
        events=events,
        floors_model=answer.floors_model,
        floor_margin_hz=margin,
        joints=model.joint_labels(),
        predicted_hz=pred,
        prediction_gap=answer.gap,
        confirmed=confirmed,
        constraints_met=constraints_met,
        status=status,
        iterations=tuple(history),
        validity=indicator,
    )


def _motion_validity(model, trajectory, Q, after):
    """The validity indicator of eq. (1) along the trajectory, against the design after.

    ``ω_1`` per sample is the lowest exact frequency the assignment solved there (targets,
    floors, bands and reported modes); a warning says when the motion is too fast for the
    frozen-pose modes the targets are set on (:mod:`pinflex.erls.validity`).
    """
    from pinflex.erls.validity import sample_rates, validity

    times = np.asarray(trajectory.times_s, dtype=float)
    if times.size < 2:
        return None
    cols = [np.asarray(after.freq_hz, dtype=float)]
    if after.sorted_hz is not None:
        cols.append(np.asarray(after.sorted_hz, dtype=float))
    w1 = 2.0 * np.pi * np.nanmin(np.hstack(cols), axis=1)
    qd, qdd = sample_rates(times, Q)
    return validity(model, times, Q, qd, qdd, w1, what="the trajectory", basis="model")


def _refusal(exc: AssignmentInfeasible, problem) -> AssignmentInfeasible:
    """The QP's refusal, saying which model refused it."""
    groups = set(problem.constraint_groups)
    model_based = bool(groups & {"floor", "band"})
    who = "taylor" if model_based else "constraints"
    text = ("refused by the partially linear Taylor model (floors/bands on the polynomial)"
            if model_based else "refused by the box and linear constraints (exact)")
    return AssignmentInfeasible(f"{exc} [{text}]", exc.problem, exc.result, refused_by=who)


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


