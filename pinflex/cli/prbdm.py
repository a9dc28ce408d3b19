"""``pinflex prbdm``: fit a pseudo-rigid-body dynamic model to a beam and report it.

Registered on the main parser by :func:`add_parser`; :func:`run` executes the parsed
arguments and returns the exit status (errors are reported by :func:`pinflex.cli.main`). With
``--json`` one JSON object goes to stdout (progress bars go to stderr).
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from pinflex.prbdm.loads import LOAD_SETS
from pinflex.prbdm.options import DEFINITIONS, OBJECTIVES, STIFFNESS_LAWS


def add_parser(subparsers) -> argparse.ArgumentParser:
    """Register the ``prbdm`` subcommand on an argparse subparsers object.

    Args:
        subparsers: The object returned by ``ArgumentParser.add_subparsers()``.

    Returns:
        The new subparser (its default ``func`` is :func:`run`).
    """
    parser = subparsers.add_parser(
        "prbdm", help="fit an nR pseudo-rigid-body dynamic model to a compliant beam",
        description="Fit link lengths and spring stiffnesses of an nR PRBDM so that its "
                    "frequencies and/or large tip deflections match a converged beam model.")
    parser.add_argument("--beam", choices=("uniform", "random"), default="uniform",
                        help="paper 001's uniform steel beam or a seeded random planform")
    parser.add_argument("--seed", type=int, default=0,
                        help="seed of the random planform and of the multistart points")
    parser.add_argument("--sections", type=int, default=10,
                        help="interior vertices p of a random planform (paper: 10)")
    parser.add_argument("--links", type=int, default=5, help="number of revolute joints n")
    parser.add_argument("--modes", type=int, default=None,
                        help="bending modes to match (default: n)")
    parser.add_argument("--objective", choices=OBJECTIVES, default="combined",
                        help="what the mapping minimises (default: combined, frequencies and "
                             "large deflections; an eigen-only fit of n modes at one pose is "
                             "exactly determined and is reported as such)")
    parser.add_argument("--stiffness-law", choices=STIFFNESS_LAWS, default="segment",
                        help="'segment' (pose-independent physical springs, default) or "
                             "'paper' (eq. 14, one factor per pose)")
    parser.add_argument("--poses", choices=("straight", "paper"), default="straight",
                        help="poses where frequencies are compared")
    parser.add_argument("--definitions", choices=DEFINITIONS, default="pinflex",
                        help="what the fit minimises and reports: pinflex's own losses "
                             "(default), 'paper-text' (paper 001 as printed: eq. 14 with the "
                             "area moment, eq. 15a summed over the poses xi = 0.05 + i eps, eps "
                             "0.1) or 'paper-code' (what the paper's code computes: eigenvalues "
                             "of M^-1 K against omega^2, mean over the poses 0.1:0.01:pi/(2n), "
                             "eq. 14 with the links' rotational inertia, its tip-position "
                             "deflection case); the paper's definitions fit one factor per "
                             "pose by a global search and print their own losses beside "
                             "pinflex's")
    parser.add_argument("--epsilon", type=float, default=None,
                        help="pose step [rad] of the paper's definitions (text 0.1, code 0.01)")
    parser.add_argument("--code-force", type=float, default=None, metavar="NEWTON",
                        help="tip force of the code's deflection case [N] (default: the force "
                             "that deflects the tip by 0.1437 L, as the code's 1 MN did on "
                             "its beam)")
    parser.add_argument("--samples", type=int, default=None,
                        help="global sample size of the paper's definitions' search (default "
                             "65536 eigen-only, 4096 with deflection)")
    parser.add_argument("--starts", type=int, default=None,
                        help="multistart points per search (default 8); with --definitions "
                             "paper-*, the polished starts of the global search (default 48 "
                             "eigen-only; 16 with deflection, extended up to 48 until two "
                             "agree on the best)")
    parser.add_argument("--tol", type=float, default=None, metavar="TOL",
                        help="pick the fewest joints (from --modes, default 1, up to --links) "
                             "whose estimated combined error against the converged beam truth "
                             "is at most TOL; the estimate is the combined fit's residual "
                             "against that truth")
    parser.add_argument("--loads", choices=LOAD_SETS, default="paper",
                        help="load cases of the deflection loss: 'paper' (transverse tip "
                             "forces, alpha = 0.5, 1, 2, 5) or 'extended' (tip moments, "
                             "inclined and combined end loads, fixed-guided ends, up to "
                             "alpha = 10; at least 2 joints); see docs/prbdm.md")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    parser.add_argument("--no-progress", action="store_true", help="hide the progress bar")
    parser.add_argument("--html", default=None, metavar="FILE",
                        help="write an offline HTML preview of the fitted chain over its beam")
    parser.add_argument("--export", default=None, metavar="FILE",
                        help="write the fitted chain as MJCF (.xml, joint stiffness for MuJoCo) "
                        "or URDF (.urdf plus .springs.json); see docs/mujoco.md")
    parser.add_argument("--force", action="store_true", help="overwrite an existing --export")
    parser.set_defaults(func=run)
    return parser


def run(args: argparse.Namespace) -> int:
    """Execute ``pinflex prbdm``; return the process exit status."""
    from pinflex.exceptions import ConfigurationError
    from pinflex.outputs import check_file_target
    from pinflex.prbdm.beams import random_beam, uniform_beam
    from pinflex.prbdm.loads import load_set
    from pinflex.prbdm.mapping import fit_prbdm
    from pinflex.prbdm.problem import compute_truth
    from pinflex.validation import require_count

    require_count(args.seed, "--seed", minimum=0, error=ConfigurationError)
    paper = args.definitions != "pinflex"
    if args.starts is None and not paper:
        args.starts = 8
    if args.starts is not None:
        require_count(args.starts, "--starts", minimum=1, maximum=1000,
                      error=ConfigurationError)
    if args.samples is not None:
        require_count(args.samples, "--samples", minimum=1, error=ConfigurationError)
    if paper and (args.stiffness_law != "segment" or args.poses != "straight"
                  or args.tol is not None):
        raise ConfigurationError(f"--definitions {args.definitions} sets the spring law and the "
                                 "poses; drop --stiffness-law/--poses/--tol")
    if not paper and (args.epsilon is not None or args.code_force is not None
                      or args.samples is not None):
        raise ConfigurationError("--epsilon, --code-force and --samples belong to "
                                 "--definitions paper-text/paper-code")
    if args.loads != "paper" and (paper or args.tol is not None):
        raise ConfigurationError(f"--loads {args.loads} is a pinflex-definitions fit of a given "
                                 "chain size: drop --definitions/--tol")
    if args.epsilon is not None and not (np.isfinite(args.epsilon) and args.epsilon > 0):
        raise ConfigurationError(f"--epsilon {args.epsilon!r} must be a positive angle [rad]")
    if args.code_force is not None and not (np.isfinite(args.code_force)
                                            and args.code_force != 0):
        raise ConfigurationError(f"--code-force {args.code_force!r} must be a non-zero force "
                                 "[N]")
    require_count(args.links, "--links", minimum=1, maximum=64, error=ConfigurationError)
    if args.modes is not None:
        require_count(args.modes, "--modes", minimum=1, maximum=64, error=ConfigurationError)
    require_count(args.sections, "--sections", minimum=0, maximum=1000,
                  error=ConfigurationError)
    if args.html:
        check_file_target(args.html, "--html")
    if args.export:
        from pinflex.lumped.chain import export_targets

        export_targets(args.export, args.force)
    beam = (uniform_beam() if args.beam == "uniform"
            else random_beam(args.seed, n_sections=args.sections))
    choice = None
    if args.tol is not None:
        from pinflex.prbdm.fidelity import links_for_tolerance

        if args.objective != "combined" or args.stiffness_law != "segment" \
                or args.poses != "straight":
            raise ConfigurationError("--tol judges combined fits with the segment law at the "
                                     "straight pose; drop --objective/--stiffness-law/--poses")
        n_modes = args.modes if args.modes is not None else 1
        truth = compute_truth(beam, max(n_modes, 1))
        choice = links_for_tolerance(beam, args.tol, n_modes=n_modes, max_links=args.links,
                                     n_starts=args.starts, seed=args.seed, truth=truth,
                                     progress=not args.no_progress)
        fit = choice.fit
        args.links = choice.n_joints
    else:
        n_modes = args.modes if args.modes is not None else args.links
        truth = compute_truth(beam, max(n_modes, 1),
                              loads=None if args.loads == "paper" else load_set(args.loads))
        fit = fit_prbdm(beam, args.links, n_modes, objective=args.objective,
                        stiffness_law=args.stiffness_law, poses=args.poses,
                        n_starts=args.starts, seed=args.seed, truth=truth,
                        progress=not args.no_progress, definitions=args.definitions,
                        epsilon=args.epsilon, code_force_n=args.code_force,
                        n_samples=args.samples)
    fidelity = None if choice is None else {
        "tol": args.tol, "n_joints": choice.n_joints, "estimate": choice.estimate,
        "estimator": "combined loss of the fit against the converged beam truth",
        "truth_error": choice.truth_error,
        "levels": [{"n_joints": n, "estimate": e, "eigen_error": g, "deflection_error": d}
                   for n, e, g, d in choice.levels]}
    html = None
    if args.html:
        from pinflex.visualization import prbdm_preview_html

        html = str(prbdm_preview_html(beam, fit, args.html))
    if args.export:
        from pinflex.lumped.chain import export_chain

        written = export_chain(fit.chain(beam), args.export, planform=beam, force=args.force)
        print(f"wrote {', '.join(str(p) for p in written)}", file=sys.stderr if args.json
              else sys.stdout)
    if args.json:
        if html is None and fidelity is None:
            print(fit.to_json())
        else:
            import json

            extra: dict = {} if html is None else {"html": html}
            if fidelity is not None:
                extra["fidelity"] = fidelity
            print(json.dumps(dict(json.loads(fit.to_json()), **extra)))
        return 0
    out = fit.to_dict()
    print(f"{args.links}R PRBDM of the {fit.beam} beam, objective {fit.objective}, "
          f"stiffness law {fit.stiffness_law}")
    print(f"  link lengths [m]   {[round(v, 5) for v in out['link_lengths_m']]}")
    print(f"  stiffness [N m/rad] {[float(f'{v:.6g}') for v in out['stiffness']]}")
    print(f"  truth [Hz]         {[round(v, 4) for v in out['truth_hz']]}")
    print(f"  model [Hz]         {[round(v, 4) for v in out['model_hz']]}")
    if choice is not None:
        print(f"  --tol {args.tol:g}: {choice.n_joints}R is the fewest joints meeting it, "
              f"estimated error {choice.estimate:.3e} (combined loss against the converged "
              f"truth, whose own error is ~{choice.truth_error:.0e}); tried "
              + ", ".join(f"{n}R {e:.2e}" for n, e, _, _ in choice.levels))
    print(f"  {fit.determinacy}: {fit.n_free_parameters} free parameters, "
          f"{fit.n_matched} matched quantities")
    if paper:
        _print_paper(fit)
        return 0
    if fit.exactly_determined:
        print(f"  residual (not a loss) {fit.eigen_error:.3e}; frequencies can be matched "
              "exactly along a manifold of designs, so this says nothing of model quality")
        if np.isfinite(fit.deflection_error):
            print(f"  deflection error   {fit.deflection_error:.3e} (not fitted)")
        return 0
    loads = ("load cases " + ", ".join(fit.load_labels) if fit.load_labels
             else "alpha = " + ", ".join(f"{a:g}" for a in fit.alphas))
    print("  losses, pinflex definitions (RMS per-mode frequency error; tip error over the "
          f"tip displacement; {loads}):")
    print(f"    eigen {fit.eigen_error:.3e}  deflection {fit.deflection_error:.3e}  "
          f"combined {fit.combined_error:.3e}")
    if fit.load_labels:
        print("  tip error per load case (over its tip displacement): "
              + ", ".join(f"{name} {err:.3e}" for name, err in
                          zip(fit.load_labels, fit.load_errors)))
    print(f"  paper 001's definitions at this fit's {fit.n_poses} pose(s) (eq. 15a sum of "
          "eq. 16; eq. 19 over the tip position, same loads):")
    print(f"    eq. 15a sum {fit.eq15a_sum:.3e}  (mean over poses {fit.eq15a_mean:.3e})  "
          f"eq. 19 {fit.deflection_error_position:.3e}")
    if html:
        print(f"  wrote {html}")
    return 0


def _print_paper(fit) -> None:
    """The losses of a fit made by the paper's definitions, beside pinflex's of its chain."""
    pct = {k: 100.0 * v for k, v in fit.losses.items()}
    print(f"  losses by {fit.definitions} over its {fit.n_poses} poses, in %: "
          + ", ".join(f"{k} {v:.4g}" for k, v in pct.items()))
    print("  per mode, the largest |f/f_truth - 1| over those poses, in %: "
          + ", ".join(f"{100.0 * v:.3g}" for v in fit.mode_errors)
          + "  (the loss can be small while a mode is far off)")
    print(f"  global search: {fit.n_samples} samples, {len(fit.start_values)} polished starts, "
          f"{fit.starts_at_best} within 0.1 % of the best")
    if fit.load_n:
        print("  deflection case: tip force " + ", ".join(f"({f[0]:g}, {f[1]:.6g}) N"
                                                       for f in fit.load_n))
    print("  the same chain (mean factor, eq. 25) by pinflex's definitions at the straight "
          f"pose: eigen {fit.eigen_error:.3e}  deflection {fit.deflection_error:.3e}  "
          f"combined {fit.combined_error:.3e}")
