"""Eigenfrequencies of a UR5 whose upper arm and forearm are hollow aluminium tubes.

The upstream URDF from example-robot-data is used unchanged: ``urdf/ur5_flexible.xml`` is an
overlay that names it and adds the beams and a payload. Run ``python examples/ur5_flexible_modes.py``.
"""

from pathlib import Path

import numpy as np

import pinflex

URDF = Path(__file__).resolve().parents[1] / "urdf" / "ur5_flexible.xml"

arm = pinflex.FlexibleModel(URDF)
q = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])  # [rad], Pinocchio's joint values
result = arm.modes(q, n_modes=6)
# the lowest frequency with a 2 kg payload instead of 1 kg
heavier = arm.frequencies(q, {"payload": 2.0}, n_modes=1)[0]

if __name__ == "__main__":
    print(f"{arm.ndof} dof ({arm.nx} elastic + {arm.nv} rigid); design {arm.design_names}")
    for i, f in enumerate(result.freq_hz, start=1):
        print(f"mode {i}: {f:9.3f} Hz")
    print(f"mode 1 with a 2 kg payload: {heavier:.3f} Hz")
