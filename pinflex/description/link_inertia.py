"""What a beam link keeps of its URDF inertia, and rigid bodies with full inertia on links.

A URDF link's ``<inertial>`` is the whole link: structure, motors, gearboxes, flanges. When
``<pinflex:flexible>`` turns the link into a beam, the beam brings its own mass (section ×
material × length); what the URDF has beyond it is kept as a rigid body at its centre of mass
unless told otherwise (``inertia=`` on ``<pinflex:flexible>``):

* ``keep-excess`` (default): the URDF inertia minus the beam's own rigid-body inertia at the
  file's nominal design, both as spatial inertias at the link origin (mass, first moment,
  second moment). The excess is fixed: a design that changes the tube changes the beam, not
  the motors. When the beam is at least as heavy as the URDF link nothing is kept. When the
  excess mass is positive but its rotational inertia is not that of a rigid body (the URDF's
  is smaller than the beam's about some axis), its second-moment tensor
  ``P = tr(I)/2 · 1 − I`` (``Σ m r rᵀ`` about the centre of mass) is projected on the
  positive semidefinite cone (negative principal values set to 0) and ``I = tr(P) · 1 − P``
  rebuilt: the nearest physical inertia with the same mass and centre, and the notice says by
  how much it changed.
* ``keep``: the whole URDF inertia is kept besides the beam (the beam is then extra
  structure).
* ``beam-only``: the URDF inertia is dropped (the pre-2 behaviour; benchmark A's links have
  URDF inertials equal to their rods', so the default keeps nothing there either).

Each choice leaves one line in :attr:`pinflex.description.RobotDescription.inertia_notes`,
which the command line prints.
"""

from __future__ import annotations

import numpy as np

__all__ = ["beam_rigid_inertia", "kept_link_inertia", "physical_inertia", "second_moments"]

#: Relative mass below which an excess counts as none (round-off of equal masses).
MASS_RTOL = 1e-9


def beam_rigid_inertia(tip: np.ndarray, rotation: np.ndarray, rhoA: float, rhoIp: float):
    """``(mass, com, inertia about com in link axes)`` of a uniform beam moving rigidly.

    Equal to ``Jᵀ M J`` of the consistent beam mass (its shape functions hold rigid motions
    exactly): mass ``ρA L`` at ``tip / 2``, ``ρIp L`` about the beam axis and ``ρA L³ / 12``
    about the two transverse axes.
    """
    L = float(np.linalg.norm(tip))
    I_beam = np.diag([rhoIp * L, rhoA * L**3 / 12.0, rhoA * L**3 / 12.0])
    return rhoA * L, np.asarray(tip, dtype=float) / 2.0, rotation @ I_beam @ rotation.T


def _about_origin(m: float, c: np.ndarray, I_c: np.ndarray) -> np.ndarray:
    return I_c + m * (float(c @ c) * np.eye(3) - np.outer(c, c))


def second_moments(I: np.ndarray) -> np.ndarray:
    """``P = Σ m r rᵀ`` of a rotational inertia ``I`` about the centre of mass."""
    return 0.5 * np.trace(I) * np.eye(3) - I


def physical_inertia(I: np.ndarray) -> tuple[np.ndarray, float]:
    """The nearest rigid-body inertia (second moments clipped at 0) and the change's norm."""
    P = second_moments(0.5 * (I + I.T))
    w, V = np.linalg.eigh(P)
    if w.min() >= -1e-12 * max(abs(w).max(), 1e-300):
        return I, 0.0
    P2 = (V * np.maximum(w, 0.0)) @ V.T
    I2 = np.trace(P2) * np.eye(3) - P2
    return I2, float(np.linalg.norm(I2 - I, 2))


def kept_link_inertia(link: str, option: str, urdf, tip, rotation, rhoA: float, rhoIp: float):
    """What a beam link keeps of its URDF inertia.

    Args:
        link: Link name.
        option: ``'keep-excess'``, ``'keep'`` or ``'beam-only'``.
        urdf: The link's URDF inertial (:class:`~pinflex.description.types.RigidInertia`) or
            None.
        tip, rotation: The beam's end [m] and axes in the link frame.
        rhoA, rhoIp: The beam's mass per length [kg/m] and rotary inertia per length [kg m]
            at the file's nominal design.

    Returns:
        ``(body, note)``: ``(mass [kg], com (3,) [m], inertia about com (3, 3) [kg m²])`` or
        None, and one line saying what was kept or dropped.
    """
    m_b, c_b, I_b = beam_rigid_inertia(tip, rotation, rhoA, rhoIp)
    if urdf is None or urdf.mass <= 0.0:
        return None, f"{link}: no URDF inertia to keep; the beam alone ({m_b:.4g} kg)"
    m_u, c_u, I_u = float(urdf.mass), np.asarray(urdf.com, float), np.asarray(urdf.inertia, float)
    if option == "beam-only":
        return None, (f"{link}: URDF inertia ({m_u:.4g} kg) dropped (inertia=\"beam-only\"); "
                      f"the beam alone ({m_b:.4g} kg)")
    if option == "keep":
        return (m_u, c_u, I_u), (f"{link}: URDF inertia ({m_u:.4g} kg at "
                                 f"{_fmt(c_u)} m) kept besides the beam ({m_b:.4g} kg)")
    m_e = m_u - m_b
    if m_e <= MASS_RTOL * max(m_u, m_b):
        return None, (f"{link}: nothing kept, the beam ({m_b:.4g} kg) accounts for the URDF "
                      f"link's {m_u:.4g} kg" + (" and more" if m_e < 0 else ""))
    c_e = (m_u * c_u - m_b * c_b) / m_e
    I_eO = _about_origin(m_u, c_u, I_u) - _about_origin(m_b, c_b, I_b)
    I_e = I_eO - m_e * (float(c_e @ c_e) * np.eye(3) - np.outer(c_e, c_e))
    I_e = 0.5 * (I_e + I_e.T)
    I_p, change = physical_inertia(I_e)
    note = (f"{link}: kept {m_e:.4g} kg of the URDF link's {m_u:.4g} kg (motors, flanges) at "
            f"{_fmt(c_e)} m besides the beam ({m_b:.4g} kg)")
    if change > 0.0:
        note += (f"; its rotational inertia (URDF minus beam) was not a rigid body's and was "
                 f"projected to the nearest one (changed by {change:.3g} kg m^2)")
    return (m_e, c_e, I_p), note


def _fmt(v) -> str:
    return "(" + ", ".join(f"{x:.4g}" for x in np.ravel(v)) + ")"
