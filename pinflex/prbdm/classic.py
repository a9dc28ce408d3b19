r"""Classic static pseudo-rigid-body models, evaluated like the fitted PRBDMs.

* **Howell 1R** (Howell, Midha and Norton 1996): one pivot at :math:`(1-\gamma)L` from the root
  with :math:`\gamma = 0.85` and spring :math:`K = \gamma K_\Theta EI/L`, :math:`K_\Theta = 2.65`.
* **Su 3R** (Su 2009, "A pseudorigid-body 3R model for determining large deflection of
  cantilever beams subject to tip loads", J. Mech. Robot. 1(2)): link fractions
  :math:`\gamma = [0.10, 0.35, 0.40, 0.15]` (root to tip) and springs
  :math:`K_i = k_i EI/L`. Three sets of k are published for these fractions:
  :data:`SU_3R`, the **load-independent** set of the paper's Table 1,
  :math:`k = [3.51, 2.99, 2.58]` (for loads not known in advance); :data:`SU_3R_MOMENT`,
  fitted to a pure end moment, :math:`k = [3.51933, 2.78518, 2.79756]`; :data:`SU_3R_FORCE`,
  fitted to a transverse end force, :math:`k = [3.71591, 2.87128, 2.26417]`.

All were derived for uniform beams under tip loads; on a non-uniform planform EI is taken as
:math:`EI_{eq}` (:func:`~pinflex.prbdm.beams.equivalent_bending_stiffness`, the uniform beam
with the same linear tip compliance). They are static models: here their links carry the
planform's mass, centre of mass and rotational inertia, exactly as the fitted PRBDM's do, so
their frequencies can be compared too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .beams import Planform, equivalent_bending_stiffness
from .chain import PrbdmChain, build_chain


@dataclass(frozen=True)
class ClassicModel:
    """A classic PRBM: link fractions (root to tip) and stiffness coefficients k (K = k EI/L)."""

    name: str
    link_fractions: tuple[float, ...]
    stiffness_coefficients: tuple[float, ...]
    source: str

    def chain(self, planform: Planform) -> PrbdmChain:
        """The model on a beam, EI = EI_eq, links carrying the planform's mass properties."""
        ei = equivalent_bending_stiffness(planform)
        k = np.asarray(self.stiffness_coefficients) * ei / planform.length_m
        return build_chain(planform, np.asarray(self.link_fractions), k)


HOWELL_1R = ClassicModel("Howell 1R", (0.15, 0.85), (0.85 * 2.65,),
                         "Howell, Midha and Norton, J. Mech. Des. 118(1), 1996")
SU_3R = ClassicModel("Su 3R (load-independent, Table 1)", (0.10, 0.35, 0.40, 0.15),
                     (3.51, 2.99, 2.58), "Su, J. Mech. Robot. 1(2), 2009, Table 1")
SU_3R_MOMENT = ClassicModel("Su 3R (end-moment set)", (0.10, 0.35, 0.40, 0.15),
                            (3.51933, 2.78518, 2.79756),
                            "Su, J. Mech. Robot. 1(2), 2009, pure end moment")
SU_3R_FORCE = ClassicModel("Su 3R (end-force set)", (0.10, 0.35, 0.40, 0.15),
                           (3.71591, 2.87128, 2.26417),
                           "Su, J. Mech. Robot. 1(2), 2009, transverse end force")
CLASSIC_MODELS = (HOWELL_1R, SU_3R, SU_3R_MOMENT, SU_3R_FORCE)
