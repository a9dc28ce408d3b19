"""Linear models for control design: M, K, damping and a state-space model (A, B, C, D).

At a pose ``q`` (at rest, ``q̇ = 0``, no gravity) the ERLS equations of small motion are

    M p̈ + Dₚ ṗ + K p = Bᵤ τ,       p = [x; q]  (ndof = nx + nv),

with ``x`` the elastic nodal coordinates (``arm.x_names``: ``<link>.n<k>.<u|r><x|y|z>``, small
translations [m] and rotations [rad] of beam node k in the beam axes of its link) and ``q`` the
joint coordinates (``arm.joint_names``, the arm's convention), and ``τ`` the joint torques
(forces for prismatic joints). By default (``torque_input="motor"``) ``τ`` is a **motor
torque**: the actuator acts on both bodies of the joint, doing work on the joint's physical
relative motion ``r = G p`` (between the parent's deformed attachment and the child,
:meth:`~pinflex.FlexibleModel.relative_motion_rows`), so ``Bᵤ = Gᵀ``: it loads the joint
coordinate and, through the elastic offset of the attachment, the parent's deformation (the
stator's reaction), as ``pinflex.dynamics`` (simulation and receptances) reads a joint torque.
``torque_input="generalized"`` gives the generalized-coordinate reading ``Bᵤ = [0; I_nv]``
(relative coordinates; ``[0; Cᵀ]`` for absolute ones, ``q_rel = C q_abs``), which leaves the
reaction on a flexible parent out. A locked joint's column is zero (its torque is a reaction).

State ``z = [p; ṗ]`` (2 ndof): ``A = [[0, I], [−M⁻¹K, −M⁻¹Dₚ]]``, ``B = [[0], [M⁻¹Bᵤ]]``,
``C = [I, 0]`` (outputs: every generalized position) and ``D = 0``. With no damping the
eigenvalues of ``A`` are ``±iω`` of the modal problem plus ``2 nv`` zeros (the free joints'
rigid motion).

Damping ``Dₚ``: none (default), modal (a ratio ζ for every elastic mode:
``Dₚ = M Φ diag(2 ζ ω) Φᵀ M`` with the mass-normalised elastic mode shapes ``Φ``, leaving the
rigid modes undamped), or Rayleigh ``(α, β)`` with its one meaning in pinflex
(:func:`pinflex.linalg.held_rayleigh`): ``α M_H + β K_H`` on the deformation rates, ``M_H``,
``K_H`` the mass and stiffness of the arm with its motors held, so each locked-joint mode
decays at ``α/2 + β ω²/2`` and the rigid motion is not damped (as in the simulations and FRFs).
The joints' dampers (``<pinflex:joint damping=...>``, :meth:`FlexibleModel.joint_damping`)
are added to any of them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg

from pinflex.checks import check_q, check_y
from pinflex.exceptions import ConfigurationError
from pinflex.linalg import held_rayleigh
from pinflex.validation import require_array, require_number


def _relative_rows(arm, q: np.ndarray) -> np.ndarray:
    """``G`` (nv, ndof): the joints' physical relative motion over the solver coordinates."""
    G = arm.relative_motion_rows(q)
    if arm.ndof != arm.nx + arm.nv:  # locked joints: [x; q_all] = T [x; q_kept]
        G = G @ arm.joint_transform(q)
    return G


def _one_pose(arm, q: np.ndarray, y, zeta: float, rayleigh, torque_input: str) -> dict:
    M, K = arm.matrices(q, y)
    nd, nv, nx = arm.ndof, arm.nv, arm.nx
    nr = arm.n_rigid  # free joints (joint springs and locks: pinflex.erls.joints)
    if rayleigh is not None:  # the deformation's, motors held (linalg.held_rayleigh)
        alpha, beta = (float(v) for v in rayleigh)
        G = _relative_rows(arm, q)
        G = G[np.abs(G).max(axis=1) > 0.0]  # locked joints have no relative motion
        damping = held_rayleigh(M, K, G, nx, alpha, beta)
    else:
        damping = np.zeros_like(M)
    damping = damping + arm.joint_damping(q)  # the joints' dampers (zero without)
    lam, phi = scipy.linalg.eigh(K, M)
    # the elastic modes are the largest ones (the free joints' rigid ones have λ = 0)
    lam_e, phi_e = lam[nr:], phi[:, nr:]
    if zeta:
        w = np.sqrt(np.clip(lam_e, 0.0, None))
        MP = M @ phi_e
        damping = damping + MP @ np.diag(2.0 * zeta * w) @ MP.T
    if torque_input == "motor":
        Bu = _relative_rows(arm, q).T
    else:
        Bu = np.zeros((nx + nv, nv))
        Bu[nx:, :] = arm.coord_map.T
        if nd != nx + nv:  # locked joints: torques through [x; q_all] = T [x; q_kept]
            Bu = arm.joint_transform(q).T @ Bu
    sol = np.linalg.solve(M, np.hstack([K, damping, Bu]))
    A = np.zeros((2 * nd, 2 * nd))
    A[:nd, nd:] = np.eye(nd)
    A[nd:, :nd] = -sol[:, :nd]
    A[nd:, nd:] = -sol[:, nd:2 * nd]
    B = np.vstack([np.zeros((nd, nv)), sol[:, 2 * nd:]])
    C = np.hstack([np.eye(nd), np.zeros((nd, nd))])
    freq = np.sqrt(arm.eigvals_from(M, K)) / (2.0 * np.pi)
    return {"M": M, "K": K, "damping": damping, "A": A, "B": B, "C": C,
            "D": np.zeros((nd, nv)), "freq_hz": freq}


def linear_model(arm, q, y=None, *, zeta: float = 0.0, rayleigh=None,
                 torque_input: str = "motor") -> dict:
    """M, K, damping and (A, B, C, D) at one pose (nv,) or along poses (ns, nv).

    Args:
        arm: A :class:`~pinflex.FlexibleModel`.
        q: Joint coordinates, one pose (nv,) or several (ns, nv) (Pinocchio configurations
            of length nq are accepted) [rad or m].
        y: Design values [kg] (default: nominal).
        zeta: Modal damping ratio of every elastic mode (>= 0).
        rayleigh: ``(alpha [1/s], beta [s])``: Rayleigh damping of the deformation (module
            doc), added to the modal damping.
        torque_input: ``"motor"`` (default: the actuator acts on both bodies, ``Bᵤ = Gᵀ``)
            or ``"generalized"`` (``τ`` on the joint coordinates only); module doc.

    Returns:
        A dictionary of arrays: ``M``, ``K``, ``damping`` (ndof, ndof), ``A`` (2 ndof, 2 ndof),
        ``B`` (2 ndof, nv), ``C`` (ndof, 2 ndof), ``D`` (ndof, nv), ``freq_hz`` (nx,) — each
        with a leading (ns,) axis for several poses — plus the coordinate names
        ``coordinates`` (ndof,), ``states`` (2 ndof,), ``inputs`` (nv,), ``outputs`` (ndof,)
        and ``q``, ``y``.
    """
    zeta = require_number(zeta, "zeta (a damping ratio, not a percentage)", ge=0.0, le=1.0)
    if rayleigh is not None:
        rayleigh = tuple(require_array(rayleigh, "rayleigh (alpha, beta)").tolist())
        if len(rayleigh) != 2 or min(rayleigh) < 0.0 or rayleigh[0] > 1e6 or \
                rayleigh[1] > 1.0:  # beyond: damping ratios of 1e3 and more at any mode
            raise ConfigurationError(
                f"rayleigh must be (alpha [1/s], beta [s]) with 0 <= alpha <= 1e6 and "
                f"0 <= beta <= 1, got {rayleigh}")
    if torque_input not in ("motor", "generalized"):
        raise ConfigurationError(f"torque_input = {torque_input!r}: choose 'motor' (the "
                                 "actuator on both bodies of the joint) or 'generalized'")
    Q = check_q(arm, q)
    yv = check_y(arm, y)
    poses = [_one_pose(arm, qk, yv, zeta, rayleigh, torque_input) for qk in np.atleast_2d(Q)]
    out = {k: (poses[0][k] if Q.ndim == 1 else np.stack([p[k] for p in poses]))
           for k in poses[0]}
    coords = list(arm.x_names) + list(arm.kept_joints)
    out.update(
        coordinates=np.array(coords),
        states=np.array(coords + [f"d({c})/dt" for c in coords]),
        inputs=np.array([f"tau({n})" for n in arm.joint_names]),
        outputs=np.array(coords),
        q=np.asarray(Q),
        y=np.asarray(yv),
        design_names=np.array(arm.design_names),
        zeta=np.array(float(zeta)),
        rayleigh=np.array(rayleigh if rayleigh is not None else (0.0, 0.0), dtype=float),
        torque_input=np.array(torque_input),
    )
    return out


def save_linear_model(data: dict, path: str | Path) -> Path:
    """Write :func:`linear_model` output to ``.npz`` (NumPy) or ``.mat`` (MATLAB, scipy.io).

    In the ``.mat`` file string arrays become char/cell arrays; the leading sample axis of
    several poses stays the first axis.
    """
    from pinflex.outputs import atomic_path

    path = Path(path)
    if path.suffix not in (".npz", ".mat"):
        raise ConfigurationError(f"'{path.name}': export to .npz or .mat")
    with atomic_path(path, "exported model") as tmp, open(tmp, "wb") as stream:
        if path.suffix == ".npz":
            np.savez(stream, **data)
        else:
            import scipy.io

            scipy.io.savemat(stream, {k: (v.tolist() if v.dtype.kind == "U" else v)
                                      for k, v in ((k, np.asarray(v)) for k, v in data.items())})
    return path
