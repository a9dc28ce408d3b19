"""The Taylor order a tolerance needs: two-term estimates over the samples of use.

A Taylor model of order ``p`` is judged where it will be evaluated (samples of joints and
design values). With ``T_p`` the polynomial of order ``p`` and ``D_{p+1}`` the sum of its
degree-``p + 1`` terms, the relative change the next order would make is

    e_p(x) = |D_{p+1}(x)| / |T_{p+1}(x)|,

and the truncation error of order ``p`` is estimated by the larger of the next two orders'
terms,

    E_p(x) = max(e_p(x), e_{p+1}(x)).

One term alone vanishes wherever that order's coefficients do: at a pose where the frequency
is even in the joint offsets (benchmark A with the arm stretched, elbow offsets within
±0.4 rad) the odd terms are zero, so ``e_2`` was ~1e-19 for an order-2 model whose exact
error is 5.4e-3; the second term is the first non-vanishing one there. One expansion at order
``P`` gives every ``E_p`` for ``p ≤ P − 2`` (the coefficients of degree ≤ ``p`` do not depend
on the order the expansion was run at), so :func:`order_for_tolerance` expands at a ladder of
orders (4, 6, 8, …) until some ``E_p`` over all samples and modes meets the tolerance, and
returns the model of the lowest such order: no more model than the samples need.

This is an estimate, not a bound: it assumes the omitted series is led by its first
non-vanishing term, and two consecutive orders that both vanish along the samples would still
fool it. Against the exact frequencies (``python benchmarks/bench_taylor_fidelity.py``) it is
1.06–1.92 × the actual error on benchmark A's trajectory (modes 1–3, orders 1–8; the single
term was 0.88 × at order 1) and 0.83–1.11 × on the flexible UR5 at 40 samples within ±0.1 rad
of a general pose (orders 1–5); where it is below the actual error, the chosen model can miss
the tolerance by that factor.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from types import MappingProxyType

import numpy as np

from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.jets.evaluation import monomial_rows
from pinflex.parametric.expansion import expand_at_order as expand
from pinflex.parametric.taylor import TaylorModel
from pinflex.resources import MAX_TAYLOR_ORDER

TWO_TERM_RULE = ("two-term estimate max(|T_(p+1) - T_p| / |T_(p+1)|, "
                 "|T_(p+2) - T_(p+1)| / |T_(p+2)|)")
"""The two-term estimate's formula, as the choices that use it record it."""

__all__ = ["OrderChoice", "next_order_estimates", "order_for_tolerance",
           "two_term_estimates"]


@dataclass(frozen=True)
class OrderChoice:
    """The Taylor order picked for a tolerance.

    Attributes:
        model: The Taylor model of the chosen order.
        order: The chosen order p.
        estimate: Its two-term estimate ``max E_p`` over samples and modes
            (``E_p = max(e_p, e_(p+1))``, see the module docstring).
        estimates: ``{order: estimate}`` of every order judged.
        tol: The tolerance.
    """

    model: TaylorModel
    order: int
    estimate: float
    estimates: dict[int, float]
    tol: float


def next_order_estimates(tm: TaylorModel, Q, Y=None, *, quantity: str = "freq_hz"
                         ) -> np.ndarray:
    """Next-order estimates ``e_p`` (order, samples, modes) for ``p = 0 .. tm.order − 1``.

    Args:
        tm: A Taylor model of order ``P ≥ 1``.
        Q: Joint samples (n, nv), user coordinates.
        Y: Design values (n, ny) or (ny,) [kg] (default the model's ``y0``).
        quantity: 'freq_hz' or 'eigval'.
    """
    P = tm.order
    if P < 1:
        raise ConfigurationError("next-order estimates need a Taylor model of order >= 1")
    dx = tm.offsets(Q, Y, warn=False)
    rows = monomial_rows(tm.space, dx.T)
    C = tm.coefficients(quantity)
    off = tm.space.degree_offsets
    parts = np.stack([(C[off[d]:off[d + 1]].T @ rows[off[d]:off[d + 1]]).T
                      for d in range(P + 1)])  # (degree, n, k)
    partial = np.cumsum(parts, axis=0)
    with np.errstate(divide="ignore", invalid="ignore"):
        est = np.abs(parts[1:]) / np.abs(partial[1:])
    return np.where(np.isfinite(est), est, np.inf)


def two_term_estimates(tm: TaylorModel, Q, Y=None, *, quantity: str = "freq_hz"
                       ) -> np.ndarray:
    """Two-term estimates ``E_p`` (order, samples, modes) for ``p = 0 .. tm.order − 2``.

    ``E_p = max(e_p, e_(p+1))``: the larger of the next two orders' relative terms
    (:func:`next_order_estimates`), so that a vanishing next-order coefficient (a pose where
    the frequency is even in a joint) does not report a tiny error.

    Args:
        tm: A Taylor model of order ``P ≥ 2``.
        Q: Joint samples (n, nv), user coordinates.
        Y: Design values (n, ny) or (ny,) [kg] (default the model's ``y0``).
        quantity: 'freq_hz' or 'eigval'.
    """
    if tm.order < 2:
        raise ConfigurationError("two-term estimates need a Taylor model of order >= 2")
    e = next_order_estimates(tm, Q, Y, quantity=quantity)
    return np.maximum(e[:-1], e[1:])


def order_for_tolerance(model: FlexibleModel, q0, y0=None, *, Q, Y=None, tol: float,
                        modes: Sequence[int] = (1,), orders: Sequence[int] | None = None,
                        quantity: str = "freq_hz", joints: Sequence[str] | None = None,
                        design: Sequence[str] | None = None) -> OrderChoice:
    """The lowest Taylor order whose two-term estimate over the samples meets ``tol``.

    Order ``p`` is judged by ``max(e_p, e_(p+1))`` (the larger of the next two orders'
    relative terms, from an expansion at least two orders higher; see the module docstring).

    Args:
        model: The flexible model.
        q0: Expansion pose (nv,).
        y0: Expansion design [kg] (default nominal).
        Q: Samples where the model will be used (n, nv).
        Y: Their design values (n, ny) or (ny,) [kg] (default ``y0``).
        tol: Relative tolerance on ``quantity``.
        modes: Non-rigid modes (every one must meet ``tol``).
        orders: Orders allowed (default 1–8; at most ``MAX_TAYLOR_ORDER − 2``, each is judged
            by the next two).
        quantity: 'freq_hz' or 'eigval'.
        joints: Joints to expand (default all).
        design: Design variables to expand (default all).

    Raises:
        ConfigurationError: ``tol`` is not positive, or no allowed order meets it (the error
            names the best estimate reached).
    """
    if not (isinstance(tol, int | float) and not isinstance(tol, bool) and tol > 0
            and np.isfinite(tol)):
        raise ConfigurationError(f"tol = {tol!r}: give a positive relative tolerance")
    allowed = sorted({int(p) for p in (range(1, 9) if orders is None else orders)})
    if not allowed or allowed[0] < 1 or allowed[-1] > MAX_TAYLOR_ORDER - 2:
        raise ConfigurationError(
            f"orders {allowed}: give orders from 1 to {MAX_TAYLOR_ORDER - 2} (each is judged "
            "by the next two)")
    estimates: dict[int, float] = {}
    top = 4
    while True:
        # expansions at orders 4, 6, 8, ...: each judges the orders up to two below it
        top = min(top, allowed[-1] + 2)
        tm = expand(model, q0, y0, order=top, modes=modes, joints=joints, design=design)
        est = two_term_estimates(tm, Q, Y, quantity=quantity)
        for p in range(1, top - 1):
            estimates[p] = float(np.max(est[p]))
        hit = [p for p in allowed if p in estimates and estimates[p] <= tol]
        if hit:
            p = hit[0]
            chosen = expand(model, q0, y0, order=p, modes=modes, joints=joints, design=design)
            return OrderChoice(chosen, p, estimates[p], dict(estimates), float(tol))
        if top == allowed[-1] + 2:
            break
        top += 2
    best = min(estimates, key=lambda p: estimates[p])
    raise ConfigurationError(
        f"no Taylor order in {allowed} meets tol = {tol:g} on these samples (best: order "
        f"{best}, two-term estimate {estimates[best]:.3g}); expand closer or use several "
        "expansion points (pinflex.parametric.expand_along)")


def expand_for_tolerance(model, q0, y0, order, modes, joints, design, tol, over):
    """:func:`pinflex.parametric.expand` with ``tol``: the order from two-term estimates."""
    import dataclasses

    if over is None:
        raise ConfigurationError("expand(tol=...) needs over=Q (or (Q, Y)): the samples where "
                                 "the model will be used")
    Q, Y = over if isinstance(over, tuple) else (over, None)
    cap = max(1, int(order)) if order is not None else 8
    choice = order_for_tolerance(model, q0, y0, Q=Q, Y=Y, tol=tol, modes=modes,
                                 orders=range(1, cap + 1), joints=joints, design=design)
    info = MappingProxyType({"tol": choice.tol, "order": choice.order,
                             "estimate": choice.estimate,
                             "estimates": MappingProxyType(dict(choice.estimates)),
                             "method": f"{TWO_TERM_RULE}, frequency [Hz], max over "
                                       "samples and modes"})
    return dataclasses.replace(choice.model, order_choice=info)
