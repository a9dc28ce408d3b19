"""A spatial two-link arm whose modes really cross along an elbow motion, and its global FE.

Benchmark A's geometry (links of 0.6 m and 0.45 m, joints about world z, point masses at the
elbow and the tip) with a section four times stiffer out of the plane of motion than in it
(Iy = 4 Iz, a bar standing on its edge). Spatial beams: in-plane modes (ux, uy, θz) and
out-of-plane modes (uz, θx, θy) do not interact while the arm moves in its plane, so their
branches cross exactly. Near the stretched pose the second out-of-plane mode (≈ 209 Hz at
elbow 0) falls through the first in-plane mode (≈ 197 Hz): sorted modes 2 and 3 exchange
between elbow angles 0.1 and 0.2 rad (with m1 = m2 = 0.125 kg).

The reference is the global 3D frame of ``reference_fe`` (no pinflex code): its mode
*families* are told apart by where the motion lives (in-plane or out-of-plane world dofs),
which is a second, independent way of following a mode through a crossing.
"""

from __future__ import annotations

import numpy as np
from reference_fe import Beam, spatial_frame_model

L1, L2 = 0.6, 0.45
N1, N2 = 4, 3
E, G, RHO = 69e9, 26e9, 2700.0
A, IY, IZ, J = 7.07e-4, 4 * 3.97e-8, 3.97e-8, 7.94e-8


def urdf(m1: float = 0.125, m2: float = 0.125, tilt: float = 0.0) -> str:
    """URDF of the arm; ``tilt`` [rad] leans the elbow axis to link 1 (couples the families)."""
    axis2 = f"{float(np.sin(tilt))!r} 0 {float(np.cos(tilt))!r}"
    sec = f'A="{A}" Iy="{IY}" Iz="{IZ}" J="{J}"'
    mat = f'E="{E}" G="{G}" density="{RHO}"'
    return f"""<robot name="edge_bar_arm" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/><link name="link2"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <joint name="q2" type="revolute"><parent link="link1"/><child link="link2"/>
    <origin xyz="{L1} 0 0"/><axis xyz="{axis2}"/>
    <limit lower="-7" upper="7" effort="1" velocity="1"/></joint>
  <pinflex:flexible link="link1" elements="{N1}" tip="{L1} 0 0" normal="0 0 1">
    <pinflex:material {mat}/><pinflex:section {sec}/></pinflex:flexible>
  <pinflex:flexible link="link2" elements="{N2}" tip="{L2} 0 0" normal="0 0 1">
    <pinflex:material {mat}/><pinflex:section {sec}/></pinflex:flexible>
  <pinflex:point_mass name="m1" link="link1" xyz="{L1} 0 0" mass="{m1}"
                      design="true" lower="0" upper="0.25"/>
  <pinflex:point_mass name="m2" link="link2" xyz="{L2} 0 0" mass="{m2}"
                      design="true" lower="0" upper="0.25"/>
</robot>"""


def reference_families(q_rel, m1: float, m2: float, n: int = 4):
    """Global-FE frequencies [Hz] of the lowest ``n`` in-plane and out-of-plane modes.

    Args:
        q_rel: Pinocchio joint values (base angle, elbow angle) [rad].
        m1: Elbow mass [kg].
        m2: Tip mass [kg].
        n: Modes per family.

    Returns:
        ``(in_plane, out_of_plane)``, each (n,) ascending [Hz].
    """
    a1, a2 = q_rel[0], q_rel[0] + q_rel[1]
    p1 = L1 * np.array([np.cos(a1), np.sin(a1), 0.0])
    p2 = p1 + L2 * np.array([np.cos(a2), np.sin(a2), 0.0])
    beam = dict(EA=E * A, GJ=G * J, EIy=E * IY, EIz=E * IZ, rhoA=RHO * A,
                rho_Ip=RHO * (IY + IZ), vecxz=(0.0, 0.0, 1.0))
    z = np.array([0.0, 0.0, 1.0])
    fe = spatial_frame_model(np.array([np.zeros(3), p1, p2]),
                             [Beam(n_elements=N1, **beam), Beam(n_elements=N2, **beam)], [z],
                             point_masses=[(p1, m1), (p2, m2)], base=z)
    import scipy.linalg

    lam, V = scipy.linalg.eigh(fe.K, fe.M)
    lam, V = lam[fe.n_rigid:], V[:, fe.n_rigid:]
    full = fe.T @ V  # world nodal dofs (ux, uy, uz, thx, thy, thz) per node
    per_node = full.reshape(-1, 6, full.shape[1])
    inplane = (per_node[:, [0, 1, 5]] ** 2).sum(axis=(0, 1))
    total = (per_node**2).sum(axis=(0, 1))
    is_in = inplane / total > 0.5
    assert np.all((inplane / total > 1 - 1e-9) | (inplane / total < 1e-9)), "families mix"
    f = np.sqrt(lam) / (2 * np.pi)
    return f[is_in][:n], f[~is_in][:n]
