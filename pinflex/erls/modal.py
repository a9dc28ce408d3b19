"""Modal analysis of an ERLS model: reduced eigenproblem, mode shapes, nodal motion."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex.checks import check_q, check_y
from pinflex.erls import assembly, eigensolve, joints, kinematics, one_pose, solve, solve_conditions
from pinflex.erls.design import design_model
from pinflex.erls.preload import Preload, preload_stiffness
from pinflex.erls.terms import BatchAlgebra
from pinflex.exceptions import ConfigurationError, EigenSolverError, PreloadBuckles
from pinflex.linalg import rotate_twist


@dataclass(frozen=True)
class ModalResult:
    """Modal analysis at one pose.

    Attributes:
        q: Joint coordinates (user convention) [rad or m], (nv,).
        y: Design values, (ny,), each in its variable's unit (``design_units``).
        ndof: Number of modal coordinates nx + (joints not locked).
        rigid_modes: Number of rigid (zero-frequency) modes (the free joints).
        eigvals: Non-rigid eigenvalues λ = ω² ascending [rad²/s²], (k,).
        shapes: Mass-normalised mode shapes over the modal coordinates ``[x; q_kept]``
            (``q_kept``: the joints that are not locked), (ndof, k).
        node_positions: World positions of beam nodes per flexible link [m], (N+1, 3) each.
        node_motion: Per flexible link, the world-axes nodal translation and rotation of each
            mode, (k, N+1, 6); ``node_elastic`` the elastic part only (rigid ERLS motion removed).
        design_names: Names of the design variables of ``y``.
        design_units: Their units (``kg``, ``m``, ``Pa``, ...).
        preload: The static loads whose stiffness entered the analysis
            (:class:`~pinflex.erls.preload.Preload`), or None.
    """

    q: np.ndarray
    y: np.ndarray
    ndof: int
    rigid_modes: int
    eigvals: np.ndarray
    shapes: np.ndarray
    node_positions: dict[str, np.ndarray]
    node_motion: dict[str, np.ndarray]
    node_elastic: dict[str, np.ndarray]
    design_names: tuple[str, ...] = ()
    design_units: tuple[str, ...] = ()
    preload: Preload | None = None

    @property
    def omega_rad_s(self) -> np.ndarray:
        """Angular eigenfrequencies [rad/s]."""
        return np.sqrt(self.eigvals)

    @property
    def freq_hz(self) -> np.ndarray:
        """Eigenfrequencies [Hz] of the non-rigid modes, ascending."""
        return np.sqrt(self.eigvals) / (2.0 * np.pi)

    def __repr__(self) -> str:
        """A short table: pose, design, and one line per mode."""
        def vec(v, unit=""):
            return "[" + ", ".join(f"{x:.4g}" for x in np.ravel(v)) + "]" + unit

        lines = [
            f"ModalResult({self.eigvals.size} modes, {self.rigid_modes} rigid, "
            f"ndof={self.ndof})",
            f"  q = {vec(self.q)}",
        ]
        if np.size(self.y):
            if len(self.design_names) == np.size(self.y):
                lines.append("  y: " + ", ".join(
                    f"{n} = {v:.4g} {u}".rstrip() for n, v, u in
                    zip(self.design_names, np.ravel(self.y), self.design_units)))
            else:
                lines.append(f"  y = {vec(self.y)}")
        if self.preload is not None:
            lines.append(f"  preload: {self.preload}")
        lines.append(f"  {'mode':>4}  {'f [Hz]':>12}  {'omega [rad/s]':>14}")
        shown = self.eigvals.size if self.eigvals.size <= 12 else 10
        for k in range(shown):
            lines.append(f"  {k + 1:>4}  {self.freq_hz[k]:>12.6g}  {self.omega_rad_s[k]:>14.6g}")
        if shown < self.eigvals.size:
            lines.append(
                f"  ... {self.eigvals.size - shown} more (up to {self.freq_hz[-1]:.6g} Hz); "
                "see .freq_hz"
            )
        return "\n".join(lines)


def design_labels(model) -> dict:
    """``design_names`` and ``design_units`` of a :class:`ModalResult` of ``model``."""
    return {"design_names": tuple(d.name for d in model.design),
            "design_units": tuple(d.unit for d in model.design)}


def reduced(model, M: np.ndarray, K: np.ndarray):
    """Elastic mass with the free joints' coordinates condensed out, and the elastic K.

    The elastic block holds ``x`` and the coordinates of spring-held joints; the free joints'
    coordinates carry no stiffness and are condensed out exactly.
    """
    lay = model.plan.conditions
    if lay.plain:
        nx = model.nx
        Mee, Mer, Mrr = M[..., :nx, :nx], M[..., :nx, nx:], M[..., nx:, nx:]
        Kee = K[..., :nx, :nx]
    else:
        M, K = relative_joint_values(model, M, K)
        e, r = lay.elastic_cols, lay.rigid_cols
        Mee, Mer, Mrr = M[..., e[:, None], e], M[..., e[:, None], r], M[..., r[:, None], r]
        Kee = K[..., e[:, None], e]
    if Mrr.shape[-1]:
        try:
            Lq = np.linalg.cholesky(Mrr)
        except np.linalg.LinAlgError as exc:
            raise EigenSolverError(
                "the ERLS mass matrix Mqq is singular: a joint moves no mass; "
                "add inertia to the links it drives"
            ) from exc
        Z = np.linalg.inv(Lq) @ np.swapaxes(Mer, -1, -2)
        Mred = Mee - np.swapaxes(Z, -1, -2) @ Z
    else:
        Mred = Mee
    return Mred, Kee


def relative_joint_values(model, M: np.ndarray, K: np.ndarray):
    """``M``, ``K`` with the kept joints in relative values (where free joints carry no K)."""
    Winv = model.plan.conditions.modal_Winv
    if Winv is None:
        return M, K
    P = np.eye(model.ndof)
    P[model.nx:, model.nx:] = Winv
    return P.T @ M @ P, P.T @ K @ P


def frequencies(model, Q, y=None, *, n_modes: int | None = None, check_bounds=True, data=None,
                preload: Preload | None = None):
    """Non-rigid eigenfrequencies [Hz] at one or many poses, ascending.

    Batched: all poses are assembled and solved together, by the conditioned solve of
    :mod:`pinflex.erls.solve` (free joints) or :mod:`pinflex.erls.solve_conditions` (joint
    springs, locks, section and material design), the same as :func:`modes`; with a
    ``preload`` by the nodal pencil ``(M, K + K_P)`` (:func:`preloaded_pencil`).

    Returns:
        (k,) for one pose or (n, k).
    """
    data = model.workspace(data)
    if preload is not None:
        return _frequencies_preloaded(model, Q, y, preload, n_modes=n_modes,
                                      check_bounds=check_bounds, data=data)
    plain = solve.supported(model)
    if not plain and not solve_conditions.covered(model):
        return _frequencies_nodal(model, Q, y, n_modes=n_modes, check_bounds=check_bounds,
                                  data=data)
    y = check_y(model, y, bounds=check_bounds)  # Q: checked by FlexibleModel.frequencies
    single = Q.ndim == 1
    Qb = Q[None] if single else Q
    if y.ndim == 2 and y.shape[0] != Qb.shape[0]:
        raise ConfigurationError(
            f"got {y.shape[0]} design vectors for {Qb.shape[0]} poses; give one or one per pose"
        )
    _check_n_modes(n_modes)
    if not plain:  # springs, locks, beam design: relative joint values
        terms = kinematics.pose_terms(model, Qb, data=data)

        def pencil_c(i):  # nodal-coordinate pair of pose i, for high modes of extreme spectra
            Mi, Ki = assembly.matrices_from_terms(model, _pose(terms, i),
                                                  y if y.ndim == 1 else y[i], 1)
            return (*reduced(model, Mi[0], Ki[0]), Mi[0])

        P = solve_conditions.pencil(model, terms, y, Qb.shape[0], data)
        f = np.sqrt(solve_conditions.eigvals(model, P, n_modes, pencil_c)) / (2.0 * np.pi)
        return f[0] if single else f
    layout = one_pose.one_pose_layout(model, data) if single and y.ndim == 1 else None
    if layout is not None:  # one pose: one product S^T W S instead of the block assembly
        terms = kinematics.pose_terms_one(model, Q, data=data)
        twist = one_pose.root_twists_one(model, solve.solve_plan(model, data), terms, data)
        M = one_pose.mass_one(model, layout, terms, twist, y)[0]

        def pencil1():
            Mi, Ki = assembly.matrices_from_terms(model, terms, y, 1)
            return (*reduced(model, Mi[0], Ki[0]), Mi[0])

        lam = eigensolve.eigvals_one(model, M, n_modes, pencil1)
        return np.sqrt(lam) / (2.0 * np.pi)
    terms = kinematics.pose_terms(model, Qb, data=data)
    M = solve.mass(model, terms, y, Qb.shape[0], data=data)

    def pencil(i):  # nodal-coordinate pair of pose i, for high modes of extreme spectra
        Mi, Ki = assembly.matrices_from_terms(model, _pose(terms, i), y if y.ndim == 1 else y[i], 1)
        return (*reduced(model, Mi[0], Ki[0]), Mi[0])

    lam = eigensolve.eigvals(model, M, n_modes, pencil)
    f = np.sqrt(lam) / (2.0 * np.pi)
    return f[0] if single else f


def _pose(terms, i: int):
    """Pose terms of pose i of a batch."""
    return type(terms)({k: v[i : i + 1] for k, v in terms.jac.items()},
                       {k: v[i : i + 1] for k, v in terms.rot.items()},
                       {k: v[i : i + 1] for k, v in terms.slide.items()})


def _check_n_modes(n_modes) -> None:
    if n_modes is None:
        return
    if isinstance(n_modes, bool) or not isinstance(n_modes, (int, np.integer)) or n_modes < 1:
        raise ConfigurationError(f"n_modes = {n_modes!r}: give a positive whole number of modes")


def _frequencies_nodal(model, Q, y=None, *, n_modes: int | None = None, check_bounds=True,
                       data=None):
    """Frequencies from the nodal-coordinate pencil (models the conditioned solve lacks).

    Returns:
        (k,) for one pose or (n, k).
    """
    M, K = model.matrices(Q, y, check_bounds=check_bounds, data=data)
    lam = eigvals_from(model, M, K)
    if n_modes is not None:
        lam = lam[..., :n_modes]
    return np.sqrt(lam) / (2.0 * np.pi)


def cholesky_standard_form(model, M: np.ndarray, K: np.ndarray):
    """The reduced pencil (K_xx, M_red) of stacked pairs in standard form A = L⁻¹ K_xx L⁻ᵀ.

    Returns:
        ``(Mred, Li, A)``: the condensed elastic mass, ``L⁻¹`` of its Cholesky factor and the
        symmetric standard-form matrix, each (..., nx, nx).

    Raises:
        EigenSolverError: If the reduced elastic mass matrix is not positive definite.
    """
    Mred, Kxx = reduced(model, M, K)
    try:
        L = np.linalg.cholesky(Mred)
    except np.linalg.LinAlgError as exc:
        raise EigenSolverError("the reduced elastic mass matrix is not positive") from exc
    Li = np.linalg.inv(L)
    A = Li @ Kxx @ np.swapaxes(Li, -1, -2)
    return Mred, Li, 0.5 * (A + np.swapaxes(A, -1, -2))


def eigvals_from(model, M: np.ndarray, K: np.ndarray) -> np.ndarray:
    """Non-rigid eigenvalues λ [rad²/s²] of stacked matrix pairs (..., ndof, ndof)."""
    if model.n_elastic == 0:
        return np.zeros(M.shape[:-2] + (0,))
    _, Li, A = cholesky_standard_form(model, M, K)
    lam = np.linalg.eigvalsh(A)
    if np.any(lam <= 0.0):
        raise EigenSolverError(
            "a non-positive elastic eigenvalue appeared: the structure is not restrained "
            "(check that every flexible link is attached to the ground through joints, "
            "and that every joint spring has a positive stiffness)"
        )
    return lam


def modes(model, q, y=None, *, n_modes: int | None = None, check_bounds=True,
          data=None, preload: Preload | None = None) -> ModalResult:
    """Eigenfrequencies, mass-normalised mode shapes and nodal motion at one pose.

    Solved like :func:`frequencies` (the conditioned solves of :mod:`pinflex.erls.solve` and
    :mod:`pinflex.erls.solve_conditions`, or the preloaded nodal pencil); the shapes are
    returned over the nodal coordinates ``[x; q_kept]``.
    """
    data = model.workspace(data)
    if preload is not None:
        return _modes_nodal(model, q, y, n_modes=n_modes, check_bounds=check_bounds, data=data,
                            preload=preload)
    plain = solve.supported(model)
    if not plain and not solve_conditions.covered(model):
        return _modes_nodal(model, q, y, n_modes=n_modes, check_bounds=check_bounds, data=data)
    q = check_q(model, q)
    if q.ndim != 1:
        raise ConfigurationError("modes() takes one pose; use frequencies() for many")
    y = check_y(model, y, bounds=check_bounds)
    _check_n_modes(n_modes)
    if not plain:  # springs, locks, beam design: relative joint values
        return _modes_conditions(model, q, y, n_modes, data)
    terms, placements = kinematics.pose_terms_and_placements(model, q, data=data)
    plan = solve.solve_plan(model, data)
    twist = one_pose.root_twists_one(model, plan, terms, data)
    layout = one_pose.one_pose_layout(model, data) if y.ndim == 1 else None
    if layout is not None:
        M, S = one_pose.mass_one(model, layout, terms, twist, y)
    else:
        M = solve.mass(model, terms, y, 1, data=data)[0]

    def pencil():
        Mx, Kx = assembly.matrices_from_terms(model, terms, y, 1)
        return (*reduced(model, Mx[0], Kx[0]), Mx[0])

    lam, sw, sx = eigensolve.eigvecs(model, M, n_modes, pencil)
    if not sx.shape[1]:  # every mode from the inverse form: fields straight from [w; q]
        if layout is not None:
            shapes, positions, motion, elastic = _layout_fields(model, layout, S, placements,
                                                                sw)
        else:
            shapes, positions, motion, elastic = _solver_fields(model, plan, twist, terms,
                                                                placements, sw)
        return ModalResult(
            q=q, y=y, ndof=model.ndof, rigid_modes=model.n_rigid, eigvals=lam, shapes=shapes,
            node_positions=positions, node_motion=motion, node_elastic=elastic,
            **design_labels(model),
        )
    shapes = np.concatenate([eigensolve.to_nodal(model, twist, sw, data), sx], axis=1)
    return _nodal_result(model, q, y, lam, shapes, terms, data)


def _nodal_result(model, q, y, lam, shapes, terms, data) -> ModalResult:
    """The :class:`ModalResult` of shapes over ``[x; q_kept]`` (signed: largest ``x`` positive)."""
    nx = model.nx
    k = lam.size
    phix = shapes[:nx]
    idx = np.argmax(np.abs(phix), axis=0)
    shapes *= np.where(phix[idx, np.arange(k)] < 0, -1.0, 1.0)[None, :]
    positions, motion, elastic = node_fields(model, q, shapes, terms, data)
    return ModalResult(
        q=q, y=y, ndof=model.ndof, rigid_modes=model.n_rigid, eigvals=lam, shapes=shapes,
        node_positions=positions, node_motion=motion, node_elastic=elastic,
        **design_labels(model),
    )


def _layout_fields(model, layout, S: np.ndarray, placements, sw: np.ndarray):
    """As :func:`_solver_fields`, for every beam at once through the one-pose layout.

    ``Z = S sw`` holds each beam's own coordinates, root twist and frame twist per mode; the
    nodal coordinates ``X Z`` and the node twists (beam axes) ``A Z`` and ``A_el Z`` (without
    the frame motion) come from one product ``F Z`` (rows of :class:`one_pose.OnePoseLayout`);
    each node's 3-vectors are then turned to world axes, one product per beam.
    """
    nx = model.nx
    k = sw.shape[1]
    G = layout.F @ (S @ sw)  # [x; per beam: node twists, elastic node twists] per mode
    x = G[:nx]
    sign = np.where(x[np.abs(x).argmax(0), np.arange(k)] < 0, -1.0, 1.0)
    G *= sign  # largest elastic component positive
    shapes = np.empty_like(sw)
    shapes[:nx] = x
    np.multiply(sw[nx:], sign, out=shapes[nx:])
    positions, motion, elastic = {}, {}, {}
    for link, (a, b) in layout.field_rows.items():
        pl = placements[link]
        both = pl.rotation @ G[a:b].reshape(-1, 3, k)  # each 3-row block to world axes
        h = both.shape[0] // 2
        positions[link] = pl.positions_m
        motion[link] = both[:h].reshape(-1, 6, k).transpose(2, 0, 1)
        elastic[link] = both[h:].reshape(-1, 6, k).transpose(2, 0, 1)
    return shapes, positions, motion, elastic


def _solver_fields(model, plan, twist, terms, placements, sw: np.ndarray):
    """Nodal shapes and node fields of solver-coordinate shapes ``[w; q]`` (free joints).

    The elastic node twists of a link (beam axes) are ``C w_link + R (e w)`` (``e`` the
    solver-coordinate root twist), the link's nodal coordinates ``x`` are their kept rows: one
    product per link gives both the shapes over ``[x; q]`` (as :func:`eigensolve.to_nodal`) and
    the nodal motion (as :func:`node_fields`). Signs as in :func:`modes`: largest elastic
    component positive.

    Returns:
        ``(shapes, positions, motion, elastic)`` as :func:`modes` stores them.
    """
    nx = plan.nx
    k = sw.shape[1]
    shapes = np.empty_like(sw)
    shapes[nx:] = sw[nx:]
    w = sw[:nx]
    el = {}
    for link, c in plan.cores.items():
        e = twist[link]
        t = c.C @ w[c.start : c.stop]
        if e is not None:
            t += c.R @ (e[0] @ w)
        shapes[c.start : c.stop] = t[c.x_rows]
        el[link] = t
    phix = shapes[:nx]
    sign = np.where(phix[np.argmax(np.abs(phix), axis=0), np.arange(k)] < 0, -1.0, 1.0)
    shapes *= sign
    qs = shapes[nx:]
    positions, motion, elastic = {}, {}, {}
    for link, bp in model.plan.beams.items():
        n1 = bp.nodes.shape[0]
        RwT = rotate_twist(placements[link].rotation).T
        t = el[link] * sign
        tot = t + (bp.jac @ terms.jac[link][0]) @ qs
        positions[link] = placements[link].positions_m
        motion[link] = tot.T.reshape(k, n1, 6) @ RwT
        elastic[link] = t.T.reshape(k, n1, 6) @ RwT
    return shapes, positions, motion, elastic


def _modes_conditions(model, q, y, n_modes, data) -> ModalResult:
    """:func:`modes` of a model with springs, locks or beam design (:mod:`.solve_conditions`)."""
    terms = kinematics.pose_terms(model, q[None], data=data)

    def pencil():
        Mx, Kx = assembly.matrices_from_terms(model, terms, y, 1)
        return (*reduced(model, Mx[0], Kx[0]), Mx[0])

    P = solve_conditions.pencil(model, terms, y, 1, data)
    lam, sw, phie = solve_conditions.eigvecs(model, P, n_modes, pencil, data)
    nx = model.nx
    twist = solve.root_twists(model, solve.solve_plan(model, data), terms, 1)
    conds = model.plan.conditions.conditions
    kept = nx + np.array([i for i, c in enumerate(conds) if c.kind != "locked"], dtype=int)
    shapes = eigensolve.to_nodal(model, twist, sw, data)[np.concatenate([np.arange(nx), kept])]
    if phie is not None:  # high modes from the nodal pencil
        Mx, Kx = assembly.matrices_from_terms(model, terms, y, 1)
        shapes = np.concatenate([shapes, _nodal_shapes(model, Mx[0], Kx[0], phie)], axis=1)
    return _nodal_result(model, q, y, lam, shapes, terms, data)


def _nodal_shapes(model, M: np.ndarray, K: np.ndarray, phie: np.ndarray) -> np.ndarray:
    """Shapes over ``[x; q_kept]`` of eigenvectors ``phie`` of the nodal reduced pencil."""
    shapes = np.zeros((model.ndof, phie.shape[1]))
    lay = model.plan.conditions
    e, r = lay.elastic_cols, lay.rigid_cols
    shapes[e] = phie
    if r.size:
        Mi = M if lay.plain else relative_joint_values(model, M, K)[0]
        shapes[r] = -np.linalg.solve(Mi[np.ix_(r, r)], Mi[np.ix_(r, e)] @ phie)
    if lay.modal_Winv is not None:
        shapes[model.nx:] = lay.modal_Winv @ shapes[model.nx:]
    return shapes


def _modes_nodal(model, q, y=None, *, n_modes: int | None = None, check_bounds=True,
                 data=None, preload: Preload | None = None) -> ModalResult:
    """Modes from the nodal-coordinate pencil (models the conditioned solve lacks, preloads)."""
    import scipy.linalg

    q = check_q(model, q)
    if q.ndim != 1:
        raise ConfigurationError("modes() takes one pose; use frequencies() for many")
    y = check_y(model, y, bounds=check_bounds)
    terms = kinematics.pose_terms(model, q[None], data=data)
    M, K = assembly.matrices_from_terms(model, terms, y, 1)
    if preload is not None:
        K = K + preload_stiffness(design_model(model, y), q[None], preload, y)
    M, K = M[0], K[0]
    Mred, Kxx = reduced(model, M, K)
    ne = model.n_elastic
    k = ne if n_modes is None else min(int(n_modes), ne)
    if preload is not None:
        _check_stable(model, M, K, q[None])
    lam, phie = scipy.linalg.eigh(Kxx, Mred, subset_by_index=[0, k - 1] if k else None)
    shapes = _nodal_shapes(model, M, K, phie)
    # sign: largest elastic component positive
    idx = np.argmax(np.abs(phie), axis=0)
    shapes *= np.sign(phie[idx, np.arange(k)])[None, :]
    positions, motion, elastic = node_fields(model, q, shapes, terms, data)
    return ModalResult(
        q=q, y=y, ndof=model.ndof, rigid_modes=model.n_rigid, eigvals=lam, shapes=shapes,
        node_positions=positions, node_motion=motion, node_elastic=elastic,
        **design_labels(model), preload=preload,
    )


def preloaded_pencil(model, Q: np.ndarray, y: np.ndarray, preload: Preload, data=None):
    """``(M, K + K_P)`` (n, ndof, ndof) at checked poses Q (n, nv) and one design y (ny,).

    ``K_P`` is the stiffness of the preload's static loads (:mod:`pinflex.erls.preload`), on
    the model at design ``y`` (:func:`pinflex.erls.design.design_model`).
    """
    M, K = model.matrices(Q, y, check_bounds=False, data=data)
    return M, K + preload_stiffness(design_model(model, y), Q, preload, y)


def _check_stable(model, M: np.ndarray, K: np.ndarray, Q: np.ndarray) -> np.ndarray:
    """Eigenvalues (..., ne) of the preloaded pencil ``(M, K + K_P)`` (``K`` holding ``K_P``).

    Raises:
        PreloadBuckles: The lowest eigenvalue is negative beyond the rounding level.
        EigenSolverError: It lies within the rounding level (``8 ε λ_max``), or the reduced
            mass is not positive.
    """
    _, _, A = cholesky_standard_form(model, M, K)
    lam = np.linalg.eigvalsh(A)
    low = np.atleast_1d(lam[..., 0])
    noise = 8.0 * np.finfo(float).eps * np.atleast_1d(np.abs(lam).max(axis=-1))
    for i in range(low.size):
        q = np.array2string(np.atleast_2d(Q)[i], precision=4)
        if low[i] < -noise[i]:
            raise PreloadBuckles(
                f"the preload makes the arm unstable at pose {i} (q = {q}): lowest eigenvalue "
                f"{low[i]:.4g} rad^2/s^2 < 0, a load beyond buckling (or a spring too soft for "
                "the load it holds); reduce the load or stiffen the arm")
        if low[i] <= noise[i]:
            raise EigenSolverError(
                f"the preloaded pencil at pose {i} (q = {q}) cannot resolve its lowest "
                f"eigenvalue ({low[i]:.4g} rad^2/s^2 within its rounding level {noise[i]:.2g}): "
                "the arm is at its buckling load, or a joint spring is so stiff that the nodal "
                "pencil loses every digit (lock that joint instead)")
    return lam


def _frequencies_preloaded(model, Q, y, preload: Preload, *, n_modes, check_bounds, data):
    """:func:`frequencies` with a preload: the nodal pencil ``(M, K + K_P)``, batched."""
    y = check_y(model, y, bounds=check_bounds)
    if y.ndim != 1:
        raise ConfigurationError("with a preload, give one design vector (ny,) for all poses")
    _check_n_modes(n_modes)
    single = Q.ndim == 1
    Qb = Q[None] if single else Q
    M, K = preloaded_pencil(model, Qb, y, preload, data=data)
    lam = _check_stable(model, M, K, Qb)
    if n_modes is not None:
        lam = lam[..., :n_modes]
    f = np.sqrt(lam) / (2.0 * np.pi)
    return f[0] if single else f


def node_fields(model, q: np.ndarray, shapes: np.ndarray, terms=None, data=None):
    """World node positions, total and elastic nodal motion of mode shapes at pose q.

    ``terms`` are the pose terms of ``q`` when the caller already has them; ``data`` the
    workspace (default: this thread's).
    """
    if terms is None:
        terms = kinematics.pose_terms(model, q[None], data=data)
    twist = kinematics.root_twists(model, terms, BatchAlgebra(1))
    T = joints.transform(model, terms, BatchAlgebra(1), twist)
    if T is not None:  # locked joints: back to [x; q_all]
        shapes = T[0] @ shapes
    placements = model.node_placements(q, data=data)
    positions, motion, elastic = {}, {}, {}
    nx = model.nx
    for link, plan in model.plan.beams.items():
        e = twist[link]
        bx = plan.sel if e is None else plan.sel + plan.root @ e[0]
        jn = plan.jac @ terms.jac[link][0]
        Rw = rotate_twist(placements[link].rotation)
        n1 = plan.nodes.shape[0]
        el = (bx @ shapes[:nx]).T.reshape(-1, n1, 6)
        tot = el + (jn @ shapes[nx:]).T.reshape(-1, n1, 6)
        positions[link] = placements[link].positions_m
        motion[link] = np.einsum("ij,knj->kni", Rw, tot)
        elastic[link] = np.einsum("ij,knj->kni", Rw, el)
    return positions, motion, elastic
