"""Gravity preload on a bent arm: pinflex beside a world-axes frame with axial-force K_G only.

Benchmark A's arm (paper 000's two links, planar) at the bent pose q_abs = (-0.4, -2.0) with
point masses 0.2 / 0.1 kg, in-plane gravity along -y, joints locked or on springs. The
reference (tests/reference_fe.py, no pinflex code) is the global frame in world axes whose
weight is a dead load on the translations and whose prestress is each element's axial-force
geometric stiffness (planar_chain_geometric): the textbook linear prestress of a frame.
pinflex's preload (pinflex.erls.preload) keeps the joints' rigid rotations as coordinates
with the loads' exact second variation on them. Both leave out the rotation of the elastic
stiffness by the static deflection (first order in the load through the static rotations),
and they leave out different parts of it, so their frequency shifts differ by a fixed
fraction of the shift (the same at every gravity: a first-order difference, not a round-off).

Prints per case and gravity: the reference's eigenvalue shift of modes 1-4 and
(pinflex shift - reference shift) / reference shift.

Run: python benchmarks/bench_preload_frame.py
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import scipy.linalg

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from reference_fe import planar_chain_geometric, planar_chain_matrices  # noqa: E402

from pinflex import FlexibleModel  # noqa: E402

CASES = (
    ("both locked", {"q1": "locked", "q2": "locked"}, ["clamped", "clamped"]),
    ("base spring 2e5 N m/rad", {"q1": 2e5, "q2": "locked"}, [2e5, "clamped"]),
    ("elbow spring 800 N m/rad", {"q1": "locked", "q2": 800.0}, ["clamped", 800.0]),
)


def main() -> None:
    """Print the comparison table."""
    q_abs, m1, m2 = [-0.4, -2.0], 0.2, 0.1
    args = (q_abs, [0.6, 0.45], [4, 3])
    for name, joints, ref_joints in CASES:
        model = FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True, joints=joints)
        K, M = planar_chain_matrices(*args, EI=69e9 * 3.97e-8, rhoA=1.9, EA=69e9 * 7.07e-4,
                                     end_masses=[m1, m2], joints=ref_joints)
        lam0 = scipy.linalg.eigh(K, M, eigvals_only=True)[:4]
        for g in (300.0, 9.81):
            KG = planar_chain_geometric(*args, rhoA=1.9, gravity=[0.0, -g],
                                        end_masses=[m1, m2], joints=ref_joints)
            lam = scipy.linalg.eigh(K + KG, M, eigvals_only=True)[:4]
            f = model.frequencies(q_abs, [m1, m2], gravity=[0.0, -g, 0.0], n_modes=4)
            ours = (2 * math.pi * f) ** 2
            shift = lam / lam0 - 1
            rel = (ours - lam) / (lam - lam0)
            print(f"{name:26s} g {g:6.2f}  shift " + " ".join(f"{v:+.3e}" for v in shift)
                  + "   pinflex vs frame, share of the shift "
                  + " ".join(f"{v:+.2e}" for v in rel))


if __name__ == "__main__":
    main()
