"""Pinocchio reads the same URDF numbers as pinflex: a check after Pinocchio parses a file.

pinflex reads every number of a URDF with its own grammar (:mod:`pinflex.validation`) and
Pinocchio reads the same text with urdfdom's. Where the two could disagree (a value urdfdom
cannot parse is logged to stderr and the element skipped: an inertial becomes a massless
link), the model would be silently wrong. :func:`check_pinocchio_reading` compares what
Pinocchio built with what pinflex read, at the neutral pose: every link's placement, every
moving joint's axis and limits, and the inertia each joint carries (the URDF inertials of the
links it moves through fixed joints). :func:`native_stderr` keeps urdfdom's messages off the
terminal (a refusal is one line) and hands them to the error instead.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator

import numpy as np

from pinflex.exceptions import InvalidDescription


@contextlib.contextmanager
def native_stderr() -> Iterator[list[str]]:
    """Capture what native code (urdfdom, Pinocchio) writes to file descriptor 2.

    Yields a list that holds the captured lines when the block ends.
    """
    lines: list[str] = []
    try:
        saved = os.dup(2)
    except OSError:  # no stderr to redirect
        yield lines
        return
    with tempfile.TemporaryFile() as tmp:
        try:
            os.dup2(tmp.fileno(), 2)
            yield lines
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            tmp.seek(0)
            text = tmp.read(65536).decode("utf-8", "replace")
            lines.extend(line.strip() for line in text.splitlines() if line.strip())


def urdfdom_message(lines: list[str]) -> str:
    """The first error line urdfdom printed, without its source location."""
    for line in lines:
        if line.startswith("at line") or " at line " in line and line.startswith("at"):
            continue
        return line.removeprefix("Error:").strip()
    return ""


def check_pinocchio_reading(description, model, native: list[str] | None = None) -> None:
    """Compare Pinocchio's model of a URDF with pinflex's reading of the same file.

    Args:
        description: The :class:`~pinflex.description.RobotDescription`.
        model: The ``pinocchio.Model`` built from ``description.urdf_xml``.
        native: What urdfdom printed while parsing (from :func:`native_stderr`).

    Raises:
        InvalidDescription: A link placement, joint axis, joint limit or joint inertia
            differs (relative 1e-9), naming it and what urdfdom reported.
    """
    import pinocchio as pin

    desc = description
    problems: list[str] = []
    # pinflex's neutral placements of every link (world frame), from the joint origins
    world: dict[str, pin.SE3] = {desc.root: pin.SE3.Identity()}
    order = [desc.root]
    for link in order:
        for jname in desc.child_joints.get(link, ()):
            j = desc.joints[jname]
            world[j.child] = world[link] * pin.SE3(np.asarray(j.rotation), np.asarray(j.xyz))
            order.append(j.child)
    data = model.createData()
    q0 = pin.neutral(model)
    pin.forwardKinematics(model, data, q0)
    pin.updateFramePlacements(model, data)
    scale = max([1.0] + [float(np.abs(p.translation).max()) for p in world.values()])
    for link, placement in world.items():
        if not model.existFrame(link, pin.FrameType.BODY):
            problems.append(f"link '{link}' is missing from Pinocchio's model")
            continue
        got = data.oMf[model.getFrameId(link, pin.FrameType.BODY)]
        if not (np.allclose(got.translation, placement.translation, rtol=0, atol=1e-9 * scale)
                and np.allclose(got.rotation, placement.rotation, rtol=0, atol=1e-9)):
            problems.append(f"link '{link}' is at {np.round(got.translation, 9).tolist()} for "
                            f"Pinocchio and at {np.round(placement.translation, 9).tolist()} "
                            "for pinflex")
    carried: dict[int, pin.Inertia] = {}
    for link, inertia in desc.inertias.items():
        if link not in world or not model.existFrame(link, pin.FrameType.BODY):
            continue
        joint = model.frames[model.getFrameId(link, pin.FrameType.BODY)].parentJoint
        local = pin.Inertia(float(inertia.mass), np.asarray(inertia.com),
                            np.asarray(inertia.inertia))
        in_joint = (data.oMi[joint].inverse() * world[link]).act(local)
        carried[joint] = carried[joint] + in_joint if joint in carried else in_joint
    for j in range(1, model.njoints):
        mine = carried.get(j, pin.Inertia.Zero())
        theirs = model.inertias[j]
        big = max(1e-12, abs(mine.mass), abs(theirs.mass))
        if abs(mine.mass - theirs.mass) > 1e-9 * big or not np.allclose(
                mine.inertia, theirs.inertia, rtol=1e-9,
                atol=1e-9 * max(1e-12, float(np.abs(mine.inertia).max()))):
            problems.append(f"joint '{model.names[j]}' carries {theirs.mass:.9g} kg for "
                            f"Pinocchio and {mine.mass:.9g} kg for pinflex")
    for j in range(1, model.njoints):
        name = model.names[j]
        joint = desc.joints.get(name)
        if joint is None:
            continue
        S = np.asarray(data.joints[j].S).reshape(6, -1)[:, 0]
        axis = S[3:] if joint.type in ("revolute", "continuous") else S[:3]
        if not np.allclose(axis, np.asarray(joint.axis), atol=1e-9):
            problems.append(f"joint '{name}' has axis {np.round(axis, 9).tolist()} for "
                            f"Pinocchio and {np.round(joint.axis, 9).tolist()} for pinflex")
        if joint.type in ("revolute", "prismatic") and np.isfinite(joint.lower):
            iq = model.joints[j].idx_q
            lo, hi = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
            if not (np.isclose(lo, joint.lower, rtol=1e-12, atol=0)
                    and np.isclose(hi, joint.upper, rtol=1e-12, atol=0)):
                problems.append(f"joint '{name}' has limits [{lo:g}, {hi:g}] for Pinocchio "
                                f"and [{joint.lower:g}, {joint.upper:g}] for pinflex")
    if problems:
        said = urdfdom_message(native or [])
        raise InvalidDescription(
            "Pinocchio read the URDF differently from pinflex: " + "; ".join(problems[:3])
            + (f" (and {len(problems) - 3} more)" if len(problems) > 3 else "")
            + (f"; urdfdom reported: {said}" if said else "")
            + "; write every number as a plain decimal without surrounding spaces"
        )
