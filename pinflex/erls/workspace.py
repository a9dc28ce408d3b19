"""The workspace of a flexible model: everything a computation writes (after Pinocchio's Data).

A :class:`~pinflex.erls.FlexibleModel` is constant once built, like ``pinocchio.Model``. What
a computation writes or caches lives in a :class:`FlexibleData`, like ``pinocchio.Data``: the
Pinocchio ``Data`` of the kinematics passes, the constant blocks of the conditioned solve, the
one-pose row layout and the other per-model tables that are built on first use.

Every method of the model that computes takes ``data=None``: by default each thread uses its
own workspace, created on its first call (``model.workspace()``), so threads that share one
model never share one; a caller may pass its own (``model.create_data()``), as Pinocchio's
algorithms take ``(model, data, q)``.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from pinflex.exceptions import ConfigurationError


class FlexibleData:
    """Per-thread working memory of one :class:`~pinflex.erls.FlexibleModel`.

    Not shared between threads: create one per thread (``model.create_data()``) or let the
    model's methods use the calling thread's own (:meth:`FlexibleModel.workspace`).

    Attributes:
        model: The model this workspace belongs to.
        pin: The Pinocchio ``Data`` of the model's Pinocchio model (kinematics passes write it).
    """

    __slots__ = ("model", "pin", "_cache")

    def __init__(self, model):
        """A fresh workspace of ``model`` (a :class:`~pinflex.erls.FlexibleModel`)."""
        self.model = model
        self.pin = model.model.createData()
        self._cache: dict[str, Any] = {}

    def cached(self, key: str, build: Callable[[], Any]) -> Any:
        """The table ``key`` of this workspace, built by ``build()`` on first use.

        Args:
            key: Name of the table (e.g. ``"solve_plan"``).
            build: Builds it from the model alone (called once per workspace).

        Returns:
            The table (built now or before); None is a valid, cached result.
        """
        cache = self._cache
        if key in cache:
            return cache[key]
        value = build()
        cache[key] = value
        return value

    def __repr__(self) -> str:
        """The model's robot and the tables built so far."""
        return (f"FlexibleData(robot '{self.model.description.name}', "
                f"tables: {', '.join(sorted(self._cache)) or 'none yet'})")


class ThreadWorkspaces:
    """The default workspace of each thread for one model (created on demand)."""

    __slots__ = ("_local",)

    def __init__(self):
        self._local = threading.local()

    def get(self, model) -> FlexibleData:
        """The calling thread's workspace of ``model``, created on its first use."""
        data = getattr(self._local, "data", None)
        if data is None:
            data = FlexibleData(model)
            self._local.data = data
        return data


def check_data(model, data) -> FlexibleData:
    """``data`` checked to be a workspace of ``model``.

    Raises:
        ConfigurationError: ``data`` is not a :class:`FlexibleData` or belongs to another
            model (for instance one made by ``with_values``: create its own).
    """
    if not isinstance(data, FlexibleData):
        raise ConfigurationError(
            f"data= must be a FlexibleData (model.create_data()), got {type(data).__name__}"
        )
    if data.model is not model:
        raise ConfigurationError(
            "this FlexibleData belongs to another model: each model needs its own workspace "
            "(model.create_data(), or leave data= out)"
        )
    return data
