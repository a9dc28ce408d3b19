"""Dynamic response of a PRBDM chain against its beam's linear FE (paper 001, eq. 5).

Both models are linearized about the straight pose and loaded by a transverse tip force.

* Chain: ``M(θ)`` by Pinocchio's CRBA, the diagonal springs ``K``, the damping of paper 001
  eq. 5, ``C = 2 ξ (M K)^½``, read as ``C = 2 ξ M (M⁻¹K)^½`` with the *principal* square root
  of ``M⁻¹K`` (its eigenvalues are ω_i² > 0, the root has ω_i): ``C = M Φ diag(2ξω) Φᵀ M``
  for the mass-normalised modes Φ, i.e. every mode gets the damping ratio ξ. The time
  response integrates ``θ̈ = ABA(θ, θ̇, −Kθ − Cθ̇ + Jᵀ f(t))`` (Pinocchio's articulated-body
  algorithm, large rotations allowed) with ``solve_ivp`` (DOP853).
* Truth: the beam's converged Hermite FE (:mod:`pinflex.prbdm.truth`), clamped-free, with the
  same damping law (ratio ξ on every mode) and the same tip force; its time response is the
  exact modal superposition.

Accuracy measures (reported side by side): per matched mode the relative error of the
resonance frequency and of the peak receptance magnitude; the largest relative error of
``|H|`` over a log-spaced band from 0.1 f₁ to the last matched mode (dominated by the
anti-resonances and the resonances' shifts); the relative RMS error of the tip displacement
under a step load over ``periods`` periods of mode 1. Paper 001 states "dynamical response
accuracies up to 10 %" without a definition; these are ours.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
import scipy.linalg
from scipy.integrate import solve_ivp

from pinflex.exceptions import ConfigurationError


def modal_damping(M: np.ndarray, K: np.ndarray, xi: float) -> np.ndarray:
    """``2 ξ M (M⁻¹K)^½`` with the principal square root: ratio ξ on every mode."""
    lam, phi = scipy.linalg.eigh(K, M)
    B = M @ phi
    return (B * (2.0 * xi * np.sqrt(np.clip(lam, 0.0, None)))) @ B.T


@dataclass(frozen=True)
class LinearModel:
    """``M, K, C``, tip-force input ``b`` and tip-displacement output ``c`` of a model."""

    M: np.ndarray
    K: np.ndarray
    C: np.ndarray
    b: np.ndarray
    c: np.ndarray


def chain_linear(chain, xi: float) -> LinearModel:
    """The chain linearized at θ = 0 (transverse tip force in, transverse tip motion out)."""
    from pinflex.prbdm.chain import mass_matrix, tip_jacobian

    M = mass_matrix(chain)
    K = chain.stiffness_matrix
    J = tip_jacobian(chain)[1]
    return LinearModel(M, K, modal_damping(M, K, xi), J.copy(), J.copy())


def beam_linear(planform, xi: float, max_element_m: float | None = None) -> LinearModel:
    """The beam's clamped-free Hermite FE (tip w in, tip w out)."""
    from pinflex.prbdm.truth import assemble_beam, beam_mesh

    h = planform.length_m / 40 if max_element_m is None else max_element_m
    K, M = assemble_beam(planform, beam_mesh(planform, h))
    b = np.zeros(K.shape[0])
    b[-2] = 1.0
    return LinearModel(M, K, modal_damping(M, K, xi), b, b.copy())


def receptance(lm: LinearModel, freqs_hz) -> np.ndarray:
    """Tip receptance ``cᵀ (K − ω² M + iω C)⁻¹ b`` [m/N] at each frequency."""
    w = 2.0 * np.pi * np.asarray(freqs_hz, dtype=float)
    return np.array([lm.c @ np.linalg.solve(lm.K - wk**2 * lm.M + 1j * wk * lm.C, lm.b)
                     for wk in w])


def chain_step_response(chain, xi: float, force_n: float, times_s: np.ndarray) -> np.ndarray:
    """Tip transverse displacement [m] of the chain under a step tip force, by Pinocchio ABA.

    Gravity is switched off (on a copy of the chain's model), as in the beam truth.
    """
    from pinflex.prbdm.chain import tip_jacobian, tip_position

    model = pin.Model(chain.model)
    model.gravity = pin.Motion.Zero()  # the beam truth has no gravity either
    data = model.createData()
    M0 = chain_linear(chain, xi)
    C = M0.C
    K = chain.stiffness_matrix
    n = chain.n_joints
    z0 = tip_position(chain, np.zeros(n))[1]

    def rhs(t, y):
        th, om = y[:n], y[n:]
        J = tip_jacobian(chain, th)
        tau = -K @ th - C @ om + J.T @ np.array([0.0, force_n])
        return np.concatenate([om, pin.aba(model, data, th, om, tau)])

    sol = solve_ivp(rhs, (times_s[0], times_s[-1]), np.zeros(2 * n), method="DOP853",
                    t_eval=times_s, rtol=1e-9, atol=1e-12)
    if not sol.success:
        raise ConfigurationError(f"the chain's time response failed: {sol.message}")
    return np.array([tip_position(chain, th, data)[1] - z0 for th in sol.y[:n].T])


def beam_step_response(lm: LinearModel, force_n: float, times_s: np.ndarray) -> np.ndarray:
    """Tip displacement [m] of the linear beam FE under a step force (exact modal sum)."""
    lam, phi = scipy.linalg.eigh(lm.K, lm.M)
    w = np.sqrt(lam)
    zeta = np.diag(phi.T @ lm.C @ phi) / (2.0 * w)
    p = phi.T @ lm.b * force_n
    wd = w * np.sqrt(1.0 - zeta**2)
    t = np.asarray(times_s, dtype=float)[:, None]
    static = p / lam
    eta = static * (1.0 - np.exp(-zeta * w * t) * (np.cos(wd * t) + zeta * w / wd
                                                    * np.sin(wd * t)))
    return eta @ (lm.c @ phi)


def compare(planform, chain, *, xi: float = 0.02, n_modes: int | None = None,
            force_n: float | None = None, periods: float = 5.0, n_freqs: int = 400) -> dict:
    """Frequency and time responses of a chain against its beam (see the module doc)."""
    n = chain.n_joints if n_modes is None else int(n_modes)
    beam = beam_linear(planform, xi)
    ch = chain_linear(chain, xi)
    f_beam = np.sqrt(scipy.linalg.eigh(beam.K, beam.M, eigvals_only=True)[:n]) / (2 * np.pi)
    f_chain = np.sqrt(scipy.linalg.eigh(ch.K, ch.M, eigvals_only=True)[:n]) / (2 * np.pi)
    band = np.geomspace(0.1 * f_beam[0], 1.05 * f_beam[-1], n_freqs)
    Hb, Hc = receptance(beam, band), receptance(ch, band)
    peak_b = np.abs(receptance(beam, f_beam))
    peak_c = np.abs(receptance(ch, f_chain))
    static = float(np.abs(receptance(beam, [0.0])[0]))
    if force_n is None:
        force_n = 0.001 / static  # a 1 mm static tip deflection: linear range
    t = np.linspace(0.0, periods / f_beam[0], 2000)
    zb = beam_step_response(beam, force_n, t)
    zc = chain_step_response(chain, xi, force_n, t)
    return {
        "xi": xi, "modes": n, "truth_hz": f_beam.tolist(), "chain_hz": f_chain.tolist(),
        "freq_error": (f_chain / f_beam - 1.0).tolist(),
        "peak_error": (peak_c / peak_b - 1.0).tolist(),
        "max_abs_H_error_band": float(np.max(np.abs(np.abs(Hc) / np.abs(Hb) - 1.0))),
        "static_error": float(np.abs(receptance(ch, [0.0])[0]) / static - 1.0),
        "step_force_n": float(force_n),
        "step_rms_error": float(np.sqrt(np.mean((zc - zb) ** 2)) / np.sqrt(np.mean(zb**2))),
        "band_hz": [float(band[0]), float(band[-1])],
    }
