"""Gravity preload on a bent arm: pinflex beside two planar frame references.

Benchmark A's arm (paper 000's two links, planar) at the bent pose q_abs = (-0.4, -2.0) with
point masses 0.2 / 0.1 kg, in-plane gravity along -y, joints locked or on springs, 16 + 12
elements (the shipped mesh refined 4 times; the references use the same mesh). References
(tests/reference_fe.py, no pinflex code):

* ``exact``: the geometrically exact tangent stiffness at the static state (corotational
  elements, Newton statics with the joints held at the pose; planar_chain_tangent), with the
  mass of the pose;
* ``frame K_G``: the world-axes frame with each element's axial-force geometric stiffness
  (planar_chain_geometric), the textbook linear prestress of a frame.

pinflex's preload (pinflex.erls.preload) and the frame K_G both leave out what the static
deflection does to links bent across their axes (their stiffness turned with the deflected
shape, the shear-force prestress). Prints per case: the exact eigenvalue shift of modes 1-4,
then each model's shift as a multiple of the exact one (1 = right).

Run: python benchmarks/bench_preload_frame.py
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import scipy.linalg

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from reference_fe import (  # noqa: E402
    planar_chain_geometric,
    planar_chain_matrices,
    planar_chain_tangent,
)

from pinflex import FlexibleModel  # noqa: E402
from pinflex.description import load  # noqa: E402
from pinflex.erls.fidelity import refined  # noqa: E402

CASES = (
    ("both locked", {"q1": "locked", "q2": "locked"}, ["clamped", "clamped"]),
    ("base spring 2e5 N m/rad", {"q1": 2e5, "q2": "locked"}, [2e5, "clamped"]),
    ("elbow spring 800 N m/rad", {"q1": "locked", "q2": 800.0}, ["clamped", 800.0]),
)
EI, EA, RHOA = 69e9 * 3.97e-8, 69e9 * 7.07e-4, 1.9


def main() -> None:
    """Print the comparison table."""
    q_abs, masses, g = [-0.4, -2.0], [0.2, 0.1], 30.0
    mesh = [16, 12]
    args = (q_abs, [0.6, 0.45], mesh)
    desc = refined(load(ROOT / "urdf" / "two_link.urdf"), 4)
    print(f"gravity {g} m/s^2 along -y, {mesh[0]} + {mesh[1]} elements")
    for name, joints, ref_joints in CASES:
        model = FlexibleModel(desc, planar=True, joints=joints)
        K, M = planar_chain_matrices(*args, EI=EI, rhoA=RHOA, EA=EA, end_masses=masses,
                                     joints=ref_joints)
        lam0 = scipy.linalg.eigh(K, M, eigvals_only=True)[:4]
        Kt = planar_chain_tangent(*args, EI=EI, EA=EA, rhoA=RHOA, gravity=[0.0, -g],
                                  end_masses=masses, joints=ref_joints)
        exact = scipy.linalg.eigh(Kt, M, eigvals_only=True)[:4] - lam0
        KG = planar_chain_geometric(*args, rhoA=RHOA, gravity=[0.0, -g], end_masses=masses,
                                    joints=ref_joints)
        frame = scipy.linalg.eigh(K + KG, M, eigvals_only=True)[:4] - lam0
        f = model.frequencies(q_abs, masses, gravity=[0.0, -g, 0.0], n_modes=4)
        ours = (2 * math.pi * f) ** 2 - lam0
        print(f"{name:26s} exact shift " + " ".join(f"{v:+.3e}" for v in exact / lam0))
        print(f"{'':26s} pinflex / exact " + " ".join(f"{v:+7.3f}" for v in ours / exact)
              + "   frame K_G / exact " + " ".join(f"{v:+7.3f}" for v in frame / exact))



if __name__ == "__main__":
    main()
