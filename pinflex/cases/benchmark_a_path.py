"""Benchmark A's pick-and-place path (paper 000), built without the modal model."""

from __future__ import annotations

import numpy as np

from pinflex.trajectory.ik import absolute_to_relative, planar_2r_fk, planar_2r_ik
from pinflex.trajectory.paths import WorkspacePath, parse_pieces, path_timing, workspace_path
from pinflex.trajectory.samples import Trajectory

BENCHMARK_A_L1_M = 0.6
"""Length of link 1 of paper 000's two-link arm [m]."""
BENCHMARK_A_L2_M = 0.45
"""Length of link 2 [m]."""
BENCHMARK_A_Q0_ABS = (1.817, 5.312)
"""Paper 000's expansion point in ABSOLUTE link angles [rad] (relative: (1.817, 3.495))."""
BENCHMARK_A_Q0_SAMPLE = 76
"""Index of the benchmark-A sample that lies exactly at the end-effector point of q0."""

_ELBOW_MIN_RAD = 3.35  # smallest elbow angle q2 − q1 along the path (at the pick point)
_ELBOW_MAX_RAD = 3.77  # largest elbow angle, reached on the rounded far corner
_FILLET_M = 0.01  # radius of the two rounded corners [m]


def _elbow_radius(elbow_rad: float) -> float:
    """Distance from the base to the end effector for a given relative elbow angle [m]."""
    l1, l2 = BENCHMARK_A_L1_M, BENCHMARK_A_L2_M
    return float(np.sqrt(l1**2 + l2**2 + 2.0 * l1 * l2 * np.cos(elbow_rad)))


def _benchmark_a_pieces(x_pick: float) -> tuple[np.ndarray, list[tuple], float]:
    """Start, segment spec and arc-length position of p(q0) for a pick abscissa [m]."""
    p0 = planar_2r_fk(absolute_to_relative(BENCHMARK_A_Q0_ABS), BENCHMARK_A_L1_M, BENCHMARK_A_L2_M)
    y_top = float(p0[1])
    y_station = float(np.sqrt(_elbow_radius(_ELBOW_MIN_RAD) ** 2 - x_pick**2))
    f = _FILLET_M
    # the far corner's fillet (center c, radius f) touches the circle r(3.77): |c| + f = r
    x_place = f + float(np.sqrt((_elbow_radius(_ELBOW_MAX_RAD) - f) ** 2 - (y_top - f) ** 2))
    start = np.array([x_pick, y_station])
    segments = [
        ("line", (x_pick, y_top - f)),
        ("arc", (x_pick + f, y_top), (x_pick + f, y_top - f), "cw"),
        ("line", (x_place - f, y_top)),
        ("arc", (x_place, y_top - f), (x_place - f, y_top - f), "cw"),
        ("line", (x_place, y_station)),
    ]
    s_p0 = (y_top - f - y_station) + 0.5 * np.pi * f + (p0[0] - x_pick - f)
    return start, segments, float(s_p0)


def benchmark_a_path(n_samples: int = 152, duration_s: float = 1.51) -> WorkspacePath:
    """Workspace path of benchmark A (SPEC §5), a pick-and-place through paper 000's q0.

    Paper 000 shows its 152-sample path only as a figure; this one is built to match what the
    paper states: constant time steps, 152 samples, an elbow angle ``q2 − q1`` spanning about
    3.35–3.77 rad, the expansion point ``q0 = [1.817, 5.312]`` rad (absolute) about in the
    middle, and all samples inside the domain ``[3π/8, 7π/8] × [3π/2, 2π]`` of its Fig. 3.

    Construction (world x–y plane, base at the origin; no gravity in the benchmark, +y is
    called "up"): with the elbow angle folded past π, the end effector stays inside the annulus
    ``0.185 m <= r <= 0.354 m`` and the elbow angle is a function of ``r`` only, so the span is
    set by the distances reached:

    1. pick at ``A = (x_A, y_s)`` with ``|A| = r(3.35 rad)``, so the elbow angle starts at its
       minimum 3.35 rad;
    2. rise straight up to the transfer height ``y = y(q0) = 0.2104 m``;
    3. move along the line ``y = y(q0)``, through ``p(q0)``, to ``x_B``; both corners are
       rounded with 10 mm arcs, and ``x_B`` is set so that the far corner's arc touches the
       circle ``r = r(3.77 rad)``: the elbow angle peaks there at 3.77 rad;
    4. descend straight down to the place point ``B = (x_B, y_s)``.

    The timing is minimum-jerk along the whole path (rest to rest). The one free parameter
    ``x_A`` is solved (Brent) so that sample 76 of 152 falls exactly on ``p(q0)``; this gives
    ``x_A ≈ −0.0804 m``, ``y_s ≈ 0.1665 m`` (a 43.9 mm lift), ``x_B ≈ 0.2902 m``, a path
    of 0.450 m. Absolute angles stay in q1 ∈ [1.356, 2.617], q2 ∈ [5.081, 6.067] rad.

    Args:
        n_samples: Number of samples (152 in the paper); ``p(q0)`` is hit exactly only for 152.
        duration_s: Duration [s]; the default gives 10 ms steps.

    Returns:
        The sampled :class:`WorkspacePath`.
    """
    tau = BENCHMARK_A_Q0_SAMPLE / 151.0
    target = float(path_timing(np.array(tau), "minimum_jerk"))

    def mismatch(x_pick: float) -> float:
        start, segments, s_p0 = _benchmark_a_pieces(x_pick)
        lengths = [p.length for p in parse_pieces(start, segments)]
        return s_p0 / sum(lengths) - target

    from scipy.optimize import brentq

    x_pick = brentq(mismatch, -0.15, 0.05, xtol=1e-16, rtol=1e-15)
    start, segments, _ = _benchmark_a_pieces(x_pick)
    return workspace_path(start, segments, n_samples, duration_s=duration_s)


def benchmark_a_trajectory(n_samples: int = 152, duration_s: float = 1.51) -> Trajectory:
    """Joint trajectory of benchmark A in RELATIVE coordinates (Pinocchio's convention).

    The path of :func:`benchmark_a_path` solved by :func:`planar_2r_ik` on the elbow branch
    ``sin(q2 − q1) < 0`` and shifted so that the elbow angle lies in (π, 2π), as in paper 000.
    Columns, named after the joints of ``urdf/two_link.urdf``: ``q1`` = base angle and
    ``q2`` = Pinocchio's value of joint q2, the relative elbow angle q2 − q1 [rad]; use
    :func:`relative_to_absolute` for the paper's absolute angles. Elbow angle span with the
    defaults: 3.3500 rad (sample 0) to 3.7699 rad (sample 115); sample 76 equals
    ``(1.817, 3.495)`` to round-off.
    """
    path = benchmark_a_path(n_samples, duration_s)
    q_ref = absolute_to_relative(BENCHMARK_A_Q0_ABS)
    q = planar_2r_ik(path.points, BENCHMARK_A_L1_M, BENCHMARK_A_L2_M, -1, q_ref=q_ref)
    return Trajectory(path.times_s, q, ("q1", "q2"), "benchmark A pick-and-place")
