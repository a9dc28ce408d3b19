"""Taylor coefficients of the ERLS pencil in the solver coordinates of :mod:`pinflex.erls.solve`.

In the relative, element-scaled elastic coordinates ``w`` the stiffness is the identity on
``w`` (zero on the joints) at every pose, and the mass is assembled from constant per-link
blocks: the only pose-dependent factors are the links' root twists (6 × nx) and frame
Jacobians (6 × nv). Their jets are small, so the truncated products of the assembly cost a
small fraction of those of the nodal-coordinate assembly (:func:`matrix_jets`), whose factors
are the full nodal motion matrices of every link. Eigenvalues are invariant under the change
of coordinates, so their Taylor coefficients are the same. Section, material and joint-spring
terms (:mod:`pinflex.parametric.solver_design`) make ``K`` a jet too: in the design variables
only for sections and materials, through the attachment twists for springs.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pinflex.erls import FlexibleModel, eigensolve, kinematics, solve
from pinflex.exceptions import ConfigurationError
from pinflex.jets import JetSpace
from pinflex.parametric import solver_design
from pinflex.parametric.algebra import SparseJetAlgebra
from pinflex.parametric.matrices import expansion_variables, pose_jets


def static_joints(model: FlexibleModel) -> frozenset[int]:
    """User joints whose values cannot enter the solver-coordinate pencil.

    A joint that hangs from a rigid link welded to the root (through fixed joints only) turns
    its whole subtree as one rigid motion of an otherwise still world: every frame Jacobian
    and twist of the solver coordinates is expressed in the moving bodies' own frames, so
    ``M`` and ``K`` do not depend on its value (for instance a robot's base pan joint). A user
    coordinate that also drives other joints (coupled or absolute angles) is not static.
    """
    flexible = set(solve.solve_plan(model).cores)
    still = {model.plan.root} - flexible
    for j in model.plan.joints:  # parents come before children
        if not j.motion.moves and j.parent in still and j.child not in flexible:
            still.add(j.child)
    out = set()
    C = model.coord_map
    for u in range(model.nv):
        drives = [j for j in model.plan.joints if j.user_col >= 0 and C[j.user_col, u] != 0.0]
        if drives and all(j.parent in still for j in drives):
            out.add(u)
    return frozenset(out)


def _mass_jets(model: FlexibleModel, q0, y0, joint_idx, design_idx, order: int,
               pose: list | None = None):
    """Mass jet over ``joint_idx`` + ``design_idx`` (and the space), in solver coordinates.

    ``pose``, when given a list, receives the pose terms and their algebra (None for one pose).
    """
    space = JetSpace(len(joint_idx) + len(design_idx), int(order))
    nj, nd = len(joint_idx), len(design_idx)
    alg = None
    if nj:
        qspace = JetSpace(nj, int(order))
        alg = SparseJetAlgebra(qspace)
        terms = pose_jets(model, qspace, q0, {j: k for k, j in enumerate(joint_idx)}, alg)
        Mq, Mdq = solve.mass(model, terms, y0, 1, alg=alg, split=True)
        alphas = [tuple(a) for a in qspace.multi_indices.tolist()]
    else:
        terms = kinematics.pose_terms(model, q0[None])
        Mq, Mdq = solve.mass(model, terms, y0, 1, split=True)
        alphas = [()]
    if pose is not None:
        pose += [terms, alg]
    zeros = (0,) * nd
    emb = np.array([space.index[a + zeros] for a in alphas])
    # only design point masses have a mass per unit value (section parameters: zero); add
    # them in the joints' space before the one embedding copy
    masses = sorted(set(model.plan.design.mass_index.values()))  # as solve.mass reads it
    for j in masses:
        if y0[j] != 0.0:
            Mq += y0[j] * Mdq[j]
    M = np.zeros((space.ncoef,) + Mq.shape[1:])
    M[emb] = Mq
    low = [i for i, a in enumerate(alphas) if sum(a) < order]
    for j in masses:
        if j in design_idx:
            k = design_idx.index(j)
            unit = tuple(int(i == k) for i in range(nd))
            shifted = np.array([space.index[alphas[i] + unit] for i in low], dtype=int)
            M[shifted] += Mdq[j][low]
    return space, M


def solver_matrix_jets(model: FlexibleModel, q0, y0=None, *, order: int = 4,
                       joints: Sequence[str] | None = None,
                       design: Sequence[str] | None = None):
    """Exact Taylor coefficients of ``M`` and ``K`` over the solver coordinates ``[w; q]``.

    Same arguments and returns as :func:`pinflex.parametric.matrix_jets`; only the
    coordinates of the matrices differ (their eigenvalues are the same).
    """
    q0, y0, joint_idx, design_idx, order = expansion_variables(model, q0, y0, order, joints, design)
    pose: list = []
    space, M = _mass_jets(model, q0, y0, joint_idx, design_idx, order, pose)
    K0 = np.zeros(M.shape[1:])
    K0[: model.nx, : model.nx] = np.eye(model.nx)
    M, K = solver_design.add_terms(model, space, pose[0], pose[1], len(joint_idx), design_idx,
                                   y0, M, K0)
    if K.ndim == 2:
        K = np.concatenate([K[None], np.zeros((space.ncoef - 1,) + K.shape)])
    return space, M, K, joint_idx, design_idx


def reduced_solver_jets(model: FlexibleModel, q0, y0=None, *, order: int = 4,
                        joints: Sequence[str] | None = None,
                        design: Sequence[str] | None = None):
    """The mass and stiffness jets over the variables that can change them.

    Like :func:`solver_matrix_jets`, but the expanded joints that cannot enter the pencil
    (:func:`static_joints`) are left out of the jet space: every coefficient that involves
    them is exactly zero, so the eigenvalue jets over the full space are those over the
    reduced one, embedded (:func:`embed`).

    Returns:
        ``(full_space, space, keep, M, K0, joint_idx, design_idx)``: the space of all
        expanded variables, the reduced space, the full-space variable of each reduced one,
        the mass jet (space.ncoef, nd, nd), the stiffness: one matrix (nd, nd) when it is the
        constant ``blockdiag(I, 0)``, else its jet (sections, materials, joint springs:
        :func:`pinflex.parametric.solver_design.add_terms`), and the expanded indices.
    """
    q0, y0, joint_idx, design_idx, order = expansion_variables(model, q0, y0, order, joints, design)
    nj = len(joint_idx)
    full_space = JetSpace(nj + len(design_idx), int(order))
    static = static_joints(model)
    live = [k for k, j in enumerate(joint_idx) if j not in static]
    if not live and not design_idx:  # nothing moves the spectrum: keep one variable
        live = [0]
    keep = live + list(range(nj, nj + len(design_idx)))
    pose: list = []
    space, M = _mass_jets(model, q0, y0, [joint_idx[k] for k in live], design_idx, order, pose)
    K0 = np.zeros(M.shape[1:])
    K0[: model.nx, : model.nx] = np.eye(model.nx)
    M, K = solver_design.add_terms(model, space, pose[0], pose[1], len(live), design_idx, y0,
                                   M, K0)
    return full_space, space, keep, M, K, joint_idx, design_idx


def embed(full_space: JetSpace, space: JetSpace, keep: Sequence[int], jet: np.ndarray):
    """A jet over the variables ``keep`` of ``full_space`` as a jet over all of them."""
    if space == full_space:
        return jet
    rows = np.zeros((space.ncoef, full_space.nvars), dtype=np.int64)
    rows[:, list(keep)] = space.multi_indices
    pos = [full_space.index[tuple(r)] for r in rows.tolist()]
    out = np.zeros((full_space.ncoef,) + jet.shape[1:], dtype=jet.dtype)
    out[pos] = jet
    return out


def expansion_eigenpairs(model: FlexibleModel, M0: np.ndarray):
    """All eigenpairs of the solver-coordinate pencil ``(blkdiag(I, 0), M0)`` at one pose.

    The ``nv`` rigid modes come first (λ = 0, shapes ``[0; Lq⁻ᵀ]``), then the elastic ones
    from the inverse form (:func:`pinflex.erls.eigensolve.eigvecs`); all mass-normalised.

    Returns:
        ``(w, V)``: eigenvalues ascending (ndof,) and shapes (ndof, ndof).
    """
    nx, nv = model.nx, model.nv
    lam, shapes_w, shapes_x = eigensolve.eigvecs(model, M0)
    if shapes_x.shape[1]:
        raise ConfigurationError(
            f"the highest {shapes_x.shape[1]} modes at the expansion point are not resolved in "
            "solver coordinates; use fewer elements"
        )
    V = np.zeros((nx + nv, nx + nv))
    if nv:
        Lq = np.linalg.cholesky(M0[nx:, nx:])
        V[nx:, :nv] = np.linalg.inv(Lq.T)  # nv × nv, small
    V[:, nv:] = shapes_w
    return np.concatenate([np.zeros(nv), lam]), V
