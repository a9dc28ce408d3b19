"""Where ``terms="full"`` holds, and a named refusal or warning where it does not.

The speed terms of :mod:`pinflex.dynamics.speed` (centrifugal and Euler terms of the elastic
displacement, geometric stiffness of the beams' axial force) are complete for loads carried
along the beams by joints on rigid parents: a flexible link on a hub (the spin-up beam, the
rotating cantilever, a standing column), or flexible links after rigid ones. Two second-order
effects of the loads are not in them yet:

* **Joints on a deforming parent.** ERLS turns a joint's subtree about the joint's undeformed
  point, while the subtree's elastic coordinates carry the joint point's elastic translation
  ``t``; a real joint turns about its displaced point. The loads the joint carries then do the
  work ``δθ (P × a) · t`` and, with the motors holding the joint on the parent's elastic
  rotation (``δθ = A x``), the rigid loads' dependence on the joint angle enters the stiffness
  too. Without these terms a beam split into two links at a locked joint, spinning, is not the
  one beam it is: its chordwise mode 1 was 21 % above Hamza-Cherif and Houmat's table at
  γ = 4 and 79 % above at γ = 10, where the one-link beam is within the table's last digit.
  :func:`check_full_terms` refuses such a state with a :class:`~pinflex.exceptions.
  ConfigurationError` naming the joint.
* **Loads off the beam axes** (point masses and bodies beside a beam, rigid links carried by
  a beam): the second-order rise of a rigid lever under its load. :func:`check_full_terms`
  warns with :class:`~pinflex.exceptions.ModelValidityWarning` naming the links; the lever
  term is of relative size ``offset / length`` of the speed terms there.

At rest without gravity there are no loads and nothing is refused.
"""

from __future__ import annotations

import warnings
import weakref

import numpy as np

from pinflex.exceptions import ConfigurationError, ModelValidityWarning

_CHECKED: weakref.WeakSet = weakref.WeakSet()  # dynamics whose levers were looked at


def joints_on_deforming_parents(dyn, q) -> list[tuple[str, str]]:
    """``[(joint, parent link)]``: moving joints whose point moves with the parent's deformation.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics`.
        q: Joint coordinates (nv,) [rad or m] (user convention).
    """
    e, _ = dyn._root_twists(np.asarray(q, dtype=float))
    out = []
    for j in dyn.model.plan.joints:
        if j.user_col < 0 or j.kind not in ("revolute", "prismatic"):
            continue
        att = j.attach
        if att.const is not None or (att.lin is not None and e.get(j.parent) is not None):
            out.append((j.name, j.parent))
    return out


def levers(dyn) -> list[str]:
    """Links carrying mass off a beam axis that moves elastically (module doc)."""
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
        bp = plan.beams.get(p.link)
        if bp is not None:
            ex = bp.spec.tip / bp.spec.length_m
            c = c - np.clip(c @ ex, 0.0, bp.spec.length_m)[:, None] * ex[None, :]
        if np.any((np.abs(m) > 0.0) & (np.linalg.norm(c, axis=1) > 1e-9)):
            out.append(p.link)
    return out


def check_full_terms(dyn, q, qd, qdd) -> None:
    """Refuse (or warn about) a state whose loads ``terms="full"`` does not complete.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics` (its gravity counts as a load).
        q: Joint coordinates (nv,) [rad or m].
        qd: Joint velocities (nv,).
        qdd: Joint accelerations (nv,).

    Raises:
        ConfigurationError: A moving joint sits on a deforming parent and the state carries
            loads (module doc).
    """
    if not (np.any(qd) or np.any(qdd) or np.any(dyn.gravity)):
        return
    bad = joints_on_deforming_parents(dyn, q)
    if bad:
        names = ", ".join(f"'{j}' on '{p}'" for j, p in bad)
        raise ConfigurationError(
            f"terms='full' is not complete for joints on a deforming link ({names}): the loads "
            "such a joint carries couple to its elastic offset through terms pinflex does not "
            "have yet (a beam split at a locked joint and spun was 79 % off the published "
            "rotating-cantilever frequency). Use terms='eq1' (the validity indicator says how "
            "far it holds), or a model whose moving joints sit on rigid links "
            "(pinflex.dynamics.speed_scope)")
    if dyn not in _CHECKED:
        _CHECKED.add(dyn)
        off = levers(dyn)
        if off:
            warnings.warn(
                f"terms='full' leaves out the lever terms of the mass off the beam axes on "
                f"{', '.join(sorted(set(off)))} (a load at an offset r rises by "
                "θ×(θ×r)/2 as the section turns): of relative size offset/length of the "
                "speed terms (pinflex.dynamics.speed_scope)", ModelValidityWarning,
                stacklevel=3)
