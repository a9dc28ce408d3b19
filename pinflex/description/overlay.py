"""Overlay files: an upstream URDF used unchanged, plus pinflex annotations."""

from __future__ import annotations

import functools
import xml.etree.ElementTree as ET
from pathlib import Path

from pinflex.description.types import NAMESPACE
from pinflex.exceptions import InvalidDescription

ROBOT_DATA_PREFIX = "example-robot-data:"


@functools.lru_cache(maxsize=1)
def robot_data_dir() -> Path:
    """The ``robots/`` folder of the installed example-robot-data package."""
    import importlib.util

    spec = importlib.util.find_spec("cmeel")
    candidates = []
    if spec is not None and spec.submodule_search_locations:
        for loc in spec.submodule_search_locations:
            candidates.append(Path(loc).parent / "cmeel.prefix" / "share" / "example-robot-data")
    import sys

    for entry in sys.path:
        candidates.append(Path(entry) / "cmeel.prefix" / "share" / "example-robot-data")
    for cand in candidates:
        if (cand / "robots").is_dir():
            return cand / "robots"
    raise InvalidDescription(
        "the example-robot-data package is not installed: `pip install example-robot-data`"
    )


def resolve_base(base: str, folder: Path, *, allow_paths: bool = False) -> Path:
    """Path of an overlay's base URDF: ``example-robot-data:<path in robots/>`` or a file.

    The file must lie inside the overlay's folder (relative paths, no ``..`` out of it, no
    absolute path elsewhere), or inside example-robot-data's ``robots/`` folder for the
    prefixed form, unless ``allow_paths``.

    Args:
        base: The overlay's ``base`` attribute: ``example-robot-data:<path>`` or a file path,
            relative paths taken from ``folder``.
        folder: Folder of the overlay file.
        allow_paths: Accept a base anywhere.

    Returns:
        The resolved path of an existing file.

    Raises:
        InvalidDescription: ``base`` is empty, the file does not exist, or
            example-robot-data is needed and not installed.
        UnsafePath: The base lies outside those folders.
    """
    from pinflex.description.source import confine

    if not base:
        raise InvalidDescription("<pinflex:overlay> needs a base=\"...\" URDF")
    if base.startswith(ROBOT_DATA_PREFIX):
        root = robot_data_dir()
        path = confine(root / base[len(ROBOT_DATA_PREFIX):], [root], "the overlay's base URDF",
                       allow=allow_paths)
    else:
        if base.startswith("file://"):
            base = base[len("file://"):]
        path = confine(folder / base, [folder], "the overlay's base URDF", allow=allow_paths)
    try:
        found = path.is_file()
    except OSError as exc:
        raise InvalidDescription(f"the overlay's base URDF cannot be read: {exc.strerror}"
                                 ) from None
    if not found:
        raise InvalidDescription(f"the overlay's base URDF '{base}' was not found at '{path}'")
    return path


def apply_overlay(base_xml: str, overlay: ET.Element) -> str:
    """Append an overlay's pinflex elements to a base URDF, leaving the base untouched.

    An overlay file reads::

        <pinflex:overlay xmlns:pinflex="urn:pinflex:urdf:1"
                         base="example-robot-data:ur_description/urdf/ur5_robot.urdf">
          <pinflex:flexible link="upper_arm_link" ...> ... </pinflex:flexible>
        </pinflex:overlay>

    The returned text is the base URDF with the annotations as extra children of ``<robot>``
    (what an annotated URDF would contain), so Pinocchio still parses it.

    Args:
        base_xml: Text of the base URDF.
        overlay: The parsed ``<pinflex:overlay>`` element; its children are moved to the
            base and its ``name`` attribute, if any, renames the robot.

    Returns:
        The annotated URDF text.

    Raises:
        InvalidDescription: ``base_xml`` is not well-formed XML.
    """
    ET.register_namespace("pinflex", NAMESPACE)
    try:
        root_el = ET.fromstring(base_xml)
    except ET.ParseError as exc:
        raise InvalidDescription(f"the overlay's base URDF is not well-formed XML: {exc}") from exc
    for child in overlay:
        root_el.append(child)
    name = overlay.get("name")
    if name:
        root_el.set("name", name)
    return ET.tostring(root_el, encoding="unicode")
