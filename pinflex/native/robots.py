"""Descriptions of arms held in memory: Pinocchio models, example-robot-data, Python specs.

Each function returns a :class:`~pinflex.description.RobotDescription`; the models are built
from them by :meth:`pinflex.FlexibleModel.from_pinocchio` and :func:`pinflex.example_robot`.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from pathlib import Path

from pinflex.description import NAMESPACE, RobotDescription, apply_overlay, parse, robot_data_dir
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


def description_from_urdf_text(
    urdf_xml: str,
    *,
    base_dir: Path | None,
    flexible: dict[str, Beam] | None,
    masses: dict[str, Mass] | None,
    name: str | None = None,
) -> RobotDescription:
    """Description of URDF text plus Python specifications (the overlay route in memory).

    Args:
        urdf_xml: URDF text.
        base_dir: Folder for relative mesh paths, or None.
        flexible: ``{link or joint name: Beam}``; a joint name stands for the link it carries.
        masses: ``{name: Mass}`` point masses.
        name: Robot name of the overlay (default: the URDF's).
    """
    flex, mass = _resolve_keys(urdf_xml, flexible, masses)
    overlay = _overlay(annotation_elements(flex, mass), name)
    return parse(apply_overlay(urdf_xml, overlay), base_dir=base_dir)


def describe_pinocchio(
    model_or_robot,
    flexible: dict[str, Beam] | None = None,
    masses: dict[str, Mass] | None = None,
) -> RobotDescription:
    """Description of a Pinocchio model or ``RobotWrapper`` in memory plus Python specifications.

    The model's tree and inertias are written out as URDF (:func:`urdf_from_model`) and
    annotated from the specifications (see :meth:`pinflex.FlexibleModel.from_pinocchio`).

    Raises:
        ConfigurationError: Not a ``pinocchio.Model`` nor a ``RobotWrapper``.
    """
    import pinocchio as pin

    from pinflex.native.urdf import urdf_from_model

    model = getattr(model_or_robot, "model", model_or_robot)
    if not isinstance(model, pin.Model):
        raise ConfigurationError(
            "from_pinocchio expects a pinocchio.Model or a pinocchio RobotWrapper, got "
            f"{type(model_or_robot).__name__}"
        )
    return description_from_urdf_text(urdf_from_model(model), base_dir=None, flexible=flexible,
                                      masses=masses)


def example_robot_urdf(name: str) -> Path:
    """Path of the URDF of an example-robot-data arm (see :data:`EXAMPLE_ROBOTS`)."""
    if not isinstance(name, str):
        raise InvalidDescription(f"an example robot is named by a string, got {name!r}")
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


def describe_example_robot(
    name: str,
    flexible: dict[str, Beam] | None = None,
    masses: dict[str, Mass] | None = None,
) -> RobotDescription:
    """Description of an example-robot-data arm plus Python specifications.

    The description an overlay file with ``base="example-robot-data:<EXAMPLE_ROBOTS[name]>"``
    and the same annotations gives (see :func:`pinflex.example_robot`).

    Raises:
        InvalidDescription: Unknown robot, example-robot-data missing, bad specification.
        LinkNotFound: A flexible link or a mass's link is not in the URDF.
    """
    path = example_robot_urdf(name)
    return description_from_urdf_text(path.read_text(), base_dir=path.parent,
                                      flexible=flexible, masses=masses, name=None)
