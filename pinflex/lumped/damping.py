r"""Damping of a lumped arm as joint damping, the only damping MJCF and URDF joints carry.

pinflex's one damping definition (SPEC §13) is Rayleigh :math:`D = \alpha M + \beta K` or
modal ratios ζ. A simulator's joint damping is a diagonal :math:`D = \mathrm{diag}(d)` on the
joint coordinates; the lumped arm's K is diagonal on the same coordinates, so:

* **Rayleigh, stiffness part** (``rayleigh=(0, β)``): :math:`d_j = \beta k_j` on every sprung
  joint (hinges and the arm's spring joints) is *exact*.
* **Rayleigh, mass part** (α ≠ 0): :math:`\alpha M` is a full matrix over the joints and has
  no joint-damping equivalent; it is refused (:class:`DampingNotRepresentable`) rather than
  approximated silently. Use ``zeta``.
* **Modal ratios** (``zeta=ζ``): hinge dampings :math:`d \ge 0` chosen by bounded linear least
  squares so that the fitted modes' ratios :math:`\zeta_i \approx \phi_i^T D \phi_i / 2\omega_i`
  equal ζ, with a weak pull (weight 10⁻⁶, for a unique answer) towards the stiffness-proportional
  :math:`d = (2\zeta/\omega_1) k`. This is an approximation (a diagonal D cannot give every
  mode the same ratio); the ratios it achieves, from the complex eigenvalues of the damped
  lumped arm, are reported beside the target.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla
from scipy.optimize import lsq_linear

from pinflex.exceptions import ConfigurationError, DampingNotRepresentable, LumpedDampingWarning
from pinflex.lumped.model import LumpedArm

#: Modal ratios reached further than this (relative) from the target are warned about.
RATIO_TOLERANCE = 0.2


@dataclass(frozen=True)
class DampingMap:
    """Joint damping of an exported lumped arm.

    Attributes:
        kind: 'none', 'rayleigh' or 'modal'.
        damping: Joint damping (nv,) [N m s/rad or N s/m] (the arm's own joint damping
            included).
        target: Target modal ratios of the first modes (k,), NaN where not modal.
        achieved: Ratios of the first modes from the damped arm's eigenvalues (k,) [-].
        description: One line saying how the damping was mapped.
    """

    kind: str
    damping: np.ndarray
    target: np.ndarray
    achieved: np.ndarray
    description: str

    def summary(self) -> dict:
        """Plain data for JSON reports."""
        return {"kind": self.kind, "target_zeta": self.target.tolist(),
                "achieved_zeta": self.achieved.tolist(), "description": self.description}


def modal_ratios(lumped: LumpedArm, q, damping: np.ndarray, n_modes: int) -> np.ndarray:
    """Damping ratios of the lowest non-rigid modes of ``M p̈ + D ṗ + K p = 0`` at pose ``q``."""
    M = lumped.mass_matrix(q)
    kept, rigid = lumped.kept("own")
    Mk, Kk = M[np.ix_(kept, kept)], np.diag(lumped.stiffness[kept])
    Dk = np.diag(np.asarray(damping)[kept])
    n = kept.size
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -np.linalg.solve(Mk, Kk)
    A[n:, n:] = -np.linalg.solve(Mk, Dk)
    ev = sla.eigvals(A)
    mag = np.abs(ev)
    keep = (mag > 1e-6 * mag.max()) & (ev.imag > 0)
    ev = ev[keep]
    ev = ev[np.argsort(np.abs(ev))]
    return (-ev.real / np.abs(ev))[:n_modes]


def check_rayleigh(rayleigh) -> float:
    """The beta of a Rayleigh pair ``(alpha, beta)`` a lumped export can carry.

    Raises:
        DampingNotRepresentable: ``alpha != 0``.
        ConfigurationError: Values not finite or negative.
    """
    alpha, beta = (float(v) for v in rayleigh)
    if not (np.isfinite(alpha) and np.isfinite(beta)) or beta < 0.0 or alpha < 0.0:
        raise ConfigurationError(f"Rayleigh coefficients {tuple(rayleigh)} must be finite "
                                 "and >= 0")
    if alpha != 0.0:
        raise DampingNotRepresentable(
            f"Rayleigh damping alpha M (alpha = {alpha:g} 1/s) couples every joint of the "
            "lumped arm and has no MJCF/URDF joint-damping equivalent; use beta only "
            "(exact: d = beta k per joint) or modal damping (--zeta)")
    return beta


def map_damping(lumped: LumpedArm, q, *, zeta: float | None = None,
                rayleigh: tuple[float, float] | None = None, n_modes: int = 2) -> DampingMap:
    """Joint damping for an export (see the module docstring).

    Args:
        lumped: The lumped arm.
        q: Arm pose the modal ratios are set at (user convention).
        zeta: Modal damping ratio of the fitted modes.
        rayleigh: ``(alpha, beta)`` [1/s, s]; alpha must be 0.
        n_modes: Modes whose ratios are set and reported.

    Raises:
        DampingNotRepresentable: ``alpha != 0``.
        ConfigurationError: Both or invalid values.

    Warns:
        LumpedDampingWarning: Modal ratios reached more than 20 % off ``zeta``.
    """
    base = np.array(lumped.damping, dtype=float)
    k = np.asarray(lumped.stiffness)
    n_modes = min(int(n_modes), lumped.n_elastic("own"))
    if zeta is not None and rayleigh is not None:
        raise ConfigurationError("give modal damping (zeta) or Rayleigh damping, not both")
    if rayleigh is not None:
        beta = check_rayleigh(rayleigh)
        d = base + beta * k
        return DampingMap("rayleigh", d, np.full(n_modes, np.nan),
                          modal_ratios(lumped, q, d, n_modes),
                          f"stiffness-proportional: d = {beta:g} s x k on every sprung joint "
                          "(exact)")
    if zeta is None or zeta == 0.0:
        return DampingMap("none", base, np.full(n_modes, np.nan),
                          modal_ratios(lumped, q, base, n_modes),
                          "no damping beyond the arm's own joint damping")
    zeta = float(zeta)
    if not np.isfinite(zeta) or not 0.0 < zeta < 1.0:
        raise ConfigurationError(f"zeta = {zeta!r} must lie in (0, 1)")
    lam, phi = lumped.modes(q, "own")
    lam, phi = lam[:n_modes], phi[:, :n_modes]
    omega = np.sqrt(lam)
    hinges = lumped.hinge_index
    A = (phi[hinges] ** 2).T / (2.0 * omega[:, None])        # zeta_i = A d + arm part
    b = zeta - (phi ** 2).T @ base / (2.0 * omega)
    ref = 2.0 * zeta / omega[0] * k[hinges]
    scale = np.where(ref > 0, ref, 1.0)
    mu = 1e-6
    lhs = np.vstack([A * scale[None, :], mu * np.eye(hinges.size)])
    rhs = np.concatenate([b, mu * np.ones(hinges.size)])
    sol = lsq_linear(lhs, rhs, bounds=(0.0, np.inf), lsmr_tol="auto", method="bvls")
    d = base.copy()
    d[hinges] += sol.x * scale
    achieved = modal_ratios(lumped, q, d, n_modes)
    off = np.flatnonzero(np.abs(achieved / zeta - 1.0) > RATIO_TOLERANCE)
    if off.size:
        warnings.warn(LumpedDampingWarning(
            f"modal damping {zeta:g} mapped to joint damping reaches "
            + ", ".join(f"mode {i + 1}: {achieved[i]:.3g}" for i in off)
            + f" (more than {100 * RATIO_TOLERANCE:g} % off; all modes: "
            f"{np.round(achieved, 4).tolist()}): a diagonal joint damping cannot give every "
            "mode the same ratio; use stiffness-proportional damping (--rayleigh 0 BETA, "
            "exact) or accept these ratios"), stacklevel=2)
    return DampingMap("modal", d, np.full(n_modes, zeta), achieved,
                      f"modal: hinge damping fitted so that the lowest {n_modes} modes have "
                      f"ratio {zeta:g} at the export pose (approximate; achieved ratios "
                      "reported)")
