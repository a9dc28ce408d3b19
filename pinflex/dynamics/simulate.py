"""Time simulation of eq. (1): the public face of the drives and integrators.

* :mod:`~pinflex.dynamics.prescribed`: prescribed joint motion (kineto-elastodynamics);
* :mod:`~pinflex.dynamics.torque`: torque drive (forward dynamics under motor torques);
* :mod:`~pinflex.dynamics.integrators`: generalized-α (fixed and adaptive steps, Richardson),
  ``scipy.integrate`` solvers, exact propagation of the held arm;
* :mod:`~pinflex.dynamics.damping`: damping of the elastic motion;
* :mod:`~pinflex.dynamics.result`: the :class:`Simulation` record.
"""

from pinflex.dynamics.damping import Damping, modal_damping_matrix
from pinflex.dynamics.integrators import (
    RichardsonRun,
    fixed_step,
    integrate,
    newmark,
    richardson_fixed,
)
from pinflex.dynamics.prescribed import (
    PrescribedSystem,
    _ReducedSystem,
    external_forces,
    simulate_prescribed,
)
from pinflex.dynamics.result import Simulation, SimulationError
from pinflex.dynamics.torque import energy, simulate_torque

__all__ = [
    "Damping",
    "PrescribedSystem",
    "RichardsonRun",
    "Simulation",
    "SimulationError",
    "_ReducedSystem",
    "energy",
    "external_forces",
    "fixed_step",
    "integrate",
    "modal_damping_matrix",
    "newmark",
    "richardson_fixed",
    "simulate_prescribed",
    "simulate_torque",
]
