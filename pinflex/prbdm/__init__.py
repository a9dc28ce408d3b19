"""Pseudo-rigid-body dynamic models (PRBDM) of compliant beams (paper 001).

Beams (:mod:`.beams`), converged reference solutions (:mod:`.truth`), the nR chain as a
Pinocchio model (:mod:`.chain`), the mapping problem (:mod:`.problem`) and its optimisers
(:mod:`.mapping`); the names of the mapping's choices are in :mod:`.options`. Specialised
names stay in those modules. The names below are imported when first used.
"""

from typing import TYPE_CHECKING

from pinflex.lazy import lazy_exports

_EXPORTS = {
    "Planform": ".beams",
    "PrbdmChain": ".chain",
    "PrbdmFit": ".fit",
    "beam_frequencies": ".truth",
    "build_chain": ".chain",
    "chain_frequencies": ".chain",
    "compute_truth": ".problem",
    "elastica_tip": ".truth",
    "fit_prbdm": ".mapping",
    "random_beam": ".beams",
    "solve_tip_statics": ".chain",
    "to_urdf": ".chain",
    "uniform_beam": ".beams",
}

__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)

__all__ = [
    "Planform",
    "PrbdmChain",
    "PrbdmFit",
    "beam_frequencies",
    "build_chain",
    "chain_frequencies",
    "compute_truth",
    "elastica_tip",
    "fit_prbdm",
    "random_beam",
    "solve_tip_statics",
    "to_urdf",
    "uniform_beam",
]

if TYPE_CHECKING:
    from .beams import Planform, random_beam, uniform_beam
    from .chain import PrbdmChain, build_chain, chain_frequencies, solve_tip_statics, to_urdf
    from .fit import PrbdmFit
    from .mapping import fit_prbdm
    from .problem import compute_truth
    from .truth import beam_frequencies, elastica_tip
