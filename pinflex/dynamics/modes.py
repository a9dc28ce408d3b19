"""Modes of the moving arm ("modes at speed"): the locked-joint system on a rigid state.

At a joint state ``(q, q̇, q̈)`` held by the motors (the prescribed drive's locked joints), the
small elastic motion obeys ``M ẍ + C ẋ + K x = f`` (:func:`pinflex.dynamics.prescribed.
locked_coefficients`): ``C`` holds the gyroscopic (Coriolis) terms of the elastic motion and,
with ``terms="full"``, ``K`` holds the centrifugal and Euler terms and the geometric stiffness
of the axial loads (:mod:`pinflex.dynamics.speed`). Its frequencies are the imaginary parts of
the eigenvalues of the first-order form ``[[0, I], [−M⁻¹K, −M⁻¹C]]`` (a gyroscopic system at
constant speed: purely imaginary pairs while it is stable). At ``q̇ = 0`` they are the
locked-joint frequencies of the pose; on a spinning cantilever the flapwise ones rise with the
speed and the chordwise ones much less (checked against a published table in the tests).

A state whose stiffness is no longer positive (a column past buckling, a beam spun into
divergence) gives an eigenvalue with a positive real part: :class:`ModesAtSpeed` reports it in
``unstable`` and its frequency in ``growth_rate_1_s``. With an angular acceleration the frozen
system is not conservative (the Euler term): real parts of order ``|α_L| / ω_i`` of either sign
appear, which are not a growth of the moving arm. :func:`modes_at_speed_along` follows a motion.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import scipy.linalg

from pinflex.dynamics.prescribed import locked_coefficients
from pinflex.dynamics.speed import check_terms


@dataclass(frozen=True)
class ModesAtSpeed:
    """Modes of the locked-joint system at one rigid state (module doc).

    Attributes:
        freq_hz: Frequencies (k,) ascending [Hz], ``|Im λ| / 2π`` of the eigenvalue pairs.
        growth_rate_1_s: ``Re λ`` (k,) [1/s] (0 for a conservative stable state).
        shapes: Complex mode shapes (nx, k) over the elastic coordinates (displacement part).
        unstable: Whether an eigenvalue has a positive real part above round-off.
        terms: ``"eq1"`` or ``"full"``.
    """

    freq_hz: np.ndarray
    growth_rate_1_s: np.ndarray
    shapes: np.ndarray = field(repr=False)
    unstable: bool
    terms: str


def modes_at_speed(dyn, q, qd=None, qdd=None, *, terms: str = "full",
                   n_modes: int | None = None) -> ModesAtSpeed:
    """Frequencies of the locked-joint arm moving through ``(q, q̇, q̈)`` (module doc).

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics` (its design and gravity).
        q: Joint coordinates (nv,) [rad or m], user convention.
        qd: Joint velocities (nv,) (default zero).
        qdd: Joint accelerations (nv,) (default zero).
        terms: ``"full"`` (default here: the terms that change the modes at speed) or
            ``"eq1"`` (gyroscopic terms only).
        n_modes: Number of modes (default all ``nx``).

    Returns:
        :class:`ModesAtSpeed`.
    """
    terms = check_terms(terms)
    nv = dyn.nv
    q = np.asarray(q, dtype=float)
    qd = np.zeros(nv) if qd is None else np.asarray(qd, dtype=float)
    qdd = np.zeros(nv) if qdd is None else np.asarray(qdd, dtype=float)
    c = locked_coefficients(dyn, q, qd, qdd, terms=terms)
    return modes_of(c.M, c.C, c.K, terms, n_modes=n_modes)


def modes_of(M, C, K, terms: str, *, n_modes: int | None = None) -> ModesAtSpeed:
    """Modes of ``M ẍ + C ẋ + K x = 0`` (the locked-joint system of a rigid state).

    Args:
        M: Mass (nx, nx).
        C: Velocity terms (nx, nx) (gyroscopic, undamped).
        K: Stiffness (nx, nx), unsymmetric with the Euler term.
        terms: ``"eq1"`` or ``"full"``, reported.
        n_modes: Number of modes (default all ``nx``).

    Returns:
        :class:`ModesAtSpeed`.
    """
    nx = M.shape[0]
    k = nx if n_modes is None else max(1, min(int(n_modes), nx))
    if not np.any(C) and np.allclose(K, K.T, rtol=0.0, atol=1e-13 * np.abs(K).max()):
        lam, phi = scipy.linalg.eigh(K, M)
        w = np.sqrt(np.abs(lam))
        growth = np.where(lam < 0.0, w, 0.0)
        freq = np.where(lam < 0.0, 0.0, w) / (2.0 * np.pi)
        order = np.argsort(lam)[:k]
        return ModesAtSpeed(freq[order], growth[order], phi[:, order].astype(complex),
                            bool(np.any(lam < -1e-9 * np.abs(lam).max())), terms)
    lam, V = _state_eig(M, C, K)
    keep = lam.imag >= 0.0  # one of each conjugate pair (real ones: divergence)
    lam, V = lam[keep], V[:, keep]
    order = np.argsort(np.abs(lam.imag))[:k]
    lam, V = lam[order], V[:, order]
    scale = np.abs(lam).max() if lam.size else 1.0
    return ModesAtSpeed(np.abs(lam.imag) / (2.0 * np.pi), lam.real, V[:nx],
                        bool(np.any(lam.real > 1e-7 * scale)), terms)


def _state_eig(M, C, K):
    """Eigenvalues and vectors of ``ẏ = A y``, ``y = [x; ẋ]``, lowest ones to round-off.

    With ``K`` invertible, from the eigenvalues ``μ = 1/λ`` of ``A⁻¹ = [[−K⁻¹C, −K⁻¹M],
    [I, 0]]``: the low modes are then the largest of that matrix and keep their relative
    accuracy beside the stiff (axial) modes, where ``A``'s own eigenvalues lose it as
    ``(ω_max/ω)²``: on a spinning beam mode 1 came out 4e-8 relative apart between two
    descriptions of one beam, 2e-12 by ``A⁻¹``. A singular ``K`` (a rigid or critical mode)
    takes ``A`` itself.
    """
    nx = M.shape[0]
    try:
        KiCM = np.linalg.solve(K, np.hstack([C, M]))
    except np.linalg.LinAlgError:
        KiCM = None
    if KiCM is not None and np.all(np.isfinite(KiCM)):
        B = np.zeros((2 * nx, 2 * nx))
        B[:nx] = -KiCM
        B[nx:, :nx] = np.eye(nx)
        mu, V = scipy.linalg.eig(B)
        if np.all(mu != 0.0):
            return 1.0 / mu, V
    Mi = np.linalg.inv(M)
    A = np.zeros((2 * nx, 2 * nx))
    A[:nx, nx:] = np.eye(nx)
    A[nx:, :nx] = -Mi @ K
    A[nx:, nx:] = -Mi @ C
    return scipy.linalg.eig(A)


#: How the joint rates of sampled motions are obtained (:func:`modes_at_speed_along`).
RATES = ("motion", "samples")


@dataclass(frozen=True)
class ModesAtSpeedAlong:
    """Modes of the moving arm at the samples of a motion (:func:`modes_at_speed_along`).

    Attributes:
        times_s: Sample times (ns,) [s].
        freq_hz: Lowest frequencies (ns, k) [Hz], sorted at each sample.
        growth_rate_1_s: Real parts (ns, k) [1/s].
        unstable: Per sample, whether an eigenvalue grows (ns,).
        terms: ``"eq1"`` or ``"full"``.
        q: Joint coordinates (ns, nv) of the samples [rad or m].
        qd: Joint velocities (ns, nv) used.
        qdd: Joint accelerations (ns, nv) used.
        joint_names: Names of the columns of ``q``.
        rates: How ``qd``, ``qdd`` were obtained (:data:`RATES`).
        validity: The validity indicator of eq. (1) against these frequencies
            (:class:`pinflex.erls.validity.Validity`), or None.
        rates_error: With ``rates="samples"``: the estimated relative errors of the
            finite-difference rates and their effect on the speed terms
            (:func:`pinflex.erls.validity.check_sample_rates`), else None.
    """

    times_s: np.ndarray
    freq_hz: np.ndarray
    growth_rate_1_s: np.ndarray
    unstable: np.ndarray
    terms: str
    q: np.ndarray | None = field(default=None, repr=False)
    qd: np.ndarray | None = field(default=None, repr=False)
    qdd: np.ndarray | None = field(default=None, repr=False)
    joint_names: tuple[str, ...] = ()
    rates: str = "motion"
    validity: Any = field(default=None, repr=False)
    rates_error: dict | None = field(default=None, repr=False)

    def columns(self) -> list[str]:
        """CSV header: ``t``, joints, their rates, per mode frequency and growth, flags."""
        names = list(self.joint_names)
        k = self.freq_hz.shape[1]
        cols = ["t", *names, *(f"d({n})/dt" for n in names), *(f"d2({n})/dt2" for n in names)]
        cols += [f"mode{i + 1}_hz" for i in range(k)]
        cols += [f"mode{i + 1}_growth_1_s" for i in range(k)] + ["unstable"]
        if self.validity is not None:
            cols += ["speed_ratio", "accel_ratio"]
        return cols

    def to_csv(self, path) -> Path:
        """Write one row per sample (17 significant digits); returns the path."""
        import csv

        from pinflex.outputs import atomic_path

        path = Path(path)
        with atomic_path(path, "CSV") as tmp, open(tmp, "w", newline="") as stream:
            w = csv.writer(stream)
            w.writerow(self.columns())
            nan = np.full((self.times_s.size, len(self.joint_names)), np.nan)
            q, qd, qdd = (nan if a is None else a for a in (self.q, self.qd, self.qdd))
            for s in range(self.times_s.size):
                row = [self.times_s[s], *q[s], *qd[s], *qdd[s],
                       *self.freq_hz[s], *self.growth_rate_1_s[s]]
                cells = [repr(float(v)) for v in row] + [str(int(self.unstable[s]))]
                if self.validity is not None:
                    cells += [repr(float(self.validity.speed_ratio[s, 0])),
                              repr(float(self.validity.accel_ratio[s, 0]))]
                w.writerow(cells)
        return path

    def to_dict(self) -> dict:
        """JSON-ready dictionary (lists of floats)."""
        return {
            "what": "modes of the moving arm, every joint held by its motor on the motion "
                    "(pinflex.dynamics.modes)",
            "terms": self.terms,
            "rates": self.rates,
            "joint_names": list(self.joint_names),
            "times_s": self.times_s.tolist(),
            "q": None if self.q is None else self.q.tolist(),
            "qd": None if self.qd is None else self.qd.tolist(),
            "qdd": None if self.qdd is None else self.qdd.tolist(),
            "frequencies_hz": self.freq_hz.tolist(),
            "growth_rate_1_s": self.growth_rate_1_s.tolist(),
            "unstable": [bool(u) for u in self.unstable],
            "summary": [{"mode": c + 1, "min_hz": float(self.freq_hz[:, c].min()),
                         "max_hz": float(self.freq_hz[:, c].max()),
                         "start_hz": float(self.freq_hz[0, c]),
                         "end_hz": float(self.freq_hz[-1, c])}
                        for c in range(self.freq_hz.shape[1])],
            "validity": None if self.validity is None else self.validity.to_dict(),
            "rates_error": self.rates_error,
        }

    def to_json(self) -> str:
        """:meth:`to_dict` as one JSON text."""
        from pinflex.outputs import json_text

        return json_text(self.to_dict())

    def table(self) -> str:
        """A readable terminal table: one line per mode, then the validity line."""
        t = self.times_s
        lines = [f"modes at speed (terms={self.terms}, every joint held by its motor): "
                 f"{t.size} samples over {t[-1] - t[0]:.4g} s, rates from the "
                 + ("samples (second-order finite differences)" if self.rates == "samples"
                    else "rest-to-rest quintic spline"),
                 f"{'mode':>4}  {'min [Hz]':>12}  {'max [Hz]':>12}  {'start [Hz]':>12}  "
                 f"{'end [Hz]':>12}"]
        for row in self.to_dict()["summary"]:
            lines.append(f"{row['mode']:>4}  {row['min_hz']:>12.6g}  {row['max_hz']:>12.6g}  "
                         f"{row['start_hz']:>12.6g}  {row['end_hz']:>12.6g}")
        if np.any(self.unstable):
            bad = np.flatnonzero(self.unstable)
            lines.append(f"UNSTABLE at {bad.size} samples (first t = {t[bad[0]]:.4g} s): an "
                         "eigenvalue grows (buckling or spin divergence; or the frozen Euler "
                         "term at an accelerating state)")
        v = self.validity
        if v is not None:
            lines.append(
                f"validity of eq. (1): |omega|^2/omega_1^2 = {v.max_speed_ratio:.3g}, "
                f"|alpha|/omega_1^2 = {v.max_accel_ratio:.3g} (threshold {v.threshold:g}"
                + ("; the full terms are in these modes)" if self.terms == "full" else
                   f"{'; EXCEEDED: use --terms full' if v.exceeded else ''})"))
        return "\n".join(lines)

    def figure(self):
        """The chart as a matplotlib Figure: frequencies, and the indicator below (if set)."""
        from pinflex.erls.validity import figure_with_validity

        fig, (ax,), _ = figure_with_validity(self.validity, 7.5, 4.2)
        for c in range(self.freq_hz.shape[1]):
            ax.plot(self.times_s, self.freq_hz[:, c], lw=1.6, label=f"mode {c + 1} (sorted)")
        ax.set_ylabel("frequency [Hz]")
        ax.set_title(f"modes of the moving arm (terms={self.terms}, joints held)", fontsize=9)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, loc="best")
        fig.tight_layout()
        return fig

    def plot(self, path) -> Path:
        """Write :meth:`figure` as a PNG; returns the path."""
        from pinflex.outputs import save_figure

        return save_figure(self.figure(), path)


def modes_at_speed_along(dyn, trajectory, *, terms: str = "full", n_modes: int = 3,
                         times=None, rates: str = "motion", strict: bool = False,
                         validity_threshold: float | None = None,
                         progress=None) -> ModesAtSpeedAlong:
    """:func:`modes_at_speed` at every sample of a joint motion.

    Joint rates:

    * ``rates="motion"`` (default): those of the prescribed drive's joint motion
      (:class:`~pinflex.dynamics.motion.JointMotion`: its exact rates, or the rest-to-rest
      quintic spline through a trajectory's samples, which starts and ends at rest);
    * ``rates="samples"``: second-order finite differences of the trajectory's samples
      (:func:`pinflex.erls.validity.sample_rates`, ``numpy.gradient`` with second-order ends;
      exact for motions quadratic in time, e.g. a constant spin), the rates the validity
      indicator of :func:`pinflex.erls.along.modes_along` uses. A trajectory file holds
      positions only; this is the scheme of ``pinflex modes --trajectory --terms``. A
      :class:`~pinflex.exceptions.TrajectoryWarning` says when the samples are too coarse
      for the speed terms (:func:`pinflex.erls.validity.check_sample_rates`).

    The validity indicator (:mod:`pinflex.erls.validity`) is computed against the lowest
    three frequencies at each sample; with ``terms="eq1"`` it warns above its threshold
    (``strict`` refuses), with ``terms="full"`` the terms it measures are in the modes and it
    is reported only.

    Args:
        dyn: The :class:`~pinflex.dynamics.ErlsDynamics`.
        trajectory: A :class:`~pinflex.Trajectory` (columns matched to the joints by name) or a
            :class:`~pinflex.dynamics.motion.JointMotion` (``rates="motion"`` only).
        terms: ``"full"`` (default) or ``"eq1"``.
        n_modes: Modes per sample.
        times: Sample times (default the trajectory's; ``rates="motion"`` only).
        rates: ``"motion"`` or ``"samples"`` (above).
        strict: With ``terms="eq1"``, raise
            :class:`~pinflex.exceptions.ModelValidityError` above the threshold.
        validity_threshold: Default :data:`pinflex.erls.validity.VALIDITY_THRESHOLD`.
        progress: A progress bar advanced by one per sample (optional).

    Returns:
        :class:`ModesAtSpeedAlong`.
    """
    from pinflex.dynamics.motion import JointMotion
    from pinflex.erls.validity import (
        VALIDITY_THRESHOLD,
        check_sample_rates,
        sample_rates,
        validity,
    )
    from pinflex.exceptions import ConfigurationError

    terms = check_terms(terms)
    if rates not in RATES:
        raise ConfigurationError(f"rates = {rates!r}: choose 'motion' (the prescribed drive's "
                                 "joint motion) or 'samples' (finite differences)")
    names = tuple(getattr(dyn.model, "joint_names", ()))
    if rates == "samples":
        if isinstance(trajectory, JointMotion) or times is not None:
            raise ConfigurationError("rates='samples' differentiates a Trajectory's own "
                                     "samples: pass a Trajectory and no times")
        from pinflex.erls.along import trajectory_for

        q = trajectory_for(dyn.model, trajectory)
        t = np.asarray(trajectory.times_s, dtype=float)
        if t.size < 3:
            raise ConfigurationError(f"rates='samples' needs at least 3 samples, got {t.size}")
        qd, qdd = sample_rates(t, q)
    else:
        if not isinstance(trajectory, JointMotion):
            from pinflex.trajectory.samples import in_model_order

            trajectory = JointMotion(in_model_order(dyn.model, trajectory))
        motion = trajectory
        t = np.asarray(motion.trajectory.times_s if times is None else times, dtype=float)
        q, qd, qdd = motion.sample(t)
    k = max(1, min(int(n_modes), dyn.nx))
    freq, growth = np.empty((t.size, k)), np.empty((t.size, k))
    unstable = np.zeros(t.size, dtype=bool)
    for i in range(t.size):
        r = modes_at_speed(dyn, q[i], qd[i], qdd[i], terms=terms, n_modes=k)
        freq[i], growth[i], unstable[i] = r.freq_hz, r.growth_rate_1_s, r.unstable
        if progress is not None:
            progress.update(1)
    indicator = None
    if t.size >= 2:
        indicator = validity(
            dyn.model, t, q, qd, qdd, 2.0 * np.pi * freq[:, :3], strict=strict and terms == "eq1",
            warn=terms == "eq1", what="the trajectory", basis="at speed",
            threshold=VALIDITY_THRESHOLD if validity_threshold is None else validity_threshold)
    rates_error = check_sample_rates(t, q, indicator) if rates == "samples" else None
    return ModesAtSpeedAlong(t, freq, growth, unstable, terms, np.asarray(q), np.asarray(qd),
                             np.asarray(qdd), names, rates, indicator, rates_error)
