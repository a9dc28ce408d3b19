"""Material points and rotational carriers of the links, for the sums of eq. (1).

Every flexible link is sampled at 4 Gauss points per element (exact for the degree-6
integrands of the cubic Hermite fields), each a point of mass ``ρA w le``; point masses are
points; a rigid link's URDF inertia is replaced by 7 points (signed masses allowed) with the
same mass, centre of mass and inertia tensor. Point ``i`` on link ``L`` sits at ``c_i`` in the
link frame and moves elastically by ``u_i = E_i(q) x``, ``E_i = C_i + D_i e_L(q)``
(:mod:`pinflex.dynamics.terms`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from pinflex import beam
from pinflex.linalg import skew

_GX, _GW = np.polynomial.legendre.leggauss(4)
_GXI, _GWXI = 0.5 * (_GX + 1.0), 0.5 * _GW


@dataclass(frozen=True)
class Carriers:
    """Material points (or rotational carriers) of one link."""

    link: str
    c: np.ndarray  # (n, 3) positions in the link frame [m]
    X: np.ndarray  # (n, 3, 6) X(c) = [I, -[c]x] (translational) or [0, I] (rotational)
    C: np.ndarray  # (n, 3, nx) constant part of the elastic map (link axes)
    D: np.ndarray | None  # (n, 3, 6) map of the link root twist, or None
    mass: np.ndarray  # (n,) [kg] or (n, 3, 3) [kg m²] for rotational carriers
    design: np.ndarray  # (n,) index of the design variable setting the mass, or -1
    n_beam: int = 0  # the first n_beam points are the link's beam Gauss points


def xmap(c: np.ndarray) -> np.ndarray:
    """``X(c) = [I, −[c]×]`` (..., 3, 6): a link twist to the velocity of the point ``c``."""
    out = np.zeros(c.shape[:-1] + (3, 6))
    out[..., :, :3] = np.eye(3)
    out[..., :, 3:] = -skew(c)
    return out


def build_carriers(model, y: np.ndarray) -> tuple[list[Carriers], list[Carriers]]:
    """``(points, rotors)``: one translational and one rotational carrier group per link.

    A link's group lists its beam's Gauss points first (``n_beam`` of them), then the points
    of its rigid inertia and its point masses (``y`` sets the design point masses).
    """
    desc = model.description
    nx = model.nx
    points: list[Carriers] = []
    rotors: list[Carriers] = []
    for link, plan in model.plan.beams.items():
        spec = plan.spec
        n = spec.elements
        le = spec.length_m / n
        shape = beam.shape_matrix(le, _GXI)  # (4, 6, 12) beam axes
        rb = spec.rotation
        cs, Cs, Ds, ms, Crs, Drs, Irs = [], [], [], [], [], [], []
        ex = rb[:, 0]
        for el in range(n):
            rows = slice(6 * el, 6 * el + 12)
            for g in range(_GXI.size):
                Nt = rb @ shape[g, :3]
                Nr = rb @ shape[g, 3:]
                cs.append((el + _GXI[g]) / n * spec.tip)
                Cs.append(Nt @ plan.sel[rows])
                Ds.append(Nt @ plan.root[rows])
                ms.append(spec.rhoA * le * _GWXI[g])
                Crs.append(Nr @ plan.sel[rows])
                Drs.append(Nr @ plan.root[rows])
                Irs.append(spec.rhoIp * le * _GWXI[g] * np.outer(ex, ex))
        c = np.array(cs)
        points.append(Carriers(link, c, xmap(c), np.array(Cs), np.array(Ds),
                               np.array(ms), -np.ones(len(ms), dtype=int), len(ms)))
        if spec.rhoIp > 0.0 and not model.planar:
            rx = np.zeros((len(Irs), 3, 6))
            rx[:, :, 3:] = np.eye(3)
            rotors.append(Carriers(link, c, rx, np.array(Crs), np.array(Drs),
                                   np.array(Irs), -np.ones(len(Irs), dtype=int), len(Irs)))
    for link in model.plan.inertias:
        ine = desc.inertias[link]
        c, m = _equivalent_points(ine.mass, ine.com, ine.inertia)
        X = xmap(c)
        points.append(Carriers(link, c, X, np.zeros((c.shape[0], 3, nx)), X, m,
                               -np.ones(m.size, dtype=int)))
    # rigid bodies (<pinflex:body>, the URDF inertia a beam link keeps): seven signed points
    # each; on a rigid link they ride with it, on a beam with the section at their centre
    at_beam = {b.name: b for b in model.plan.bodies}
    for body in desc.bodies:
        c, m = _equivalent_points(body.mass, np.asarray(body.com, float),
                                  np.asarray(body.inertia, float))
        X = xmap(c)
        if body.name not in at_beam:
            points.append(Carriers(body.link, c, X, np.zeros((c.shape[0], 3, nx)), X, m,
                                   -np.ones(m.size, dtype=int)))
            continue
        att = at_beam[body.name].attach
        to_p = xmap(c - np.asarray(body.com, float))  # from the centre's twist
        C = np.zeros((c.shape[0], 3, nx)) if att.const is None else to_p @ att.const
        D = None if att.lin is None else to_p @ att.lin
        points.append(Carriers(body.link, c, X, C, D, m, -np.ones(m.size, dtype=int)))
    for pm in model.plan.point_masses:
        name, link, xyz, att = pm.name, pm.link, pm.xyz, pm.attach
        d = model.plan.design.mass_index.get(name, -1)
        mass = y[d] if d >= 0 else model.point_mass_values[name]
        C = np.zeros((1, 3, nx)) if att.const is None else att.const[None, :3]
        D = None if att.lin is None else att.lin[None, :3]
        points.append(Carriers(link, np.asarray(xyz, float)[None], xmap(np.asarray(
            xyz, float)[None]), C, D, np.array([float(mass)]), np.array([d])))
    return _merge(points), _merge(rotors)


def _merge(groups: list[Carriers]) -> list[Carriers]:
    """One carrier group per link (missing root maps become zeros)."""
    out = []
    for link in dict.fromkeys(g.link for g in groups):
        gs = [g for g in groups if g.link == link]
        Ds = [np.zeros(g.C.shape[:2] + (6,)) if g.D is None else g.D for g in gs]
        out.append(Carriers(
            link, np.concatenate([g.c for g in gs]), np.concatenate([g.X for g in gs]),
            np.concatenate([g.C for g in gs]), np.concatenate(Ds),
            np.concatenate([g.mass for g in gs]), np.concatenate([g.design for g in gs]),
            sum(g.n_beam for g in gs)))
    return out


def _equivalent_points(mass: float, com: np.ndarray, inertia: np.ndarray):
    """Seven points (signed masses) with the given mass, centre of mass and inertia tensor.

    The second moment ``Q = ½ tr(I) 𝟙 − I`` about the centre of mass is reproduced by pairs of
    points at ``± r_k`` along its principal axes; the centre point takes the rest of the mass.
    """
    Q = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    qk, V = np.linalg.eigh(0.5 * (Q + Q.T))
    scale = max(np.sqrt(max(np.trace(inertia), 0.0) / max(mass, 1e-300)), 1e-3)
    pts = [np.asarray(com, dtype=float)]
    masses = []
    for k in range(3):
        mk = qk[k] / (2.0 * scale**2)
        for s in (1.0, -1.0):
            pts.append(com + s * scale * V[:, k])
            masses.append(mk)
    masses.insert(0, mass - sum(masses))
    return np.array(pts), np.array(masses)

