"""Eigenpairs along samples for mode tracking: nodal or solver coordinates, one map per pose.

:func:`eigenpairs` solves the nodal pencil; :func:`solver_eigenpairs` the condensed mass in the
solver coordinates of :mod:`pinflex.erls.solve` (one batched symmetric eigensolve), with a
:class:`PoseMap` to compare shapes between poses in nodal coordinates.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pinflex.checks import check_q
from pinflex.erls import kinematics
from pinflex.exceptions import EigenSolverError


def eigenpairs(model, Q, y=None, *, n_modes: int | None = None, check_bounds: bool = True):
    """Non-rigid eigenpairs of a FlexibleModel at many poses, batched.

    Args:
        model: A :class:`~pinflex.erls.FlexibleModel`.
        Q: Joint samples (ns, nv), user coordinates.
        y: Design values (ny,) or one per sample (ns, ny) [kg] (default nominal).
        n_modes: Lowest modes to return (default all).
        check_bounds: Refuse design values outside their bounds.

    Returns:
        ``(eigvals, shapes, mass)``: λ (ns, k) ascending [rad²/s²]; shapes (ns, nx, k) over
        the elastic coordinates, mass-normalised with the condensed mass; that mass
        (ns, nx, nx).

    Raises:
        EigenSolverError: the condensed mass is not positive definite or an elastic
            eigenvalue is not positive (an unrestrained or degenerate structure).
    """
    from pinflex.erls.modal import cholesky_standard_form

    Q = np.atleast_2d(check_q(model, Q))
    M, K = model.matrices(Q, y, check_bounds=check_bounds)
    Mred, Li, A = cholesky_standard_form(model, M, K)
    lam, Z = np.linalg.eigh(A)
    k = model.n_elastic if n_modes is None else min(int(n_modes), model.n_elastic)
    lam, Z = lam[:, :k], Z[:, :, :k]
    if not np.all(np.isfinite(lam)) or np.any(lam <= 0.0):
        raise EigenSolverError(
            "a non-positive or non-finite elastic eigenvalue appeared along the samples: the "
            "structure is not restrained or the model is degenerate"
        )
    shapes = np.swapaxes(Li, -1, -2) @ Z
    return lam, shapes, Mred


class PoseMap:
    """Shapes of one pose in the solver coordinates of another pose (same nodal shape).

    A conditioned solve (:mod:`pinflex.erls.solve`) works in relative, scaled element
    coordinates ``w``; the nodal coordinates are ``x = T(q) w``, where ``T(q)`` is constant on
    each link's own columns and depends on the pose only through the elastic twist of each
    link root (its upstream links' tips turned by the joints). A shape ``φ`` of sample ``s``
    is the nodal shape ``T(q_s) φ``; :meth:`move` returns ``u = T(q_t)⁻¹ T(q_s) φ``, that same
    nodal shape in the coordinates of sample ``t``. With ``B_t`` the condensed mass of sample
    ``t`` in those coordinates, ``uᵀ B_t v`` equals the nodal-coordinate product with the
    condensed nodal mass of ``t`` (``B = Tᵀ M_red T``), so a MAC computed on moved shapes is
    the nodal MAC.

    Per link, in the order of its columns (a root twist reads upstream columns only):
    ``u_l = φ_l + G_l (E_l(q_s) φ − E_l(q_t) u)``, with ``E_l`` the root twist (6, nx) and
    ``G_l = C_l⁻¹ R_l`` the constant map of a root twist to the link's own coordinates.

    Args:
        model: A :class:`~pinflex.erls.FlexibleModel` the conditioned solve covers.
        terms: Its pose terms (:func:`pinflex.erls.kinematics.pose_terms`) of the samples.
        ns: Number of samples.
    """

    def __init__(self, model, terms, ns: int):
        from pinflex.erls import solve

        plan = solve.solve_plan(model)
        twist = solve.root_twists(model, plan, terms, ns)
        self.links = [(c.start, c.stop, twist[link], g) for link, c, g in _link_maps(model)
                      if twist.get(link) is not None]

    @classmethod
    def joined(cls, maps: Sequence[PoseMap]) -> PoseMap:
        """One map of the samples of ``maps`` (built on consecutive chunks), in their order."""
        out = cls.__new__(cls)
        out.links = [(a, z, np.concatenate([m.links[i][2] for m in maps]), G)
                     for i, (a, z, _, G) in enumerate(maps[0].links)]
        return out

    def move(self, phi: np.ndarray, src, dst) -> np.ndarray:
        """Shapes ``phi`` (b, nx, k) of samples ``src`` in the coordinates of samples ``dst``.

        ``src`` and ``dst`` are sample indices (b,) or one index each.
        """
        out = np.array(phi, dtype=float)
        for a, z, E, G in self.links:
            d = E[src][..., :a] @ phi[..., :a, :] - E[dst][..., :a] @ out[..., :a, :]
            out[..., a:z, :] += G @ d
        return out


def _link_maps(model) -> list:
    """Per flexible link ``(name, core, G = C_x⁻¹ R_x)`` in column order (cached per workspace)."""
    return model.workspace().cached("tracking_link_maps", lambda: _build_link_maps(model))


def _build_link_maps(model) -> list:
    from pinflex.erls import solve

    plan = solve.solve_plan(model)
    out = []
    for link, c in sorted(plan.cores.items(), key=lambda kv: kv[1].start):
        G = np.linalg.solve(c.C[c.x_rows], c.R[c.x_rows])
        G.setflags(write=False)
        out.append((link, c, G))
    return out


def solver_eigenpairs(model, Q, y, *, n_modes: int, one_pose: bool = False):
    """The lowest ``n_modes`` non-rigid eigenpairs at many poses in solver coordinates.

    Same eigenproblem as :func:`eigenpairs` (and as
    :meth:`~pinflex.erls.FlexibleModel.frequencies`), solved as the conditioned solve does:
    the condensed solver-coordinate mass ``B`` (stiffness ``I``), ``λ = 1/μ`` for its largest
    eigenvalues ``μ``.

    Args:
        model: A :class:`~pinflex.erls.FlexibleModel`.
        Q: Checked joint samples (ns, nv).
        y: Checked design values (ny,) or (ns, ny).
        n_modes: Number of lowest modes.
        one_pose: Every sample has the pose ``Q[0]`` (only the design changes): the mass
            is assembled once, linear in the design, and the shapes of all samples are in
            one set of coordinates.

    Returns:
        ``(eigvals, shapes, mass, pose_map)``: λ (ns, k) ascending [rad²/s²]; shapes
        (ns, nx, k) mass-normalised with ``B``; ``B`` (ns, nx, nx); a :class:`PoseMap` of
        the samples (None with ``one_pose``). None when the conditioned solve does not
        cover the model or does not resolve one of the modes (then use :func:`eigenpairs`).
    """
    from pinflex.erls import eigensolve, solve

    if not solve.supported(model):
        return None
    ns = Q.shape[0]
    k = min(int(n_modes), model.nx)
    if one_pose:
        terms = kinematics.pose_terms(model, Q[:1])
        M0, Md = solve.mass(model, terms, y, 1, split=True)
        Y = np.broadcast_to(y, (ns, model.ny))
        M = M0 + np.tensordot(Y, Md[:, 0], axes=1)  # point masses: linear in the design
    else:
        terms = kinematics.pose_terms(model, Q)
        M = solve.mass(model, terms, y, ns)
    B, _, _ = eigensolve.condense(model, M)
    mu, V = np.linalg.eigh(B)
    if not np.all(np.isfinite(mu)):
        raise EigenSolverError("a non-finite eigenvalue appeared along the samples: the mass "
                               "of the model is not finite")
    top = mu[:, ::-1][:, :k]
    if np.any(top <= eigensolve.noise_level(mu)[:, None]):
        return None  # a requested mode below the inverse form's rounding level
    V = V[:, :, ::-1][:, :, :k]
    pose_map = None if one_pose else PoseMap(model, terms, ns)
    return 1.0 / top, V / np.sqrt(top)[:, None, :], B, pose_map
