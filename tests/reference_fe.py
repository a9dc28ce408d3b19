"""Independent finite-element references for the pinflex tests.

Textbook models written from scratch with numpy and scipy only; nothing here imports
pinflex, so a test that compares pinflex against these functions compares two separate
formulations of the same mesh.

Three groups of references:

* closed forms for uniform beams and rods (Euler–Bernoulli bending, torsion, axial);
* a global planar frame model of benchmark A (paper 000's two-link arm, SPEC §5):
  2D Euler–Bernoulli frame elements in world axes, a pin at the base and a hinge at
  the elbow, either of which may instead carry a torsional spring or be clamped;
* a global spatial frame model of a serial chain of straight beams: 12-dof
  Euler–Bernoulli elements in world axes, joints that are fixed, revolute, or revolute
  with a torsional spring;
* a beam clamped to a hub in the hub's (rotating) frame: axial and bending fields with the
  geometric stiffness of a given axial force and the Coriolis coupling (:func:`beam_fe`).

Conventions shared by all models:

* SI units: lengths [m], stiffnesses EA [N], EI and GJ [N m^2], mass per length
  rhoA [kg/m], polar mass moment per length rho_Ip [kg m], point masses [kg].
* Consistent mass matrices; no rotary inertia of the cross-section in bending (plain
  Euler–Bernoulli), torsional rotary inertia rho_Ip in the spatial element.
* Eigenvalues are lambda = omega^2 [rad^2/s^2], frequencies are f = sqrt(lambda) / (2 pi)
  [Hz]. Rigid (zero) modes are counted with a relative threshold and set apart; their
  count must equal the number of revolute joints without a spring, otherwise
  ``RuntimeError``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from scipy.optimize import brentq

# |lambda| <= RIGID_RTOL * max|lambda| counts as a rigid (zero) mode. Rigid eigenvalues
# computed in double precision sit near eps * max|lambda| (~1e-16 relative), while the
# lowest elastic eigenvalue of any mesh used in the tests is above 1e-9 relative.
RIGID_RTOL = 1e-12

# ---------------------------------------------------------------------------------------
# Closed forms
# ---------------------------------------------------------------------------------------


def _sech(x: float) -> float:
    """1 / cosh(x) without overflow for large x."""
    e = math.exp(-abs(x))
    return 2.0 * e / (1.0 + e * e)


def euler_bernoulli_roots(kind: str, n: int) -> np.ndarray:
    """First ``n`` nonzero roots beta*L of a uniform Euler–Bernoulli beam.

    Each root is bracketed analytically and refined with ``scipy.optimize.brentq`` to
    full double precision.

    Args:
        kind: boundary conditions:
            ``'cantilever'`` (clamped–free): cos(bL) cosh(bL) = -1;
            ``'pinned-free'``: tan(bL) = tanh(bL), nonzero roots (the rigid rotation
            about the pin is excluded); ``'clamped-pinned'`` has the same equation;
            ``'clamped-clamped'`` / ``'free-free'``: cos(bL) cosh(bL) = 1, nonzero roots;
            ``'pinned-pinned'``: bL = k pi.
        n: number of roots.

    Returns:
        Array of shape (n,), dimensionless beta*L, ascending.

    Raises:
        ValueError: unknown ``kind`` or ``n < 1``.
    """
    if n < 1:
        raise ValueError(f"n must be >= 1, got {n}")
    k = np.arange(1, n + 1)
    if kind == "pinned-pinned":
        return k * math.pi
    if kind in ("cantilever", "clamped-free"):
        # cos x + sech x changes sign exactly once on [(k-1) pi, k pi].
        def f(x):
            return math.cos(x) + _sech(x)

        brackets = [((j - 1) * math.pi, j * math.pi) for j in k]
    elif kind in ("pinned-free", "clamped-pinned"):
        # sin x - cos x tanh x changes sign exactly once on [k pi, k pi + pi/2].
        def f(x):
            return math.sin(x) - math.cos(x) * math.tanh(x)

        brackets = [(j * math.pi, j * math.pi + 0.5 * math.pi) for j in k]
    elif kind in ("clamped-clamped", "free-free"):
        # cos x - sech x changes sign exactly once on [k pi, (k+1) pi].
        def f(x):
            return math.cos(x) - _sech(x)

        brackets = [(j * math.pi, (j + 1) * math.pi) for j in k]
    else:
        raise ValueError(
            f"unknown boundary conditions {kind!r}; expected 'cantilever', 'pinned-free', "
            "'clamped-pinned', 'clamped-clamped', 'free-free' or 'pinned-pinned'"
        )
    return np.array(
        [brentq(f, a, b, xtol=1e-15, rtol=4 * np.finfo(float).eps) for a, b in brackets]
    )


def _bending_hz(kind: str, L: float, EI: float, rhoA: float, n: int) -> np.ndarray:
    beta_l = euler_bernoulli_roots(kind, n)
    return beta_l**2 / L**2 * math.sqrt(EI / rhoA) / (2.0 * math.pi)


def cantilever_hz(L: float, EI: float, rhoA: float, n: int) -> np.ndarray:
    """First ``n`` bending frequencies [Hz] of a uniform clamped–free beam.

    f_k = (beta_k L)^2 / (2 pi L^2) * sqrt(EI / rhoA), length L [m], EI [N m^2],
    rhoA [kg/m].
    """
    return _bending_hz("cantilever", L, EI, rhoA, n)


def pinned_free_hz(L: float, EI: float, rhoA: float, n: int) -> np.ndarray:
    """First ``n`` nonzero bending frequencies [Hz] of a uniform pinned–free beam.

    Same formula as :func:`cantilever_hz` with the roots of tan(bL) = tanh(bL); the rigid
    rotation about the pin (0 Hz) is not included.
    """
    return _bending_hz("pinned-free", L, EI, rhoA, n)


def torsion_fixed_free_hz(
    L: float, G: float, J: float, rho: float, Ip: float, n: int
) -> np.ndarray:
    """First ``n`` torsional frequencies [Hz] of a uniform fixed–free shaft.

    omega_k = (2k - 1) pi / (2 L) * sqrt(G J / (rho Ip)); G [Pa], J torsion constant
    [m^4], rho [kg/m^3], Ip polar second moment of area [m^4] (the rotary inertia per
    length is rho*Ip).
    """
    k = np.arange(1, n + 1)
    return (2 * k - 1) * math.pi / (2.0 * L) * math.sqrt(G * J / (rho * Ip)) / (2.0 * math.pi)


def axial_fixed_free_hz(L: float, EA: float, rhoA: float, n: int) -> np.ndarray:
    """First ``n`` axial frequencies [Hz] of a uniform fixed–free rod.

    omega_k = (2k - 1) pi / (2 L) * sqrt(EA / rhoA); EA [N], rhoA [kg/m].
    """
    k = np.arange(1, n + 1)
    return (2 * k - 1) * math.pi / (2.0 * L) * math.sqrt(EA / rhoA) / (2.0 * math.pi)


# ---------------------------------------------------------------------------------------
# Shared eigen-solution
# ---------------------------------------------------------------------------------------


def solve_frequencies(K: np.ndarray, M: np.ndarray, n_rigid: int) -> tuple[np.ndarray, np.ndarray]:
    """Solve K phi = lambda M phi and split off the rigid modes.

    Args:
        K: symmetric positive semi-definite stiffness, shape (n, n).
        M: symmetric positive definite mass, shape (n, n).
        n_rigid: expected number of zero eigenvalues (mechanism modes).

    Returns:
        ``(eigvals, freqs_hz)``: all n eigenvalues lambda = omega^2 [rad^2/s^2] ascending
        (rigid ones included, as computed, ~0), and the n - n_rigid elastic frequencies
        [Hz] ascending.

    Raises:
        RuntimeError: the number of eigenvalues with |lambda| <= RIGID_RTOL * max|lambda|
            differs from ``n_rigid``.
    """
    eigvals = scipy.linalg.eigh(K, M, eigvals_only=True)
    zero = np.abs(eigvals) <= RIGID_RTOL * np.max(np.abs(eigvals))
    if int(zero.sum()) != n_rigid or not zero[:n_rigid].all():
        raise RuntimeError(
            f"expected {n_rigid} rigid modes, found {int(zero.sum())} eigenvalues below "
            f"{RIGID_RTOL:g} * max|lambda|; lowest eigenvalues: {eigvals[: n_rigid + 3]}"
        )
    return eigvals, np.sqrt(eigvals[n_rigid:]) / (2.0 * math.pi)


# ---------------------------------------------------------------------------------------
# Planar frame (benchmark A)
# ---------------------------------------------------------------------------------------


def planar_frame_element(
    L: float, EA: float, EI: float, rhoA: float
) -> tuple[np.ndarray, np.ndarray]:
    """Local stiffness and consistent mass of a 2D Euler–Bernoulli frame element.

    Local dof order (u1, v1, th1, u2, v2, th2): u axial, v transverse, th = dv/dx
    (counter-clockwise). Axial part EA/L [[1,-1],[-1,1]] and rhoA L/6 [[2,1],[1,2]];
    bending part the cubic Hermite matrices EI/L^3 [...] and rhoA L/420 [...].

    Returns:
        ``(k, m)``, each of shape (6, 6).
    """
    k = np.zeros((6, 6))
    m = np.zeros((6, 6))
    ax = [0, 3]
    bd = [1, 2, 4, 5]
    k[np.ix_(ax, ax)] = EA / L * np.array([[1.0, -1.0], [-1.0, 1.0]])
    m[np.ix_(ax, ax)] = rhoA * L / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    k[np.ix_(bd, bd)] = (
        EI
        / L**3
        * np.array(
            [
                [12.0, 6 * L, -12.0, 6 * L],
                [6 * L, 4 * L**2, -6 * L, 2 * L**2],
                [-12.0, -6 * L, 12.0, -6 * L],
                [6 * L, 2 * L**2, -6 * L, 4 * L**2],
            ]
        )
    )
    m[np.ix_(bd, bd)] = (
        rhoA
        * L
        / 420.0
        * np.array(
            [
                [156.0, 22 * L, 54.0, -13 * L],
                [22 * L, 4 * L**2, 13 * L, -3 * L**2],
                [54.0, 13 * L, 156.0, -22 * L],
                [-13 * L, -3 * L**2, -22 * L, 4 * L**2],
            ]
        )
    )
    return k, m


def _joint_kind(spec, where: str) -> str:
    """'hinge', 'spring' or 'clamped' from a joint spec (None, 'clamped' or a stiffness)."""
    if spec is None or (isinstance(spec, str) and spec == "hinge"):
        return "hinge"
    if isinstance(spec, str):
        if spec == "clamped":
            return "clamped"
        raise ValueError(f"{where}: unknown joint spec {spec!r}")
    if not float(spec) > 0 or not math.isfinite(float(spec)):
        raise ValueError(f"{where}: a torsional spring needs a positive finite stiffness")
    return "spring"


def planar_chain_dofs(n_elements: Sequence[int], joints: Sequence | None = None
                      ) -> list[np.ndarray]:
    """Global dof numbers of a planar chain with a base joint and joints between links.

    For link i, ``dofs[i]`` has shape (n_elements[i] + 1, 3): row j holds the global
    indices of (u, v, theta) at node j of the link, -1 for a fixed dof. Numbering walks
    the chain: base rotation first (base translations fixed), then for each link its
    nodes 1..n in order, (u, v, theta) per node; a hinge node is numbered with the link
    that ends there, and the next link only adds its own rotation there, numbered just
    before its node 1. Total 3 * sum(n_elements) + number of links with the default
    (every joint a hinge).

    ``joints`` (one per link; joint i is at the start of link i, joint 0 the base): a hinge
    or a spring gives link i its own rotation there; ``'clamped'`` shares the rotation of
    the link that ends there (the base's is fixed), so no own rotation is numbered.
    """
    kinds = [_joint_kind(None if joints is None else joints[i], f"joint {i}")
             for i in range(len(n_elements))]
    dofs = []
    counter = 0
    for i, n in enumerate(n_elements):
        table = np.full((n + 1, 3), -1, dtype=int)
        if i > 0:
            table[0, :2] = dofs[-1][-1, :2]  # hinge: shared translations
        if kinds[i] == "clamped":
            table[0, 2] = dofs[-1][-1, 2] if i > 0 else -1
        else:
            table[0, 2] = counter  # own rotation at the proximal joint
            counter += 1
        for j in range(1, n + 1):
            table[j] = np.arange(counter, counter + 3)
            counter += 3
        dofs.append(table)
    return dofs


def _sym(a: np.ndarray) -> np.ndarray:
    """Exactly symmetric copy of a matrix that is symmetric up to round-off."""
    return 0.5 * (a + a.T)


def _per_link(value, n_links: int, name: str) -> np.ndarray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (n_links,)).copy()
    if np.any(arr <= 0):
        raise ValueError(f"{name} must be positive, got {value}")
    return arr


def planar_chain_matrices(
    angles: Sequence[float],
    lengths: Sequence[float],
    n_elements: Sequence[int],
    *,
    EI,
    rhoA,
    EA,
    end_masses: Sequence[float] | None = None,
    joints: Sequence | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Assembled (K, M) of a planar serial chain of straight links, world axes.

    Link 0 starts at a pin at the origin, link i starts at the end of link i-1 where the
    two are joined by a hinge (shared translations, separate rotations). Dof layout:
    :func:`planar_chain_dofs`.

    ``joints`` (one per link, joint 0 the base, default all hinges): ``None`` a hinge, a
    number ``k`` [N m/rad] a torsional spring on the relative rotation (strain energy
    ``k (theta_child - theta_parent)^2 / 2``, ``k theta^2 / 2`` at the base), ``'clamped'``
    a rigid connection.

    Args:
        angles: absolute link angles [rad] from the world x axis, one per link.
        lengths: link lengths [m].
        n_elements: equal-length elements per link.
        EI: bending stiffness [N m^2], scalar or one per link.
        rhoA: mass per length [kg/m], scalar or one per link.
        EA: axial stiffness [N], scalar or one per link.
        end_masses: point mass [kg] at the distal end node of each link (translational
            inertia only, both directions); default none.
        joints: joint conditions, see above.

    Returns:
        ``(K, M)`` of shape (n, n), n = 3 * sum(n_elements) + len(angles).
    """
    n_links = len(angles)
    if not (len(lengths) == len(n_elements) == n_links):
        raise ValueError("angles, lengths and n_elements must have one entry per link")
    EI, rhoA, EA = (_per_link(v, n_links, s) for v, s in ((EI, "EI"), (rhoA, "rhoA"), (EA, "EA")))
    dofs = planar_chain_dofs(n_elements, joints)
    ndof = int(max(t.max() for t in dofs)) + 1
    K = np.zeros((ndof, ndof))
    M = np.zeros((ndof, ndof))
    for i in range(n_links):
        le = lengths[i] / n_elements[i]
        k_loc, m_loc = planar_frame_element(le, EA[i], EI[i], rhoA[i])
        c, s = math.cos(angles[i]), math.sin(angles[i])
        r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # local = r @ world
        t = scipy.linalg.block_diag(r, r)
        k_w, m_w = _sym(t.T @ k_loc @ t), _sym(t.T @ m_loc @ t)
        for e in range(n_elements[i]):
            idx = np.concatenate([dofs[i][e], dofs[i][e + 1]])
            keep = idx >= 0
            sel = np.ix_(idx[keep], idx[keep])
            K[sel] += k_w[np.ix_(keep, keep)]
            M[sel] += m_w[np.ix_(keep, keep)]
    if end_masses is not None:
        if len(end_masses) != n_links:
            raise ValueError("end_masses needs one entry per link")
        for i, mass in enumerate(end_masses):
            if mass < 0:
                raise ValueError(f"end mass of link {i} is negative: {mass}")
            for d in dofs[i][-1, :2]:
                M[d, d] += mass
    for i in range(n_links):
        spec = None if joints is None else joints[i]
        if _joint_kind(spec, f"joint {i}") != "spring":
            continue
        child = dofs[i][0, 2]
        parent = dofs[i - 1][-1, 2] if i > 0 else -1
        k = float(spec)
        K[child, child] += k
        if parent >= 0:
            K[parent, parent] += k
            K[parent, child] -= k
            K[child, parent] -= k
    return K, M


def n_hinges(joints: Sequence | None, n_links: int) -> int:
    """Rigid (mechanism) modes of a planar chain: the joints that are plain hinges."""
    return sum(_joint_kind(None if joints is None else joints[i], f"joint {i}") == "hinge"
               for i in range(n_links))


def planar_two_link_matrices(
    q_abs: Sequence[float],
    m1: float,
    m2: float,
    *,
    L1: float = 0.6,
    L2: float = 0.45,
    n1: int = 4,
    n2: int = 3,
    EI: float = 69e9 * 3.97e-8,
    rhoA: float = 1.9,
    EA: float = 69e9 * 7.07e-4,
    joints: Sequence | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Assembled (K, M) of benchmark A in pose ``q_abs`` (global planar frame model).

    Args:
        q_abs: absolute link angles (q1, q2) [rad], paper 000's convention (not the
            relative elbow angle).
        m1: point mass at the elbow [kg].
        m2: point mass at the tip [kg].
        L1: length of link 1 [m].
        L2: length of link 2 [m].
        n1: elements on link 1.
        n2: elements on link 2.
        EI: bending stiffness [N m^2] (SPEC §5: E = 69 GPa, I = 3.97e-8 m^4).
        rhoA: mass per length [kg/m].
        EA: axial stiffness [N] (A = 7.07e-4 m^2).
        joints: base and elbow conditions (see :func:`planar_chain_matrices`), default
            two hinges.

    Returns:
        ``(K, M)`` of shape (3*(n1+n2)+2,)*2, i.e. 23 x 23 with two hinges, with dofs
        0: base rotation; 1..3(n1-1): link-1 interior nodes (u, v, th) each;
        then the elbow (u, v, th of link 1), th of link 2 at the elbow; link-2 nodes
        1..n2 (u, v, th) each, the tip last. Default indices: elbow u, v = 10, 11,
        elbow th1 = 12, th2 = 13, tip u, v, th = 20, 21, 22.
    """
    return planar_chain_matrices(
        q_abs, [L1, L2], [n1, n2], EI=EI, rhoA=rhoA, EA=EA, end_masses=[m1, m2],
        joints=joints,
    )


def planar_two_link_frequencies(
    q_abs: Sequence[float],
    m1: float,
    m2: float,
    *,
    L1: float = 0.6,
    L2: float = 0.45,
    n1: int = 4,
    n2: int = 3,
    EI: float = 69e9 * 3.97e-8,
    rhoA: float = 1.9,
    EA: float = 69e9 * 7.07e-4,
    joints: Sequence | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues and elastic frequencies of benchmark A in pose ``q_abs``.

    Arguments as :func:`planar_two_link_matrices`.

    Returns:
        ``(eigvals, freqs_hz)``: all eigenvalues lambda = omega^2 [rad^2/s^2] ascending
        (with two hinges the first two ~0: rotation about the base pin and about the
        elbow), and the elastic frequencies [Hz] ascending (springs included: a spring's
        joint rotation is an elastic dof).
    """
    K, M = planar_two_link_matrices(
        q_abs, m1, m2, L1=L1, L2=L2, n1=n1, n2=n2, EI=EI, rhoA=rhoA, EA=EA, joints=joints
    )
    return solve_frequencies(K, M, n_rigid=n_hinges(joints, 2))


def planar_chain_geometric(
    angles: Sequence[float],
    lengths: Sequence[float],
    n_elements: Sequence[int],
    *,
    rhoA,
    gravity: Sequence[float],
    end_masses: Sequence[float] | None = None,
    joints: Sequence | None = None,
) -> np.ndarray:
    """Geometric stiffness (world axes) of a planar chain under its weight, dofs as
    :func:`planar_chain_matrices`.

    The chain is statically determinate: the axial force at a section is the axial
    component of the weight outboard of it (tension positive, ``N = F_out · e`` with ``e``
    the link direction and ``F_out`` the outboard weight). Each element adds
    ``∫ N(x) v'(x)² dx`` over its transverse Hermite dofs (v1, th1, v2, th2), ``N`` linear
    along the element, three-point Gauss (exact); the loads stay dead (vertical), so their
    potential is linear in the world-axes displacements and adds nothing else.

    Args:
        angles, lengths, n_elements, end_masses, joints: as :func:`planar_chain_matrices`.
        rhoA: mass per length [kg/m], scalar or one per link.
        gravity: world gravity (gx, gy) [m/s^2].

    Returns:
        ``K_G`` (n, n) [N/m, N, N m].
    """
    n_links = len(angles)
    rhoA = _per_link(rhoA, n_links, "rhoA")
    g = np.asarray(gravity, dtype=float)
    ends = np.zeros(n_links) if end_masses is None else np.asarray(end_masses, dtype=float)
    dofs = planar_chain_dofs(n_elements, joints)
    ndof = int(max(t.max() for t in dofs)) + 1
    KG = np.zeros((ndof, ndof))
    outboard_mass = [float(sum(rhoA[k] * lengths[k] + ends[k] for k in range(i + 1, n_links)))
                     for i in range(n_links)]
    gx, gw = np.polynomial.legendre.leggauss(3)
    for i in range(n_links):
        L, n = lengths[i], n_elements[i]
        le = L / n
        e = np.array([math.cos(angles[i]), math.sin(angles[i])])
        c, s = e
        r = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])
        t = scipy.linalg.block_diag(r, r)
        for el in range(n):
            k_loc = np.zeros((6, 6))
            for xg, wg in zip(gx, gw):
                xi = 0.5 * (xg + 1.0)
                x = (el + xi) * le  # station along the link
                mass_out = rhoA[i] * (L - x) + ends[i] + outboard_mass[i]
                N = mass_out * float(g @ e)
                # slopes of the Hermite functions of (v1, th1, v2, th2) at xi
                dN = np.array([(-6 * xi + 6 * xi**2) / le, 1 - 4 * xi + 3 * xi**2,
                               (6 * xi - 6 * xi**2) / le, -2 * xi + 3 * xi**2])
                k_loc[np.ix_([1, 2, 4, 5], [1, 2, 4, 5])] += 0.5 * wg * le * N * np.outer(dN, dN)
            k_w = _sym(t.T @ k_loc @ t)
            idx = np.concatenate([dofs[i][el], dofs[i][el + 1]])
            keep = idx >= 0
            KG[np.ix_(idx[keep], idx[keep])] += k_w[np.ix_(keep, keep)]
    return KG


# ---------------------------------------------------------------------------------------
# Spatial frame
# ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Beam:
    """Section, mesh and orientation of one straight beam of a spatial chain.

    Local axes: x from the beam's start point to its end point; ``vecxz`` is a world
    vector lying in the local x–z plane (as in OpenSees): y = vecxz × x (normalised),
    z = x × y. So local z is the part of ``vecxz`` perpendicular to the beam. Default
    ``vecxz``: world Z, or world X when the beam is parallel to Z.

    Attributes:
        EA: axial stiffness [N].
        GJ: torsional stiffness [N m^2].
        EIy: bending stiffness about local y [N m^2] (deflection along local z).
        EIz: bending stiffness about local z [N m^2] (deflection along local y).
        rhoA: mass per length [kg/m].
        rho_Ip: torsional rotary inertia per length rho*(Iy + Iz) [kg m].
        n_elements: number of equal elements.
        vecxz: optional world 3-vector fixing the local axes (see above).
    """

    EA: float
    GJ: float
    EIy: float
    EIz: float
    rhoA: float
    rho_Ip: float
    n_elements: int = 4
    vecxz: tuple[float, float, float] | None = None


def spatial_frame_element(L: float, beam: Beam, dtype=float) -> tuple[np.ndarray, np.ndarray]:
    """Local stiffness and consistent mass of a 12-dof Euler–Bernoulli element.

    Local dof order per node (u, v, w, thx, thy, thz), node 1 then node 2. Bending in
    the x–y plane uses (v, thz) with thz = dv/dx and EIz; bending in the x–z plane uses
    (w, thy) with thy = -dw/dx and EIy; axial (u) EA with mass rhoA L/6 [[2,1],[1,2]];
    torsion (thx) GJ with mass rho_Ip L/6 [[2,1],[1,2]]. The Hermite matrices are
    written out again rather than shared with :func:`planar_frame_element`, so that the
    planar/spatial cross-check compares two separate codings.

    ``dtype``: the floating type of the result (``np.longdouble`` for extended precision;
    give ``L`` in that type too).

    Returns:
        ``(k, m)``, each of shape (12, 12).
    """
    hk_scale = 1.0 / L**3
    hk = hk_scale * np.array(
        [
            [12.0, 6 * L, -12.0, 6 * L],
            [6 * L, 4 * L**2, -6 * L, 2 * L**2],
            [-12.0, -6 * L, 12.0, -6 * L],
            [6 * L, 2 * L**2, -6 * L, 4 * L**2],
        ]
    )
    hm_scale = L / 420.0
    hm = hm_scale * np.array(
        [
            [156.0, 22 * L, 54.0, -13 * L],
            [22 * L, 4 * L**2, 13 * L, -3 * L**2],
            [54.0, 13 * L, 156.0, -22 * L],
            [-13 * L, -3 * L**2, -22 * L, 4 * L**2],
        ]
    )
    flip = np.diag([1.0, -1.0, 1.0, -1.0])  # (w, thy) = (w, -dw/dx)
    rod_k = np.array([[1.0, -1.0], [-1.0, 1.0]]) / L
    rod_m = L / 6.0 * np.array([[2.0, 1.0], [1.0, 2.0]])
    k = np.zeros((12, 12), dtype=dtype)
    m = np.zeros((12, 12), dtype=dtype)
    for idx, kk, mm in (
        ([0, 6], beam.EA * rod_k, beam.rhoA * rod_m),
        ([3, 9], beam.GJ * rod_k, beam.rho_Ip * rod_m),
        ([1, 5, 7, 11], beam.EIz * hk, beam.rhoA * hm),
        ([2, 4, 8, 10], beam.EIy * flip @ hk @ flip, beam.rhoA * flip @ hm @ flip),
    ):
        k[np.ix_(idx, idx)] = kk
        m[np.ix_(idx, idx)] = mm
    return k, m


def beam_axes(start, end, vecxz=None, dtype=float) -> np.ndarray:
    """Rotation whose rows are the beam's local x, y, z axes in world coordinates.

    See :class:`Beam` for the convention. Raises ``ValueError`` for a zero-length beam
    or a ``vecxz`` parallel to it.
    """
    d = np.asarray(end, dtype) - np.asarray(start, dtype)
    length = np.linalg.norm(d)
    if length == 0:
        raise ValueError(f"beam from {start} to {end} has zero length")
    x = d / length
    if vecxz is None:
        vecxz = (
            (0.0, 0.0, 1.0)
            if np.linalg.norm(np.cross((0.0, 0.0, 1.0), x)) > 1e-6
            else (1.0, 0.0, 0.0)
        )
    y = np.cross(np.asarray(vecxz, dtype), x)
    ny = np.linalg.norm(y)
    if ny < 1e-9 * np.linalg.norm(vecxz):
        raise ValueError(f"vecxz {vecxz} is parallel to the beam from {start} to {end}")
    y /= ny
    return np.vstack([x, y, np.cross(x, y)])


def _joint_axis(spec, where: str, dtype=float) -> np.ndarray | None:
    """None for a fixed joint, the unit world axis for a revolute one."""
    if spec is None or (isinstance(spec, str) and spec == "fixed"):
        return None
    a = np.asarray(spec, dtype)
    if a.shape != (3,) or np.linalg.norm(a) == 0:
        raise ValueError(f"{where}: expected 'fixed' or a nonzero 3-vector axis, got {spec!r}")
    return a / np.linalg.norm(a)


def _perp_basis(a: np.ndarray) -> np.ndarray:
    """Two orthonormal vectors perpendicular to the unit vector ``a``, shape (2, 3)."""
    helper = np.eye(3)[np.argmin(np.abs(a))]
    e1 = np.cross(a, helper)
    e1 /= np.linalg.norm(e1)
    return np.vstack([e1, np.cross(a, e1)])


@dataclass(frozen=True)
class SpatialFrame:
    """Assembled spatial frame model.

    Attributes:
        K: stiffness in independent coordinates, shape (n, n).
        M: mass in independent coordinates, shape (n, n).
        T: map from independent coordinates to the nodal dofs of every beam, shape
            (6 * n_nodes, n); a joint node appears once per beam that touches it.
        nodes: world positions [m] of those beam nodes, shape (n_nodes, 3), beam by
            beam, start to end; node r owns rows 6r..6r+5 of ``T`` in the order
            (ux, uy, uz, thx, thy, thz), world axes.
        beam_of_node: beam index of each node, shape (n_nodes,).
        n_rigid: number of revolute joints without a spring, base included (= rigid modes).
    """

    K: np.ndarray
    M: np.ndarray
    T: np.ndarray
    nodes: np.ndarray
    beam_of_node: np.ndarray
    n_rigid: int


def spatial_frame_model(
    points,
    beams: Sequence[Beam],
    joints: Sequence = (),
    *,
    point_masses: Sequence[tuple[Sequence[float], float]] = (),
    base="fixed",
    springs: dict[int, float] | None = None,
    dtype=float,
) -> SpatialFrame:
    """Global 3D frame model of a serial chain of straight beams, world axes.

    Beam i runs from ``points[i]`` to ``points[i+1]`` and is split into
    ``beams[i].n_elements`` equal 12-dof elements (:func:`spatial_frame_element`,
    rotated to world axes with :func:`beam_axes`). Every beam node carries 6 world dofs
    (ux, uy, uz, thx, thy, thz). Joints are modelled by a transformation matrix ``T`` from
    independent coordinates to those dofs (K = T^T K_beams T, M = T^T M_beams T):

    * ``'fixed'``: the two beam ends share all 6 dofs;
    * revolute with world unit axis a: the ends share the 3 translations and the 2
      rotations perpendicular to a; each end has its own rotation about a.

    The base (start of beam 0) is ``'fixed'`` (clamped) or revolute about a world axis
    (translations and the rotations perpendicular to the axis are zero, the rotation
    about it is free). The tip (end of the last beam) is free.

    Args:
        points: world points [m], shape (n_beams + 1, 3).
        beams: one :class:`Beam` per beam.
        joints: one spec per interior joint (``points[1:-1]``): ``'fixed'`` (or None) or
            a world axis 3-vector for a revolute joint.
        point_masses: pairs (world point [m], mass [kg]); each point must be a node
            (tolerance 1e-9 of the model size). Translational inertia only.
        base: ``'fixed'`` or a world axis 3-vector for a revolute base.
        springs: torsional springs ``{joint: k}`` [N m/rad] on revolute joints, joint 0 the
            base and joint i + 1 the interior joint ``joints[i]``: strain energy
            ``k (theta_child - theta_parent)^2 / 2`` of the rotations about the joint axis
            (``k theta^2 / 2`` at the base). A sprung joint is not a mechanism, so it does
            not count in ``n_rigid``. A clamped joint is ``'fixed'``.
        dtype: The floating type of the assembly (``np.longdouble``: every element matrix,
            rotation and product in extended precision).

    Raises:
        ValueError: inconsistent sizes, non-positive section values, a zero-length beam,
            a bad axis, or a point mass that is not at a node.
    """
    points = np.asarray(points, dtype)
    n_beams = len(beams)
    if points.shape != (n_beams + 1, 3):
        raise ValueError(f"points must have shape ({n_beams + 1}, 3), got {points.shape}")
    if len(joints) != n_beams - 1:
        raise ValueError(
            f"need {n_beams - 1} joint specs between {n_beams} beams, got {len(joints)}"
        )
    for i, b in enumerate(beams):
        for name in ("EA", "GJ", "EIy", "EIz", "rhoA", "rho_Ip"):
            if not getattr(b, name) > 0:
                raise ValueError(f"beam {i}: {name} must be positive, got {getattr(b, name)}")
        if b.n_elements < 1:
            raise ValueError(f"beam {i}: n_elements must be >= 1, got {b.n_elements}")

    # Beam nodes (a joint node once per beam) and their full dof offsets.
    node_list, owner, first_node = [], [], []
    for i, b in enumerate(beams):
        first_node.append(len(node_list))
        s = np.linspace(0.0, 1.0, b.n_elements + 1, dtype=dtype)[:, None]
        node_list.extend(points[i] + s * (points[i + 1] - points[i]))
        owner.extend([i] * (b.n_elements + 1))
    nodes = np.array(node_list)
    n_full = 6 * len(nodes)

    # Independent coordinates -> full dofs: collect the columns of T.
    columns: list[dict[int, float]] = []  # one {row: value} per independent coordinate
    add = columns.append

    def add_identity(row0: int) -> None:
        for r in range(6):
            add({row0 + r: 1.0})

    springs = dict(springs or {})
    for key, k in springs.items():
        if not (0 <= key < n_beams) or not k > 0:
            raise ValueError(f"spring {key}: k = {k} must be positive on an existing joint")
    spring_pairs = []  # (stiffness, parent column or -1, child column)
    n_rigid = 0
    axis = _joint_axis(base, "base", dtype)
    if axis is not None:
        add({6 * first_node[0] + 3 + c: axis[c] for c in range(3)})
        if 0 in springs:
            spring_pairs.append((springs[0], -1, len(columns) - 1))
        else:
            n_rigid += 1
    elif 0 in springs:
        raise ValueError("a spring at the base needs a revolute base")
    for i, b in enumerate(beams):
        start = 6 * first_node[i]
        for j in range(1, b.n_elements):
            add_identity(start + 6 * j)
        end = start + 6 * b.n_elements
        if i == n_beams - 1:
            add_identity(end)
            continue
        nxt = 6 * first_node[i + 1]
        axis = _joint_axis(joints[i], f"joint {i}", dtype)
        for c in range(3):  # shared translations
            add({end + c: 1.0, nxt + c: 1.0})
        if axis is None:
            for c in range(3, 6):
                add({end + c: 1.0, nxt + c: 1.0})
        else:
            for e in _perp_basis(axis):  # shared rotations perpendicular to the axis
                add(
                    {
                        **{end + 3 + c: e[c] for c in range(3)},
                        **{nxt + 3 + c: e[c] for c in range(3)},
                    }
                )
            add({end + 3 + c: axis[c] for c in range(3)})  # parent's rotation about a
            add({nxt + 3 + c: axis[c] for c in range(3)})  # child's rotation about a
            if i + 1 in springs:
                spring_pairs.append((springs[i + 1], len(columns) - 2, len(columns) - 1))
            else:
                n_rigid += 1
    T = np.zeros((n_full, len(columns)), dtype=dtype)
    for col, entries in enumerate(columns):
        for row, val in entries.items():
            T[row, col] = val

    # Block-diagonal beam matrices in world axes.
    K_full = np.zeros((n_full, n_full), dtype=dtype)
    M_full = np.zeros((n_full, n_full), dtype=dtype)
    for i, b in enumerate(beams):
        le = np.linalg.norm(points[i + 1] - points[i]) / b.n_elements
        k_loc, m_loc = spatial_frame_element(le, b, dtype)
        t = np.kron(np.eye(4, dtype=dtype), beam_axes(points[i], points[i + 1], b.vecxz, dtype))
        k_w, m_w = _sym(t.T @ k_loc @ t), _sym(t.T @ m_loc @ t)
        for e in range(b.n_elements):
            sl = slice(6 * (first_node[i] + e), 6 * (first_node[i] + e + 2))
            K_full[sl, sl] += k_w
            M_full[sl, sl] += m_w

    size = max(1.0, float(np.ptp(points, axis=0).max()))
    for point, mass in point_masses:
        if mass < 0:
            raise ValueError(f"point mass at {point} is negative: {mass}")
        dist = np.linalg.norm(nodes - np.asarray(point, dtype), axis=1)
        r = int(np.argmin(dist))
        if dist[r] > 1e-9 * size:
            raise ValueError(f"point mass at {point} is not at a node (nearest node {nodes[r]})")
        M_full[6 * r : 6 * r + 3, 6 * r : 6 * r + 3] += mass * np.eye(3)  # one copy only

    for key in springs:
        if key > 0 and _joint_axis(joints[key - 1], f"joint {key - 1}") is None:
            raise ValueError(f"spring {key}: joint {key - 1} is fixed, not revolute")
    K_ind = T.T @ K_full @ T
    for k, parent, child in spring_pairs:
        K_ind[child, child] += k
        if parent >= 0:
            K_ind[parent, parent] += k
            K_ind[parent, child] -= k
            K_ind[child, parent] -= k
    return SpatialFrame(
        K=_sym(K_ind),
        M=_sym(T.T @ M_full @ T),
        T=T,
        nodes=nodes,
        beam_of_node=np.array(owner),
        n_rigid=n_rigid,
    )


def spatial_frame_frequencies(
    points,
    beams: Sequence[Beam],
    joints: Sequence = (),
    *,
    point_masses: Sequence[tuple[Sequence[float], float]] = (),
    base="fixed",
    springs: dict[int, float] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues and elastic frequencies of a spatial frame chain.

    Arguments as :func:`spatial_frame_model`.

    Returns:
        ``(eigvals, freqs_hz)``: all eigenvalues lambda = omega^2 [rad^2/s^2] ascending
        (the first ``n_rigid`` ~0, one per revolute joint including a revolute base), and
        the elastic frequencies [Hz] ascending.
    """
    model = spatial_frame_model(points, beams, joints, point_masses=point_masses, base=base,
                                springs=springs)
    return solve_frequencies(model.K, model.M, model.n_rigid)


def spatial_frame_frequencies_extended(
    points,
    beams: Sequence[Beam],
    joints: Sequence = (),
    *,
    point_masses: Sequence[tuple[Sequence[float], float]] = (),
    base="fixed",
    springs: dict[int, float] | None = None,
    n_modes: int = 4,
) -> np.ndarray:
    """The lowest ``n_modes`` elastic frequencies [Hz] of a spatial chain, to ~1e-11.

    The nodal coordinates of a fine mesh lose the low modes to rounding (their strain energy
    is a small difference of large nodal terms): a double-precision solve of 3 × 32 elements
    is off by ~2e-8. Here the model is assembled in extended precision (``np.longdouble``,
    every element matrix, rotation and product), the lowest modes are taken from a double
    solve and refined by a Rayleigh–Ritz step in extended precision (the reduced pencil of
    those vectors): the eigenvalue error is then second order in the vectors' error.
    Arguments as :func:`spatial_frame_model`.
    """
    model = spatial_frame_model(points, beams, joints, point_masses=point_masses, base=base,
                                springs=springs, dtype=np.longdouble)
    r, k = model.n_rigid, n_modes
    _, V = scipy.linalg.eigh(model.K.astype(float), model.M.astype(float),
                             subset_by_index=[0, r + k + 1])
    Phi = V.astype(np.longdouble)
    Kr = Phi.T @ (model.K @ Phi)
    Mr = Phi.T @ (model.M @ Phi)
    lam = scipy.linalg.eigh(_sym(Kr.astype(float)), _sym(Mr.astype(float)), eigvals_only=True)
    return np.sqrt(lam[r : r + k]) / (2.0 * math.pi)


def planar_chain_tangent(
    angles: Sequence[float],
    lengths: Sequence[float],
    n_elements: Sequence[int],
    *,
    EI: float,
    EA: float,
    rhoA: float,
    gravity: Sequence[float],
    end_masses: Sequence[float],
    joints: Sequence,
) -> np.ndarray:
    """Tangent stiffness of a planar chain at its static state under its weight, geometrically
    exact (corotational elements), dofs as :func:`planar_chain_matrices`.

    Each element's chord turns by ``β − β₀``; its local axial stretch ``l − l₀`` and end
    rotations ``θ − (β − β₀)`` carry the linear element forces (Crisfield's corotational
    beam: exact for large rigid motions, small strains). The weight is a dead load with the
    potential of the element's cubic shape, ``−w·(x_a + x_b)/2 − (w·n) l₀ (θ_a − θ_b)/12``.
    The static state is found by Newton with every joint held at the pose (springs
    compensated, as a servo does); the tangent there is the central difference of the total
    force (step 1e-7), springs added on the joints' relative rotations.

    Returns:
        ``K_t`` (n, n) [N/m, N, N m].
    """
    held = ["clamped"] * len(angles)

    def positions():
        out, start = [], np.zeros(2)
        for a, length, n in zip(angles, lengths, n_elements):
            e = np.array([math.cos(a), math.sin(a)])
            out.append(np.array([start + e * length * k / n for k in range(n + 1)]))
            start = start + e * length
        return out

    X = positions()
    g = np.asarray(gravity, dtype=float)

    def force(d, dofs, springs):
        G = np.zeros(d.size)

        def at(i):
            return d[i] if i >= 0 else 0.0

        for i, (a0, length, n) in enumerate(zip(angles, lengths, n_elements)):
            l0 = length / n
            w = rhoA * l0 * g
            for el in range(n):
                ia, ib = dofs[i][el], dofs[i][el + 1]
                xa = X[i][el] + [at(ia[0]), at(ia[1])]
                xb = X[i][el + 1] + [at(ib[0]), at(ib[1])]
                dx = xb - xa
                length_now = float(np.hypot(*dx))
                c, s = dx / length_now
                turn = math.atan2(s, c) - a0
                ta, tb = at(ia[2]) - turn, at(ib[2]) - turn
                N = EA * (length_now - l0) / l0
                M1, M2 = EI / l0 * (4 * ta + 2 * tb), EI / l0 * (2 * ta + 4 * tb)
                r = np.array([-c, -s, 0.0, c, s, 0.0])
                z = np.array([s, -c, 0.0, -s, c, 0.0]) / length_now
                f = r * N + (np.eye(6)[2] - z) * M1 + (np.eye(6)[5] - z) * M2
                nvec, evec = np.array([-s, c]), np.array([c, s])
                f[[0, 1]] -= w / 2
                f[[3, 4]] -= w / 2
                f[2] -= (w @ nvec) * l0 / 12
                f[5] += (w @ nvec) * l0 / 12
                f += (w @ evec) * l0 * (at(ia[2]) - at(ib[2])) / 12 * z
                idx = np.concatenate([ia, ib])
                np.add.at(G, idx[idx >= 0], f[idx >= 0])
        for i, m in enumerate(end_masses):
            tip = dofs[i][-1, :2]
            np.add.at(G, tip[tip >= 0], -m * g[tip >= 0])
        for child, parent, k in springs:
            rel = d[child] - (d[parent] if parent >= 0 else 0.0)
            G[child] += k * rel
            if parent >= 0:
                G[parent] -= k * rel
        return G

    def tangent(d, dofs, springs, h=1e-7):
        K = np.zeros((d.size, d.size))
        for k in range(d.size):
            step = np.zeros(d.size)
            step[k] = h
            K[:, k] = (force(d + step, dofs, springs) - force(d - step, dofs, springs)) / (2 * h)
        return _sym(K)

    dofs_h = planar_chain_dofs(n_elements, held)
    d = np.zeros(int(max(t.max() for t in dofs_h)) + 1)
    for _ in range(30):
        G = force(d, dofs_h, [])
        if np.abs(G).max() < 1e-9:
            break
        d -= np.linalg.solve(tangent(d, dofs_h, []), G)
    dofs = planar_chain_dofs(n_elements, joints)
    dj = np.zeros(int(max(t.max() for t in dofs)) + 1)
    for th, tj in zip(dofs_h, dofs):  # a held base rotation stays 0 in the sprung layout
        for a, b in zip(th.ravel(), tj.ravel()):
            if a >= 0 and b >= 0:
                dj[b] = d[a]
    springs = []
    for i, spec in enumerate(joints):
        if _joint_kind(spec, f"joint {i}") == "spring":
            springs.append((dofs[i][0, 2], dofs[i - 1][-1, 2] if i > 0 else -1, float(spec)))
    return tangent(dj, dofs, springs)


# ---------------------------------------------------------------------------------------
# A beam in a rotating frame
# ---------------------------------------------------------------------------------------


def beam_fe(n, N, *, L, EI, EA, rhoA):
    """``(M, G, K, K_N, fu, fv)`` of a uniform beam clamped at ``s = 0`` (axial ``u``, bending
    ``v`` in one plane), for its rotating-frame equations about the clamp.

    Axial (linear) and bending (cubic Hermite) fields, consistent matrices by 6-point Gauss
    quadrature over ``n`` elements of a beam of length ``L`` [m] (``EI`` [N m²], ``EA`` [N],
    ``rhoA`` [kg/m]); ``N(s)`` [N] is a callable axial force (tension positive).

    ``K_N`` is the geometric stiffness ``∫ N(s) v'² ds`` of the axial force ``N(s)``;
    ``G = Muvᵀ − Muv`` (the Coriolis coupling: ``2Ω G``); ``fu``, ``fv`` the loads
    ``∫ ρA s N ds`` on ``u`` and ``v`` (centrifugal per unit Ω², Euler per unit θ̈). Node dofs
    ``(u, v, θ)``, the root's removed.
    """
    le = L / n
    gx, gw = np.polynomial.legendre.leggauss(6)
    xi, w = 0.5 * (gx + 1.0), 0.5 * gw * le
    nd = 3 * (n + 1)
    Muu, Mvv, Muv, K, KN = (np.zeros((nd, nd)) for _ in range(5))
    fu, fv = np.zeros(nd), np.zeros(nd)
    for e in range(n):
        s = (e + xi) * le
        Nu, dNu, Nv, dNv, ddNv = (np.zeros((xi.size, nd)) for _ in range(5))
        Nu[:, 3 * e], Nu[:, 3 * e + 3] = 1.0 - xi, xi
        dNu[:, 3 * e], dNu[:, 3 * e + 3] = -1.0 / le, 1.0 / le
        cols = [3 * e + 1, 3 * e + 2, 3 * e + 4, 3 * e + 5]
        Nv[:, cols] = np.stack([1 - 3 * xi**2 + 2 * xi**3, le * (xi - 2 * xi**2 + xi**3),
                                3 * xi**2 - 2 * xi**3, le * (xi**3 - xi**2)], axis=1)
        dNv[:, cols] = np.stack([(6 * xi**2 - 6 * xi) / le, 1 - 4 * xi + 3 * xi**2,
                                 (6 * xi - 6 * xi**2) / le, 3 * xi**2 - 2 * xi], axis=1)
        ddNv[:, cols] = np.stack([(12 * xi - 6) / le**2, (6 * xi - 4) / le,
                                  (6 - 12 * xi) / le**2, (6 * xi - 2) / le], axis=1)
        Muu += rhoA * np.einsum("k,ki,kj->ij", w, Nu, Nu)
        Mvv += rhoA * np.einsum("k,ki,kj->ij", w, Nv, Nv)
        Muv += rhoA * np.einsum("k,ki,kj->ij", w, Nu, Nv)
        K += EA * np.einsum("k,ki,kj->ij", w, dNu, dNu)
        K += EI * np.einsum("k,ki,kj->ij", w, ddNv, ddNv)
        KN += np.einsum("k,k,ki,kj->ij", w, N(s), dNv, dNv)
        fu += rhoA * np.einsum("k,k,ki->i", w, s, Nu)
        fv += rhoA * np.einsum("k,k,ki->i", w, s, Nv)
    keep = np.arange(3, nd)
    Muu, Mvv, Muv, K, KN = (a[np.ix_(keep, keep)] for a in (Muu, Mvv, Muv, K, KN))
    return Muu + Mvv, Muv.T - Muv, K, KN, fu[keep], fv[keep]
