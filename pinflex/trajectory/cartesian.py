"""3-D workspace paths for any arm: waypoints, timing, Pinocchio IK, joint limits.

:func:`path_trajectory` turns a polyline of 3-D waypoints of one frame (optionally with a fixed
orientation) into a joint :class:`~pinflex.Trajectory` of a :class:`~pinflex.FlexibleModel`::

    traj = path_trajectory(arm, "ee_link", [[0.6, 0.2, 0.4], [0.6, -0.2, 0.4]],
                           n_samples=40, duration_s=2.0, q_init=q0, orientation="keep")
    traj.to_csv("traj.csv")

Timing along the polyline is the rest-to-rest minimum-jerk law
``s(τ) = S (10τ³ − 15τ⁴ + 6τ⁵)`` (or uniform). The IK is warm-started sample to sample, so it
follows one branch; continuous joints are unwrapped along the motion. Samples outside the
URDF joint limits raise :class:`~pinflex.exceptions.JointLimitsExceeded` (or warn).
"""

from __future__ import annotations

import warnings
from typing import Literal

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from pinflex.checks import check_q
from pinflex.exceptions import IKNotConverged, InvalidPath, LinkNotFound, TrajectoryWarning
from pinflex.progress import ProgressBar
from pinflex.trajectory import Trajectory, solve_ik
from pinflex.validation import require_count, require_number

#: Most samples of a workspace path: each is an inverse-kinematics solve (a few ms), and
#: each later costs a modal analysis; 20,000 samples already take minutes.
MAX_PATH_SAMPLES = 20_000


def sample_polyline(
    waypoints, n_samples: int, duration_s: float, profile: str = "minimum_jerk"
) -> tuple[np.ndarray, np.ndarray]:
    """Times (ns,) [s] and points (ns, 3) [m] along straight lines through the waypoints."""
    pts = np.asarray(waypoints, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3 or pts.shape[0] < 2:
        raise InvalidPath(f"waypoints must have shape (k, 3) with k >= 2, got {pts.shape}")
    if not np.all(np.isfinite(pts)):
        raise InvalidPath("waypoints must be finite")
    n_samples = require_count(n_samples, "n_samples (path samples)", minimum=2,
                              maximum=MAX_PATH_SAMPLES, error=InvalidPath)
    duration_s = require_number(duration_s, "duration_s", gt=0.0, le=1e6, unit="s",
                                error=InvalidPath)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    if np.any(seg <= 1e-12):
        k = int(np.argmin(seg))
        raise InvalidPath(f"waypoints {k} and {k + 1} coincide (zero-length segment)")
    cum = np.concatenate([[0.0], np.cumsum(seg)])
    times = np.linspace(0.0, float(duration_s), int(n_samples))
    tau = times / duration_s
    if profile == "minimum_jerk":
        frac = tau**3 * (10.0 - 15.0 * tau + 6.0 * tau**2)
    elif profile == "uniform":
        frac = tau
    else:
        raise InvalidPath(f"unknown timing profile {profile!r}; use 'minimum_jerk' or 'uniform'")
    s = cum[-1] * frac
    k = np.clip(np.searchsorted(cum, s, side="right") - 1, 0, seg.size - 1)
    w = ((s - cum[k]) / seg[k])[:, None]
    return times, (1.0 - w) * pts[k] + w * pts[k + 1]


def solve_pose_ik(
    model: pin.Model,
    data: pin.Data,
    frame_id: int,
    points: np.ndarray,
    rotation: np.ndarray,
    q_init: np.ndarray,
    *,
    tol: float = 1e-10,
    max_iter: int = 200,
    progress: ProgressBar | None = None,
) -> np.ndarray:
    """Position and orientation IK (Levenberg–Marquardt), warm-started along the points.

    The error is ``[p* − p; log₃(R* Rᵀ)]`` in world axes (metres and radians weighted alike),
    the Jacobian the frame's LOCAL_WORLD_ALIGNED one; a step is kept when it lowers the error.

    ``progress`` (optional) is advanced by one per sample solved.

    Returns:
        Configurations (ns, nq).

    Raises:
        IKNotConverged: A sample whose error stays above ``tol``.
    """
    q = np.array(q_init, dtype=float)
    out = np.empty((points.shape[0], model.nq))

    def error(qv, target):
        pin.framesForwardKinematics(model, data, qv)
        oMf = data.oMf[frame_id]
        return np.concatenate([target - oMf.translation, pin.log3(rotation @ oMf.rotation.T)])

    for k, target in enumerate(points):
        e = error(q, target)
        norm = float(np.linalg.norm(e))
        mu = 1e-3 * norm**2
        it = 0
        while norm > tol and it < max_iter and mu < 1e12:
            it += 1
            J = pin.computeFrameJacobian(model, data, q, frame_id, pin.LOCAL_WORLD_ALIGNED)
            dq = J.T @ np.linalg.solve(J @ J.T + (mu + 1e-14) * np.eye(6), e)
            q_new = pin.integrate(model, q, dq)
            e_new = error(q_new, target)
            n_new = float(np.linalg.norm(e_new))
            if n_new < norm:
                q, e, norm, mu = q_new, e_new, n_new, max(mu / 10.0, 1e-14)
            else:
                mu = 10.0 * mu + 1e-12
        if norm > tol:
            raise IKNotConverged(k, target, norm, q, tol)
        out[k] = q
        if progress is not None:
            progress.update()
    return out


def path_trajectory(
    arm,
    frame: str,
    waypoints: ArrayLike,
    *,
    n_samples: int = 50,
    duration_s: float = 1.0,
    profile: Literal["minimum_jerk", "uniform"] = "minimum_jerk",
    q_init=None,
    orientation=None,
    on_limits: Literal["raise", "warn"] = "raise",
    tol: float = 1e-10,
    name: str | None = None,
    progress: ProgressBar | None = None,
) -> Trajectory:
    """Joint trajectory of ``arm`` whose ``frame`` follows straight lines through waypoints.

    Args:
        arm: A :class:`~pinflex.FlexibleModel`.
        frame: Frame (link or joint name) whose origin follows the path.
        waypoints: Points (k, 3) in the world frame [m], k >= 2; the first is where the motion
            starts (``q_init`` need not reach it exactly: the first IK solve moves there).
        n_samples: Samples ns >= 2, at equal time steps.
        duration_s: Duration [s].
        profile: ``"minimum_jerk"`` (rest to rest) or ``"uniform"`` speed.
        q_init: Start of the IK in the arm's coordinates (nv,) or a Pinocchio configuration
            (nq,); default zeros. It selects the IK branch.
        orientation: ``None`` (position only), ``"keep"`` (the frame's orientation at
            ``q_init`` is held), or a rotation matrix (3, 3) / roll-pitch-yaw (3,) [rad] in the
            world frame.
        on_limits: ``"raise"`` (:class:`JointLimitsExceeded`) or ``"warn"`` when a sample is
            outside the URDF joint limits.
        tol: IK tolerance [m, rad].
        name: Label of the trajectory.
        progress: A progress bar advanced by one per sample solved (optional; its total
            should be ``n_samples``).

    Returns:
        A :class:`~pinflex.Trajectory` in the arm's coordinates with its joint names.

    Raises:
        InvalidPath: Bad waypoints, counts or orientation.
        IKNotConverged: A point out of reach (sample index, target and residual in the message).
        JointLimitsExceeded: A sample outside the joint limits (with ``on_limits="raise"``).
    """
    model, data = arm.model, arm.model.createData()
    if not model.existFrame(frame):
        raise LinkNotFound(frame, [f.name for f in model.frames])
    fid = model.getFrameId(frame)
    times, pts = sample_polyline(waypoints, n_samples, duration_s, profile)
    q0 = np.zeros(arm.nv) if q_init is None else check_q(arm, q_init)
    qpin0 = arm.pin_configuration(q0)
    if orientation is None:
        qpin = np.array(solve_ik(model, data, fid, pts, qpin0, tol_m=tol, progress=progress).q)
    else:
        if isinstance(orientation, str):
            if orientation != "keep":
                raise InvalidPath(f"orientation={orientation!r}: use 'keep', None or a rotation")
            pin.framesForwardKinematics(model, data, qpin0)
            R = data.oMf[fid].rotation.copy()
        else:
            R = np.asarray(orientation, dtype=float)
            if R.shape == (3,):
                R = pin.rpy.rpyToMatrix(*R)
            if R.shape != (3, 3) or np.abs(R.T @ R - np.eye(3)).max() > 1e-9:
                raise InvalidPath("orientation must be a rotation matrix (3, 3) or rpy (3,)")
        qpin = solve_pose_ik(model, data, fid, pts, R, qpin0, tol=tol, progress=progress)
    q = arm.from_configuration(qpin)
    # continuous joints come back in (-pi, pi]: unwrap along the motion, starting near q_init
    rel = q @ arm.coord_map.T
    for j in range(1, model.njoints):
        if model.joints[j].nq == 2:
            v = model.joints[j].idx_v
            col = np.unwrap(np.concatenate([[(arm.coord_map @ q0)[v]], rel[:, v]]))[1:]
            rel[:, v] = col
    q = np.linalg.solve(arm.coord_map, rel.T).T
    traj = Trajectory(times, q, arm.joint_names, name)
    check_joint_limits(arm, traj, on_violation=on_limits)
    return traj


def joint_limits(arm) -> tuple[np.ndarray, np.ndarray]:
    """URDF position limits of the moving joints (relative values), (nv,) each [rad or m]."""
    lo = np.array([arm.description.joints[n].lower for n in arm.joint_names])
    hi = np.array([arm.description.joints[n].upper for n in arm.joint_names])
    return lo, hi


def check_joint_limits(arm, traj: Trajectory, *,
                       on_violation: Literal["warn", "raise"] = "raise") -> np.ndarray:
    """Samples of ``traj`` (arm coordinates) outside the URDF joint limits, (ns, nv) mask.

    Joint values that look like degrees are named first (:func:`warn_if_degrees`).
    """
    lo, hi = joint_limits(arm)
    rel = Trajectory(traj.times_s, traj.q @ arm.coord_map.T, traj.joint_names, traj.name)
    warn_if_degrees(arm, rel.q)
    return rel.check_limits(lo, hi, on_violation=on_violation)


def warn_if_degrees(arm, q_relative: np.ndarray) -> None:
    """Warn (TrajectoryWarning) when a revolute or continuous joint goes beyond one turn.

    Joint values are in radians; |q| > 2π on a turning joint looks like degrees, and a
    continuous joint without limits would otherwise take 90 for a quarter turn silently.

    Args:
        arm: The flexible model.
        q_relative: Relative (Pinocchio) joint values, (ns, nv) [rad or m].
    """
    q = np.atleast_2d(np.asarray(q_relative, dtype=float))
    joints = [arm.description.joints[n] for n in arm.joint_names]
    big = [k for k, j in enumerate(joints) if j.type in ("revolute", "continuous")
           and np.max(np.abs(q[:, k])) > 2 * np.pi + 1e-9]
    if big:
        worst = ", ".join(f"'{joints[k].name}' reaches {np.max(np.abs(q[:, k])):.4g}"
                          for k in big[:4])
        warnings.warn(
            f"joint values beyond one turn ({worst}) look like degrees: joint values are in "
            "radians (convert with numpy.radians)", TrajectoryWarning, stacklevel=3)


__all__ = [
    "check_joint_limits",
    "warn_if_degrees",
    "joint_limits",
    "path_trajectory",
    "sample_polyline",
    "solve_pose_ik",
]


def frame_position(arm, frame: str, q) -> np.ndarray:
    """World position [m] of a frame's origin at joint coordinates ``q`` of the arm."""
    model = arm.model
    if not model.existFrame(frame):
        raise LinkNotFound(frame, [f.name for f in model.frames])
    data = model.createData()
    pin.framesForwardKinematics(model, data, arm.pin_configuration(check_q(arm, q)))
    return data.oMf[model.getFrameId(frame)].translation.copy()


_PATH_KEYS = {"frame", "waypoints", "relative", "start_q", "samples", "duration_s", "profile",
              "orientation", "on_limits"}


def path_from_spec(arm, spec: dict, *, name: str | None = None,
                   progress: ProgressBar | None = None) -> Trajectory:
    """Trajectory of a path specification (the ``[trajectory.path]`` table of a study).

    Keys: ``frame`` (required), ``waypoints`` (required, list of [x, y, z] [m]),
    ``relative`` (waypoints are offsets from the frame's position at ``start_q``, which is
    prepended as the first point; default false), ``start_q`` (joint values, default zeros),
    ``samples`` (default 50), ``duration_s`` (default 1), ``profile``
    (``minimum_jerk``/``uniform``), ``orientation`` (``"keep"``, ``"free"`` (default) or
    roll-pitch-yaw [rad]), ``on_limits`` (``raise``/``warn``). ``progress`` (optional) is
    advanced by one per sample solved.
    """
    unknown = set(spec) - _PATH_KEYS
    if unknown:
        raise InvalidPath(f"unknown path keys {sorted(unknown)}; known: {sorted(_PATH_KEYS)}")
    for key in ("frame", "waypoints"):
        if key not in spec:
            raise InvalidPath(f"a path needs '{key}'")
    q0 = np.zeros(arm.nv) if spec.get("start_q") is None else check_q(arm, spec["start_q"])
    pts = np.asarray(spec["waypoints"], dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise InvalidPath(f"waypoints must be a list of [x, y, z], got shape {pts.shape}")
    if spec.get("relative", False):
        p0 = frame_position(arm, spec["frame"], q0)
        pts = np.vstack([p0, p0 + pts])
    orientation = spec.get("orientation", "free")
    if orientation == "free":
        orientation = None
    return path_trajectory(
        arm, spec["frame"], pts,
        n_samples=int(spec.get("samples", 50)),
        duration_s=float(spec.get("duration_s", 1.0)),
        profile=spec.get("profile", "minimum_jerk"),
        q_init=q0, orientation=orientation,
        on_limits=spec.get("on_limits", "raise"), name=name, progress=progress,
    )
