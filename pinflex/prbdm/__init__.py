"""Pseudo-rigid-body dynamic models (PRBDM) of compliant beams (paper 001).

Beams (:mod:`.beams`), converged reference solutions (:mod:`.truth`), the nR chain as a
Pinocchio model (:mod:`.chain`), the mapping problem (:mod:`.problem`) and its optimisers
(:mod:`.mapping`). Specialised names stay in those modules.
"""

from .beams import Planform, random_beam, uniform_beam
from .chain import PrbdmChain, build_chain, chain_frequencies, solve_tip_statics, to_urdf
from .mapping import PrbdmFit, fit_prbdm
from .problem import compute_truth
from .truth import beam_frequencies, elastica_tip

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
