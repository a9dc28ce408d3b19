"""MJCF and URDF exports of paper 001's fitted nR chains (:class:`pinflex.prbdm.chain.PrbdmChain`).

The chain's springs become MJCF joint ``stiffness`` (rest ``springref`` 0, the straight beam)
and, in the URDF export, ``<pinflex:joint stiffness>`` annotations plus the spring-data file
of :mod:`pinflex.lumped.urdf`, so that MuJoCo loads an elastic model (``jnt_stiffness`` > 0)
and :func:`~pinflex.lumped.urdf.load_lumped_urdf` gives Pinocchio the chain's mass matrix and
stiffness exactly. Link 0 is clamped to the world along +X; joints turn about +Y (bending in
the X–Z plane). Each link is drawn as a box of the planform's mean width over the link and
the beam's thickness (when a planform is given), else as a thin cylinder.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from pinflex.exceptions import OutputExists
from pinflex.lumped.mjcf import MjcfBody, MjcfJoint, mjcf_text, num, suggested_timestep, vec
from pinflex.lumped.urdf import UrdfJoint, springs_json, tree_urdf


def _box(length: float, width: float, thickness: float) -> str:
    return (f'<geom type="box" pos="{num(length / 2)} 0 0" '
            f'size="{vec([length / 2, width / 2, thickness / 2])}" contype="0" '
            'conaffinity="0" group="1" rgba="0.6 0.65 0.75 1"/>')


def _widths(chain, planform) -> tuple[np.ndarray, float]:
    """Mean width of links 0..n and the thickness, or a thin default."""
    lengths = np.asarray(chain.link_lengths_m)
    if planform is None:
        return np.full(lengths.size, 0.02 * chain.length_m), 0.02 * chain.length_m
    ends = np.concatenate([[0.0], np.cumsum(lengths)])
    x = np.linspace(0.0, 1.0, 33)
    widths = []
    for a, b in zip(ends[:-1], ends[1:]):
        xs = a + (b - a) * x
        widths.append(2.0 * float(np.interp(xs, planform.x_m, planform.half_width_m).mean()))
    return np.array(widths), float(planform.thickness_m)


def chain_mjcf(chain, *, name: str = "prbdm", planform=None, damping: np.ndarray | None = None,
               gravity=(0.0, 0.0, -9.81), timestep: float | None = None) -> str:
    """MJCF text of an nR chain.

    Args:
        chain: The :class:`~pinflex.prbdm.chain.PrbdmChain`.
        name: Model name.
        planform: The beam, to draw the links at their width and thickness (optional).
        damping: Joint damping (n,) [N m s/rad] (default none).
        gravity: Gravity (3,) [m/s^2].
        timestep: Step [s] (default: 1/20 of the highest chain mode's period, at most 2 ms).
    """
    from pinflex.prbdm.chain import chain_frequencies

    model = chain.model
    d = np.zeros(chain.n_joints) if damping is None else np.asarray(damping, dtype=float)
    widths, thickness = _widths(chain, planform)
    bodies = []
    for j in range(1, model.njoints):
        joint = MjcfJoint(model.names[j], "hinge", np.array([0.0, 1.0, 0.0]),
                          stiffness=float(chain.stiffness_nm_rad[j - 1]), damping=float(d[j - 1]))
        bodies.append(MjcfBody(f"link_{j}", (j,), [joint],
                               [_box(chain.link_lengths_m[j], widths[j], thickness)]))
    if timestep is None:
        timestep = suggested_timestep(float(chain_frequencies(chain).max()))
    return mjcf_text(model, bodies, name=name, timestep=timestep, gravity=gravity,
                     world_geoms=[_box(chain.link_lengths_m[0], widths[0], thickness)],
                     qpos={model.names[j]: 0.0 for j in range(1, model.njoints)},
                     comment=f"pinflex {chain.n_joints}R pseudo-rigid-body chain: joint "
                     "stiffness is the fitted spring stiffness [N m/rad], rest straight")


def chain_urdf(chain, *, name: str = "prbdm", damping: np.ndarray | None = None
               ) -> tuple[str, str]:
    """URDF and spring-data texts of an nR chain (see :mod:`pinflex.lumped.urdf`)."""
    model = chain.model
    d = np.zeros(chain.n_joints) if damping is None else np.asarray(damping, dtype=float)
    bodies, joints = [], []
    for j in range(1, model.njoints):
        joint = UrdfJoint(model.names[j], "revolute", np.array([0.0, 1.0, 0.0]),
                          float(chain.stiffness_nm_rad[j - 1]), 0.0, float(d[j - 1]))
        joints.append(joint)
        bodies.append((f"link_{j}", (j,), [joint]))
    text = tree_urdf(model, bodies, name=name, root="link_0")
    # the tip frame as a fixed child, as the chain's own URDF has it
    tip = model.frames[chain.tip_frame_id].placement.translation
    text = text.replace("</robot>", (
        f'  <link name="tip"/>\n  <joint name="tip_joint" type="fixed">\n'
        f'    <parent link="link_{model.njoints - 1}"/>\n    <child link="tip"/>\n'
        f'    <origin xyz="{vec(tip)}" rpy="0 0 0"/>\n  </joint>\n</robot>'))
    return text, springs_json(joints, {j.name: 0.0 for j in joints})


def export_targets(path: str | Path, force: bool = False) -> list[Path]:
    """The files an export to ``path`` writes, checked before any work.

    Raises:
        OutputExists: A target exists and ``force`` is off.
        ConfigurationError: The suffix is neither ``.xml`` nor ``.urdf``.
        OutputError: A target cannot be written.
    """
    from pinflex.exceptions import ConfigurationError
    from pinflex.outputs import check_file_target

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in (".xml", ".mjcf", ".urdf"):
        raise ConfigurationError(f"--export '{path}': give a .xml (MJCF) or .urdf file name")
    targets = [path]
    if suffix == ".urdf":
        targets.append(path.with_name(path.stem + ".springs.json"))
    for target in targets:
        if target.exists() and not force:
            raise OutputExists(f"'{target}' exists; pass --force to overwrite it")
        check_file_target(target, "--export")
    return targets


def export_chain(chain, path: str | Path, *, planform=None, force: bool = False,
                 name: str = "prbdm") -> list[Path]:
    """Write a chain as MJCF (``.xml``) or URDF (``.urdf`` plus ``.springs.json``).

    Args:
        chain: The chain.
        path: Output file; its suffix picks the format.
        planform: The beam (for the MJCF drawing).
        force: Overwrite existing files.
        name: Model name.

    Returns:
        The files written.

    Raises:
        OutputExists: A target exists and ``force`` is off.
        ConfigurationError: The suffix is neither ``.xml`` nor ``.urdf``.
    """
    from pinflex.outputs import write_text

    targets = export_targets(path, force)
    path = targets[0]
    if path.suffix.lower() == ".urdf":
        text, springs = chain_urdf(chain, name=name)
        write_text(path, text)
        write_text(targets[1], springs)
    else:
        write_text(path, chain_mjcf(chain, name=name, planform=planform))
    return targets


__all__ = ["chain_mjcf", "chain_urdf", "export_chain", "export_targets"]
