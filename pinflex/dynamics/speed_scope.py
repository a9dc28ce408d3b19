"""Where ``terms="full"`` holds, and a named warning where it does not.

The speed terms of :mod:`pinflex.dynamics.speed` are the second variation of the locked
system about the moving state: centrifugal and Euler terms of the elastic displacement,
geometric stiffness of the beams' axial force, and, for joints on deforming links, the turn of
the joint's subtree by its elastic offset and the joint turning about its displaced point
(:func:`pinflex.dynamics.speed.locked_speed_stiffness`). A beam split into links at held
joints is the one beam it is, spinning, to 1e-12 (``tests/test_speed_joints.py``).

Left out, as in the beams' ``K_G``: bending-moment and torsion prestress. A beam split at a joint
and loaded across its axis (an angular acceleration, gravity across the beam) differs from the
one beam at second order in that load (2e-7 relative at 2 rad/s² on Kane's beam): both leave
those terms out, in different places.

**Loads off the beam axes**: a load at an offset ``r`` from the section it rides on rises by
``θ × (θ × r) / 2`` as the section turns by ``θ``. For point masses this lever term is in the
full terms (:func:`pinflex.dynamics.speed.point_mass_levers`; an off-axis tip mass on a
spinning beam equals a rotating-frame FE with a rigid lever to 1e-9). For bodies beside a beam
and rigid links carried by a beam it is not: :func:`check_full_terms` warns with
:class:`~pinflex.exceptions.ModelValidityWarning` naming the links; the lever term is of
relative size ``offset / length`` of the speed terms there.
"""

from __future__ import annotations

import warnings
import weakref

import numpy as np

from pinflex.exceptions import ModelValidityWarning

_CHECKED: weakref.WeakSet = weakref.WeakSet()  # dynamics whose levers were looked at


def levers(dyn) -> list[str]:
    """Links carrying mass off a beam axis that moves elastically, other than point masses
    (their lever term is in :func:`pinflex.dynamics.speed.point_mass_levers`; module doc)."""
    plan = dyn.model.plan
    moving = set(plan.beams)
    for j in plan.joints:  # parents first
        if j.parent in moving:
            moving.add(j.child)
    out = []
    for p in dyn._points:
        if p.link not in moving:
            continue
        c = p.c[p.n_beam:]
        m = p.mass[p.n_beam:]
        pms = [np.asarray(pm.xyz, dtype=float) for pm in plan.point_masses if pm.link == p.link]
        if pms:  # the point masses' own carriers
            own = np.any(np.all(np.abs(c[:, None, :] - np.array(pms)[None]) <= 1e-15, axis=2),
                         axis=1)
            c, m = c[~own], m[~own]
        bp = plan.beams.get(p.link)
        if bp is not None:
            ex = bp.spec.tip / bp.spec.length_m
            c = c - np.clip(c @ ex, 0.0, bp.spec.length_m)[:, None] * ex[None, :]
        if np.any((np.abs(m) > 0.0) & (np.linalg.norm(c, axis=1) > 1e-9)):
            out.append(p.link)
    return out


def check_full_terms(dyn, q, qd, qdd) -> None:
    """Warn (once per dynamics) about loads off the beam axes ``terms="full"`` leaves out.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics` (its gravity counts as a load).
        q: Joint coordinates (nv,) [rad or m].
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).
    """
    if not (np.any(qd) or np.any(qdd) or np.any(dyn.gravity)):
        return
    if dyn not in _CHECKED:
        _CHECKED.add(dyn)
        off = levers(dyn)
        if off:
            warnings.warn(
                f"terms='full' leaves out the lever terms of the bodies and rigid links off the beam axes on "
                f"{', '.join(sorted(set(off)))} (a load at an offset r rises by "
                "θ×(θ×r)/2 as the section turns): of relative size offset/length of the "
                "speed terms (pinflex.dynamics.speed_scope)", ModelValidityWarning,
                stacklevel=3)
