"""Helpers of the ringing tests: a rest-to-rest motion and a frequency read off a signal.

Written without pinflex: the motion is a quintic blend, the frequency a least-squares fit of
a sum of undamped sinusoids whose frequencies are free (the guesses only start the search).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import least_squares


def quintic(t: np.ndarray, duration: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Rest-to-rest blend s(t) from 0 to 1 over ``duration`` [s], with s' and s''."""
    u = np.clip(np.asarray(t, dtype=float) / duration, 0.0, 1.0)
    s = 10 * u**3 - 15 * u**4 + 6 * u**5
    ds = (30 * u**2 - 60 * u**3 + 30 * u**4) / duration
    dds = (60 * u - 180 * u**2 + 120 * u**3) / duration**2
    inside = (np.asarray(t) >= 0) & (np.asarray(t) <= duration)
    return s, np.where(inside, ds, 0.0), np.where(inside, dds, 0.0)


def ring_frequencies(t: np.ndarray, y: np.ndarray, guesses_hz) -> np.ndarray:
    """Frequencies [Hz] of ``y(t) = c + sum_i a_i cos(w_i t) + b_i sin(w_i t)``, fitted.

    Args:
        t: Sample times [s].
        y: Signal.
        guesses_hz: Starting frequencies, one per sinusoid.
    """
    t = np.asarray(t, dtype=float) - t[0]
    scale = np.abs(y - y.mean()).max()
    y = (y - y.mean()) / scale

    def amplitudes(w):
        cols = [np.ones_like(t)]
        for wi in w:
            cols += [np.cos(wi * t), np.sin(wi * t)]
        A = np.column_stack(cols)
        coef = np.linalg.lstsq(A, y, rcond=None)[0]
        return A, coef

    def residual(w):
        A, coef = amplitudes(w)
        return A @ coef - y

    w0 = 2 * np.pi * np.asarray(guesses_hz, dtype=float)
    sol = least_squares(residual, w0, x_scale=w0, xtol=1e-15, ftol=1e-15, gtol=1e-15)
    return sol.x / (2 * np.pi)
