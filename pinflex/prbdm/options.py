"""Names of the PRBDM mapping's choices, shared by the mapping, the batch studies and the CLI."""

#: What a mapping minimises (:func:`pinflex.prbdm.fit_prbdm`).
OBJECTIVES = ("eigen", "deflection", "combined", "pareto")
#: Spring laws: pose-independent physical springs, or paper 001's eq. (14) per pose.
STIFFNESS_LAWS = ("segment", "paper")
#: Load levels PL²/EI of the elastica reference (paper 001).
DEFAULT_ALPHAS = (0.5, 1.0, 2.0, 5.0)
#: Sets of definitions a fit is made and scored by (:mod:`pinflex.prbdm.paper`).
DEFINITIONS = ("pinflex", "paper-text", "paper-code")
