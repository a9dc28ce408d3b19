"""Time simulation and frequency responses of flexible-link arms (paper 000 eq. 1).

* :mod:`~pinflex.dynamics.terms`: the terms ``M, C, K, F`` of eq. (1) at a state;
* :mod:`~pinflex.dynamics.speed`: the terms eq. (1) leaves out, for ``terms="full"``;
* :mod:`~pinflex.dynamics.modes`: modes of the moving arm ("modes at speed");
* :mod:`~pinflex.dynamics.motion`: joint motion through trajectory samples;
* :mod:`~pinflex.dynamics.prescribed`: prescribed joint motion (kineto-elastodynamics);
* :mod:`~pinflex.dynamics.torque`: torque drive (forward dynamics under motor torques);
* :mod:`~pinflex.dynamics.saved`: a run saved as data (``pinflex simulate --out``), read back;
* :mod:`~pinflex.dynamics.integrators`: generalized-α and ``scipy`` integrators, exact holds;
* :mod:`~pinflex.dynamics.damping`: one damping definition for simulation, FRF and export;
* :mod:`~pinflex.dynamics.frf`: receptances at a pose;
* :mod:`~pinflex.dynamics.export`: linear models (state space) about a moving state;
* :mod:`~pinflex.dynamics.response`: a frame's deflection, peak, RMS, residual vibration.

How far eq. (1) holds along a motion (the validity indicator every simulation reports):
:mod:`pinflex.erls.validity`.
"""

from pinflex.dynamics.modes import ModesAtSpeed, modes_at_speed, modes_at_speed_along
from pinflex.dynamics.motion import JointMotion
from pinflex.dynamics.response import (
    VibrationReport,
    dominant_frequency,
    frame_deflection,
    locked_frequencies,
    vibration_report,
)
from pinflex.dynamics.simulate import (
    Damping,
    Simulation,
    SimulationError,
    newmark,
    simulate_prescribed,
)
from pinflex.dynamics.terms import EomTerms, ErlsDynamics
from pinflex.dynamics.torque import simulate_torque

__all__ = [
    "Damping",
    "EomTerms",
    "ErlsDynamics",
    "JointMotion",
    "ModesAtSpeed",
    "Simulation",
    "SimulationError",
    "VibrationReport",
    "dominant_frequency",
    "frame_deflection",
    "locked_frequencies",
    "modes_at_speed",
    "modes_at_speed_along",
    "newmark",
    "simulate_prescribed",
    "simulate_torque",
    "vibration_report",
]
