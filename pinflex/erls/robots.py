"""Flexible models of example-robot-data arms, annotated from Python specifications."""

from __future__ import annotations

from pinflex.erls.model import FlexibleModel
from pinflex.native.robots import describe_example_robot
from pinflex.native.spec import Beam, Mass


def example_robot(
    name: str,
    flexible: dict[str, Beam] | None = None,
    masses: dict[str, Mass] | None = None,
    joints=None,
    **kwargs,
) -> FlexibleModel:
    """A flexible model of an example-robot-data arm, without writing an overlay file.

    The result is the model that an overlay file with
    ``base="example-robot-data:<EXAMPLE_ROBOTS[name]>"`` and the same annotations gives.

    Args:
        name: Short name (``"ur10"``, ``"ur5"``, ``"panda"``, ``"kinova"``, ... see
            :data:`pinflex.native.robots.EXAMPLE_ROBOTS`) or a ``.urdf`` path inside
            example-robot-data's ``robots/`` folder.
        flexible: Flexible links ``{link or joint name: Beam}``; a joint name stands for the
            link it carries.
        masses: Point masses ``{name: Mass}``.
        joints: Joint conditions of the modal model, as for :class:`~pinflex.FlexibleModel`
            (``"free"``, ``"locked"``, ``"annotated"`` or ``{joint: "free" | "locked" |
            stiffness}``); Python specifications carry no joint annotations, so by default
            every joint is free.
        **kwargs: Passed to :class:`~pinflex.FlexibleModel` (``planar``, ``values``,
            ``coordinates``).

    Returns:
        A :class:`~pinflex.FlexibleModel`.

    Raises:
        InvalidDescription: Unknown robot, example-robot-data missing, bad specification.
        LinkNotFound: A flexible link or a mass's link is not in the URDF.
    """
    return FlexibleModel(describe_example_robot(name, flexible, masses), joints=joints, **kwargs)
