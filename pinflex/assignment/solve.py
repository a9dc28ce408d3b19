"""Solving the assignment QP: ProxQP with an active-set polish, and a SciPy cross-check."""

from __future__ import annotations

import numpy as np

from pinflex.assignment.problem import AssignmentQP, QPSolution
from pinflex.exceptions import AssignmentInfeasible
from pinflex.linalg import readonly as _readonly


def _scaled(problem: AssignmentQP):
    """Scale the cost by its largest Hessian entry and each row by its largest coefficient.

    The minimiser is unchanged; tolerances then act on numbers of order one whatever the
    units (eigenvalues of order 1e6 rad²/s² give Hessians of order 1e12).
    """
    s = float(np.max(np.abs(problem.R))) if problem.R.size else 0.0
    if not s > 0.0:
        s = max(float(np.max(np.abs(problem.h), initial=0.0)), 1.0)
    ra = np.max(np.abs(problem.A), axis=1, initial=0.0)
    rc = np.max(np.abs(problem.C), axis=1, initial=0.0)
    ra, rc = np.where(ra > 0.0, ra, 1.0), np.where(rc > 0.0, rc, 1.0)  # keep all-zero rows
    return (
        problem.R / s, problem.h / s, s,
        problem.A / ra[:, None], problem.b / ra,
        problem.C / rc[:, None], problem.l / rc, problem.u / rc, ra, rc,
    )


def solve_assignment_qp(
    problem: AssignmentQP, *, eps_abs: float = 1e-10, max_iter: int = 1000, polish: bool = True
) -> QPSolution:
    """Solve an assignment QP with proxsuite's dense ProxQP.

    If there are equality or inequality rows, a linear program (HiGHS, through scipy) first
    tests feasibility, because ProxQP does not reliably flag infeasible problems (it can run
    to ``max_iter``). The cost is divided by ``max |R|`` and each constraint row by its
    largest coefficient before the solve (the minimiser does not change). ProxQP runs with
    ``eps_abs`` on the primal and dual residuals, ``eps_rel = 0``, and the duality-gap test
    enabled at the same tolerance (without it, ProxQP can stop with active constraints not
    quite tight).

    ProxQP's stopping test bounds residuals, not the error in δy: a constraint with a small
    multiplier can be left ~1e-8 from tight at ``eps_abs = 1e-10``. With ``polish`` (default),
    the constraints whose ProxQP multipliers are non-zero are taken as active and the
    equality-constrained KKT system is solved directly; the polished point replaces ProxQP's
    if it solves that system, is feasible to 1e-12 (scaled) and its multipliers have the
    right signs — a KKT point, hence the optimum of the convex QP. ``QPSolution.polished``
    says whether that happened; the duals are ProxQP's.

    Args:
        problem: From :func:`build_assignment_qp`.
        eps_abs: Absolute tolerance on the scaled residuals and the duality gap.
        max_iter: ProxQP iteration limit.
        polish: Refine the answer on ProxQP's active set.

    Returns:
        The :class:`QPSolution` (``time_s`` is ProxQP's own setup + solve time).

    Raises:
        AssignmentInfeasible: No δy satisfies the constraints (the message names the
            conflicting groups — box, equalities, inequalities, floors, bands — as found by a
            linear-programming feasibility test; ``result`` is then None), or ProxQP stopped
            without an optimum (``result`` is its :class:`QPSolution`, ``found=False``).
    """
    from proxsuite import proxqp

    H, g, s, A, b, C, lc, uc, ra, rc = _scaled(problem)
    ny, n_eq, n_in = problem.ny, A.shape[0], C.shape[0]
    has_box = bool(np.any(np.isfinite(problem.lower)) or np.any(np.isfinite(problem.upper)))
    if np.any(problem.lower > problem.upper) or n_eq + n_in > 0:
        # an LP feasibility test first: ProxQP only reports infeasibility slowly, if at all
        message = _diagnose(problem)
        if message is not None:
            raise AssignmentInfeasible(message, problem, None)
    qp = proxqp.dense.QP(ny, n_eq, n_in, has_box)
    st = qp.settings
    st.eps_abs, st.eps_rel = eps_abs, 0.0
    st.check_duality_gap = True
    st.eps_duality_gap_abs, st.eps_duality_gap_rel = eps_abs, 0.0
    st.max_iter = int(max_iter)
    st.compute_timings = True
    st.verbose = False
    args = [H, g, A if n_eq else None, b if n_eq else None]
    args += [C, lc, uc] if n_in else [None, None, None]
    if has_box:
        args += [problem.lower, problem.upper]
    qp.init(*args)
    qp.solve()
    res = qp.results
    status = str(res.info.status).rsplit(".", 1)[-1]
    dy = np.array(res.x, dtype=float)
    z = np.array(res.z, dtype=float)
    found = status == "PROXQP_SOLVED"
    polished = False
    if found and polish:
        box = (problem.lower, problem.upper) if has_box else None
        dy, polished = _polish(H, g, A, b, C, lc, uc, box, dy, z[:n_in], z[n_in:])
    solution = QPSolution(
        found=found,
        dy=_readonly(dy),
        iterations=int(res.info.iter),
        time_s=1e-6 * float(res.info.run_time),
        status=status,
        objective=problem.cost(dy),
        max_violation=problem.max_violation(dy),
        dual_eq=_readonly(s * np.asarray(res.y, dtype=float) / ra) if n_eq else np.zeros(0),
        dual_in=_readonly(s * z[:n_in] / rc) if n_in else np.zeros(0),
        dual_box=_readonly(s * z[n_in:]) if has_box else np.zeros(0),
        polished=polished,
    )
    if not solution.found:
        message = _diagnose(problem)
        if message is None:
            message = (
                f"ProxQP stopped with status {status} after {solution.iterations} iterations "
                f"although the constraints are feasible; raise max_iter (now {max_iter}) or "
                "loosen eps_abs"
            )
        raise AssignmentInfeasible(message, problem, solution)
    return solution


def _polish(H, g, A, b, C, lc, uc, box, x, z_in, z_box) -> tuple[np.ndarray, bool]:
    """Solve the KKT system on the active set read from ProxQP's multipliers (scaled data)."""
    ny = x.size
    z_all = np.concatenate([z_in, z_box])
    tiny = 1e-9 * max(1.0, float(np.max(np.abs(z_all), initial=0.0)))
    eye = np.eye(ny)
    up_c, lo_c = z_in > tiny, z_in < -tiny
    rows = [A, C[up_c], C[lo_c]]
    rhs = [b, uc[up_c], lc[lo_c]]
    signs = [np.ones(up_c.sum()), -np.ones(lo_c.sum())]
    if box is not None:
        up_b, lo_b = z_box > tiny, z_box < -tiny
        rows += [eye[up_b], eye[lo_b]]
        rhs += [box[1][up_b], box[0][lo_b]]
        signs += [np.ones(up_b.sum()), -np.ones(lo_b.sum())]
    E, e, sign = np.vstack(rows).reshape(-1, ny), np.concatenate(rhs), np.concatenate(signs)
    if not np.all(np.isfinite(e)):
        return x, False
    m, n_eq = E.shape[0], A.shape[0]
    kkt = np.block([[H, E.T], [E, np.zeros((m, m))]])
    sol = np.linalg.lstsq(kkt, np.concatenate([-g, e]), rcond=None)[0]
    x_p, nu = sol[:ny], sol[ny + n_eq:]

    def violation(v):
        parts = [np.abs(A @ v - b), np.maximum(C @ v - uc, 0.0), np.maximum(lc - C @ v, 0.0)]
        if box is not None:
            parts += [np.maximum(v - box[1], 0.0), np.maximum(box[0] - v, 0.0)]
        return max((float(np.max(p)) for p in parts if p.size), default=0.0)

    rhs_all = np.concatenate([-g, e])
    scale = max(1.0, float(np.max(np.abs(rhs_all))))
    # a feasible KKT point with correctly signed multipliers is the optimum of the convex QP
    ok = (
        float(np.max(np.abs(kkt @ sol - rhs_all))) <= 1e-10 * scale
        and violation(x_p) <= 1e-12 * max(1.0, float(np.max(np.abs(x_p))))
        and bool(np.all(sign * nu >= -1e-9 * max(1.0, float(np.max(np.abs(nu), initial=0.0)))))
    )
    return (x_p, True) if ok else (x, False)


def solve_assignment_qp_scipy(problem: AssignmentQP, *, tol: float = 1e-12) -> QPSolution:
    """Solve an assignment QP independently of proxsuite (for cross-checks).

    SLSQP (scipy) on the same scaled problem, then a primal active-set refinement started
    from the constraints SLSQP leaves within ``1e-7`` of tight: solve the equality-constrained
    KKT system, add the most violated constraint or drop the one with the most negative
    multiplier, until the KKT conditions hold (then the answer is exact to round-off); if that
    does not settle within 50 steps, SLSQP's point is returned.

    Args:
        problem: From :func:`build_assignment_qp`.
        tol: SLSQP ``ftol``.

    Returns:
        The :class:`QPSolution` (``iterations`` are SLSQP's, ``time_s`` is 0: not measured).

    Raises:
        AssignmentInfeasible: As :func:`solve_assignment_qp`.
    """
    from scipy.optimize import minimize

    message = _diagnose(problem)
    if message is not None:
        raise AssignmentInfeasible(message, problem, None)
    H, g, _, A, b, C, lc, uc, _, _ = _scaled(problem)
    # all inequalities as G x <= r (box rows included)
    eye = np.eye(problem.ny)
    G = np.vstack([C, -C, eye, -eye])
    r = np.concatenate([uc, -lc, problem.upper, -problem.lower])
    keep = np.isfinite(r)
    G, r = G[keep], r[keep]
    constraints = []
    if A.shape[0]:
        constraints.append({"type": "eq", "fun": lambda x: A @ x - b, "jac": lambda x: A})
    if G.shape[0]:
        constraints.append({"type": "ineq", "fun": lambda x: r - G @ x, "jac": lambda x: -G})
    x0 = np.clip(np.zeros(problem.ny), problem.lower, problem.upper)
    out = minimize(
        lambda x: 0.5 * x @ H @ x + g @ x, x0, jac=lambda x: H @ x + g, method="SLSQP",
        constraints=constraints, options={"ftol": tol, "maxiter": 1000},
    )
    x = _active_set_refine(H, g, A, b, G, r, np.asarray(out.x, dtype=float))
    return QPSolution(
        found=bool(out.success),
        dy=_readonly(x),
        iterations=int(out.nit),
        time_s=0.0,
        status=str(out.message),
        objective=problem.cost(x),
        max_violation=problem.max_violation(x),
    )


def _active_set_refine(H, g, A, b, G, r, x, max_steps: int = 50) -> np.ndarray:
    """Refine ``x`` for ``min ½xᵀHx + gᵀx`` s.t. ``Ax = b``, ``Gx <= r`` (rows scaled to 1)."""
    ny, n_eq = x.size, A.shape[0]
    active = np.abs(G @ x - r) <= 1e-7 * np.maximum(1.0, np.abs(r))
    for _ in range(max_steps):
        E = np.vstack([A, G[active]])
        m = E.shape[0]
        kkt = np.block([[H, E.T], [E, np.zeros((m, m))]])
        sol = np.linalg.lstsq(kkt, np.concatenate([-g, b, r[active]]), rcond=None)[0]
        x_new, mult = sol[:ny], sol[ny + n_eq:]
        slack = G @ x_new - r
        tol = 1e-12 * max(1.0, float(np.max(np.abs(x_new))))
        if slack.size and np.max(np.where(active, -np.inf, slack)) > tol:
            active[int(np.argmax(np.where(active, -np.inf, slack)))] = True
        elif mult.size and mult.min() < -1e-10 * max(1.0, float(np.max(np.abs(mult)))):
            active[np.flatnonzero(active)[int(np.argmin(mult))]] = False
        else:
            return x_new
    return x


def _diagnose(problem: AssignmentQP) -> str | None:
    """Return a message naming conflicting constraint groups, or None if feasible.

    Feasibility of the box with each group, then each pair of groups, is tested by a
    linear program (HiGHS through scipy); the first infeasible combination is reported.
    """
    from scipy.optimize import linprog

    ny = problem.ny
    bad = np.flatnonzero(problem.lower > problem.upper)
    if bad.size:
        j = int(bad[0])
        return (
            f"the assignment QP has no feasible point: box bound of {problem.names[j]} has "
            f"lower {problem.lower[j]:g} > upper {problem.upper[j]:g}; fix the bounds"
        )
    _, _, _, A, b, C, lc, uc, _, _ = _scaled(problem)
    groups = np.array(problem.constraint_groups)
    present = ([("equalities", None)] if A.shape[0] else []) + [
        (name, name) for name in ("inequality", "floor", "band") if np.any(groups == name)
    ]
    bounds = [
        (None if not np.isfinite(a) else a, None if not np.isfinite(z) else z)
        for a, z in zip(problem.lower, problem.upper)
    ]

    def feasible(selection) -> bool:
        use_eq = any(g is None for _, g in selection)
        mask = np.isin(groups, [g for _, g in selection if g is not None])
        Cs, ls, us = C[mask], lc[mask], uc[mask]
        fu, fl = np.isfinite(us), np.isfinite(ls)
        A_ub = np.vstack([Cs[fu], -Cs[fl]]).reshape(-1, ny)
        b_ub = np.concatenate([us[fu], -ls[fl]])
        out = linprog(
            np.zeros(ny), A_ub=A_ub if A_ub.size else None, b_ub=b_ub if b_ub.size else None,
            A_eq=A if use_eq and A.shape[0] else None, b_eq=b if use_eq and A.shape[0] else None,
            bounds=bounds, method="highs",
        )
        return out.status != 2

    if feasible(present):
        return None
    label = {"equalities": "the equality constraints", "inequality": "the linear inequalities "
             "(e.g. a mass budget)", "floor": "the frequency floors", "band": "the band rows"}
    for size in (1, 2):
        for i, first in enumerate(present):
            for second in present[i + 1:] if size == 2 else [None]:
                selection = [first] if second is None else [first, second]
                if not feasible(selection):
                    what = " and ".join(label[name] for name, _ in selection)
                    return (
                        f"the assignment QP has no feasible point: the box bounds and {what} "
                        "cannot hold together; widen the bounds or relax those constraints"
                    )
    return (
        "the assignment QP has no feasible point: the box bounds and all constraint groups "
        f"({', '.join(name for name, _ in present)}) together cannot hold, although any two "
        "can; relax one of them"
    )
