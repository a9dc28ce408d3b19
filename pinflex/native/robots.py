"""Flexible models from Pinocchio models in memory and from example-robot-data arms."""

from __future__ import annotations

import inspect
import xml.etree.ElementTree as ET
from pathlib import Path

from pinflex.description import NAMESPACE, apply_overlay, parse, robot_data_dir
from pinflex.exceptions import ConfigurationError, InvalidDescription, LinkNotFound
from pinflex.native.spec import Beam, Mass, annotation_elements

#: Fixed-base arms of example-robot-data by short name: path of the URDF under ``robots/``.
EXAMPLE_ROBOTS: dict[str, str] = {
    "ur3": "ur_description/urdf/ur3_robot.urdf",
    "ur3_limited": "ur_description/urdf/ur3_joint_limited_robot.urdf",
    "ur5": "ur_description/urdf/ur5_robot.urdf",
    "ur5_limited": "ur_description/urdf/ur5_joint_limited_robot.urdf",
    "ur10": "ur_description/urdf/ur10_robot.urdf",
    "ur10_limited": "ur_description/urdf/ur10_joint_limited_robot.urdf",
    "panda": "panda_description/urdf/panda.urdf",
    "kinova": "kinova_description/robots/kinova.urdf",
    "double_pendulum": "double_pendulum_description/urdf/double_pendulum.urdf",
    "double_pendulum_continuous": (
        "double_pendulum_description/urdf/double_pendulum_continuous.urdf"
    ),
}


def _overlay(elements: list[ET.Element], name: str | None) -> ET.Element:
    ET.register_namespace("pinflex", NAMESPACE)
    root = ET.Element("{" + NAMESPACE + "}overlay")
    if name:
        root.set("name", name)
    root.extend(elements)
    return root


def _model_kwargs(joints, kwargs: dict) -> dict:
    """FlexibleModel keyword arguments, with ``joints`` passed on when the model takes it."""
    from pinflex.erls import FlexibleModel

    out = dict(kwargs)
    if joints is None:
        return out
    if "joints" in inspect.signature(FlexibleModel.__init__).parameters:
        out["joints"] = joints
        return out
    if joints != "free":
        raise ConfigurationError(
            f"joints={joints!r}: this version of pinflex models every joint as free "
            "(no joint stiffness); use joints='free' or None"
        )
    return out


def _resolve_keys(desc_xml: str, flexible, masses) -> tuple[dict, dict]:
    """Accept joint names for flexible links (the link a joint carries); check link names."""
    probe = parse(desc_xml)
    flex = {}
    for key, spec in (flexible or {}).items():
        link = key
        if key not in probe.links and key in probe.joints:
            link = probe.joints[key].child
        if link not in probe.links:
            raise LinkNotFound(key, probe.links)
        flex[link] = spec
    for name, spec in (masses or {}).items():
        if isinstance(spec, Mass) and spec.link not in probe.links:
            raise LinkNotFound(spec.link, probe.links)
    return flex, dict(masses or {})


def model_from_urdf_text(
    urdf_xml: str,
    *,
    base_dir: Path | None,
    flexible: dict[str, Beam] | None,
    masses: dict[str, Mass] | None,
    joints=None,
    name: str | None = None,
    coordinates: str | None = None,
    **kwargs,
):
    """FlexibleModel of URDF text plus Python specifications (the overlay route in memory)."""
    from pinflex.erls import FlexibleModel

    flex, mass = _resolve_keys(urdf_xml, flexible, masses)
    overlay = _overlay(annotation_elements(flex, mass), name)
    desc = parse(apply_overlay(urdf_xml, overlay), base_dir=base_dir)
    return FlexibleModel(desc, coordinates=coordinates, **_model_kwargs(joints, kwargs))


def from_pinocchio(
    model_or_robot,
    flexible: dict[str, Beam] | None = None,
    masses: dict[str, Mass] | None = None,
    joints=None,
    **kwargs,
):
    """A :class:`~pinflex.FlexibleModel` of a Pinocchio model or ``RobotWrapper`` in memory.

    See :meth:`pinflex.FlexibleModel.from_pinocchio`.
    """
    import pinocchio as pin

    from pinflex.native.urdf import urdf_from_model

    model = getattr(model_or_robot, "model", model_or_robot)
    if not isinstance(model, pin.Model):
        raise ConfigurationError(
            "from_pinocchio expects a pinocchio.Model or a pinocchio RobotWrapper, got "
            f"{type(model_or_robot).__name__}"
        )
    text = urdf_from_model(model)
    return model_from_urdf_text(
        text, base_dir=None, flexible=flexible, masses=masses, joints=joints, **kwargs
    )


def example_robot_urdf(name: str) -> Path:
    """Path of the URDF of an example-robot-data arm (see :data:`EXAMPLE_ROBOTS`)."""
    if name in EXAMPLE_ROBOTS:
        rel = EXAMPLE_ROBOTS[name]
    elif name.endswith(".urdf"):
        rel = name
    else:
        raise InvalidDescription(
            f"unknown example robot '{name}'; known: {', '.join(sorted(EXAMPLE_ROBOTS))}, or a "
            "path ending in .urdf inside example-robot-data's robots/ folder"
        )
    path = robot_data_dir() / rel
    if not path.is_file():
        raise InvalidDescription(
            f"example robot '{name}': '{rel}' is not in the installed example-robot-data"
        )
    return path


def example_robot(
    name: str,
    flexible: dict[str, Beam] | None = None,
    masses: dict[str, Mass] | None = None,
    joints=None,
    **kwargs,
):
    """A flexible model of an example-robot-data arm, without writing an overlay file.

    The result is the model that an overlay file with
    ``base="example-robot-data:<EXAMPLE_ROBOTS[name]>"`` and the same annotations gives.

    Args:
        name: Short name (``"ur10"``, ``"ur5"``, ``"panda"``, ``"kinova"``, ... see
            :data:`EXAMPLE_ROBOTS`) or a ``.urdf`` path inside example-robot-data's
            ``robots/`` folder.
        flexible: Flexible links ``{link or joint name: Beam}``; a joint name stands for the
            link it carries.
        masses: Point masses ``{name: Mass}``.
        joints: Joint conditions of the modal model, as for :class:`~pinflex.FlexibleModel`
            (``"free"``, ``"locked"``, ``"annotated"`` or ``{joint: "free" | "locked" |
            stiffness}``); default free.
        **kwargs: Passed to :class:`~pinflex.FlexibleModel` (``planar``, ``values``,
            ``coordinates``).

    Returns:
        A :class:`~pinflex.FlexibleModel`.

    Raises:
        InvalidDescription: Unknown robot, example-robot-data missing, bad specification.
        LinkNotFound: A flexible link or a mass's link is not in the URDF.
    """
    path = example_robot_urdf(name)
    return model_from_urdf_text(
        path.read_text(),
        base_dir=path.parent,
        flexible=flexible,
        masses=masses,
        joints=joints,
        name=None,
        **kwargs,
    )
