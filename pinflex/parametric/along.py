"""Taylor models along a trajectory: several expansion points, and fixed samples."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pinflex import jets
from pinflex.checks import check_q, check_y
from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.jets import JetSpace
from pinflex.linalg import readonly as _readonly
from pinflex.parametric.model import TaylorModel, expand


@dataclass(frozen=True)
class TrajectoryExpansion:
    """Several Taylor models covering a trajectory, each on a run of consecutive samples.

    Attributes:
        models: The Taylor models (joints expanded, design fixed).
        segments: Sample ranges ``(start, stop)`` (stop exclusive) covered by each model.
        order: Their common order p.
        tol: Relative tolerance they were chosen for.
        max_error: Largest relative error over all samples, checked with the exact model.
        candidates: ``{order: number of expansion points}`` for every order tried.
        estimate: With ``criterion="estimate"``: the largest two-term estimate over the
            samples, each from its segment's model (None with the exact criterion).
    """

    models: tuple[TaylorModel, ...]
    segments: tuple[tuple[int, int], ...]
    order: int
    tol: float
    max_error: float
    candidates: dict[int, int]
    estimate: float | None = None

    def evaluate(self, Q, *, quantity: str = "freq_hz") -> np.ndarray:
        """Values at the trajectory's own samples Q (ns, nv), each from its segment's model.

        Args:
            Q: The joint samples (ns, nv) the expansion was built on, user convention
                [rad or m]; sample ``i`` is evaluated by the model of the segment holding
                ``i`` (radius warnings off).
            quantity: ``'freq_hz'`` (default, [Hz]) or ``'eigval'`` ([rad²/s²]).

        Returns:
            Values (ns, k).

        Raises:
            ConfigurationError: ``Q`` has the wrong number of joint values.
        """
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        out: np.ndarray | None = None
        for tm, (a, b) in zip(self.models, self.segments):
            v = tm.evaluate(Q[a:b], quantity=quantity, warn=False)
            if out is None:
                out = np.empty((Q.shape[0],) + v.shape[1:])
            out[a:b] = v
        return np.empty((Q.shape[0], 0)) if out is None else out


def two_term_estimates(hi: TaylorModel, Q, order: int, *, quantity: str = "freq_hz"
                       ) -> np.ndarray:
    """Error estimate (samples, modes) of order ``order`` from a model ``hi`` of order + 2.

    The larger of the next two orders' relative terms,
    ``max(|T_(p+1) − T_p| / |T_(p+1)|, |T_(p+2) − T_(p+1)| / |T_(p+2)|)``. One term alone
    vanishes wherever the next coefficient does (a pose where the frequency is even in a
    joint has no odd terms; benchmark A at tol 1e-4: one term gave 3.2e-5 for an order-3 cover
    whose exact error is 8.1e-4, two terms give 1.2e-3).
    """
    from pinflex.parametric.fidelity import two_term_estimates as _all_orders

    return _all_orders(hi, Q, quantity=quantity)[order]


def _cover(model, Q, y, exact, tol, order, modes, joints, quantity, step):
    """Greedy cover of the samples by expansions of one order; returns models and segments.

    ``exact`` None: judge each sample by the two-term estimate (:func:`two_term_estimates`:
    an expansion two orders higher), else by the exact values.
    """
    ns = Q.shape[0]
    models, segments = [], []
    s = 0
    while s < ns:
        best = None
        c = s
        while c < ns:
            if exact is None:
                hi = expand(model, Q[c], y, order=order + 2, modes=modes, joints=joints,
                            design=[])
                est = two_term_estimates(hi, Q, order, quantity=quantity).max(axis=1)
                ok = est <= tol
                tm = expand(model, Q[c], y, order=order, modes=modes, joints=joints, design=[])
            else:
                tm = expand(model, Q[c], y, order=order, modes=modes, joints=joints, design=[])
                approx = tm.evaluate(Q, quantity=quantity, warn=False)
                ok = np.all(np.abs(approx / exact - 1) <= tol, axis=1)
            a = c
            while a > s and ok[a - 1]:
                a -= 1
            if a > s:  # this centre no longer reaches back to s
                break
            b = c
            while b < ns and ok[b]:
                b += 1
            if best is None or b > best[2]:
                best = (tm, s, b)
            if b >= ns:
                break
            c += step
        tm, a, b = best
        models.append(tm)
        segments.append((a, b))
        s = b
    return models, segments


def expand_along(model: FlexibleModel, Q, y=None, *, tol: float = 1e-3, modes=(1,),
                 orders: Sequence[int] = tuple(range(1, 9)), joints=None,
                 quantity: str = "freq_hz", step: int | None = None,
                 criterion: str = "exact") -> TrajectoryExpansion:
    """Cover a trajectory with the fewest Taylor expansions, then the lowest order, within tol.

    For each order p the samples are covered greedily from the start: among expansion points
    tried every ``step`` samples ahead, the one whose validity run (relative error ≤ ``tol``
    against the exact model, for every requested mode) reaches back to the first uncovered
    sample and furthest forward is kept. The answer is the order with the fewest expansion
    points, the lowest order on ties: no more model than the trajectory needs.

    Args:
        model: The flexible model.
        Q: Trajectory samples (ns, nv), user coordinates.
        y: Design values [kg] (fixed; default nominal).
        tol: Relative tolerance on the expanded quantity.
        modes: Non-rigid modes to cover.
        orders: Orders to try.
        joints: Joints to expand (default all).
        quantity: 'freq_hz' or 'eigval'.
        step: Spacing of candidate expansion points in samples (default ns // 38 + 1).
        criterion: ``"exact"``: a sample is covered where the relative error against the exact
            model meets ``tol``; ``"estimate"``: where the two-term estimate
            (:func:`two_term_estimates`: the larger of the next two orders' relative terms,
            from an expansion two orders higher per candidate point; no exact solve in the
            choice) does. Either way ``max_error`` is then checked with the exact model, and a
            :class:`~pinflex.exceptions.TaylorRadiusWarning` says when the estimate's cover
            misses ``tol`` (the estimate assumes the omitted orders decrease). A single
            next-order term was used before and failed where a coefficient vanishes: on
            benchmark A's trajectory (modes 1–2, tol 1e-4) 0.29× the exact error of its cover.
    """
    if criterion not in ("exact", "estimate"):
        raise ConfigurationError(f"criterion={criterion!r}: expected 'exact' or 'estimate'")
    Q = check_q(model, Q)
    y = check_y(model, y)
    modes = tuple(int(m) for m in np.atleast_1d(modes))
    f = model.frequencies(Q, y, n_modes=max(modes))[:, [m - 1 for m in modes]]
    exact = f if quantity == "freq_hz" else (2 * np.pi * f) ** 2
    step = step or (Q.shape[0] // 38 + 1)
    best: tuple[int, list, list] | None = None
    candidates = {}
    judge = exact if criterion == "exact" else None
    for p in orders:
        models, segments = _cover(model, Q, y, judge, tol, p, modes, joints, quantity, step)
        candidates[int(p)] = len(models)
        if best is None or len(models) < len(best[1]):
            best = (p, models, segments)
    if best is None:
        raise ConfigurationError("give at least one Taylor order in 'orders'")
    p, models, segments = best
    result = TrajectoryExpansion(tuple(models), tuple(segments), int(p), tol, 0.0, candidates)
    err = float(np.max(np.abs(result.evaluate(Q, quantity=quantity) / exact - 1)))
    estimate = None
    if criterion == "estimate":
        estimate = 0.0
        for tm, (a, b) in zip(models, segments):
            hi = expand(model, tm.q0, y, order=int(p) + 2, modes=modes, joints=joints, design=[])
            estimate = max(estimate, float(np.max(two_term_estimates(hi, Q[a:b], int(p),
                                                                     quantity=quantity))))
        if err > tol:  # the estimate was optimistic somewhere: say so, with the exact figure
            import warnings

            from pinflex.exceptions import TaylorRadiusWarning

            warnings.warn(
                f"expand_along(criterion='estimate'): the chosen cover ({len(models)} points, "
                f"order {p}) has an exact relative error of {err:.3g} against tol = {tol:g} "
                f"(largest two-term estimate {estimate:.3g}); use criterion='exact' or a "
                "smaller tol", TaylorRadiusWarning, stacklevel=2)
    return TrajectoryExpansion(tuple(models), tuple(segments), int(p), tol, err, candidates,
                               estimate)


@dataclass(frozen=True)
class SampledTaylor:
    """A Taylor model restricted to fixed joint samples, fast to evaluate for new designs.

    On a fixed trajectory only the design changes between evaluations (an optimizer's inner
    loop), so the joint monomials are summed once: ``f(q_k, y) = Σ_β G_β[k] δy^β``.

    Attributes:
        space_y: Jet space of the expanded design variables (None when none is expanded).
        G: Coefficients (nβ, ns, k) per design monomial β.
        y0: Expansion design [kg], (ny,).
        design_idx: Indices of the expanded design variables.
    """

    space_y: JetSpace | None
    G: np.ndarray
    y0: np.ndarray
    design_idx: tuple[int, ...]
    # derived once at construction: G as (ns·k, nβ), the value shape, and the monomial tree
    _Gt: np.ndarray = field(init=False, repr=False, compare=False)
    _shape: tuple[int, ...] = field(init=False, repr=False, compare=False)
    _parent: list[int] = field(init=False, repr=False, compare=False)
    _var: list[int] = field(init=False, repr=False, compare=False)

    def values(self, y=None) -> np.ndarray:
        """Polynomial values (ns, k) at the samples for design ``y`` [kg] (default y0).

        Args:
            y: Design values (ny,) over all design variables [kg] (only the expanded ones are
                read, not validated); None for ``y0``.

        Returns:
            Values (ns, k) in the unit of the sampled quantity ([Hz] or [rad²/s²]).
        """
        if self.space_y is None or y is None:
            return self.G[0]
        dy = [float(y[j]) - float(self.y0[j]) for j in self.design_idx]
        # one design point: its monomials in plain Python, then a single matrix product
        parent, var = self._parent, self._var
        mon = [1.0]
        for c in range(1, len(parent)):
            mon.append(mon[parent[c]] * dy[var[c]])
        return self._Gt.dot(np.array(mon)).reshape(self._shape)

    def __post_init__(self) -> None:
        object.__setattr__(self, "G", _readonly(self.G))
        object.__setattr__(self, "y0", _readonly(self.y0))
        gt = np.ascontiguousarray(self.G.reshape(self.G.shape[0], -1).T)
        gt.setflags(write=False)
        object.__setattr__(self, "_Gt", gt)
        object.__setattr__(self, "_shape", self.G.shape[1:])
        object.__setattr__(self, "_parent", [0])
        object.__setattr__(self, "_var", [0])
        if self.space_y is not None:
            object.__setattr__(self, "_parent", self.space_y.parent.tolist())
            object.__setattr__(self, "_var", self.space_y.parent_var.tolist())


def sample(tm: TaylorModel, Q, *, quantity: str = "freq_hz",
           linear_in_design: bool = False) -> SampledTaylor:
    """Fix the joint samples of a Taylor model (see :class:`SampledTaylor`).

    Args:
        tm: The Taylor model.
        Q: Joint samples (nv,) or (ns, nv), user convention [rad or m]; joints that are not
            expanded must stay at ``tm.q0``.
        quantity: ``'freq_hz'`` (default, [Hz]) or ``'eigval'`` ([rad²/s²]).
        linear_in_design: Keep only the terms of degree <= 1 in the design variables.

    Returns:
        :class:`SampledTaylor` with ``G`` (nβ, ns, k), a polynomial in the design offsets only.

    Raises:
        ConfigurationError: ``Q`` has the wrong shape or moves a joint that is not expanded,
            or ``quantity`` is unknown.
    """
    coef = tm.coefficients(quantity, linear_in_design=bool(linear_in_design))  # (ncoef, k)
    nj, nd = len(tm.joint_idx), len(tm.design_idx)
    mi = tm.space.multi_indices
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    if nj:
        qspace = JetSpace(nj, tm.order)
        dq = tm.offsets(Q, None, warn=True)[:, :nj]
        mon_q = jets.monomials(qspace, dq)  # (ns, ncq)
        qpos = np.array([qspace.index[tuple(a)] for a in mi[:, :nj].tolist()])
    else:
        mon_q = np.ones((Q.shape[0], 1))
        qpos = np.zeros(len(mi), dtype=int)
    if nd:
        yspace = JetSpace(nd, tm.order)
        ypos = np.array([yspace.index[tuple(b)] for b in mi[:, nj:].tolist()])
        nb = yspace.ncoef
    else:
        yspace, ypos, nb = None, np.zeros(len(mi), dtype=int), 1
    G = np.zeros((nb, Q.shape[0], coef.shape[1]))
    for c in range(len(mi)):
        G[ypos[c]] += mon_q[:, qpos[c], None] * coef[c][None, :]
    return SampledTaylor(yspace, G, tm.y0, tm.design_idx)
