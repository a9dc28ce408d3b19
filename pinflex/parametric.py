"""Parametric modal model: exact Taylor expansion of eigenvalues in pose and design.

Paper 000 eq. (3)–(9). The Taylor coefficients of ``M(q, y)`` and ``K(q, y)`` come from the
same ERLS assembly as the exact model (:meth:`pinflex.erls.FlexibleModel.assemble`), run in
truncated Taylor arithmetic (:mod:`pinflex.jets`) instead of on numbers: the joint
kinematics are propagated down the URDF tree as jets (a revolute joint's rotation is the
exact series of ``I + sin θ [a]× + (1 − cos θ) [a]×²``, a prismatic joint's offset is linear),
so every coefficient is exact to round-off. Design variables (point masses) enter ``M``
linearly. The eigenvalue jets follow from the recursion of :mod:`pinflex.taylor_eig`.

What is expanded: the eigenvalue ``λ = ω²`` [rad²/s²] of paper 000 eq. (2). The frequency
polynomial ``f = √λ / 2π`` [Hz] is derived from it by exact jet arithmetic
(:func:`pinflex.jets.sqrt`) and is available with ``quantity="freq_hz"``; which of the two is
more linear in ``y`` is measured in ``benchmarks/bench_taylor.py``.

Variables are user coordinates (see :class:`~pinflex.erls.FlexibleModel`): joint values in
the model's convention, then design values [kg]. Only the joints and design variables asked
for are expanded; the others stay at their expansion values.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pinflex import jets
from pinflex.erls import BatchAlgebra, FlexibleModel, _PoseTerms
from pinflex.exceptions import ConfigurationError, TaylorRadiusWarning
from pinflex.jets import JetSpace
from pinflex.kinematics import axis_rotation, skew
from pinflex.taylor_eig import eigen_jets


def _monomials(space: JetSpace, dx: np.ndarray) -> np.ndarray:
    """Monomials (n, ncoef) of offsets (n, nvars): powers by cumulative products, then gathers."""
    n, nv = dx.shape
    powers = np.empty((nv, space.order + 1, n))
    powers[:, 0] = 1.0
    if space.order:
        np.cumprod(np.repeat(dx.T[:, None, :], space.order, axis=1), axis=1,
                   out=powers[:, 1:])
    mi = space.multi_indices
    mon = powers[0, mi[:, 0]]
    for k in range(1, nv):
        mon *= powers[k, mi[:, k]]
    return mon.T


class JetAlgebra:
    """Taylor coefficients on the leading axis (see :class:`pinflex.erls.BatchAlgebra`)."""

    def __init__(self, space: JetSpace):
        self.space = space

    def const(self, c: np.ndarray) -> np.ndarray:
        """Jet of a constant array."""
        return jets.constant(self.space, c)

    def mm(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Truncated product of two matrix jets."""
        return jets.matmul(self.space, a, b)


def _angle_terms(model: FlexibleModel, joint_vars: dict[int, int], col: int):
    """Variables and factors of δq_pin[col] = Σ_l C[col, l] δq_user[l]."""
    return [(var, model.coord_map[col, j]) for j, var in joint_vars.items()
            if model.coord_map[col, j] != 0.0]


def _rotation_jet(space: JetSpace, axis: np.ndarray, angle0: float, terms) -> np.ndarray:
    """Jet of the rotation about ``axis`` by ``angle0 + Σ c_k δx_k``."""
    R = jets.constant(space, axis_rotation(axis, np.array([angle0]))[0])
    k1 = skew(axis)
    k2 = k1 @ k1
    one = jets.constant(space, 1.0)
    for var, c in terms:
        s, co = jets.sin_cos_of_variable(space, var, 0.0)
        scale = float(c) ** space.multi_indices[:, var]
        s, co = s * scale, co * scale
        step = (jets.constant(space, np.eye(3)) + s[:, None, None] * k1
                + (one - co)[:, None, None] * k2)
        R = jets.matmul(space, R, step)
    return R


def pose_jets(model: FlexibleModel, space: JetSpace, q0: np.ndarray,
              joint_vars: dict[int, int]) -> _PoseTerms:
    """Jets of the ERLS pose terms (frame Jacobians, joint rotations) at ``q0``.

    Args:
        model: The flexible model.
        space: Jet space.
        q0: Expansion pose in user coordinates, (nv,).
        joint_vars: Map user joint index -> jet variable index of the expanded joints.
    """
    nv, nc = model.nv, space.ncoef
    q0p = model.coord_map @ q0
    J = {model._order[0]: np.zeros((nc, 6, nv))}
    rot, slide = {}, {}
    for j in model._joints:
        if j.kind == "revolute":
            terms = _angle_terms(model, joint_vars, j.user_col)
            R = j.R_o @ _rotation_jet(space, j.axis, q0p[j.user_col], terms)
            t = jets.constant(space, j.xyz)
            rot[j.name] = R
        elif j.kind == "prismatic":
            d = jets.constant(space, q0p[j.user_col])
            for var, c in _angle_terms(model, joint_vars, j.user_col):
                d = d + c * jets.variable(space, var, 0.0)
            R = jets.constant(space, j.R_o)
            offset = d[:, None] * (j.R_o @ j.axis)[None, :]
            slide[j.name] = offset
            t = jets.constant(space, j.xyz) + offset
        else:
            R = jets.constant(space, j.R_o)
            t = jets.constant(space, j.xyz)
        JP = J[j.parent]
        if nv == 0:
            J[j.child] = JP
            continue
        RT = np.swapaxes(R, -1, -2)
        lin = JP[:, :3] - jets.matmul(space, skew(t), JP[:, 3:])
        Jc = np.concatenate([jets.matmul(space, RT, lin), jets.matmul(space, RT, JP[:, 3:])],
                            axis=1)
        if j.kind == "revolute":
            Jc[0, 3:, j.user_col] += j.axis
        elif j.kind == "prismatic":
            Jc[0, :3, j.user_col] += j.axis
        J[j.child] = Jc
    jac = {link: J[link] @ model.coord_map for link in model._carriers}
    return _PoseTerms(jac, rot, slide)


def matrix_jets(model: FlexibleModel, q0, y0=None, *, order: int = 4,
                joints: Sequence[str] | None = None, design: Sequence[str] | None = None):
    """Exact Taylor coefficients of ``M(q, y)`` and ``K(q, y)`` at ``(q0, y0)``.

    Args:
        model: The flexible model.
        q0: Expansion pose (user coordinates) [rad or m], (nv,).
        y0: Expansion design values [kg] (default nominal).
        order: Truncation order p.
        joints: Names of the joints to expand (default all).
        design: Names of the design variables to expand (default all).

    Returns:
        ``(space, M_jet, K_jet, joint_idx, design_idx)``: jets of shape (ncoef, ndof, ndof);
        the variables are the listed joints then the listed design variables, in order.
    """
    q0 = model.check_q(q0).astype(float)
    if q0.ndim != 1:
        raise ConfigurationError("the expansion point must be a single pose")
    y0 = model.check_y(y0)
    joint_idx = [model.joint_index(n) for n in (model.joint_names if joints is None else joints)]
    names = model.design_names if design is None else tuple(design)
    design_idx = []
    for n in names:
        if n not in model.design_names:
            from pinflex.exceptions import DesignVariableNotFound

            raise DesignVariableNotFound(n, model.design_names)
        design_idx.append(model.design_names.index(n))
    nvars = len(joint_idx) + len(design_idx)
    if nvars == 0:
        raise ConfigurationError("expand at least one joint or design variable")
    if order < 0:
        raise ConfigurationError(f"order = {order} must be >= 0")
    space = JetSpace(nvars, int(order))
    nj, nd = len(joint_idx), len(design_idx)
    # The pose terms depend on the joints only: assemble in the joints' own (smaller) jet
    # space, then embed. Design masses enter M linearly: δy_j shifts coefficients by e_j.
    if nj:
        qspace = JetSpace(nj, int(order))
        terms = pose_jets(model, qspace, q0, {j: k for k, j in enumerate(joint_idx)})
        Mq, Mdq, Kq = model.assemble(terms, JetAlgebra(qspace))
        alphas = [tuple(a) for a in qspace.multi_indices.tolist()]
    else:
        Mq, Mdq, Kq = model.assemble(model.pose_terms(q0[None]), BatchAlgebra(1))
        alphas = [()]
    zeros = (0,) * nd
    emb = np.array([space.index[a + zeros] for a in alphas])
    shape = (space.ncoef,) + Mq.shape[1:]
    M, K = np.zeros(shape), np.zeros(shape)
    M[emb] = Mq
    K[emb] = Kq
    for j in range(model.ny):
        M[emb] += y0[j] * Mdq[j]
        if j in design_idx:
            k = design_idx.index(j)
            unit = tuple(int(i == k) for i in range(nd))
            low = [i for i, a in enumerate(alphas) if sum(a) < order]
            shifted = np.array([space.index[alphas[i] + unit] for i in low], dtype=int)
            M[shifted] += Mdq[j][low]
    return space, M, np.array(K), joint_idx, design_idx


@dataclass(frozen=True)
class TaylorModel:
    """Taylor polynomials of eigenvalues around ``(q0, y0)`` (paper 000 eq. 4 and 7–9).

    Attributes:
        space: Jet space (variables: expanded joints, then expanded design variables).
        q0: Expansion pose, user coordinates, (nv,).
        y0: Expansion design values [kg], (ny,).
        modes: Non-rigid mode numbers (1 = lowest), (k,).
        joint_idx: User indices of the expanded joints.
        design_idx: Indices of the expanded design variables.
        eigval_jets: Jets of λ_i = ω_i² [rad²/s²], (ncoef, k).
        radius: Estimated convergence radius along each variable axis, (nvars, k), in the
            variables' own units [rad, m or kg].
    """

    space: JetSpace
    q0: np.ndarray
    y0: np.ndarray
    modes: tuple[int, ...]
    joint_idx: tuple[int, ...]
    design_idx: tuple[int, ...]
    eigval_jets: np.ndarray
    radius: np.ndarray
    freq_jets: np.ndarray | None = None

    def __post_init__(self):
        if self.freq_jets is None:
            f = jets.sqrt(self.space, self.eigval_jets) / (2.0 * np.pi)
            object.__setattr__(self, "freq_jets", f)

    @property
    def order(self) -> int:
        """Truncation order p."""
        return self.space.order

    def jet(self, quantity: str = "eigval") -> np.ndarray:
        """Coefficients of λ (``eigval``, [rad²/s²]) or of the frequency (``freq_hz``, [Hz])."""
        if quantity == "eigval":
            return self.eigval_jets
        if quantity == "freq_hz":
            return self.freq_jets
        raise ConfigurationError(f"quantity='{quantity}': expected 'eigval' or 'freq_hz'")

    def offsets(self, Q, Y=None, *, warn: bool = True) -> np.ndarray:
        """Offsets (n, nvars) of samples from the expansion point; checks fixed joints."""
        Q = np.asarray(Q, dtype=float)
        if Q.ndim == 1:
            Q = Q[None]
        if Q.ndim != 2 or Q.shape[1] != self.q0.size:
            raise ConfigurationError(
                f"expected {self.q0.size} joint values per sample, got shape {Q.shape}"
            )
        jidx = self.__dict__.get("_jidx_arr")
        if jidx is None:
            jidx = np.asarray(self.joint_idx, dtype=int)
            self.__dict__["_jidx_arr"] = jidx
        if len(jidx) < self.q0.size:
            fixed = [i for i in range(self.q0.size) if i not in self.joint_idx]
            if np.any(np.abs(Q[:, fixed] - self.q0[fixed]) > 1e-12):
                raise ConfigurationError(
                    f"joints {fixed} are not expanded in this Taylor model; keep them at q0 "
                    f"({self.q0[fixed].tolist()}) or expand them"
                )
        if not self.design_idx:
            dx = Q[:, jidx] - self.q0[jidx]
        else:
            dx = np.empty((Q.shape[0], self.space.nvars))
            nj = len(jidx)
            dx[:, :nj] = Q[:, jidx] - self.q0[jidx]
            if Y is None:
                dx[:, nj:] = 0.0
            else:
                Y = np.asarray(Y, dtype=float)
                didx = list(self.design_idx)
                dx[:, nj:] = Y[..., didx] - self.y0[didx]
        if warn:
            self.check_radius(dx)
        return dx

    def check_radius(self, dx: np.ndarray, fraction: float = 1.0) -> float:
        """Warn when samples lie beyond ``fraction`` of the estimated convergence radius.

        The radius is estimated along each sample's own ray from the expansion point (root
        test of the ray's univariate coefficients, see :func:`root_test_radius`), so mixed
        joint and design offsets are judged in their actual direction.

        Returns:
            The largest ratio ``distance / radius`` over samples and modes.
        """
        dx = np.atleast_2d(dx)
        dist = np.linalg.norm(dx, axis=1)
        moving = dist > 0
        if not np.any(moving):
            return 0.0
        rays = dx[moving] / dist[moving, None]
        c = jets.ray_coefficients(self.space, self.eigval_jets, rays)  # (n, p+1, k)
        radius = _root_test(c, self.order)  # (n, k)
        with np.errstate(divide="ignore"):
            ratio = float(np.max(dist[moving, None] / radius))
        if ratio > fraction:
            warnings.warn(
                f"Taylor model evaluated at {ratio:.2f}x its estimated convergence radius "
                "along the sample's direction; the polynomial may diverge there: expand "
                "closer, raise the order, or use several expansion points "
                "(pinflex.parametric.expand_along)",
                TaylorRadiusWarning,
                stacklevel=3,
            )
        return ratio

    def evaluate(self, Q, Y=None, *, quantity: str = "eigval", linear_in_design=False,
                 warn: bool = True) -> np.ndarray:
        """Polynomial values at samples: (n, k) eigenvalues [rad²/s²] or frequencies [Hz].

        Args:
            Q: Joint values (n, nv) in user coordinates.
            Y: Design values (n, ny) or (ny,) [kg] (default y0).
            quantity: 'eigval' or 'freq_hz'.
            linear_in_design: Use the partially linear polynomial λ̂ (eq. 7) instead of λ^p.
            warn: Warn beyond the estimated convergence radius.
        """
        coef = self._coefficients(quantity, bool(linear_in_design))
        dx = self.offsets(Q, Y, warn=warn)
        return _monomials(self.space, dx) @ coef

    def _coefficients(self, quantity: str, linear: bool) -> np.ndarray:
        """Coefficient matrix (ncoef, k) of a polynomial, cached."""
        cache = self.__dict__.setdefault("_coef_cache", {})
        key = (quantity, linear)
        if key not in cache:
            jet = self.jet(quantity)
            if linear:
                jet = jets.partially_linear(self.space, jet, self._design_vars)
            cache[key] = np.ascontiguousarray(jet.reshape(self.space.ncoef, -1))
        return cache[key]

    @property
    def _design_vars(self) -> list[int]:
        n = len(self.joint_idx)
        return list(range(n, n + len(self.design_idx)))

    def linear_parts(self, Q, *, quantity: str = "eigval"):
        """Values of l_{i,0}(q) and l_{i,j}(q) of eq. (9) at samples.

        Returns:
            ``(l0, L)``: l0 (n, k) and L (n, k, ny_expanded), so that
            ``λ̂_i = l0[:, i] + L[:, i, :] @ δy``.
        """
        if not self.design_idx:
            raise ConfigurationError("the Taylor model expands no design variable")
        if not self.joint_idx:
            jet = self.jet(quantity)
            l0 = np.repeat(jet[:1], np.atleast_2d(Q).shape[0], axis=0)
            grads = jet[1 : 1 + len(self.design_idx)]
            return l0, np.repeat(grads.T[None], l0.shape[0], axis=0)
        qspace, l0, l1 = jets.design_split(self.space, self.jet(quantity), self._design_vars)
        dq = self.offsets(Q, None)[:, : len(self.joint_idx)]
        mon = jets.monomials(qspace, dq)
        return mon @ l0, np.einsum("nc,jck->nkj", mon, l1)


def _root_test(c: np.ndarray, p: int, noise_rtol: float = 1e-13) -> np.ndarray:
    """Root-test radius from univariate coefficients c of shape (n, p+1, *shape)."""
    out = np.full((c.shape[0],) + c.shape[2:], np.inf)
    if p < 1:
        return out
    c0 = np.abs(c[:, 0])
    c0 = np.where(c0 > 0, c0, 1.0)
    for j in range(max(1, (p + 1) // 2), p + 1):
        ratio = np.abs(c[:, j]) / c0
        with np.errstate(divide="ignore"):
            out = np.minimum(out, np.where(ratio > noise_rtol, ratio ** (-1.0 / j), np.inf))
    return out


def root_test_radius(space: JetSpace, jet: np.ndarray) -> np.ndarray:
    """Convergence radius along each variable axis by the root test (Cauchy–Hadamard).

    Along a ray the univariate coefficients ``c_j`` give ``R_j = |c_j / c_0|^{-1/j}``; the
    estimate is the smallest ``R_j`` over the upper half of the orders (``j ≥ ⌈p/2⌉``), a
    finite-order stand-in for ``1 / limsup |c_j|^{1/j}``. Coefficients below ``1e-13 |c_0|``
    count as zero; a ray with none left gets ``inf`` (a polynomial). On benchmark A the
    estimate tightens with the order (about 1.4 rad at p = 4, 1.1 rad at p = 8 and 12 along
    the elbow angle, where the series visibly diverges beyond about 1 rad): a guide, not a
    bound.

    Returns:
        Radii (nvars, *shape) in the variables' units.
    """
    c = jets.ray_coefficients(space, jet, np.eye(space.nvars))
    return _root_test(c, space.order)


def expand(model: FlexibleModel, q0, y0=None, *, order: int = 4, modes: Sequence[int] = (1,),
           joints: Sequence[str] | None = None, design: Sequence[str] | None = None
           ) -> TaylorModel:
    """Build the Taylor model of the given non-rigid modes at ``(q0, y0)``.

    Raises:
        RepeatedEigenvalue: a requested mode is (nearly) repeated at the expansion point.
    """
    modes = tuple(int(m) for m in np.atleast_1d(modes))
    if min(modes) < 1 or max(modes) > model.nx:
        raise ConfigurationError(f"modes {modes} must lie in 1..{model.nx}")
    space, M, K, jidx, didx = matrix_jets(model, q0, y0, order=order, joints=joints,
                                          design=design)
    idx = [model.nv + m - 1 for m in modes]
    lam, _ = eigen_jets(space, M, K, idx)
    radius = root_test_radius(space, lam)
    return TaylorModel(
        space=space,
        q0=np.asarray(q0, dtype=float),
        y0=model.check_y(y0),
        modes=modes,
        joint_idx=tuple(jidx),
        design_idx=tuple(didx),
        eigval_jets=lam,
        radius=np.atleast_2d(radius),
    )


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
    """

    models: tuple[TaylorModel, ...]
    segments: tuple[tuple[int, int], ...]
    order: int
    tol: float
    max_error: float
    candidates: dict[int, int]

    def evaluate(self, Q, *, quantity: str = "freq_hz") -> np.ndarray:
        """Values at the trajectory's own samples Q (ns, nv), each from its segment's model."""
        Q = np.atleast_2d(np.asarray(Q, dtype=float))
        out = None
        for tm, (a, b) in zip(self.models, self.segments):
            v = tm.evaluate(Q[a:b], quantity=quantity, warn=False)
            if out is None:
                out = np.empty((Q.shape[0],) + v.shape[1:])
            out[a:b] = v
        return out


def _cover(model, Q, y, exact, tol, order, modes, joints, quantity, step):
    """Greedy cover of the samples by expansions of one order; returns models and segments."""
    ns = Q.shape[0]
    models, segments = [], []
    s = 0
    while s < ns:
        best = None
        c = s
        while c < ns:
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
                 quantity: str = "freq_hz", step: int | None = None) -> TrajectoryExpansion:
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
    """
    Q = model.check_q(Q)
    y = model.check_y(y)
    modes = tuple(int(m) for m in np.atleast_1d(modes))
    f = model.frequencies(Q, y, n_modes=max(modes))[:, [m - 1 for m in modes]]
    exact = f if quantity == "freq_hz" else (2 * np.pi * f) ** 2
    step = step or (Q.shape[0] // 38 + 1)
    best = None
    candidates = {}
    for p in orders:
        models, segments = _cover(model, Q, y, exact, tol, p, modes, joints, quantity, step)
        candidates[int(p)] = len(models)
        if best is None or len(models) < len(best[1]):
            best = (p, models, segments)
    p, models, segments = best
    result = TrajectoryExpansion(tuple(models), tuple(segments), int(p), tol, 0.0, candidates)
    err = float(np.max(np.abs(result.evaluate(Q, quantity=quantity) / exact - 1)))
    return TrajectoryExpansion(tuple(models), tuple(segments), int(p), tol, err, candidates)


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

    def values(self, y=None) -> np.ndarray:
        """Polynomial values (ns, k) at the samples for design ``y`` [kg] (default y0)."""
        if self.space_y is None or y is None:
            return self.G[0]
        dy = [float(y[j]) - float(self.y0[j]) for j in self.design_idx]
        # one design point: its monomials in plain Python, then a single matrix product
        parent, var = self._parent, self._var
        mon = [1.0]
        for c in range(1, len(parent)):
            mon.append(mon[parent[c]] * dy[var[c]])
        return self._Gt.dot(np.array(mon)).reshape(self._shape)

    def __post_init__(self):
        object.__setattr__(self, "_Gt", np.ascontiguousarray(self.G.reshape(self.G.shape[0], -1).T))
        object.__setattr__(self, "_shape", self.G.shape[1:])
        if self.space_y is not None:
            object.__setattr__(self, "_parent", self.space_y.parent.tolist())
            object.__setattr__(self, "_var", self.space_y.parent_var.tolist())


def sample(tm: TaylorModel, Q, *, quantity: str = "freq_hz",
           linear_in_design: bool = False) -> SampledTaylor:
    """Fix the joint samples of a Taylor model (see :class:`SampledTaylor`)."""
    coef = tm._coefficients(quantity, bool(linear_in_design))  # (ncoef, k)
    nj, nd = len(tm.joint_idx), len(tm.design_idx)
    mi = tm.space.multi_indices
    Q = np.atleast_2d(np.asarray(Q, dtype=float))
    if nj:
        qspace = JetSpace(nj, tm.order)
        dq = tm.offsets(Q, None, warn=True)[:, :nj]
        mon_q = _monomials(qspace, dq)  # (ns, ncq)
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
