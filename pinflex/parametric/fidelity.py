"""The Taylor order a tolerance needs: next-order estimates over the samples of use.

A Taylor model of order ``p`` is judged where it will be evaluated (samples of joints and
design values). Its truncation error is estimated by the next order: with ``T_p`` the
polynomial of order ``p`` and ``D_{p+1}`` the sum of its degree-``p + 1`` terms,

    e_p(x) = |D_{p+1}(x)| / |T_{p+1}(x)|,

the relative change the next order would make. One expansion at order ``P`` gives every
``e_p`` for ``p < P`` (the coefficients of degree ≤ ``p`` do not depend on the order the
expansion was run at), so :func:`order_for_tolerance` expands at a ladder of orders (3, 5,
7, …) until some ``e_p`` over all samples and modes meets the tolerance, and returns the
model of the lowest such order: no more model than the samples need.

This is an estimate, not a bound: it assumes the omitted series is led by its first term. On
benchmark A's trajectory (modes 1–3, nominal design) it is 0.88–1.9 × the actual error for
orders 1–8, on the flexible UR5 at 40 samples within ±0.1 rad of a general pose 0.83–1.1 × for
orders 1–5 (``python benchmarks/bench_taylor_fidelity.py``); where it is below the actual error,
by up to ~20 % there, the chosen model can miss the tolerance by that much.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pinflex.erls import FlexibleModel
from pinflex.exceptions import ConfigurationError
from pinflex.jets.evaluation import monomial_rows
from pinflex.parametric.model import TaylorModel, expand
from pinflex.resources import MAX_TAYLOR_ORDER

__all__ = ["OrderChoice", "next_order_estimates", "order_for_tolerance"]


@dataclass(frozen=True)
class OrderChoice:
    """The Taylor order picked for a tolerance.

    Attributes:
        model: The Taylor model of the chosen order.
        order: The chosen order p.
        estimate: Its next-order estimate ``max e_p`` over samples and modes.
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


def order_for_tolerance(model: FlexibleModel, q0, y0=None, *, Q, Y=None, tol: float,
                        modes: Sequence[int] = (1,), orders: Sequence[int] | None = None,
                        quantity: str = "freq_hz", joints: Sequence[str] | None = None,
                        design: Sequence[str] | None = None) -> OrderChoice:
    """The lowest Taylor order whose next-order estimate over the samples meets ``tol``.

    Args:
        model: The flexible model.
        q0: Expansion pose (nv,).
        y0: Expansion design [kg] (default nominal).
        Q: Samples where the model will be used (n, nv).
        Y: Their design values (n, ny) or (ny,) [kg] (default ``y0``).
        tol: Relative tolerance on ``quantity``.
        modes: Non-rigid modes (every one must meet ``tol``).
        orders: Orders allowed (default 1–8).
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
    if not allowed or allowed[0] < 1 or allowed[-1] >= MAX_TAYLOR_ORDER:
        raise ConfigurationError(
            f"orders {allowed}: give orders from 1 to {MAX_TAYLOR_ORDER - 1} (each is judged "
            "by the next one)")
    estimates: dict[int, float] = {}
    top = 3
    while True:
        top = min(top, allowed[-1] + 1)  # expansions at orders 3, 5, 7, ...: each judges below
        tm = expand(model, q0, y0, order=top, modes=modes, joints=joints, design=design)
        est = next_order_estimates(tm, Q, Y, quantity=quantity)
        for p in range(1, top):
            estimates[p] = float(np.max(est[p]))
        hit = [p for p in allowed if p in estimates and estimates[p] <= tol]
        if hit:
            p = hit[0]
            chosen = expand(model, q0, y0, order=p, modes=modes, joints=joints, design=design)
            return OrderChoice(chosen, p, estimates[p], dict(estimates), float(tol))
        if top == allowed[-1] + 1:
            break
        top += 2
    best = min(estimates, key=lambda p: estimates[p])
    raise ConfigurationError(
        f"no Taylor order in {allowed} meets tol = {tol:g} on these samples (best: order "
        f"{best}, next-order estimate {estimates[best]:.3g}); expand closer or use several "
        "expansion points (pinflex.parametric.expand_along)")
