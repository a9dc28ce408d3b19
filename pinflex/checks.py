"""Checks of the inputs of a flexible model's computations: poses, designs, mode counts.

Free functions of the model, as Pinocchio's algorithms are free functions of its ``Model``:
``check_q(model, q)``, ``check_y(model, y)``, ``check_n_modes(model, n_modes)``. Every
computing method of :class:`~pinflex.erls.model.FlexibleModel` runs them on its arguments;
other layers call them before they work on raw arrays. They read only the model's public
attributes, so the layers below the model (paths, exports) check with them too.
"""

from __future__ import annotations

import numpy as np

from pinflex.description import NAMESPACE
from pinflex.exceptions import (
    ConfigurationError,
    DesignVariableNotFound,
    DesignVariableOutOfBounds,
    NoFlexibleLink,
)
from pinflex.validation import require_array, require_count


def check_q(model, q) -> np.ndarray:
    """Validate joint coordinates and return them as user coordinates (nv,) or (n, nv).

    Accepts one value per moving joint (length ``nv``, the user convention) or a Pinocchio
    configuration vector (length ``nq``, which differs from ``nv`` when the arm has
    continuous joints, stored as ``(cos θ, sin θ)``); see
    :meth:`~pinflex.erls.model.FlexibleModel.from_configuration`.

    Args:
        model: The flexible model.
        q: One pose (nv,) or many (n, nv) in the user convention [rad or m], or Pinocchio
            configurations (nq,) or (n, nq) when ``nq != nv``.

    Returns:
        Float array (nv,) or (n, nv) of user coordinates [rad or m].

    Raises:
        ConfigurationError: Not numbers, non-finite values, or a wrong shape.
    """
    q = require_array(q, "joint values q")
    nq, nv = model.model.nq, model.nv
    if q.ndim in (1, 2) and q.shape[-1] == nq != nv:
        return model.from_configuration(q)
    if q.shape[-1:] != (nv,) or q.ndim not in (1, 2):
        extra = f" or a Pinocchio configuration of {nq}" if nq != nv else ""
        raise ConfigurationError(
            f"expected {nv} joint values ({', '.join(model.joint_names)}){extra} per "
            f"pose, got an array of shape {q.shape}"
        )
    return q  # finite: require_array checked it


def check_y(model, y, *, bounds: bool = True) -> np.ndarray:
    """Validate design values (ny,) or per-pose (n, ny); ``None`` gives the nominal ones.

    Args:
        model: The flexible model.
        y: Design values [kg] (ny,) or (n, ny), a ``{name: value}`` dict (missing names
            take their nominal values), or ``None`` for ``model.y0``.
        bounds: Check every value against its design bounds (tolerance 1e-12).

    Returns:
        Float array (ny,) or (n, ny) [kg].

    Raises:
        DesignVariableNotFound: A dict key is not a design variable.
        ConfigurationError: Not numbers, non-finite values, or a wrong shape.
        DesignVariableOutOfBounds: ``bounds`` is set and a value leaves its bounds.
    """
    if y is None:
        return model.y0
    if isinstance(y, dict):
        unknown = set(y) - set(model.design_names)
        if unknown:
            raise DesignVariableNotFound(sorted(unknown)[0], model.design_names)
        y = [y.get(d.name, d.nominal) for d in model.design]
    y = require_array(y, "design values y")
    if y.shape[-1:] != (model.ny,) or y.ndim not in (1, 2):
        raise ConfigurationError(
            f"expected {model.ny} design values ({', '.join(model.design_names)}), "
            f"got shape {y.shape}"
        )
    if not np.all(np.isfinite(y)):
        raise ConfigurationError("design values must be finite")
    if bounds:
        for d, v in zip(model.design, np.atleast_2d(y).T):
            bad = (v < d.lower - 1e-12) | (v > d.upper + 1e-12)
            if np.any(bad):
                raise DesignVariableOutOfBounds(d.name, float(v[bad][0]), d.lower, d.upper)
    return y


def check_n_modes(model, n_modes):
    """``n_modes`` checked: None, or an int >= 1 (capped at the number of modes).

    Args:
        model: The flexible model.
        n_modes: Requested number of lowest modes, or None for all.

    Returns:
        None, or ``min(n_modes, model.n_elastic)``.

    Raises:
        NoFlexibleLink: The model has no non-rigid mode (no beam and no joint spring).
        ConfigurationError: ``n_modes`` is not an integer >= 1 (0, -1, 2.5, True, "3").
    """
    if model.n_elastic == 0:
        raise NoFlexibleLink(
            f"robot '{model.description.name}' has no flexible link (nor joint spring), so "
            "no elastic modes: "
            f"declare one with <pinflex:flexible link=... elements=...> in the namespace "
            f"{NAMESPACE} (links: {', '.join(model.description.links)})"
        )
    if n_modes is None:
        return None
    n = require_count(n_modes, "n_modes", minimum=1)
    return min(n, model.n_elastic)
