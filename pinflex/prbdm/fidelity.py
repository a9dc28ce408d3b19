r"""Model no more than the scene needs: the fewest PRBDM links that meet an error tolerance.

:func:`links_for_tolerance` fits nR chains for n = k, k + 1, ... (k = the modes the scene
needs: a chain with n joints has n modes) and returns the first whose estimated error meets
the tolerance.

The error of an nR chain is its combined loss against the converged beam truth,
:math:`e = \sqrt{e_{eig}^2 + e_{defl}^2}`, with :math:`e_{eig}` the RMS relative error of
the k lowest frequencies at the straight pose and :math:`e_{defl}` the RMS tip error over the
tip displacement at the truth's load levels (:mod:`pinflex.prbdm.problem`). The *estimator*
is the fit's own residual against that truth: the truth is the Richardson-extrapolated beam FE
(relative error estimate ~1e-9) and the elastica (ODE tolerance 1e-11), so the residual is the
error against the exact beam up to those levels, far below any useful tolerance. It is the
error on the fitted quantities (the k modes, the fitted loads), not a bound elsewhere: loads
beyond the largest fitted level are extrapolations of the chain.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..exceptions import ConfigurationError
from .beams import Planform
from .fit import PrbdmFit
from .mapping import fit_prbdm
from .problem import TruthData, compute_truth


@dataclass(frozen=True)
class LinkChoice:
    """The number of PRBDM joints picked for a tolerance.

    Attributes:
        n_joints: Joints n of the chosen chain.
        estimate: Its estimated error (combined loss against the converged truth) [-].
        truth_error: Relative error estimate of the truth's frequencies (the floor) [-].
        fit: The chosen chain's fit.
        levels: ``(n, estimate, eigen_error, deflection_error)`` of every chain fitted.
    """

    n_joints: int
    estimate: float
    truth_error: float
    fit: PrbdmFit
    levels: tuple[tuple[int, float, float, float], ...]


def links_for_tolerance(planform: Planform, tol: float, *, n_modes: int = 1,
                        max_links: int = 8, n_starts: int = 8, seed: int = 0,
                        truth: TruthData | None = None, progress: bool = False) -> LinkChoice:
    """Fewest joints n (from ``n_modes`` up) whose combined error against the truth is <= tol.

    Args:
        planform: The beam.
        tol: Tolerance on the combined relative error (frequencies and tip deflection) [-].
        n_modes: Modes the scene needs, k (frequencies of modes 1..k are judged).
        max_links: Largest n tried.
        n_starts: Multistart points per search of each fit.
        seed: Seed of the start points.
        truth: Precomputed truth with at least ``n_modes`` modes.
        progress: Progress bars on stderr.

    Returns:
        The choice, with every level fitted on the way.

    Raises:
        ConfigurationError: ``tol`` is not positive, ``n_modes`` or ``max_links`` is out of
            range, or no chain up to ``max_links`` joints meets the tolerance (the message
            gives the best estimate reached).
    """
    if not np.isfinite(tol) or tol <= 0.0:
        raise ConfigurationError(f"tol = {tol!r}: give a positive relative tolerance")
    if int(n_modes) != n_modes or n_modes < 1:
        raise ConfigurationError(f"n_modes = {n_modes!r} must be a positive integer")
    if int(max_links) != max_links or max_links < n_modes:
        raise ConfigurationError(f"max_links = {max_links!r} must be an integer >= n_modes "
                                 f"({n_modes}): an nR chain has n modes")
    if truth is None:
        truth = compute_truth(planform, int(n_modes))
    elif truth.modes.freq_hz.size < n_modes:
        raise ConfigurationError(f"the truth has {truth.modes.freq_hz.size} modes; "
                                 f"{n_modes} are needed")
    floor = float(np.max(truth.modes.rel_error_estimate[:n_modes]))
    levels = []
    for n in range(int(n_modes), int(max_links) + 1):
        fit = fit_prbdm(planform, n, int(n_modes), "combined", n_starts=n_starts, seed=seed,
                        truth=truth, progress=progress)
        estimate = float(fit.combined_error)
        levels.append((n, estimate, float(fit.eigen_error), float(fit.deflection_error)))
        if estimate <= tol:
            return LinkChoice(n, estimate, floor, fit, tuple(levels))
    best = min(levels, key=lambda level: level[1])
    raise ConfigurationError(
        f"no PRBDM up to {max_links} joints meets tol = {tol:g}: the best is {best[0]}R with "
        f"an estimated error of {best[1]:.3g}; raise max_links or the tolerance")
