"""Time simulation and frequency responses of flexible-link arms (paper 000 eq. 1).

* :mod:`~pinflex.dynamics.terms`: the terms ``M, C, K, F`` of eq. (1) at a state;
* :mod:`~pinflex.dynamics.speed`: the terms eq. (1) leaves out, for ``terms="full"``;
* :mod:`~pinflex.dynamics.modes`: modes of the moving arm ("modes at speed");
* :func:`validity` (from :mod:`pinflex.erls.validity`): how far eq. (1) holds along a motion;
* :mod:`~pinflex.dynamics.motion`: joint motion through trajectory samples;
* :mod:`~pinflex.dynamics.prescribed`: prescribed joint motion (kineto-elastodynamics);
* :mod:`~pinflex.dynamics.torque`: torque drive (forward dynamics under motor torques);
* :mod:`~pinflex.dynamics.integrators`: generalized-α and ``scipy`` integrators, exact holds;
* :mod:`~pinflex.dynamics.damping`: one damping definition for simulation, FRF and export;
* :mod:`~pinflex.dynamics.frf`: receptances at a pose;
* :mod:`~pinflex.dynamics.response`: a frame's deflection, peak, RMS, residual vibration.

The names below are imported when first used (:mod:`pinflex.lazy`): the validity indicator
loads neither SciPy nor the integrators.
"""

from typing import TYPE_CHECKING

from pinflex.lazy import lazy_exports

_EXPORTS = {
    "Damping": "pinflex.dynamics.damping",
    "EomTerms": "pinflex.dynamics.terms",
    "ErlsDynamics": "pinflex.dynamics.terms",
    "JointMotion": "pinflex.dynamics.motion",
    "ModesAtSpeed": "pinflex.dynamics.modes",
    "Simulation": "pinflex.dynamics.result",
    "SimulationError": "pinflex.dynamics.result",
    "Validity": "pinflex.erls.validity",
    "VibrationReport": "pinflex.dynamics.response",
    "dominant_frequency": "pinflex.dynamics.response",
    "frame_deflection": "pinflex.dynamics.response",
    "locked_frequencies": "pinflex.dynamics.response",
    "modes_at_speed": "pinflex.dynamics.modes",
    "newmark": "pinflex.dynamics.integrators",
    "simulate_prescribed": "pinflex.dynamics.prescribed",
    "simulate_torque": "pinflex.dynamics.torque",
    "validity": "pinflex.erls.validity",
    "vibration_report": "pinflex.dynamics.response",
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "Damping",
    "EomTerms",
    "ErlsDynamics",
    "JointMotion",
    "ModesAtSpeed",
    "Simulation",
    "SimulationError",
    "Validity",
    "VibrationReport",
    "dominant_frequency",
    "frame_deflection",
    "locked_frequencies",
    "modes_at_speed",
    "newmark",
    "simulate_prescribed",
    "simulate_torque",
    "validity",
    "vibration_report",
]

if TYPE_CHECKING:
    from pinflex.dynamics.damping import Damping
    from pinflex.dynamics.integrators import newmark
    from pinflex.dynamics.modes import ModesAtSpeed, modes_at_speed
    from pinflex.dynamics.motion import JointMotion
    from pinflex.dynamics.prescribed import simulate_prescribed
    from pinflex.dynamics.response import (
        VibrationReport,
        dominant_frequency,
        frame_deflection,
        locked_frequencies,
        vibration_report,
    )
    from pinflex.dynamics.result import Simulation, SimulationError
    from pinflex.dynamics.terms import EomTerms, ErlsDynamics
    from pinflex.dynamics.torque import simulate_torque
    from pinflex.erls.validity import Validity, validity
