"""How far eq. (1) holds along a motion: the validity indicator.

Eq. (1) (paper 000) leaves out the products of the elastic displacement ``u`` with the rigid
motion of its link, ``α × u`` and ``ω × (ω × u)``, and the geometric stiffness of the axial
loads they come with (:mod:`pinflex.dynamics.speed`). Against the elastic restoring force
``ω_i² u`` of a mode they are of relative size

    |ω_L|² / ω_i²   (centrifugal, with the centrifugal axial load)   and   |α_L| / ω_i²   (Euler),

``ω_L`` and ``α_L`` the angular velocity [rad/s] and acceleration [rad/s²] of a link that
deforms (a flexible link or a link carried by one), ``ω_i`` an elastic eigenfrequency [rad/s]
of the arm at that pose: the locked-joint one for a prescribed or servo-held motion, the
constrained (free-joint elastic) one for modes along a motion. :func:`validity` computes both
ratios per sample and per mode; the **indicator** is the largest of them over the motion (at
the lowest mode).

Threshold (:data:`VALIDITY_THRESHOLD` = 0.1): on Kane, Ryan and Banerjee's spin-up beam the
peak tip deflection of eq. (1) differs from the full linear model by 0.39 % at indicator 0.069
(Ωs = 1 rad/s), 4.8 % at 1.1, 9.5 % at 2.5 and 22 % at 6.9 (``docs/speed.md``); the relative
difference stays below about 0.06 × indicator there. Above the threshold a
:class:`~pinflex.exceptions.ModelValidityWarning` says so; ``strict=True`` raises
:class:`~pinflex.exceptions.ModelValidityError` instead. Only revolute motion is measured: a
prismatic joint's linear acceleration loads a beam axially too (in ``terms="full"``) but is not
in the indicator.

The module loads NumPy and Pinocchio only: the modes along a motion
(:func:`pinflex.erls.along.modes_along`), the simulations (:mod:`pinflex.dynamics`) and the
assignment call it. :func:`sample_rates` gives joint velocities and accelerations of sampled
motions (second-order finite differences).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pinflex.exceptions import ConfigurationError, ModelValidityError, ModelValidityWarning

#: Indicator above which eq. (1) is warned about (see the module doc for its calibration).
VALIDITY_THRESHOLD = 0.1


@dataclass(frozen=True)
class Validity:
    """The validity indicator of a motion (module doc), per sample and per mode.

    Attributes:
        times_s: Sample times (n,) [s].
        link_speed_rad_s: Largest angular speed of a deforming link (n,) [rad/s].
        link_accel_rad_s2: Largest angular acceleration of a deforming link (n,) [rad/s²].
        omega_rad_s: Elastic eigenfrequencies used (n, k) [rad/s].
        speed_ratio: ``|ω_L|² / ω_i²`` (n, k).
        accel_ratio: ``|α_L| / ω_i²`` (n, k).
        threshold: The warning threshold of the indicator.
        basis: What ``ω_i`` are (``"locked"``, ``"constrained"``, ...).
    """

    times_s: np.ndarray = field(repr=False)
    link_speed_rad_s: np.ndarray = field(repr=False)
    link_accel_rad_s2: np.ndarray = field(repr=False)
    omega_rad_s: np.ndarray = field(repr=False)
    speed_ratio: np.ndarray = field(repr=False)
    accel_ratio: np.ndarray = field(repr=False)
    threshold: float = VALIDITY_THRESHOLD
    basis: str = "locked"

    @property
    def max_speed_ratio(self) -> float:
        """Largest ``|ω_L|² / ω_i²`` over samples and modes."""
        return _max(self.speed_ratio)

    @property
    def max_accel_ratio(self) -> float:
        """Largest ``|α_L| / ω_i²`` over samples and modes."""
        return _max(self.accel_ratio)

    @property
    def indicator(self) -> float:
        """The larger of the two largest ratios (0 for a motion at rest)."""
        return max(self.max_speed_ratio, self.max_accel_ratio)

    @property
    def exceeded(self) -> bool:
        """Whether the indicator is above the threshold."""
        return self.indicator > self.threshold

    def worst(self) -> tuple[float, str]:
        """``(time [s], "speed" | "acceleration")`` of the largest ratio."""
        ratio = np.maximum(np.nan_to_num(self.speed_ratio[:, 0]),
                           np.nan_to_num(self.accel_ratio[:, 0])) if self.times_s.size else []
        if not len(ratio):
            return float("nan"), "speed"
        i = int(np.argmax(ratio))
        kind = "speed" if self.speed_ratio[i, 0] >= self.accel_ratio[i, 0] else "acceleration"
        return float(self.times_s[i]), kind

    def summary(self) -> dict:
        """JSON-ready maxima, threshold and the time of the worst sample."""
        t, kind = self.worst()
        return {"indicator": self.indicator, "max_speed_ratio": self.max_speed_ratio,
                "max_accel_ratio": self.max_accel_ratio, "threshold": self.threshold,
                "exceeded": self.exceeded, "worst_time_s": None if np.isnan(t) else t,
                "worst_term": kind, "basis": self.basis,
                "definition": "max over samples of |omega_link|^2/omega_i^2 and "
                              "|alpha_link|/omega_i^2 (pinflex.erls.validity)"}

    def to_dict(self) -> dict:
        """:meth:`summary` plus the per-sample ratios of mode 1 (``times_s``,
        ``speed_ratio``, ``accel_ratio``; None where a frequency was not positive)."""

        def clean(a):
            return [float(x) if np.isfinite(x) else None for x in np.asarray(a, dtype=float)]

        return {**self.summary(), "times_s": clean(self.times_s),
                "speed_ratio": clean(self.speed_ratio[:, 0]),
                "accel_ratio": clean(self.accel_ratio[:, 0])}

    def write_csv(self, path) -> Path:
        """One row per sample: time, link rates and both ratios per mode.

        Args:
            path: Output file (written atomically).

        Returns:
            The path written.
        """
        from pinflex.outputs import write_text

        k = self.omega_rad_s.shape[1]
        head = (["time_s", "link_speed_rad_s", "link_accel_rad_s2"]
                + [f"omega{i + 1}_rad_s" for i in range(k)]
                + [f"speed_ratio_mode{i + 1}" for i in range(k)]
                + [f"accel_ratio_mode{i + 1}" for i in range(k)])
        lines = [",".join(head)]
        for i in range(self.times_s.size):
            row = [self.times_s[i], self.link_speed_rad_s[i], self.link_accel_rad_s2[i],
                   *self.omega_rad_s[i], *self.speed_ratio[i], *self.accel_ratio[i]]
            lines.append(",".join(f"{float(v):.9g}" for v in row))
        p = Path(path)
        write_text(p, "\n".join(lines) + "\n", "validity CSV")
        return p


def draw_validity(ax, v: Validity, *, label: str = "", color=None,
                  threshold: bool = True) -> dict:
    """Draw both ratios of mode 1 against time on ``ax`` (log scale), with the threshold.

    The one drawing of the indicator on every chart (simulation, modes along a motion,
    assignment): ``|ω_L|²/ω₁²`` solid, ``|α_L|/ω₁²`` dashed, the threshold dotted. Ratios
    below 1e-12 are drawn at 1e-12 (a motion at rest has zeros on a log axis).

    Args:
        ax: A matplotlib Axes.
        v: The :class:`Validity`.
        label: Prefix of the legend entries (e.g. a design name).
        color: Line colour (default: the axes' next one).
        threshold: Draw the threshold line (once per axes).

    Returns:
        The arrays drawn: ``times_s``, ``speed_ratio``, ``accel_ratio`` (mode 1, as in
        :meth:`Validity.write_csv` and the tables) and ``threshold``.
    """
    pre = f"{label}: " if label else ""
    speed = np.asarray(v.speed_ratio[:, 0], dtype=float)
    accel = np.asarray(v.accel_ratio[:, 0], dtype=float)
    line, = ax.semilogy(v.times_s, np.maximum(np.nan_to_num(speed), 1e-12), lw=1.0,
                        color=color, label=f"{pre}|ω|²/ω₁²")
    ax.semilogy(v.times_s, np.maximum(np.nan_to_num(accel), 1e-12), lw=1.0, ls="--",
                color=line.get_color(), label=f"{pre}|α|/ω₁²")
    if threshold:
        ax.axhline(v.threshold, color="k", lw=0.9, ls=":", label=f"threshold {v.threshold:g}")
        top = max(v.threshold, v.indicator)
        ax.set_ylim(bottom=1e-5 * top, top=3.0 * top)
    ax.grid(alpha=0.3, which="both")
    return {"times_s": np.asarray(v.times_s, dtype=float), "speed_ratio": speed,
            "accel_ratio": accel, "threshold": float(v.threshold)}


def figure_with_validity(validity: Validity | None, width: float, height: float,
                         panels: int = 1, dpi: int = 110):
    """A Figure of ``panels`` stacked panels sharing time, plus the indicator's panel below.

    Args:
        validity: The :class:`Validity` to draw (:func:`draw_validity`), or None (no panel).
        width: Figure width [in].
        height: Height of the ``panels`` [in] (the indicator's panel adds 1.8 in).
        panels: Number of panels above the indicator.
        dpi: Resolution.

    Returns:
        ``(fig, axes, low)``: the Figure (on its own Agg canvas: pyplot is left alone), the list
        of the upper axes and the indicator's axes (None without ``validity``); the lowest
        panel carries the time label.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(width, height + (1.8 if validity is not None else 0.0)), dpi=dpi)
    FigureCanvasAgg(fig)
    n = panels + (validity is not None)
    ratios = [2.2] * panels + ([1.0] if validity is not None else [])
    axes = list(fig.subplots(n, 1, sharex=True, squeeze=False, height_ratios=ratios)[:, 0])
    low = None
    if validity is not None:
        low = axes.pop()
        draw_validity(low, validity)
        low.set_ylabel("eq. (1) validity", fontsize=8)
        low.legend(fontsize=6, loc="best")
    (low or axes[-1]).set_xlabel("time [s]")
    return fig, axes, low


def _max(a: np.ndarray) -> float:
    a = np.asarray(a, dtype=float)
    return float(np.nanmax(a)) if a.size and np.any(np.isfinite(a)) else 0.0


def deforming_links(model) -> tuple[str, ...]:
    """Links that carry elastic displacement: the flexible links and every link below one."""
    plan = model.plan
    out = set(plan.beams)
    for j in plan.joints:  # breadth-first: a parent is seen before its children
        if j.parent in out:
            out.add(j.child)
    return tuple(link for link in plan.links if link in out)


def link_rates(model, q, qd, qdd) -> tuple[np.ndarray, np.ndarray]:
    """Largest angular speed and acceleration of a deforming link at each sample.

    Args:
        model: The :class:`~pinflex.FlexibleModel`.
        q: Joint coordinates (n, nv) in the user convention [rad or m].
        qd: Joint velocities (n, nv).
        qdd: Joint accelerations (n, nv).

    Returns:
        ``(speed [rad/s], accel [rad/s²])``, each (n,).
    """
    import pinocchio as pin

    q, qd, qdd = (np.atleast_2d(np.asarray(v, dtype=float)) for v in (q, qd, qdd))
    pm = model.model
    data = pm.createData()
    fids = [model.plan.frame_ids[link] for link in deforming_links(model)]
    C = model.coord_map
    speed, accel = np.zeros(q.shape[0]), np.zeros(q.shape[0])
    for i in range(q.shape[0]):
        pin.forwardKinematics(pm, data, model.pin_configuration(q[i]), C @ qd[i], C @ qdd[i])
        for fid in fids:
            w = pin.getFrameVelocity(pm, data, fid, pin.LOCAL).angular
            a = pin.getFrameAcceleration(pm, data, fid, pin.LOCAL).angular
            speed[i] = max(speed[i], float(np.linalg.norm(w)))
            accel[i] = max(accel[i], float(np.linalg.norm(a)))
    return speed, accel


def sample_rates(times_s, q) -> tuple[np.ndarray, np.ndarray]:
    """Joint velocities and accelerations of samples (second-order finite differences).

    Args:
        times_s: Sample times (n,) [s], increasing.
        q: Joint samples (n, nv).

    Returns:
        ``(qd, qdd)``, each (n, nv); zeros for fewer than 3 samples.
    """
    t = np.asarray(times_s, dtype=float)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if t.size < 3:
        return np.zeros_like(q), np.zeros_like(q)
    qd = np.gradient(q, t, axis=0, edge_order=2)
    return qd, np.gradient(qd, t, axis=0, edge_order=2)


#: Size of the speed terms' error from finite-difference rates, relative to the elastic
#: forces, above which :func:`check_sample_rates` warns.
RATES_TOLERANCE = 1e-2


def sample_rates_error(times_s, q) -> tuple[float, float]:
    """Estimated error of :func:`sample_rates`, relative to the peak rates.

    ``|r_h − r_2h|`` at the samples shared with every other sample (Richardson with a
    first-order factor: the accelerations are second-order accurate inside and first-order at
    the ends; inside the estimate is about three times the error).

    Args:
        times_s: Sample times (n,) [s].
        q: Joint samples (n, nv).

    Returns:
        ``(velocity, acceleration)`` errors, each the largest over the shared samples and the
        joints relative to the largest rate of the samples (0 for a motion at rest; NaN for
        fewer than 5 samples).
    """
    t = np.asarray(times_s, dtype=float)
    q = np.atleast_2d(np.asarray(q, dtype=float))
    if t.size < 5:
        return float("nan"), float("nan")
    qd, qdd = sample_rates(t, q)
    qd2, qdd2 = sample_rates(t[::2], q[::2])
    out = []
    for fine, coarse in ((qd, qd2), (qdd, qdd2)):
        peak = float(np.abs(fine).max())
        out.append(float(np.abs(fine[::2] - coarse).max()) / peak if peak > 0 else 0.0)
    return out[0], out[1]


def check_sample_rates(times_s, q, indicator: Validity | None,
                       what: str = "the trajectory") -> dict:
    """Whether finite-difference rates are good enough for the speed terms; warn if not.

    The speed terms are ``|ω_L|²/ω_i²`` and ``|α_L|/ω_i²`` of the elastic forces, so relative
    rate errors ``e_v``, ``e_a`` (:func:`sample_rates_error`) change them by about
    ``2 e_v · max |ω_L|²/ω_i² + e_a · max |α_L|/ω_i²`` of the elastic forces. Above
    :data:`RATES_TOLERANCE` a :class:`~pinflex.exceptions.TrajectoryWarning` says so (resample
    finer, or take the interpolated motion's rates).

    Args:
        times_s: Sample times (n,) [s].
        q: Joint samples (n, nv).
        indicator: The :class:`Validity` of the motion (None: the rate errors themselves are
            compared with the tolerance).
        what: Name of the motion in the message.

    Returns:
        ``{"velocity": e_v, "acceleration": e_a, "terms": the change of the terms}`` (None
        where fewer than 5 samples leave nothing to compare).
    """
    from pinflex.exceptions import TrajectoryWarning

    e_v, e_a = sample_rates_error(times_s, q)
    if not np.isfinite(e_v):
        return {"velocity": None, "acceleration": None, "terms": None}
    if indicator is None:
        effect = max(e_v, e_a)
    else:
        effect = 2.0 * e_v * indicator.max_speed_ratio + e_a * indicator.max_accel_ratio
    if effect > RATES_TOLERANCE:
        warnings.warn(
            f"{what} is sampled too coarsely for its velocities and accelerations by finite "
            f"differences (estimated errors {100 * e_v:.2g} % and {100 * e_a:.2g} % of their "
            f"peaks): the speed terms change by about {effect:.2g} of the elastic forces; "
            "resample it finer, or take the rates of the interpolated motion (rates='motion', "
            "--rates motion)", TrajectoryWarning, stacklevel=2)
    return {"velocity": e_v, "acceleration": e_a, "terms": effect}


def validity(model, times_s, q, qd, qdd, omega_rad_s, *, threshold: float = VALIDITY_THRESHOLD,
             strict: bool = False, warn: bool = True, what: str = "the motion",
             basis: str = "locked") -> Validity:
    """The validity indicator of eq. (1) along a motion (module doc); warn or refuse above it.

    Args:
        model: The :class:`~pinflex.FlexibleModel`.
        times_s: Sample times (n,) [s].
        q: Joint coordinates (n, nv) [rad or m], user convention.
        qd: Joint velocities (n, nv).
        qdd: Joint accelerations (n, nv).
        omega_rad_s: Elastic eigenfrequencies at each sample (n, k) or (n,) [rad/s], the
            lowest first (non-positive or non-finite values are skipped).
        threshold: Indicator above which to warn (default :data:`VALIDITY_THRESHOLD`).
        strict: Raise :class:`ModelValidityError` instead of warning.
        warn: Warn with :class:`ModelValidityWarning` above the threshold.
        what: Name of the motion in the message.
        basis: What the frequencies are, reported (``"locked"``, ``"constrained"``).

    Returns:
        :class:`Validity`.

    Raises:
        ConfigurationError: Shapes do not match or the threshold is not positive.
        ModelValidityError: ``strict`` and the indicator is above the threshold.
    """
    t = np.atleast_1d(np.asarray(times_s, dtype=float))
    w = np.asarray(omega_rad_s, dtype=float)
    w = w[:, None] if w.ndim == 1 else w
    if w.ndim != 2 or w.shape[0] != t.size:
        raise ConfigurationError(f"omega_rad_s must have one row per sample ({t.size}), got "
                                 f"shape {np.shape(omega_rad_s)}")
    if not (np.isfinite(threshold) and threshold > 0.0):
        raise ConfigurationError(f"threshold = {threshold!r} must be a positive number")
    speed, accel = link_rates(model, q, qd, qdd)
    if speed.size != t.size:
        raise ConfigurationError(f"q has {speed.size} samples, times_s {t.size}")
    w2 = np.where((w > 0.0) & np.isfinite(w), w * w, np.nan)
    with np.errstate(invalid="ignore"):
        out = Validity(t, speed, accel, w, speed[:, None] ** 2 / w2, accel[:, None] / w2,
                       float(threshold), basis)
    if out.exceeded and (strict or warn):
        when, kind = out.worst()
        msg = (f"{what} is fast for eq. (1): the terms it leaves out reach {out.indicator:.3g} "
               f"of the elastic forces (|omega|^2/omega_1^2 = {out.max_speed_ratio:.3g}, "
               f"|alpha|/omega_1^2 = {out.max_accel_ratio:.3g}; worst at t = {when:.4g} s, "
               f"{kind}), above the threshold {threshold:g}: use terms='full' (centrifugal, "
               "Euler and geometric-stiffness terms) or a slower motion")
        if strict:
            raise ModelValidityError(msg, out)
        warnings.warn(msg, ModelValidityWarning, stacklevel=2)
    return out
