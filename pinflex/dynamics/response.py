"""Outputs of a time simulation: a frame's elastic deflection, its peak, RMS, residual vibration.

Deflection of a frame: the difference between the frame's position on the flexible arm and
its position on a rigid arm at the same *physical* joint angles, in world axes,
``δ = T(q) x + S(q) A x`` (``T`` the elastic translation of the point, ``S`` its ERLS Jacobian,
``A x`` the elastic offset of the ERLS joint coordinates). It is what a camera fixed to the
ground sees against the commanded motion.

Metrics (all in metres, on ``|δ|``):

* ``tip_peak_m``: the largest ``|δ|`` over the whole record;
* ``tip_rms_m``: the RMS of ``|δ|`` from the start to the stop (along the motion);
* ``residual_amplitude_m``: the largest ``|δ − δ_static|`` after the stop, ``δ_static`` the
  static deflection at the final pose (zero without gravity);
* ``dominant_frequency_hz``: the frequency of the residual vibration, from the largest peak of
  the Hann-windowed, zero-padded spectrum of ``δ − δ_static`` projected on its principal
  direction, refined by a least-squares fit of one sinusoid (with offset and exponential
  decay) around that peak.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field

import numpy as np
from scipy.optimize import least_squares

from pinflex.exceptions import ConfigurationError


@dataclass(frozen=True)
class VibrationReport:
    """Deflection of a frame along a simulated motion and its metrics (see module doc).

    Attributes:
        name: Label of the design.
        frame: ``"link"`` or ``"link@x,y,z"`` of the output point.
        times_s: Output times (nt,) [s]; ``stop_s`` the end of the drive.
        deflection_m: World-axes deflection (nt, 3) [m].
        static_m: Static deflection at the final pose (3,) [m].
        tip_peak_m, tip_rms_m, residual_amplitude_m: See the module doc [m].
        dominant_frequency_hz: Dominant frequency after the stop [Hz] (NaN if the record after
            the stop is shorter than 3 periods of it or has no vibration).
        joint_condition: ``"locked"`` or ``"free"``: the joints during the residual vibration.
        reference_hz: Lowest eigenfrequencies of the final pose for that joint condition [Hz].
        steps, time_s: Integrator steps and compute time [s].
        error_estimate: Richardson estimate of the time-step error of a prescribed motion
            (``Simulation.error_estimate``; NaN for the adaptive integrators).
        y: Design values [kg] by name; final_q: final ERLS joint coordinates (user convention).
        validity: The validity indicator's summary
            (:meth:`pinflex.erls.validity.Validity.summary`), or None.
        terms: ``"eq1"`` or ``"full"``: the terms simulated.
        linearisation_error: The torque drive's linearised route: its linearisation error
            estimate (``Simulation.linearisation_error``); NaN otherwise.
    """

    name: str
    frame: str
    times_s: np.ndarray = field(repr=False)
    stop_s: float
    deflection_m: np.ndarray = field(repr=False)
    static_m: np.ndarray
    tip_peak_m: float
    tip_rms_m: float
    residual_amplitude_m: float
    dominant_frequency_hz: float
    joint_condition: str
    reference_hz: tuple[float, ...]
    steps: int
    time_s: float
    y: dict
    final_q: tuple[float, ...]
    error_estimate: float = float("nan")
    validity: dict | None = None
    terms: str = "eq1"
    linearisation_error: float = float("nan")

    def summary(self) -> dict:
        """The JSON-ready metrics (no time series)."""
        d = asdict(self)
        for k in ("times_s", "deflection_m"):
            d.pop(k)
        d["static_m"] = [float(v) for v in self.static_m]
        d["reference_hz"] = [float(v) for v in self.reference_hz]
        d["final_q"] = [float(v) for v in self.final_q]
        d["dominant_frequency_hz"] = (None if not np.isfinite(self.dominant_frequency_hz)
                                      else float(self.dominant_frequency_hz))
        d["error_estimate"] = (None if not np.isfinite(self.error_estimate)
                               else float(self.error_estimate))
        d["linearisation_error"] = (None if not np.isfinite(self.linearisation_error)
                                    else float(self.linearisation_error))
        return d

    def to_json(self, *, series: bool = False) -> str:
        """JSON text of :meth:`summary`, with the time series when ``series``.

        Args:
            series: Also write ``times_s`` (nt,) [s] and ``deflection_m`` (nt, 3) [m] as lists.

        Returns:
            One JSON object as a string.
        """
        d = self.summary()
        if series:
            d["times_s"] = self.times_s.tolist()
            d["deflection_m"] = self.deflection_m.tolist()
        from pinflex.outputs import json_text

        return json_text(d)


def frame_deflection(dyn, sim, frame: str = "tool", xyz=(0.0, 0.0, 0.0), *,
                     spacing_s: float = 5e-3) -> np.ndarray:
    """World deflection (nt, 3) of a point of a link along a :class:`Simulation`.

    The maps ``T(q)``, ``S(q) A(q)`` are evaluated exactly at every output sample of a torque
    drive and, for a prescribed motion, every ``spacing_s`` along the motion (cubic spline in
    time in between; they change with the pose only) and once for the held pose. On benchmark
    A 5 ms changes the deflection by 1.4e-6 of its peak against 0.25 ms.

    Args:
        dyn: The :class:`ErlsDynamics` the simulation ran on.
        sim: The :class:`Simulation` (``times_s`` (nt,), elastic coordinates ``x`` (nt, nx),
            joint coordinates ``q`` / ``q_physical`` (nt, nv)).
        frame: Name of the link carrying the point.
        xyz: Position (3,) of the point in the link frame [m].
        spacing_s: Time spacing [s] of the exact evaluations of the maps along a prescribed
            motion (default 5 ms); unused for a torque drive.

    Returns:
        Deflection ``δ`` (nt, 3) in world axes [m].

    Raises:
        LinkNotFound: ``frame`` is not a link.
    """
    from scipy.interpolate import CubicSpline

    at = dyn.frame_map(frame, xyz)
    t = sim.times_s
    nx = dyn.nx

    def maps(q):
        T, S = at(q)
        return T[:3] + S[:3] @ dyn.joint_offsets(q)[0]

    if sim.drive == "torque":
        return np.array([maps(sim.q[i]) @ sim.x[i] for i in range(t.size)])
    out = np.empty((t.size, 3))
    hold = t > sim.stop_s
    if np.any(hold):
        out[hold] = sim.x[hold] @ maps(sim.q_physical[-1]).T
    during = ~hold
    if np.any(during):
        td = t[during]
        n = max(4, int(np.ceil((td[-1] - td[0]) / spacing_s)) + 1)
        grid = np.linspace(td[0], td[-1], n)
        qg = np.array([np.interp(grid, td, sim.q_physical[during, j])
                       for j in range(dyn.nv)]).T
        Pg = np.array([maps(q) for q in qg]).reshape(n, 3 * nx)
        P = CubicSpline(grid, Pg, axis=0)(td).reshape(-1, 3, nx) if n > 1 else Pg.reshape(
            -1, 3, nx)
        out[during] = np.einsum("tax,tx->ta", P, sim.x[during])
    return out


def dominant_frequency(times: np.ndarray, signal: np.ndarray) -> float:
    """Dominant frequency [Hz] of a uniformly sampled (n,) or (n, 3) signal (module doc).

    Args:
        times: Sample times (n,) [s], uniformly spaced.
        signal: Samples (n,) or (n, 3), any unit; a (n, 3) signal is projected on its
            principal direction.

    Returns:
        The frequency [Hz], or NaN when there are fewer than 8 samples, the signal is zero,
        or the record is shorter than 3 periods of the spectral peak.
    """
    t = np.asarray(times, dtype=float)
    s = np.asarray(signal, dtype=float)
    if s.ndim == 2:
        s = s - s.mean(axis=0)
        _, _, vt = np.linalg.svd(s, full_matrices=False)
        s = s @ vt[0]
    s = s - s.mean()
    n = s.size
    if n < 8 or not np.any(s):
        return float("nan")
    dt = float(np.mean(np.diff(t)))
    nfft = 1 << int(np.ceil(np.log2(16 * n)))
    spec = np.abs(np.fft.rfft(s * np.hanning(n), nfft))
    freqs = np.fft.rfftfreq(nfft, dt)
    k = int(np.argmax(spec[1:])) + 1
    f0 = float(freqs[k])
    if f0 * (t[-1] - t[0]) < 3.0:
        return float("nan")
    tt = t - t[0]
    scale = float(np.abs(s).max())

    def resid(p):
        f, a, b, c, d = p
        env = np.exp(-d * tt)
        return (env * (a * np.cos(2 * np.pi * f * tt) + b * np.sin(2 * np.pi * f * tt)) + c
                - s / scale)

    fit = least_squares(resid, [f0, 1.0, 0.0, 0.0, 0.0],
                        bounds=([0.8 * f0, -np.inf, -np.inf, -np.inf, -50.0 * f0],
                                [1.2 * f0, np.inf, np.inf, np.inf, 50.0 * f0]),
                        x_scale=[f0, 1, 1, 1, f0 + 1.0])
    return float(fit.x[0])


def vibration_report(dyn, sim, *, name: str = "design", frame: str = "tool",
                     xyz=(0.0, 0.0, 0.0), n_reference: int = 3) -> VibrationReport:
    """Deflection of a frame along a simulation and its metrics.

    Args:
        dyn: The :class:`ErlsDynamics` the simulation ran on.
        sim: The :class:`Simulation` to evaluate.
        name: Label of the design in the report.
        frame: Name of the link carrying the output point.
        xyz: Position (3,) of the point in the link frame [m].
        n_reference: Number of lowest eigenfrequencies of the final pose to report.

    Returns:
        :class:`VibrationReport` (metrics in [m], frequencies in [Hz]).

    Raises:
        ConfigurationError: ``xyz`` has not 3 coordinates.
        LinkNotFound: ``frame`` is not a link.
    """
    xyz = np.asarray(xyz, dtype=float)
    if xyz.shape != (3,):
        raise ConfigurationError("the output point must have 3 coordinates [m]")
    defl = frame_deflection(dyn, sim, frame, xyz)
    t = sim.times_s
    during = t <= sim.stop_s
    after = ~during
    final_q = sim.q_physical[-1]
    ref, static = reference_modes(dyn, final_q, sim.joint_condition, frame, xyz, n_reference,
                                  servo_stiffness=getattr(sim, "servo_stiffness", 0.0))
    mag = np.linalg.norm(defl, axis=1)
    resid = defl[after] - static
    label = frame if not np.any(xyz) else f"{frame}@{','.join(f'{v:g}' for v in xyz)}"
    return VibrationReport(
        name=name, frame=label, times_s=t, stop_s=sim.stop_s, deflection_m=defl,
        static_m=static, tip_peak_m=float(mag.max()),
        tip_rms_m=float(np.sqrt(np.mean(mag[during] ** 2))) if np.any(during) else 0.0,
        residual_amplitude_m=float(np.linalg.norm(resid, axis=1).max()) if np.any(after)
        else 0.0,
        dominant_frequency_hz=dominant_frequency(t[after], resid) if after.sum() > 8
        else float("nan"),
        joint_condition=sim.joint_condition, reference_hz=tuple(float(v) for v in ref),
        steps=sim.steps, time_s=sim.time_s, error_estimate=float(sim.error_estimate),
        y={d.name: float(v) for d, v in zip(dyn.model.design, dyn.y)},
        final_q=tuple(float(v) for v in sim.q[-1]),
        validity=None if getattr(sim, "validity", None) is None else sim.validity.summary(),
        terms=getattr(sim, "terms", "eq1"),
        linearisation_error=float(getattr(sim, "linearisation_error", float("nan"))),
    )


def locked_system(dyn, q):
    """``(Mr, Kr, f, A)``: locked-joint elastic mass, stiffness, static load at pose q."""
    M, _, K, F = dyn.linear_terms(q)
    A = dyn.joint_offsets(q)[0]
    Z = np.vstack([np.eye(dyn.nx), A])
    return Z.T @ M @ Z, Z.T @ K @ Z, Z.T @ (F - K[:, dyn.nx:] @ np.asarray(q, float)), A


def locked_validity(dyn, times_s, q, qd, qdd, *, terms: str = "eq1", strict: bool = False,
                    threshold: float | None = None, n_modes: int = 3,
                    what: str = "the motion"):
    """The validity indicator of eq. (1) along a joint motion, against the locked modes.

    The lowest ``n_modes`` locked-joint eigenfrequencies (eq. 1's, the joints held by their
    motors) are solved at 200 of the samples at most and interpolated linearly between (they
    change slowly with the pose); the indicator is :func:`pinflex.erls.validity.validity`
    with them. Locked frequencies are the lowest a held arm rings at, so for a servo-held or
    torque-driven arm the indicator errs on the side of warning.

    Args:
        dyn: The :class:`ErlsDynamics`.
        times_s: Sample times (n,) [s].
        q: Joint coordinates (n, nv), user convention; ``qd``, ``qdd`` their rates.
        qd: Joint velocities (n, nv).
        qdd: Joint accelerations (n, nv).
        terms: ``"full"``: reported, never warned about or refused (the terms are in).
        strict: Refuse above the threshold (``terms="eq1"``).
        threshold: Warning threshold (default :data:`pinflex.erls.validity.VALIDITY_THRESHOLD`).
        n_modes: Modes per sample.
        what: Name of the motion in the message.

    Returns:
        :class:`pinflex.erls.validity.Validity`.
    """
    import scipy.linalg

    from pinflex.erls.validity import VALIDITY_THRESHOLD, validity

    t = np.asarray(times_s, dtype=float)
    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    k = max(1, min(int(n_modes), dyn.nx))
    at = np.unique(np.linspace(0, t.size - 1, min(t.size, 200)).round().astype(int))
    wa = np.empty((at.size, k))
    for n, i in enumerate(at):
        Mr, Kr, _, _ = locked_system(dyn, q[i])
        lam = scipy.linalg.eigh(Kr, Mr, eigvals_only=True, subset_by_index=[0, k - 1])
        wa[n] = np.sqrt(np.clip(lam, 0.0, None))
    w = wa if at.size == t.size else np.column_stack(
        [np.interp(t, t[at], wa[:, j]) for j in range(k)])
    return validity(dyn.model, t, q, qd, qdd, w,
                    threshold=VALIDITY_THRESHOLD if threshold is None else threshold,
                    strict=strict and terms == "eq1", warn=terms == "eq1", what=what,
                    basis="locked")


def locked_frequencies(dyn, q) -> np.ndarray:
    """Eigenfrequencies [Hz] of the arm with every joint locked (physical angles held) at q.

    Args:
        dyn: The :class:`ErlsDynamics` of the arm.
        q: Joint coordinates (nv,) in the user convention [rad or m]; not validated.

    Returns:
        All ``nx`` locked-joint eigenfrequencies (nx,) ascending [Hz] (negative eigenvalues
        from round-off clipped to 0).
    """
    import scipy.linalg

    Mr, Kr, _, _ = locked_system(dyn, q)
    return np.sqrt(np.clip(scipy.linalg.eigh(Kr, Mr, eigvals_only=True), 0, None)) / (2 * np.pi)


def reference_modes(dyn, q, condition: str, frame: str, xyz, n: int, *,
                    servo_stiffness: float = 0.0):
    """Lowest frequencies [Hz] at a pose for a joint condition; the frame's static deflection.

    The static deflection [m] is that of the locked-joint arm (zero without gravity).
    """
    Mr, Kr, f, A = locked_system(dyn, q)
    at = dyn.frame_map(frame, xyz)
    T, S = at(q)
    if condition == "locked":
        ref = locked_frequencies(dyn, q)[:n]
    elif condition == "servo":
        from pinflex.erls import FlexibleModel

        m = dyn.model
        springs = FlexibleModel(m.description, planar=m.planar, coordinates=m.coordinates,
                                joints={j: servo_stiffness for j in m.joint_names})
        ref = springs.frequencies(q, dyn.y)[:n]
    else:
        ref = dyn.model.frequencies(q, dyn.y)[:n]
    static = np.zeros(3)
    if np.any(f):
        x = np.linalg.solve(Kr, f)
        static = T[:3] @ x + S[:3] @ (A @ x)
    return np.asarray(ref), static
