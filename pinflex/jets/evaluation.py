"""Jets as polynomials: truncation, derivatives, evaluation, partial linearization."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pinflex.jets.space import JetSpace, _check_jet, _check_var


def truncate(space: JetSpace, jet: np.ndarray, new_space: JetSpace) -> np.ndarray:
    """Drop the coefficients of degree above ``new_space.order``.

    Args:
        space: Space of ``jet``.
        jet: Jet of shape ``(ncoef, *shape)``.
        new_space: Target space, same ``nvars`` and an order ≤ ``space.order``.

    Returns:
        Jet of shape ``(new_space.ncoef, *shape)`` (a copy).

    Raises:
        ValueError: The spaces are incompatible.
    """
    jet = _check_jet(space, jet)
    if new_space.nvars != space.nvars or new_space.order > space.order:
        raise ValueError(
            f"cannot truncate a jet of (nvars={space.nvars}, order={space.order}) to "
            f"(nvars={new_space.nvars}, order={new_space.order}): keep nvars and lower the order"
        )
    return jet[: new_space.ncoef].copy()


def restrict(space: JetSpace, jet: np.ndarray, keep: Sequence[int]) -> tuple[JetSpace, np.ndarray]:
    """Freeze every variable not in ``keep`` at its expansion point.

    Args:
        space: Space of ``jet``.
        jet: Jet of shape ``(ncoef, *shape)``.
        keep: Indices of the variables to keep, in the order of the new space.

    Returns:
        ``(sub_space, sub_jet)`` with ``sub_space = JetSpace(len(keep), order)``.

    Raises:
        ValueError: ``keep`` is empty, repeats a variable or is out of range.
    """
    jet = _check_jet(space, jet)
    keep = [_check_var(space, k) for k in keep]
    if not keep or len(set(keep)) != len(keep):
        raise ValueError(f"keep = {keep}: give distinct variable indices, at least one")
    sub = JetSpace(len(keep), space.order)
    full = np.zeros((sub.ncoef, space.nvars), dtype=np.int64)
    full[:, keep] = sub.multi_indices
    pos = [space.index[tuple(row)] for row in full.tolist()]
    return sub, jet[pos].copy()


def derivative(space: JetSpace, jet: np.ndarray, alpha: Sequence[int]) -> np.ndarray:
    """Raw partial derivative ``∂^α f(x0)`` at the expansion point.

    Args:
        space: Jet space.
        jet: Jet of ``f``, shape ``(ncoef, *shape)``.
        alpha: Multi-index, ``nvars`` non-negative integers with ``|α| ≤ order``.

    Returns:
        Array of shape ``shape``: the stored coefficient times ``α!``.

    Raises:
        ValueError: ``alpha`` is not in the space.
    """
    jet = _check_jet(space, jet)
    pos = space.position(alpha)
    return jet[pos] * space.factorials[pos]


def monomials(space: JetSpace, dx: np.ndarray) -> np.ndarray:
    """Monomials ``δx^α`` of every coefficient at every sample.

    Args:
        space: Jet space.
        dx: Offsets from the expansion point, shape ``(nsamples, nvars)`` (or ``(nvars,)``).

    Returns:
        Array of shape ``(nsamples, ncoef)`` (``(ncoef,)`` for a single offset).

    Raises:
        ValueError: ``dx`` does not have ``nvars`` columns.
    """
    dx = np.asarray(dx)
    single = dx.ndim == 1
    dx2 = dx[None, :] if single else dx
    if dx2.ndim != 2 or dx2.shape[1] != space.nvars:
        raise ValueError(f"dx has shape {dx.shape}; expected (nsamples, {space.nvars})")
    rows = monomial_rows(space, dx2.T, np.result_type(dx2, float))
    mon = rows.T
    return mon[0] if single else mon


def monomial_rows(space: JetSpace, dx_t: np.ndarray, dtype=float) -> np.ndarray:
    """Monomials as rows: ``(ncoef, nsamples)`` from offsets ``dx_t`` (nvars, nsamples).

    One copy of the offsets, then the contiguous products of
    :attr:`JetSpace.monomial_plan` (each degree from the one below it).
    """
    rows = np.empty((space.ncoef, dx_t.shape[1]), dtype=dtype)
    rows[0] = 1.0
    if space.order:
        rows[1 : 1 + space.nvars] = dx_t
    for d0, d1, s0, s1, r in space.monomial_plan:
        np.multiply(rows[s0:s1], rows[r], out=rows[d0:d1])
    return rows


def evaluate(space: JetSpace, jet: np.ndarray, dx: np.ndarray) -> np.ndarray:
    """Evaluate the Taylor polynomial ``Σ_α jet[α] δx^α`` at many offsets.

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)``.
        dx: Offsets from the expansion point, shape ``(nsamples, nvars)`` (or ``(nvars,)``).

    Returns:
        Values of shape ``(nsamples, *shape)`` (``shape`` for a single offset).
    """
    jet = _check_jet(space, jet)
    mon = monomials(space, dx)
    if mon.ndim == 1:
        return np.tensordot(mon, jet, axes=(0, 0))
    return (mon @ jet.reshape(space.ncoef, -1)).reshape(mon.shape[0], *jet.shape[1:])


def ray_coefficients(space: JetSpace, jet: np.ndarray, directions: np.ndarray) -> np.ndarray:
    """Univariate Taylor coefficients along rays ``t ↦ f(x0 + t v)``.

    ``c_k(v) = Σ_{|α|=k} jet[α] v^α``.

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)``.
        directions: Ray directions ``v``, shape ``(ndir, nvars)``.

    Returns:
        Array of shape ``(ndir, order + 1, *shape)``.
    """
    jet = _check_jet(space, jet)
    mon = monomials(space, np.atleast_2d(directions))
    weighted = mon.reshape(*mon.shape, *((1,) * (jet.ndim - 1))) * jet[None]
    return np.add.reduceat(weighted, space.degree_offsets[:-1], axis=1)


def partially_linear_mask(space: JetSpace, design: Sequence[int]) -> np.ndarray:
    """Coefficients kept by the partial linearization of eq. (7): ``|β| ≤ 1``.

    Args:
        space: Jet space.
        design: Indices of the design variables ``y`` (the others are the joints ``q``).

    Returns:
        Boolean mask of shape ``(ncoef,)``.
    """
    design = [_check_var(space, k) for k in design]
    return space.multi_indices[:, design].sum(axis=1) <= 1


def partially_linear(space: JetSpace, jet: np.ndarray, design: Sequence[int]) -> np.ndarray:
    """Jet with every coefficient of degree ≥ 2 in the design variables set to zero (eq. 7).

    Args:
        space: Jet space.
        jet: Jet of shape ``(ncoef, *shape)``.
        design: Indices of the design variables ``y``.

    Returns:
        Jet of the same shape, linear in ``δy`` (a copy).
    """
    jet = _check_jet(space, jet)
    mask = partially_linear_mask(space, design)
    return jet * mask.reshape(-1, *((1,) * (jet.ndim - 1)))


def design_split(
    space: JetSpace, jet: np.ndarray, design: Sequence[int]
) -> tuple[JetSpace, np.ndarray, np.ndarray]:
    """Split a jet into the polynomials ``l_0(q)`` and ``l_j(q)`` of eq. (9).

    ``f̂(q, y) = l_0(δq) + Σ_j l_j(δq) δy_j`` where ``l_0`` has order ``p`` and each ``l_j``
    order ``p − 1`` (its degree-``p`` coefficients are zero).

    Args:
        space: Jet space in all variables.
        jet: Jet of shape ``(ncoef, *shape)``.
        design: Indices of the design variables ``y``, in the order of the output ``j`` axis.
            The remaining variables, in increasing index order, are the joints ``q``.

    Returns:
        ``(q_space, l0, l1)`` with ``q_space = JetSpace(nq, order)``, ``l0`` of shape
        ``(q_space.ncoef, *shape)`` and ``l1`` of shape ``(ny, q_space.ncoef, *shape)``; both
        evaluate with :func:`monomials` of ``q_space``.

    Raises:
        ValueError: ``design`` repeats a variable, is out of range or leaves no joint.
    """
    jet = _check_jet(space, jet)
    design = [_check_var(space, k) for k in design]
    if len(set(design)) != len(design):
        raise ValueError(f"design = {design} repeats a variable")
    joints = [k for k in range(space.nvars) if k not in design]
    if not joints:
        raise ValueError("design_split needs at least one joint variable besides the design")
    q_space = JetSpace(len(joints), space.order)
    full = np.zeros((q_space.ncoef, space.nvars), dtype=np.int64)
    full[:, joints] = q_space.multi_indices
    l0 = jet[[space.index[tuple(row)] for row in full.tolist()]]
    l1 = np.zeros((len(design), *l0.shape), dtype=jet.dtype)
    n_low = int(q_space.degree_offsets[space.order]) if space.order >= 1 else 0
    for j, k in enumerate(design):
        rows = full[:n_low].copy()
        rows[:, k] += 1
        l1[j, :n_low] = jet[[space.index[tuple(row)] for row in rows.tolist()]]
    return q_space, l0.copy(), l1
