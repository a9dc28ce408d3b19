"""Joint trajectories, planar workspace paths and inverse kinematics.

A :class:`Trajectory` is the time grid ``t_k`` and the joint samples ``q(t_k)`` along which
paper 000 (Belotti et al. 2021, Sec. 2.4) integrates its assignment cost, eq. (10): the
integrals (13)–(14) become weighted sums with :meth:`Trajectory.trapezoid_weights`, as the
paper does in Sec. 3.3.

Conventions:

* ``q`` holds the model's joint coordinates, one value per joint: revolute angles [rad],
  prismatic displacements [m]. For the benchmark-A arm these are Pinocchio's coordinates, the
  base angle and the RELATIVE elbow angle, ``q_rel = (q1, q2 - q1)``; paper 000 prints ABSOLUTE
  link angles. :func:`absolute_to_relative` and :func:`relative_to_absolute` convert.
* Workspace paths live in the x–y plane of the world frame [m]; planar arms turn about z.

:func:`planar_2r_ik` inverts the planar two-link arm in closed form (benchmark A's
pick-and-place motion, :mod:`pinflex.cases.benchmark_a_path`, is built with it). The
Pinocchio solver :func:`solve_ik` handles any model and is checked against the closed form
in the tests.
"""

from pinflex.trajectory.ik import (
    IKSolution,
    absolute_to_relative,
    planar_2r_fk,
    planar_2r_ik,
    relative_to_absolute,
    solve_ik,
)
from pinflex.trajectory.paths import WorkspacePath, workspace_path
from pinflex.trajectory.samples import Trajectory, trapezoid_weights

__all__ = [
    "IKSolution",
    "Trajectory",
    "WorkspacePath",
    "absolute_to_relative",
    "planar_2r_fk",
    "planar_2r_ik",
    "relative_to_absolute",
    "solve_ik",
    "trapezoid_weights",
    "workspace_path",
]
