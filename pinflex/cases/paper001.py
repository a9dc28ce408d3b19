"""Paper 001's published numbers (Vedant and Allison, J. Mech. Des. 142(5), 2020).

Facts and figures only: the published losses and designs of Tables 3-5, beam 17,572's
eigenvalues (eq. 24), and the numbers that the paper's public code fixes (its pose sweep and
the deflection case of its Pareto script). The definitions that produced each figure are
:mod:`pinflex.prbdm.paper`'s; which definition belongs to which figure is recorded here.
"""

from __future__ import annotations

#: Published losses [%]: eigen-only fits of 4 and 5 modes (Tables 3-4), of 3 modes with a 4R and
#: a 5R chain, and the combined (eq. 27) designs of Table 5. Random beam 17,572.
PUBLISHED_LOSS_PERCENT: dict[str, dict[int, float]] = {
    "eigen": {4: 0.0327, 5: 0.0283},
    "eigen_3_modes": {4: 0.0151, 5: 0.0101},
    "combined": {3: 59.8087, 4: 12.9613, 5: 10.1844},
}

#: The definition that produced each published figure. The eigen-only figures come from the
#: conference code (``findKL``: eigenvalues of M^-1 K against omega^2, mean over the poses
#: 0.1:0.01:pi/(2n), 1024 starts); Table 5 from the journal code's Pareto search
#: (``findKL_eig_def``: the same frequency loss beside a tip-position loss).
PUBLISHED_DEFINITION = {"eigen": "paper-code", "eigen_3_modes": "paper-code",
                        "combined": "paper-code"}

#: Published designs: (SCF_mean, joint distances of links 0..n [m]), Tables 3-5.
PUBLISHED_DESIGNS: dict[str, dict[int, tuple[float, tuple[float, ...]]]] = {
    "eigen": {4: (5.3145, (0.2778, 0.2354, 0.0308, 0.2250, 0.2309)),
              5: (10.5298, (0.1429, 0.4505, 0.0288, 0.2089, 0.0493, 0.1196))},
    "eigen_3_modes": {4: (2.1469, (0.2773, 0.0939, 0.3549, 0.1477, 0.1262)),
                      5: (2.6642, (0.1919, 0.1100, 0.4646, 0.0922, 0.1027, 0.0387))},
    "combined": {3: (10.2578, (0.2144, 0.6069, 0.1119, 0.0669)),
                 4: (71.3214, (0.2938, 0.2038, 0.1438, 0.0200, 0.3388)),
                 5: (97.3296, (0.1556, 0.2756, 0.1856, 0.0200, 0.3056, 0.0576))},
}

#: Beam 17,572's five bending "eigenvalues" (eq. 24; the code compares their squares with the
#: eigenvalues of M^-1 K). The planform's vertices are in neither public repository.
BEAM_17572_EIGENVALUES = (48.342, 359.4, 1013.5, 5711.4, 7816.0)

#: Multistart size of the eigen-only fits (Sec. 4.1.1, and the conference code).
PUBLISHED_STARTS = 1024

#: The journal code's deflection case: one vertical tip force [N] and the tip position it
#: targets [m] (beam 17,572, the COMSOL value).
CODE_TIP_FORCE_N = -1.0e6
CODE_TIP_TARGET_M = (1.0 - 0.0083, -0.1437)

#: Pose counts of the code's sweep 0.1:0.01:pi/(2n) for n = 3, 4, 5.
CODE_POSE_COUNTS = {3: 43, 4: 30, 5: 22}
