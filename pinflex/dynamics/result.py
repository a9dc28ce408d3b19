"""The record of a time simulation (:class:`Simulation`) and its error type."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from pinflex.exceptions import ConfigurationError, PinflexError


class SimulationError(PinflexError):
    """A time simulation could not be set up or its integrator failed."""



@dataclass
class Simulation:
    """The raw result of a time simulation.

    Attributes:
        times_s: Output times [s], (nt,).
        x: Elastic coordinates (nt, nx); ``xd`` their rates.
        q: ERLS joint coordinates, user convention (nt, nv); ``qd`` their rates.
        q_physical: Physical (motor) joint coordinates, user convention (nt, nv).
        stop_s: Time the drive stops (last trajectory sample) [s].
        drive: ``"prescribed"`` or ``"torque"``.
        joint_condition: Joint condition of the vibration after the stop: ``"locked"``
            (prescribed motion), ``"free"`` (torque drive without feedback) or ``"servo"``
            (torque drive with PD feedback: joint springs of stiffness ``servo_stiffness``).
        torque_times_s: Times of ``torques`` (the trajectory samples and the end) [s].
        torques: Motor torques in Pinocchio's joint convention (nk, nv) [N m or N].
        steps: Accepted integrator steps; ``nfev`` right-hand-side evaluations.
        time_s: Wall time of the integration (and coefficient set-up) [s].
        method: Integrator.
        error_estimate: ``"fixed"`` integrator: Richardson estimate of the time-step error
            (:class:`RichardsonRun`), relative to the largest elastic coordinate; NaN otherwise.
        observed_order: ``"fixed"`` with a ``tol`` ladder: observed order of the step error.
        validity: The validity indicator of eq. (1) along the motion
            (:class:`~pinflex.erls.validity.Validity`), or None.
        terms: ``"eq1"`` or ``"full"`` (:mod:`pinflex.dynamics.speed`).
        linearisation_error: The torque drive's linearised route
            (:mod:`pinflex.dynamics.torque_linear`): estimate of its linearisation error,
            relative to the largest elastic coordinate; NaN for the other routes.
    """

    times_s: np.ndarray
    x: np.ndarray
    xd: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    q_physical: np.ndarray
    stop_s: float
    drive: str
    joint_condition: str
    torque_times_s: np.ndarray
    torques: np.ndarray
    steps: int
    nfev: int
    time_s: float
    method: str
    servo_stiffness: float = 0.0
    error_estimate: float = float("nan")
    observed_order: float = float("nan")
    validity: Any = None
    terms: str = "eq1"
    linearisation_error: float = float("nan")


def output_times(t0: float, t1: float, sample_hz: float) -> np.ndarray:
    """Uniform output times from ``t0`` to ``t1`` [s] at about ``sample_hz`` [Hz] (at least 2)."""
    n = max(2, int(round((t1 - t0) * sample_hz)) + 1)
    return np.linspace(t0, t1, n)



def check_positive(**values) -> None:
    """Raise :class:`ConfigurationError` naming every value that is not positive and finite."""
    bad = [f"{k} = {v!r}" for k, v in values.items()
           if isinstance(v, bool | np.bool_) or not isinstance(v, int | float | np.integer |
                                                              np.floating)
           or not (np.isfinite(v) and v > 0.0)]
    if bad:
        raise ConfigurationError("must be positive and finite: " + ", ".join(bad))
