"""Time of ERLS modal analysis: assembly against eigensolve, one pose and 152 poses.

Run: ``python benchmarks/bench_modal.py``. Prints, for benchmark A (planar, 23 dof) and the
flexible UR5 (spatial), the time of one modal analysis split into assembly and eigensolve, and
the time of exact frequencies along 152 poses against the bare generalized eigensolves
(``scipy.linalg.eigh(K, M)`` one by one) of the same 152 matrix pairs (SPEC §7 target: at most
1.5×).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.linalg
from timing import best_of

from pinflex.erls import FlexibleModel

ROOT = Path(__file__).resolve().parents[1]


def one_pose(name, model, q):
    """Print assembly vs eigensolve for one pose."""
    t_asm = best_of(lambda: model.matrices(q), number=20)
    M, K = model.matrices(q)
    t_eig = best_of(lambda: model.eigvals_from(M[None], K[None]), number=20)
    t_modes = best_of(lambda: model.modes(q), number=10)
    total = t_asm + t_eig
    print(f"{name}: {model.ndof} dof; one modal analysis (frequencies) {1e3 * total:.3f} ms = "
          f"assembly {1e3 * t_asm:.3f} ms ({100 * t_asm / total:.0f} %) + eigensolve "
          f"{1e3 * t_eig:.3f} ms ({100 * t_eig / total:.0f} %); with mode shapes and nodal "
          f"motion {1e3 * t_modes:.3f} ms")


def many_poses(name, model, Q):
    """Print exact frequencies at many poses against bare eigensolves of the same pairs."""
    M, K = model.matrices(Q)
    t_bare = best_of(lambda: [scipy.linalg.eigh(K[i], M[i], eigvals_only=True)
                              for i in range(len(Q))], repeat=5)
    t_ours = best_of(lambda: model.frequencies(Q), repeat=5)
    t_asm = best_of(lambda: model.matrices(Q), repeat=5)
    print(f"{name}: exact frequencies at {len(Q)} poses {1e3 * t_ours:.2f} ms (assembly "
          f"{1e3 * t_asm:.2f} ms); bare eigh of the same {len(Q)} pairs {1e3 * t_bare:.2f} ms; "
          f"ratio {t_ours / t_bare:.2f}x (target <= 1.5x)")


def main():
    """Run the benchmark."""
    a = FlexibleModel(ROOT / "urdf" / "two_link.urdf", planar=True)
    q0 = np.array([1.817, 5.312])
    one_pose("benchmark A", a, q0)
    t = np.linspace(0, 1, 152)
    Q = np.column_stack([1.817 + 0.6 * np.sin(2 * np.pi * t), 5.312 + 0.2 * np.cos(2 * np.pi * t)])
    many_poses("benchmark A", a, Q)
    ur5 = FlexibleModel(ROOT / "urdf" / "ur5_flexible.xml")
    qu = np.array([0.0, -1.0, 1.2, 0.3, 0.5, 0.0])
    one_pose("flexible UR5", ur5, qu)
    many_poses("flexible UR5", ur5, qu + 0.3 * np.sin(np.outer(2 * np.pi * t, np.arange(1, 7))))


if __name__ == "__main__":
    main()
