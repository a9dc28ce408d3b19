"""The assignment QP of paper 000 (eq. 12–14) from a Taylor model sampled on the trajectory.

:func:`build_assignment` expands the chosen modes at ``(q0, y0)`` (:mod:`pinflex.parametric`)
or reuses a given model, samples the partially linear polynomials ``l_{i,0}(q(t))``,
``l_{i,j}(q(t))`` on the trajectory and returns the QP with the trapezoidal rule on the
trajectory grid (:mod:`pinflex.assignment.problem`); :func:`design_region` says where in the
design box a model chosen by tolerance must hold.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence

import numpy as np

from pinflex.assignment.points import PiecewiseTaylor
from pinflex.assignment.problem import AssignmentQP, build_assignment_qp
from pinflex.assignment.targets import Target, target_matrix
from pinflex.checks import check_q, check_y
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.parametric import TaylorModel, expand
from pinflex.trajectory import Trajectory

__all__ = ["HIGHEST_CHOSEN_ORDER", "affordable_order", "budget_mass", "build_assignment",
           "design_region", "predicted_hz"]

#: Highest Taylor order a tolerance may choose (each order is judged by the next two).
HIGHEST_CHOSEN_ORDER = 8


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
    Q = check_q(model, trajectory.in_order(model.joint_names))
    if Q.ndim != 2:
        raise ConfigurationError("the trajectory needs joint samples of shape (ns, nv)")
    ns = Q.shape[0]
    if q0 is None:
        q0 = Q[ns // 2]
    y0 = check_y(model, y0)
    modes = []
    for m in [t.mode for t in targets] + [f[0] for f in floors] + [b[0] for b in bands]:
        if m not in modes:
            modes.append(int(m))
    if taylor_tol is not None and points_tol is not None:
        raise ConfigurationError("give taylor_tol (one point, order by tolerance) or "
                                 "points_tol (expansion points by tolerance), not both")
    if taylor is None and (points_tol is not None or taylor_tol is not None):
        # bounded before any work: each order is judged by expansions two orders higher
        nd = model.ny if design is None else len(design)
        cap = affordable_order(model, model.nv + nd, nd)
    if taylor is None and points_tol is not None:
        from pinflex.assignment.points import points_for_tolerance

        taylor = _capped(lambda: points_for_tolerance(
            model, Q, y0, tol=points_tol, modes=modes, design=design, quantity=quantity,
            orders=range(1, cap + 1)), cap, model, nd)
    elif taylor is None and taylor_tol is not None:
        over = design_region(model, Q, y0, design)
        taylor = _capped(lambda: expand(model, q0, y0, order=cap, modes=modes, design=design,
                                        tol=taylor_tol, over=over), cap, model, nd)
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
        m0, grad = budget_mass(model, y0v, didx, order=1)
        A_rows.append(grad[didx])
        b_rows.append(float(mass_budget_kg) - m0)
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



def budget_mass(model: FlexibleModel, y: np.ndarray, didx: Sequence[int], *, order: int = 0):
    """The mass a budget counts: the design mass of the chosen variables [kg].

    Design point masses plus the beams of links whose section or material the variables set
    (:func:`pinflex.erls.design.design_mass`), less the design point masses that are not
    chosen (they are fixed during the assignment).

    Args:
        model: The flexible model.
        y: Design vector (ny,).
        didx: Indices of the chosen variables.
        order: 0 for the mass, 1 for ``(mass, gradient (ny,))``.
    """
    from pinflex.erls.design import design_mass

    others = [j for j in range(model.ny) if j not in set(didx)]
    fixed = float(np.sum(np.asarray(y)[others])) if all(
        model.design[j].kind == "mass" for j in others) else 0.0
    if order == 0:
        return design_mass(model, y) - fixed
    m, grad = design_mass(model, y, order=1)
    return m - fixed, grad


def predicted_hz(taylor: TaylorModel | PiecewiseTaylor, Q: np.ndarray, y: np.ndarray,
                 modes: Sequence[int], quantity: str = "freq_hz") -> np.ndarray:
    """The QP's prediction of the frequencies of ``modes`` at design ``y`` [Hz], (ns, k).

    The partially linear polynomial of eq. (9), ``l0 + L (y − y0)``, in the expanded
    ``quantity`` converted to Hz; NaN for modes the Taylor model does not carry. This one
    function gives the predictions that results, reports and the confirmation compare with
    the exact model.
    """
    l0, L = taylor.linear_parts(Q, quantity=quantity)
    didx = list(taylor.design_idx)
    dy = np.asarray(y, dtype=float)[didx] - taylor.y0[didx]
    pred = l0 + np.einsum("kmj,j->km", L, dy)
    if quantity == "eigval":
        pred = np.sqrt(np.maximum(pred, 0.0)) / (2.0 * np.pi)
    out = np.full((pred.shape[0], len(modes)), np.nan)
    for c, m in enumerate(modes):
        if m in taylor.modes:
            out[:, c] = pred[:, taylor.modes.index(m)]
    return out


def affordable_order(model: FlexibleModel, nvars: int, ndesign: int,
                     highest: int = HIGHEST_CHOSEN_ORDER) -> int:
    """The highest order up to ``highest`` a tolerance may choose within the memory limit.

    An order ``p`` chosen by tolerance is judged by an expansion of order ``p + 2``
    (:func:`pinflex.parametric.fidelity.order_for_tolerance`), so that is the expansion whose
    memory (:func:`pinflex.resources.taylor_estimate`) must fit
    (:func:`pinflex.resources.memory_limit_bytes`). Checked before any expansion, so a
    request that cannot fit is refused at once instead of after the lower orders' work.

    Raises:
        ResourceLimitExceeded: Not even order 1 (judged at order 3) fits.
    """
    from pinflex.exceptions import ResourceLimitExceeded
    from pinflex.resources import check_memory, taylor_estimate

    for p in range(highest, 0, -1):
        try:
            check_memory(taylor_estimate(nvars, p + 2, model.ndof, ndesign)[0],
                         f"a Taylor expansion of order {p + 2} in {nvars} variables on "
                         f"{model.ndof} dof (judging order {p})",
                         "lower the tolerance's demand, expand fewer design variables, or use "
                         "fewer elements")
        except ResourceLimitExceeded:
            if p == 1:
                raise
            continue
        return p
    return 1


def _capped(run, cap: int, model, nd: int):
    """Run a choice by tolerance; say when the memory limit capped its orders."""
    try:
        return run()
    except ConfigurationError as exc:
        if cap >= HIGHEST_CHOSEN_ORDER:
            raise
        from pinflex.resources import format_gb, taylor_estimate

        need = taylor_estimate(model.nv + nd, cap + 3, model.ndof, nd)[0]
        raise ConfigurationError(
            f"{exc}; orders above {cap} were not tried: judging order {cap + 1} needs an "
            f"expansion of order {cap + 3} in {model.nv + nd} variables on {model.ndof} dof, "
            f"about {format_gb(need)} of memory (more than allowed: PINFLEX_MAX_MEMORY_GB)") from None
