"""Damping of the elastic motion: Rayleigh or modal ratios, one meaning everywhere.

Rayleigh ``(α, β)`` damps the deformation only (the rigid motion is not damped), with the mass
and stiffness of the arm whose motors are held (:func:`pinflex.linalg.held_rayleigh`):
``C_x = α M_H + β K_H`` on the elastic coordinates. Each locked-joint mode ``i`` decays at
``α/2 + β ω_i²/2`` (damping ratio ``α/(2 ω_i) + β ω_i / 2``), in the prescribed drive, the
torque drive, the receptances (:mod:`pinflex.dynamics.frf`) and the exported linear models
(:func:`pinflex.native.export.linear_model`). Modal ratios ``ζ_i`` are those of the
locked-joint modes in the simulations and of the analysed system's elastic modes in the
receptances and exports.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex.exceptions import ConfigurationError


@dataclass(frozen=True)
class Damping:
    """Damping of the elastic motion.

    Attributes:
        kind: ``"none"``, ``"rayleigh"`` (``α M_H + β K_H`` of the deformation, module doc)
            or ``"modal"`` (ratios ζ).
        alpha: Mass-proportional coefficient α [1/s].
        beta: Stiffness-proportional coefficient β [s].
        ratios: Modal damping ratios ζ_i of the lowest locked-joint modes; the last value is
            used for the higher modes.
    """

    kind: str = "none"
    alpha: float = 0.0
    beta: float = 0.0
    ratios: tuple[float, ...] = ()

    def __post_init__(self):
        problems = []
        if self.kind not in ("none", "rayleigh", "modal"):
            problems.append(f"kind = {self.kind!r} must be 'none', 'rayleigh' or 'modal'")
        for name in ("alpha", "beta"):
            v = getattr(self, name)
            if not np.isfinite(v) or v < 0.0:
                problems.append(f"{name} = {v!r} must be a finite number >= 0")
        if self.kind == "modal" and not self.ratios:
            problems.append("modal damping needs at least one ratio")
        for r in self.ratios:
            if not np.isfinite(r) or not 0.0 <= r < 1.0:
                problems.append(f"damping ratio {r!r} must lie in [0, 1)")
        if problems:
            raise ConfigurationError("invalid damping: " + "; ".join(problems))


def check_damping(damping) -> None:
    """Refuse anything but a :class:`Damping` or None (``damping="rayleigh"`` was an
    AttributeError deep in the integrator)."""
    if damping is not None and not isinstance(damping, Damping):
        raise ConfigurationError(
            f"damping must be a pinflex Damping (e.g. Damping('rayleigh', alpha, beta)) or None, "
            f"got {damping!r}")


def modal_damping_matrix(Mr: np.ndarray, Kr: np.ndarray, ratios) -> np.ndarray:
    """``Mr Φ diag(2 ζ_i ω_i) Φᵀ Mr`` for the mass-normalised modes of ``(Kr, Mr)``."""
    import scipy.linalg

    lam, phi = scipy.linalg.eigh(Kr, Mr)
    omega = np.sqrt(np.clip(lam, 0.0, None))
    z = np.asarray(ratios, dtype=float)
    zeta = np.concatenate([z, np.full(max(0, omega.size - z.size), z[-1])])[: omega.size]
    B = Mr @ phi
    return (B * (2.0 * zeta * omega)) @ B.T

