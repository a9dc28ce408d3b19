"""Helpers of the lumped-arm tests and benchmark, written without pinflex.

A rest-to-rest motion (quintic blend); a frequency read off a signal (least-squares fit of a
sum of undamped sinusoids whose frequencies are free: the guesses only start the search); a
clamped straight link as annotated URDF; the static tip deflection of an exported lumped
link read from MuJoCo's own model.
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


def clamped_link_urdf(length: float, E: float, second_moment: float, linear_density: float,
                      elements: int) -> str:
    """A straight flexible link along x, clamped at its root (its joint locked), bending in y."""
    return f"""<robot name="link1" xmlns:pinflex="urn:pinflex:urdf:1">
  <link name="base"/><link name="link1"/>
  <joint name="q1" type="revolute"><parent link="base"/><child link="link1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <pinflex:joint name="q1" locked="true"/>
  <pinflex:flexible link="link1" elements="{elements}" tip="{length} 0 0" normal="0 0 1">
    <pinflex:material E="{E}" linear_density="{linear_density}"/>
    <pinflex:section A="7.07e-4" Iy="{second_moment}" Iz="{second_moment}"
                     J="{2 * second_moment}"/>
  </pinflex:flexible>
</robot>"""


def mujoco_tip_deflection(mujoco, m, force: float, length: float) -> float:
    """Static tip deflection [m] of a clamped lumped link MJCF under a transverse tip force.

    From MuJoCo's own model of the file: the translation Jacobian (``mj_jac``) at the far end
    of the last segment's cylinder and the joint stiffnesses, ``d = J K^-1 J^T F`` (hinges
    about z, force along y).
    """
    d = mujoco.MjData(m)
    mujoco.mj_forward(m, d)
    g = m.ngeom - 1  # the last segment's cylinder (from its hinge to the link's tip)
    body = int(m.geom_bodyid[g])
    half = d.geom_xmat[g].reshape(3, 3)[:, 2] * m.geom_size[g][1]
    tip = max((d.geom_xpos[g] + half, d.geom_xpos[g] - half),
              key=lambda p: float(np.linalg.norm(p - d.xpos[body])))  # not the hinge end
    if abs(tip[0] - length) > 1e-9 * length:
        raise RuntimeError(f"tip point {tip} is not the link's end")
    jacp = np.zeros((3, m.nv))
    mujoco.mj_jac(m, d, jacp, None, tip, body)
    k = np.array(m.jnt_stiffness[m.dof_jntid])
    return float(jacp[1] @ (jacp[1] / k) * force)
