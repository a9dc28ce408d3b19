r"""Load cases of the deflection truth and loss: end forces at any angle, end moments, two ends.

A :class:`LoadCase` is nondimensional, so one list serves every beam:

* :math:`\alpha = |F| L^2 / EI_{eq}`, the dead end force's level, and its direction
  ``angle_deg`` measured from the undeformed axis (+X) towards -Z (90: the transverse force of
  paper 001; 180 would be pure compression; Howell's load factor n, a horizontal component
  :math:`-nP` beside the transverse P, is :math:`\varphi = \mathrm{atan2}(1, -n)`);
* :math:`\beta = M L / EI_{eq}`, the end moment (positive turns +X towards -Z);
* ``boundary``: ``"cantilever"`` (free end) or ``"fixed-guided"`` (end rotation held zero,
  end free to translate; it takes no applied moment).

:math:`EI_{eq}` is :func:`~pinflex.prbdm.beams.equivalent_bending_stiffness` (EI for a uniform
beam). The paper's loads are :func:`force_cases` of ``DEFAULT_ALPHAS``; :data:`EXTENDED_CASES`
adds tip moments, inclined and combined loads and the fixed-guided beam up to
:math:`\alpha = 10`. The truth of a case is :func:`case_truth`
(:func:`~pinflex.prbdm.elastica.end_load_equilibrium`); the chain's answer to it is
:func:`~pinflex.prbdm.chain.solve_tip_statics` with the case's force, moment and boundary.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from ..exceptions import ConfigurationError, InvalidChain, NewtonDivergence
from .beams import Planform, equivalent_bending_stiffness
from .chain import PrbdmChain, solve_tip_statics
from .elastica import BOUNDARIES, ElasticaSolution, end_load_equilibrium

#: Largest load level a case may ask for (alpha and |beta|): the range the truth is tested on.
MAX_LEVEL = 10.0


@dataclass(frozen=True)
class LoadCase:
    """One nondimensional end load (see the module docstring).

    Attributes:
        alpha: Force level :math:`|F| L^2 / EI_{eq}`, in [0, 10].
        angle_deg: Force direction from +X towards -Z [deg], in (-180, 180).
        beta: End moment :math:`M L / EI_{eq}`, in [-10, 10]; 0 for a fixed-guided end.
        boundary: ``"cantilever"`` or ``"fixed-guided"``.
    """

    alpha: float = 0.0
    angle_deg: float = 90.0
    beta: float = 0.0
    boundary: str = "cantilever"

    def __post_init__(self) -> None:
        for name in ("alpha", "angle_deg", "beta"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) \
                    or not math.isfinite(value):
                raise InvalidChain(f"load case {name} = {value!r} must be a finite number")
            object.__setattr__(self, name, float(value))
        if not 0.0 <= self.alpha <= MAX_LEVEL:
            raise InvalidChain(f"load case alpha = {self.alpha:g} must be in [0, {MAX_LEVEL:g}] "
                               "(|F| L^2 / EI_eq)")
        if abs(self.beta) > MAX_LEVEL:
            raise InvalidChain(f"load case beta = {self.beta:g} must be in [-{MAX_LEVEL:g}, "
                               f"{MAX_LEVEL:g}] (M L / EI_eq)")
        if not -180.0 < self.angle_deg < 180.0:
            raise InvalidChain(f"load case angle_deg = {self.angle_deg:g} must be in "
                               "(-180, 180): 180 is pure compression, a buckling bifurcation")
        if self.boundary not in BOUNDARIES:
            raise InvalidChain(f"load case boundary = {self.boundary!r}; expected one of "
                               f"{BOUNDARIES}")
        if self.boundary == "fixed-guided" and self.beta != 0.0:
            raise InvalidChain("a fixed-guided end holds its rotation and takes no applied "
                               f"moment: beta = {self.beta:g} must be 0")
        if self.alpha == 0.0 and self.beta == 0.0:
            raise InvalidChain("a load case needs a force (alpha > 0) or a moment (beta != 0)")

    @property
    def label(self) -> str:
        """Short name, e.g. ``a=5 @90`` or ``guided a=10 @90`` or ``b=1``."""
        parts = []
        if self.alpha:
            parts.append(f"a={self.alpha:g} @{self.angle_deg:g}")
        if self.beta:
            parts.append(f"b={self.beta:g}")
        text = " ".join(parts)
        return f"guided {text}" if self.boundary == "fixed-guided" else text

    def force_n(self, planform: Planform) -> np.ndarray:
        """The dead end force (Fx, Fz) on a beam [N]."""
        size = self.alpha * equivalent_bending_stiffness(planform) / planform.length_m**2
        exact = {0.0: (1.0, 0.0), 90.0: (0.0, 1.0), -90.0: (0.0, -1.0)}
        angle = math.radians(self.angle_deg)
        cos, sin = exact.get(self.angle_deg, (math.cos(angle), math.sin(angle)))
        return np.array([size * cos, -size * sin])

    def moment_nm(self, planform: Planform) -> float:
        """The end moment on a beam [N m]."""
        return self.beta * equivalent_bending_stiffness(planform) / planform.length_m

    def to_dict(self) -> dict:
        """The case as plain data (JSON)."""
        return {"alpha": self.alpha, "angle_deg": self.angle_deg, "beta": self.beta,
                "boundary": self.boundary, "label": self.label}


def force_cases(alphas: Iterable[float]) -> tuple[LoadCase, ...]:
    """Transverse dead tip forces on the cantilever (paper 001's loads) at levels ``alphas``."""
    return tuple(LoadCase(alpha=float(a)) for a in alphas)


#: Tip moments, inclined and combined end loads and the fixed-guided beam, up to level 10.
EXTENDED_CASES: tuple[LoadCase, ...] = (
    LoadCase(beta=0.5), LoadCase(beta=1.5), LoadCase(beta=3.0),
    LoadCase(alpha=2.0, angle_deg=45.0), LoadCase(alpha=10.0, angle_deg=45.0),
    LoadCase(alpha=10.0, angle_deg=90.0),
    LoadCase(alpha=2.0, angle_deg=135.0), LoadCase(alpha=5.0, angle_deg=135.0),
    LoadCase(alpha=2.0, angle_deg=90.0, beta=1.0),
    LoadCase(alpha=5.0, angle_deg=45.0, beta=-1.0),
    LoadCase(alpha=2.0, boundary="fixed-guided"), LoadCase(alpha=10.0, boundary="fixed-guided"),
)

#: Named sets of load cases (CLI ``--loads``).
LOAD_SETS = ("paper", "extended")


def load_set(name: str, alphas: Sequence[float] = (0.5, 1.0, 2.0, 5.0)) -> tuple[LoadCase, ...]:
    """A named set: ``"paper"`` (transverse forces at ``alphas``) or ``"extended"``.

    Raises:
        InvalidChain: For an unknown name.
    """
    if name == "paper":
        return force_cases(alphas)
    if name == "extended":
        return EXTENDED_CASES
    raise InvalidChain(f"load set {name!r}; expected one of {LOAD_SETS}")


def case_truth(planform: Planform, case: LoadCase) -> ElasticaSolution:
    """The elastica of a beam under one load case (the deflection truth)."""
    return end_load_equilibrium(planform, case.force_n(planform), case.moment_nm(planform),
                                case.boundary)


def case_errors(planform: Planform, chain: PrbdmChain, cases: Sequence[LoadCase],
                truth_tips_m: np.ndarray | None = None, load_steps: int = 4) -> np.ndarray:
    """Tip error of a chain under each case, over the truth's tip displacement [-].

    The chain's own statics (:func:`~pinflex.prbdm.chain.solve_tip_statics` from rest in
    ``load_steps`` equal steps) against the elastica (:func:`case_truth`, or the given tips).
    A case the chain cannot take (a guided end on a 1R chain) or whose Newton fails is NaN.

    Args:
        planform: The beam.
        chain: A :class:`~pinflex.prbdm.chain.PrbdmChain` of the beam.
        cases: The load cases.
        truth_tips_m: Elastica tips of the cases, shape (l, 2) [m] (computed if None).
        load_steps: Load steps of each chain solve.

    Returns:
        Errors, shape (l,).
    """
    tips = (np.array([case_truth(planform, c).tip_m for c in cases]).reshape(-1, 2)
            if truth_tips_m is None else np.asarray(truth_tips_m, dtype=float))
    undeformed = np.array([planform.length_m, 0.0])
    out = np.full(len(cases), np.nan)
    for i, case in enumerate(cases):
        try:
            tip = solve_tip_statics(chain, case.force_n(planform), load_steps=load_steps,
                                    moment_nm=case.moment_nm(planform),
                                    boundary=case.boundary).tip_m
        except (ConfigurationError, NewtonDivergence):
            continue
        out[i] = np.linalg.norm(tip - tips[i]) / np.linalg.norm(tips[i] - undeformed)
    return out
