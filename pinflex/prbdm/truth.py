r"""Reference ("truth") solutions for a non-uniform cantilever beam.

Two independent references replace paper 001's COMSOL runs:

* **Bending frequencies** from a 1D Euler-Bernoulli finite-element model with Hermite cubic
  elements and consistent mass, nodes on every planform vertex (the width is linear inside each
  element, so element matrices are integrated exactly by Gauss rules).
* **Large deflection** from the geometrically exact planar elastica under dead end loads (a
  force of fixed direction and an end moment; cantilever or fixed-guided), solved by shooting
  in :mod:`pinflex.prbdm.elastica` (:func:`elastica_tip` and :func:`end_load_equilibrium` are
  re-exported here).

Conditioning: the direct generalized problem :math:`K\phi = \lambda M\phi` loses digits as
elements are added, because a symmetric eigensolver's absolute error is about
:math:`\varepsilon\,\lambda_{max}` and :math:`\lambda_{max}/\lambda_1 \sim N^4`; the nodal
compliance form :math:`M\phi = \mu K\phi` helps but still inherits the Cholesky factor of an
ill-conditioned K. pinflex instead rewrites the same Hermite model in energy-normalised relative
(element-deformation) coordinates, where the stiffness is the identity and the low modes are the
largest eigenvalues of a well-scaled symmetric matrix (:func:`relative_compliance_matrix`).
Meshes are graded so that near-hinges stay in the asymptotic range (:func:`beam_mesh`), and the
:math:`h^4` discretisation error is removed by Richardson extrapolation on three nested meshes,
whose two extrapolants must agree (a built-in convergence check, :func:`beam_frequencies`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from ..beam import hermite_shapes
from ..exceptions import InvalidBeam, TruthNotConverged
from .beams import Planform
from .elastica import ElasticaSolution, elastica_tip, end_load_equilibrium

# Exact for EI of degree <= 3 (a linear depth taper: I ~ t^3) and rho A of degree <= 2.
_GAUSS2 = np.polynomial.legendre.leggauss(3)
_GAUSS4 = np.polynomial.legendre.leggauss(5)

__all__ = ["BeamModes", "ElasticaSolution", "assemble_beam", "beam_frequencies", "beam_mesh",
           "elastica_tip", "element_matrices", "end_load_equilibrium", "fe_eigenvalues",
           "relative_compliance_matrix"]


def beam_mesh(planform: Planform, max_element_m: float, max_stiffness_ratio: float = 1.5,
              refine: int = 1) -> np.ndarray:
    r"""Graded mesh with every planform vertex a node [m].

    In each planform piece the nodes are equally spaced in
    :math:`g(x) = (x - x_1)/h_{max} + |\ln(EI(x)/EI(x_1))| / \ln r_{max}`, so no element is
    longer than ``max_element_m`` and no element's bending stiffness varies by more than the
    ratio ``max_stiffness_ratio``. Near a pinch (a vertex of very small width) this grades the
    mesh geometrically, which keeps the Hermite elements in their asymptotic range. Meshes with
    ``refine = 1, 2, 4, ...`` are nested images of uniform meshes under the same smooth map, as
    Richardson extrapolation needs.

    Args:
        planform: The beam.
        max_element_m: Largest element length of the ``refine = 1`` mesh [m].
        max_stiffness_ratio: Largest EI ratio across one element of that mesh (> 1).
        refine: Integer subdivision factor applied to every piece.

    Returns:
        Node abscissae, shape (n_elements + 1,), increasing from 0 to L [m].

    Raises:
        InvalidBeam: If a mesh parameter is out of range.
    """
    if not np.isfinite(max_element_m) or max_element_m <= 0.0:
        raise InvalidBeam(f"max_element_m = {max_element_m!r} must be a positive length [m]")
    if not max_stiffness_ratio > 1.0:
        raise InvalidBeam(f"max_stiffness_ratio = {max_stiffness_ratio!r} must exceed 1")
    if int(refine) != refine or refine < 1:
        raise InvalidBeam(f"refine = {refine!r} must be a positive integer")
    x1, x2 = planform.x_m[:-1], planform.x_m[1:]
    i1, i2 = planform.area_moment_m4(x1), planform.area_moment_m4(x2)
    # A taper to zero at the tip: grade towards a floor of EI (the elements stay exact).
    i2 = np.maximum(i2, 1e-4 * i1)
    log_r = np.log(max_stiffness_ratio)

    def g(x: np.ndarray, piece: np.ndarray) -> np.ndarray:
        frac = (x - x1[piece]) / (x2[piece] - x1[piece])
        ratio = 1.0 + frac * (i2[piece] / i1[piece] - 1.0)
        return (x - x1[piece]) / max_element_m + np.abs(np.log(ratio)) / log_r

    pieces = np.arange(x1.size)
    g_end = g(x2, pieces)
    counts = np.maximum(1, np.ceil(g_end - 1e-9)).astype(int) * int(refine)
    piece = np.repeat(pieces, counts)
    step = np.concatenate([np.arange(c) for c in counts])
    target = step / counts[piece] * g_end[piece]
    lo, hi = x1[piece].copy(), x2[piece].copy()
    for _ in range(64):
        mid = 0.5 * (lo + hi)
        below = g(mid, piece) < target
        lo = np.where(below, mid, lo)
        hi = np.where(below, hi, mid)
    nodes = np.where(step == 0, x1[piece], 0.5 * (lo + hi))
    return np.concatenate([nodes, planform.x_m[-1:]])


def element_matrices(planform: Planform, nodes_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Hermite element stiffness and consistent mass matrices, vectorised over elements.

    Exact for a width and a thickness linear inside each element (3-point Gauss for stiffness,
    5-point for mass). Element dofs are (w1 [m], w1' [rad], w2 [m], w2' [rad]).

    Args:
        planform: The beam (its vertices must be nodes of the mesh).
        nodes_m: Node abscissae, shape (N + 1,) [m].

    Returns:
        (k_el, m_el), each shape (N, 4, 4).
    """
    x1, x2 = nodes_m[:-1], nodes_m[1:]
    h = (x2 - x1)[:, None]
    e = planform.material.youngs_modulus_pa
    rho = planform.material.density_kg_m3
    xi2 = 0.5 * (_GAUSS2[0] + 1.0)
    xi4 = 0.5 * (_GAUSS4[0] + 1.0)
    _, b = hermite_shapes(xi2[None, :], h)
    ei = e * planform.area_moment_m4(x1[:, None] + h * xi2)
    k_el = np.einsum("eq,eqi,eqj->eij", 0.5 * _GAUSS2[1] * h * ei, b, b)
    n, _ = hermite_shapes(xi4[None, :], h)
    rho_a = rho * planform.area_m2(x1[:, None] + h * xi4)
    m_el = np.einsum("eq,eqi,eqj->eij", 0.5 * _GAUSS4[1] * h * rho_a, n, n)
    return k_el, m_el


def assemble_beam(planform: Planform, nodes_m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Clamped-free stiffness and consistent mass matrices of the Hermite beam mesh.

    Degrees of freedom per node are (w [m], w' [rad]); the root node is removed (clamped).

    Args:
        planform: The beam (its vertices must be nodes of the mesh).
        nodes_m: Node abscissae, shape (N + 1,) [m].

    Returns:
        (K, M), each shape (2N, 2N).
    """
    k_el, m_el = element_matrices(planform, nodes_m)
    n_el = k_el.shape[0]
    dofs = 2 * np.arange(n_el)[:, None] + np.arange(4)
    rows = np.broadcast_to(dofs[:, :, None], (n_el, 4, 4)).ravel()
    cols = np.broadcast_to(dofs[:, None, :], (n_el, 4, 4)).ravel()
    size = 2 * (n_el + 1)
    k_glob = np.zeros((size, size))
    m_glob = np.zeros((size, size))
    np.add.at(k_glob, (rows, cols), k_el.ravel())
    np.add.at(m_glob, (rows, cols), m_el.ravel())
    return k_glob[2:, 2:], m_glob[2:, 2:]


def relative_compliance_matrix(planform: Planform, nodes_m: np.ndarray) -> np.ndarray:
    r"""Mass matrix in energy-normalised relative (element-deformation) coordinates.

    Each element's deformation relative to the rigid motion of its left node,
    :math:`d_e = (w_{e+1} - w_e - h_e w'_e,\ w'_{e+1} - w'_e)`, enters the strain energy only
    through its own clamped-left element stiffness :math:`k_e = R_e R_e^T`, so
    :math:`\chi_e = R_e^T d_e` makes the stiffness the identity. Nodal displacements follow
    from :math:`\chi` by cumulative sums of rotations and offsets (no cancellation), giving
    :math:`u = B\chi` and :math:`C = B^T M B`. The eigenvalues of C are
    :math:`\mu = 1/\omega^2` of exactly the same Hermite model, but an ordinary symmetric
    eigensolver now computes the large :math:`\mu` (low modes) to about machine precision
    relative to :math:`\mu_1`, whatever the mesh grading.

    Args:
        planform: The beam.
        nodes_m: Node abscissae, shape (N + 1,) [m].

    Returns:
        C, shape (2N, 2N), symmetric positive definite [s^2].
    """
    nodes = np.asarray(nodes_m, dtype=float)
    k_el, m_el = element_matrices(planform, nodes)
    n_el = k_el.shape[0]
    chol = np.linalg.cholesky(k_el[:, 2:, 2:])
    g = np.linalg.inv(np.swapaxes(chol, 1, 2))
    offset = nodes[1:, None] - nodes[None, 1:]
    reach = (np.arange(n_el)[:, None] >= np.arange(n_el)[None, :]).astype(float)
    b4 = np.zeros((n_el, 2, n_el, 2))
    b4[:, 0, :, :] = reach[:, :, None] * (g[None, :, 0, :] + offset[:, :, None] * g[None, :, 1, :])
    b4[:, 1, :, :] = reach[:, :, None] * g[None, :, 1, :]
    b = b4.reshape(2 * n_el, 2 * n_el)
    _, m_glob = assemble_beam(planform, nodes)
    c = b.T @ (m_glob @ b)
    return 0.5 * (c + c.T)


def fe_eigenvalues(planform: Planform, nodes_m: np.ndarray, n_modes: int,
                   formulation: str = "relative") -> np.ndarray:
    r"""Lowest bending eigenvalues of one Hermite mesh, without extrapolation.

    Args:
        planform: The beam.
        nodes_m: Node abscissae including every planform vertex, shape (N + 1,) [m].
        n_modes: Number of modes.
        formulation: ``"relative"`` (default) solves the standard problem of
            :func:`relative_compliance_matrix`; ``"compliance"`` solves
            :math:`M\phi = \mu K\phi` in nodal coordinates; ``"stiffness"`` solves
            :math:`K\phi = \lambda M\phi` directly, which loses about :math:`\log_{10} N^4`
            digits on mode 1 (kept to show the effect).

    Returns:
        Eigenvalues :math:`\lambda = \omega^2`, shape (n_modes,), ascending [rad^2/s^2].

    Raises:
        InvalidBeam: If the mesh has fewer dofs than modes or the formulation is unknown.
    """
    nodes = np.asarray(nodes_m, dtype=float)
    size = 2 * (nodes.size - 1)
    if n_modes < 1 or n_modes > size:
        raise InvalidBeam(f"n_modes = {n_modes} must be in [1, {size}] for this mesh")
    top = [size - n_modes, size - 1]
    if formulation == "relative":
        mu = sla.eigh(relative_compliance_matrix(planform, nodes), eigvals_only=True,
                      subset_by_index=top)
        return np.sort(1.0 / mu)
    k, m = assemble_beam(planform, nodes)
    if formulation == "compliance":
        return np.sort(1.0 / sla.eigh(m, k, eigvals_only=True, subset_by_index=top))
    if formulation == "stiffness":
        return sla.eigh(k, m, eigvals_only=True, subset_by_index=[0, n_modes - 1])
    raise InvalidBeam(f"formulation = {formulation!r}; expected 'relative', 'compliance' "
                      "or 'stiffness'")


@dataclass(frozen=True)
class BeamModes:
    r"""Converged bending frequencies of a cantilever beam.

    Attributes:
        freq_hz: Extrapolated frequencies, shape (n_modes,) [Hz].
        eigval: Extrapolated eigenvalues :math:`\omega^2`, shape (n_modes,) [rad^2/s^2].
        mesh_eigval: Raw eigenvalues on the three nested meshes, shape (3, n_modes).
        n_elements: Element counts of the three meshes.
        observed_order: Observed convergence order per mode from the three meshes (about 4).
        rel_error_estimate: Relative difference of the two Richardson extrapolants per mode,
            an estimate of the frequency error [-].
    """

    freq_hz: np.ndarray
    eigval: np.ndarray
    mesh_eigval: np.ndarray
    n_elements: tuple[int, int, int]
    observed_order: np.ndarray
    rel_error_estimate: np.ndarray


def beam_frequencies(planform: Planform, n_modes: int = 5, max_element_m: float | None = None,
                     max_stiffness_ratio: float = 1.5, formulation: str = "relative",
                     rtol: float = 1e-7) -> BeamModes:
    r"""Converged out-of-plane bending frequencies of the clamped-free beam.

    Three nested meshes (N, 2N, 4N elements, each planform piece halved) give two Richardson
    extrapolants :math:`(16\lambda_{2h} - \lambda_h)/15`; the finer one is returned, and the
    relative gap between them must stay below ``rtol``. Meshes come from :func:`beam_mesh`.

    Args:
        planform: The beam.
        n_modes: Number of modes.
        max_element_m: Largest element of the coarsest mesh [m]; default L/32.
        max_stiffness_ratio: Largest EI ratio across an element of the coarsest mesh.
        formulation: Eigenproblem form, see :func:`fe_eigenvalues`.
        rtol: Largest accepted relative gap between the two extrapolated frequencies [-].

    Returns:
        The frequencies with their convergence record.

    Raises:
        TruthNotConverged: If the extrapolants disagree by more than ``rtol``: the mesh is too
            coarse for the wanted modes, or round-off dominates (too fine a mesh, or the
            ``"stiffness"`` formulation).
    """
    if max_element_m is None:
        max_element_m = planform.length_m / 32.0
    meshes = [beam_mesh(planform, max_element_m, max_stiffness_ratio, 2**level)
              for level in range(3)]
    lam = np.array([fe_eigenvalues(planform, nodes, n_modes, formulation) for nodes in meshes])
    rich = (16.0 * lam[1:] - lam[:-1]) / 15.0
    gap = 0.5 * np.abs(rich[1] - rich[0]) / rich[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        order = np.log2(np.abs((lam[0] - lam[1]) / (lam[1] - lam[2])))
    n_el = tuple(int(nodes.size - 1) for nodes in meshes)
    if np.any(~np.isfinite(gap)) or np.any(gap > rtol):
        worst = int(np.nanargmax(gap))
        raise TruthNotConverged(
            f"beam frequencies not converged: mode {worst + 1} extrapolants differ by "
            f"{gap[worst]:.2e} (relative, allowed {rtol:.1e}) on meshes of {n_el} elements, "
            f"observed orders {np.round(order, 2).tolist()} (expected 4); use the 'relative' "
            "formulation, a coarser max_element_m if round-off dominates, or a finer one if "
            "the observed order is below 4"
        )
    return BeamModes(
        freq_hz=np.sqrt(rich[1]) / (2.0 * np.pi), eigval=rich[1], mesh_eigval=lam,
        n_elements=(n_el[0], n_el[1], n_el[2]), observed_order=order, rel_error_estimate=gap,
    )
