"""Exact frequencies of straight Euler–Bernoulli beam chains, written from beam theory.

Nothing here imports pinflex. Two independent references for the conditioning tests:

* **Transfer matrices of the continuous beam** (no discretization): a straight chain of
  uniform segments along one axis, bending in one plane, with point elements between them
  (a hinge with a torsional spring, a free hinge, a point mass, a rotary inertia) and a
  root that is clamped, pinned or held by a torsional spring; the tip is free. The state
  ``[w, θ, M, V]`` (``M = EI w''``, ``V = EI w'''``) obeys ``w' = θ``, ``θ' = M/EI``,
  ``M' = V``, ``V' = ρA ω² w``; over a segment the transfer matrix is closed form in the
  Krylov functions of ``x = βL`` (``β⁴ = ρA ω²/EI``), written with their series near 0 so
  that very low frequencies (a soft spring, a heavy tip) keep full precision. A frequency
  is a root in ω of the determinant of the tip conditions; roots are bracketed on a scan
  and refined by ``brentq``. Axial motion of the same chain (clamped rod, point masses)
  has the analogous two-state transfer matrix.

  Point elements (from the stationarity of ``½∫EI w''² − ½ω²(∫ρA w² + m w² + J θ²)``):
  a point mass ``V⁺ = V⁻ + ω² m w``; a rotary inertia ``M⁺ = M⁻ − ω² J θ``; a hinge with
  a torsional spring ``k``: an unknown jump ``Δθ`` of ``θ`` with ``M = k Δθ`` (``w, M, V``
  continuous; ``k = 0`` a free hinge), written so that no ``1/k`` appears. Root: clamped
  ``w = θ = 0``; pinned ``w = 0, M = 0``; spring ``w = 0, M = k θ``. Free tip: ``M = V = 0``.

* **The same mesh, solved in inverse form from the exact flexibility** (cantilevers): a
  Hermite-cubic (bending) and linear (axial) element mesh is nodally exact for point loads,
  so the inverse of its stiffness is the beam-theory flexibility of the nodes, which is
  written directly (influence coefficients, all positive: no cancellation). With ``F = L Lᵀ``
  the mesh's eigenvalues are ``λ = 1/μ``, ``μ`` the eigenvalues of ``Lᵀ M L``: a symmetric
  problem whose largest ``μ`` (the low modes) keep full relative accuracy at any mesh size.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq


def _krylov(x: float) -> tuple[float, float, float, float]:
    """``S(x), T(x)/x, U(x)/x², V(x)/x³`` of the Krylov functions (x ≥ 0).

    ``S = (cosh + cos)/2``, ``T = (sinh + sin)/2``, ``U = (cosh − cos)/2``,
    ``V = (sinh − sin)/2``; each a power series in ``x⁴`` once divided as above.
    """
    if x < 2.0:
        x4 = x**4
        out = []
        for p in range(4):  # Σ_m x^{4m} / (4m + p)!
            term = 1.0 / math.factorial(p)
            total = term
            m = 0
            while True:
                m += 1
                term *= x4 / ((4 * m + p) * (4 * m + p - 1) * (4 * m + p - 2) * (4 * m + p - 3))
                total += term
                if term < 1e-18 * total:
                    break
            out.append(total)
        return out[0], out[1], out[2], out[3]
    ch, sh, c, s = math.cosh(x), math.sinh(x), math.cos(x), math.sin(x)
    return 0.5 * (ch + c), 0.5 * (sh + s) / x, 0.5 * (ch - c) / x**2, 0.5 * (sh - s) / x**3


def bending_transfer(L: float, EI: float, rhoA: float, omega2: float) -> np.ndarray:
    """Transfer matrix (4 × 4) of ``[w, θ, M, V]`` over a uniform segment of length L."""
    a = rhoA * omega2 / EI * L**4  # x⁴
    s0, s1, s2, s3 = _krylov(a**0.25)
    return np.array([
        [s0, L * s1, L**2 * s2 / EI, L**3 * s3 / EI],
        [a / L * s3, s0, L * s1 / EI, L**2 * s2 / EI],
        [EI * a / L**2 * s2, EI * a / L * s3, s0, L * s1],
        [EI * a / L**3 * s1, EI * a / L**2 * s2, a / L * s3, s0],
    ])


@dataclass(frozen=True)
class Segment:
    """A uniform beam segment: length [m], EI [N m²], ρA [kg/m], EA [N] (axial)."""

    L: float
    EI: float
    rhoA: float
    EA: float = np.inf


@dataclass(frozen=True)
class Point:
    """A point element between segments (or at the tip).

    ``hinge``: None (rigid continuity), a torsional stiffness [N m/rad], or 0.0 for a free
    hinge. ``mass`` [kg] and ``inertia`` [kg m²] (rotary, about the bending axis).
    """

    hinge: float | None = None
    mass: float = 0.0
    inertia: float = 0.0


def _bending_det(omega2: float, segments, points, root) -> float:
    """Determinant of the tip conditions at ω² (scaled to stay of order one)."""
    if root == "clamped":
        S = np.array([[0.0, 0.0], [0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])
    elif root == "pinned":
        S = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [0.0, 1.0]])
    else:  # a torsional spring of stiffness `root`
        S = np.array([[0.0, 0.0], [1.0, 0.0], [float(root), 0.0], [0.0, 1.0]])
    conditions = []
    for seg, pt in zip(segments, points):
        S = bending_transfer(seg.L, seg.EI, seg.rhoA, omega2) @ S
        S = S / np.max(np.abs(S))  # the determinant's sign is what counts
        if pt is None:
            continue
        if pt.hinge is not None:  # θ jumps by an unknown Δθ with M = k Δθ (k = 0: free)
            conditions.append(np.append(S[2], -float(pt.hinge)))
            S = np.concatenate([S, np.array([[0.0], [1.0], [0.0], [0.0]])], axis=1)
        S = S.copy()
        S[2] -= omega2 * pt.inertia * S[1]
        S[3] += omega2 * pt.mass * S[0]
    rows = [np.pad(c, (0, S.shape[1] - c.size)) for c in conditions] + [S[2], S[3]]
    A = np.array(rows)
    A = A / np.maximum(np.max(np.abs(A), axis=1, keepdims=True), 1e-300)
    return float(np.linalg.det(A))


def _axial_det(omega2: float, segments, points) -> float:
    """Tip condition ``N = 0`` of the clamped rod (state ``[u, N]``, start u = 0, N = 1)."""
    s = np.array([0.0, 1.0])
    for seg, pt in zip(segments, points):
        kappa = math.sqrt(seg.rhoA * omega2 / seg.EA)
        x = kappa * seg.L
        sinc = math.sin(x) / x if x > 0 else 1.0
        T = np.array([[math.cos(x), seg.L * sinc / seg.EA],
                      [-seg.EA * kappa * math.sin(x), math.cos(x)]])
        s = T @ s
        if pt is not None:
            s = s.copy()
            s[1] -= omega2 * pt.mass * s[0]
        s = s / np.max(np.abs(s))
    return float(s[1])


def _roots(f, omega_max: float, n: int, omega_min: float) -> np.ndarray:
    """First ``n`` roots of ``f(ω²)`` in ``(omega_min, omega_max)``: log-then-linear scan."""
    # bending roots are about evenly spaced in √ω; a log scan first for very low ones
    top = math.sqrt(omega_max)
    grid = np.concatenate([np.geomspace(omega_min, 1e-4 * omega_max, 300, endpoint=False),
                           np.linspace(1e-2 * top, top, 3000) ** 2])
    vals = np.array([f(w * w) for w in grid])
    out = []
    for i in np.flatnonzero(np.sign(vals[:-1]) * np.sign(vals[1:]) < 0):
        r = brentq(lambda w: f(w * w), grid[i], grid[i + 1], xtol=1e-300, rtol=1e-15,
                   maxiter=500)
        out.append(r)
        if len(out) == n:
            break
    if len(out) < n:
        raise RuntimeError(f"found {len(out)} roots below ω = {omega_max:g}, wanted {n}")
    return np.array(out)


def bending_hz(segments: Sequence[Segment], points: Sequence[Point | None], root, n: int,
               omega_max: float, omega_min: float = 1e-9) -> np.ndarray:
    """First ``n`` nonzero bending frequencies [Hz] of a straight chain.

    Args:
        segments: Root to tip.
        points: One per segment: the point element at its far end (None: nothing).
        root: 'clamped', 'pinned' or a root spring stiffness [N m/rad].
        n: Number of frequencies.
        omega_max: Upper end of the scan [rad/s] (above the n-th frequency).
        omega_min: Lower end of the scan [rad/s] (below the first frequency).
    """
    w = _roots(lambda o2: _bending_det(o2, segments, points, root), omega_max, n, omega_min)
    return w / (2.0 * math.pi)


def axial_hz(segments: Sequence[Segment], points: Sequence[Point | None], n: int,
             omega_max: float, omega_min: float = 1e-9) -> np.ndarray:
    """First ``n`` axial frequencies [Hz] of the chain as a rod clamped at the root."""
    w = _roots(lambda o2: _axial_det(o2, segments, points), omega_max, n, omega_min)
    return w / (2.0 * math.pi)


def planar_chain_hz(segments, points, root, n: int, omega_max: float,
                    omega_min: float = 1e-9) -> np.ndarray:
    """The lowest ``n`` in-plane frequencies [Hz]: bending and axial families merged."""
    b = bending_hz(segments, points, root, n, omega_max, omega_min)
    try:
        a = axial_hz(segments, points, n, omega_max, omega_min)
    except RuntimeError:  # fewer axial modes below omega_max: keep those found
        a = _axial_below(segments, points, omega_max, omega_min)
    return np.sort(np.concatenate([b, a]))[:n]


def _axial_below(segments, points, omega_max, omega_min):
    for k in range(8, -1, -1):
        try:
            return axial_hz(segments, points, k, omega_max, omega_min) if k else np.zeros(0)
        except RuntimeError:
            continue
    return np.zeros(0)


# ---------------------------------------------------------------------------------------
# The same mesh in inverse form (cantilevers)
# ---------------------------------------------------------------------------------------


def cantilever_mesh_hz(L: float, EI: float, EA: float, rhoA: float, n_el: int,
                       tip_mass: float = 0.0, n: int = 3) -> np.ndarray:
    """Lowest ``n`` in-plane frequencies [Hz] of an ``n_el``-element clamped-free mesh.

    Bending: Hermite cubics with consistent mass; axial: linear elements with consistent
    mass; a point mass at the tip on both. Solved from the exact nodal flexibility in inverse
    form (module docstring).
    """
    le = L / n_el
    x = le * np.arange(1, n_el + 1)  # free nodes
    # bending flexibility, nodal dofs (w_i, θ_i) interleaved
    xi, xj = np.meshgrid(x, x, indexing="ij")  # response at xi, load at xj
    lo, hi = np.minimum(xi, xj), np.maximum(xi, xj)
    # unit force at s: w(x) = x²(3s − x)/6 (x ≤ s), s²(3x − s)/6 (x ≥ s); θ = w'
    ww = lo**2 * (3 * hi - lo) / 6.0
    tw = np.where(xi <= xj, xi * (2 * xj - xi) / 2.0, xj**2 / 2.0)  # θ(xi) from force at xj
    tt = lo  # θ(xi) from a unit moment at xj: min(xi, xj)
    F = np.empty((2 * n_el, 2 * n_el))
    F[0::2, 0::2] = ww
    F[1::2, 0::2] = tw
    F[0::2, 1::2] = tw.T
    F[1::2, 1::2] = tt
    F /= EI
    # consistent bending mass
    m = rhoA * le / 420.0 * np.array([
        [156, 22 * le, 54, -13 * le],
        [22 * le, 4 * le**2, 13 * le, -3 * le**2],
        [54, 13 * le, 156, -22 * le],
        [-13 * le, -3 * le**2, -22 * le, 4 * le**2],
    ])
    Mb = np.zeros((2 * n_el + 2, 2 * n_el + 2))
    for e in range(n_el):
        Mb[2 * e : 2 * e + 4, 2 * e : 2 * e + 4] += m
    Mb = Mb[2:, 2:]
    Mb[-2, -2] += tip_mass
    Fa = np.minimum(xi, xj) / EA
    ma = rhoA * le / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    Ma = np.zeros((n_el + 1, n_el + 1))
    for e in range(n_el):
        Ma[e : e + 2, e : e + 2] += ma
    Ma = Ma[1:, 1:]
    Ma[-1, -1] += tip_mass
    lam = []
    for Fm, Mm in ((F, Mb), (Fa, Ma)):
        Lf = np.linalg.cholesky(0.5 * (Fm + Fm.T))
        mu = np.linalg.eigvalsh(Lf.T @ Mm @ Lf)[::-1]
        lam.append(1.0 / mu[:n])
    return np.sqrt(np.sort(np.concatenate(lam))[:n]) / (2.0 * math.pi)
