"""PRBDM benchmark: truth, paper 001 side by side, classic PRBMs, Pareto, SCF, speed.

Run ``python benchmarks/bench_prbdm.py`` (all sections) or pick sections with
``--sections truth table chart speed condition fitspeed paper classic pareto scf equal``.
``--sections fitspeed --links 3 4 5`` times whole beams of the random-beam study (one fit per
link count, as ``pinflex batch prbdm --links 3 4 5`` runs them) with the ratio of each link
count beside the ratio per beam.
``--quick`` runs small versions (fewer starts, rounds and models); ``--json FILE`` writes the
numbers of the new sections as one JSON object. Charts go to ``--outdir`` (default: the
working directory). Speed ratios are measured interleaved in one process (CPU time, one BLAS
thread); the machine may be loaded by other work, which the output reports.
"""

from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np
from timing import best_of as best_time

from pinflex.prbdm.beams import equivalent_bending_stiffness, random_beam, uniform_beam
from pinflex.prbdm.chain import build_chain, chain_frequencies, mass_matrix_condition, tip_jacobian
from pinflex.prbdm.mapping import fit_prbdm
from pinflex.prbdm.problem import compute_truth
from pinflex.prbdm.truth import beam_frequencies, beam_mesh, elastica_tip, fe_eigenvalues

BETA_L = np.array([1.875104, 4.694091, 7.854757, 10.995541, 14.137168])
MATTIASSON = {1.0: (0.30172, 0.05643), 2.0: (0.49346, 0.16064), 5.0: (0.71379, 0.38763),
              10.0: (0.81061, 0.55500)}
PAPER_EIGEN = {4: 0.0327, 5: 0.0283}  # percent, Tables 3-4
PAPER_COMBINED = {3: 59.8087, 4: 12.9613, 5: 10.1844}  # percent, Table 5


def section_truth() -> None:
    """Uniform-beam FE against the beta-L roots, elastica against Mattiasson's table."""
    beam = uniform_beam()
    ei = beam.material.youngs_modulus_pa * float(beam.area_moment_m4(0.0))
    rho_a = beam.material.density_kg_m3 * float(beam.area_m2(0.0))
    exact_hz = BETA_L**2 * np.sqrt(ei / rho_a) / (2.0 * np.pi)
    modes = beam_frequencies(beam, 5)
    print("== truth: uniform cantilever frequencies vs beta-L roots (relative error)")
    print("   FE (relative coordinates, Richardson on", modes.n_elements, "elements):",
          np.array2string(modes.freq_hz / exact_hz - 1.0, precision=2))
    print("   mesh-refinement study, mode-1 relative error by formulation:")
    for n_el in (50, 100, 400, 800):
        nodes = np.linspace(0.0, 1.0, n_el + 1)
        row = []
        for form in ("stiffness", "compliance", "relative"):
            lam = fe_eigenvalues(beam, nodes, 1, form)[0]
            row.append(np.sqrt(lam) / (2 * np.pi) / exact_hz[0] - 1.0)
        print(f"   N={n_el:4d}  stiffness {row[0]: .1e}  compliance {row[1]: .1e}  "
              f"relative {row[2]: .1e}")
    print("== truth: elastica vs Mattiasson (1981) Table 1, alpha = P L^2 / EI")
    for alpha, (w_ref, u_ref) in MATTIASSON.items():
        sol = elastica_tip(beam, np.array([0.0, -alpha * ei]))
        w, u = -sol.tip_m[1], 1.0 - sol.tip_m[0]
        print(f"   alpha={alpha:4.1f}  w/L {w:.5f} (ref {w_ref:.5f})  u/L {u:.5f} "
              f"(ref {u_ref:.5f})  tip rotation {sol.tip_rotation_rad:.5f} rad")


def section_table(seed: int, starts: int) -> None:
    """Eigen-only and combined losses for 3R/4R/5R beside paper 001's Tables 3-5."""
    beam = random_beam(seed)
    truth = compute_truth(beam, 5)
    print(f"== loss table, random beam seed {seed} (p = 10), truth Hz "
          f"{np.round(truth.modes.freq_hz, 3).tolist()}")
    print("   losses in percent; eigen = RMS per-mode relative frequency error (n modes, poses);")
    print("   combined = sqrt(eigen^2 + deflection^2), deflection normalised by tip displacement")
    header = (f"   {'model':5s} {'paper eig':>10s} {'ours eig':>10s} {'paper-law eig':>14s} "
              f"{'paper comb':>11s} {'ours comb':>10s} ({'eig':>7s}, {'defl':>7s}) "
              f"{'paper-law comb':>15s}")
    print(header)
    for n in (3, 4, 5):
        row = {}
        for law, poses in (("segment", "straight"), ("paper", "paper")):
            eig = fit_prbdm(beam, n, n, "eigen", law, poses, starts, seed, truth)
            comb = fit_prbdm(beam, n, n, "pareto", law, poses, starts, seed, truth)
            row[law] = (eig, comb)
        pap0 = fit_prbdm(beam, n, n, "eigen", "paper", "straight", starts, seed, truth)
        ours_e, ours_c = row["segment"]
        pap_e, pap_c = row["paper"]
        paper_e = f"{PAPER_EIGEN[n]:.4f}" if n in PAPER_EIGEN else "-"
        print(f"   {n}R    {paper_e:>10s} {100 * ours_e.eigen_error:10.2e} "
              f"{100 * pap_e.eigen_error:14.2e} {PAPER_COMBINED[n]:11.4f} "
              f"{100 * ours_c.combined_error:10.4f} ({100 * ours_c.eigen_error:7.4f}, "
              f"{100 * ours_c.deflection_error:7.4f}) {100 * pap_c.combined_error:15.4f}")
        print(f"        ours combined: gamma {np.round(ours_c.link_fractions, 4).tolist()}, "
              f"factors {np.round(ours_c.correction_factors, 3).tolist()}, eq.16 eigen "
              f"{100 * ours_c.eigen_error_eq16:.4f} %, deflection by tip position (eq. 19) "
              f"{100 * ours_c.deflection_error_position:.4f} %")
        print(f"        ours front (eigen %, deflection %): "
              f"{[(round(100 * a, 4), round(100 * b, 4)) for a, b in ours_c.pareto]}")
        print(f"        paper-law eigen-only at theta = 0 only: {100 * pap0.eigen_error:.2e} %")


def section_chart(seed: int, starts: int, out: str) -> None:
    """Error against evaluation cost for 1R..8R PRBDMs and the beam FE."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    beam = random_beam(seed)
    truth = compute_truth(beam, 8)
    ref = truth.modes.freq_hz
    prbdm = {"eigen": [], "combined": []}
    for n in range(1, 9):
        for objective in prbdm:
            fit = fit_prbdm(beam, n, n, objective, n_starts=starts, seed=seed, truth=truth)
            gamma, k = np.array(fit.link_fractions), np.array(fit.stiffness)
            chain = build_chain(beam, gamma, k)
            data = chain.model.createData()
            cost = best_time(lambda c=chain, d=data: chain_frequencies(c, None, d), number=50)
            build = best_time(lambda g=gamma, k=k: chain_frequencies(build_chain(beam, g, k)),
                              number=20)
            hz = chain_frequencies(chain)
            err = float(np.max(np.abs(hz / ref[:n] - 1.0)))
            prbdm[objective].append((n, cost, err, build))
            print(f"   {n}R {objective:8s} frequencies {cost * 1e6:7.1f} us (with build "
                  f"{build * 1e6:7.1f} us)  max freq error {err:.2e} (first {n} modes)  "
                  f"deflection error {fit.deflection_error:.2e}")
    fe = []
    for h, ratio in ((1 / 2, 400.0), (1 / 4, 20.0), (1 / 8, 4.0), (1 / 16, 2.0), (1 / 32, 1.5),
                     (1 / 64, 1.25), (1 / 128, 1.1)):
        nodes = beam_mesh(beam, h, max_stiffness_ratio=ratio)
        cost = best_time(lambda nodes=nodes: fe_eigenvalues(beam, nodes, 5), number=3)
        hz = np.sqrt(fe_eigenvalues(beam, nodes, 5)) / (2 * np.pi)
        err = float(np.max(np.abs(hz / ref[:5] - 1.0)))
        fe.append((nodes.size - 1, cost, err))
        print(f"   FE {nodes.size - 1:4d} elements cost {cost * 1e3:8.2f} ms  max error "
              f"{err:.2e} (first 5 modes)")
    conv_cost = best_time(lambda: beam_frequencies(beam, 5), repeat=2)
    fig, ax = plt.subplots(figsize=(7.5, 5))
    styles = (("eigen", "o", "eigen-only fit: its n modes to round-off"),
              ("combined", "s", "combined fit (frequencies + large deflection)"))
    for objective, marker, label in styles:
        data = np.array([(c, max(e, 1e-16), b) for _, c, e, b in prbdm[objective]])
        line = ax.loglog(data[:, 0], data[:, 1], marker + "-", label=f"nR PRBDM, {label}")[0]
        if objective == "combined":
            ax.loglog(data[:, 2], data[:, 1], marker, mfc="none", color=line.get_color(),
                      label="same, timed with building the chain from its parameters")
        for n, c, e, _ in prbdm[objective]:
            ax.annotate(f"{n}R", (c, max(e, 1e-16)), fontsize=7)
    data = np.array([(c, e) for _, c, e in fe])
    ax.loglog(data[:, 0], data[:, 1], "^-", label="Hermite beam FE, one graded mesh (5 modes)")
    for n_el, c, e in fe:
        ax.annotate(f"{n_el}", (c, e), fontsize=7)
    ax.axvline(conv_cost, color="gray", ls="--", label="converged FE truth (3 meshes)")
    ax.axhline(5e-4, color="gray", ls=":", label="0.05 % (SPEC target)")
    ax.set_xlabel("evaluation time of the frequencies [s]")
    ax.set_ylabel("max relative frequency error over the modes carried [-]")
    ax.set_title(f"Speed against accuracy, random beam seed {seed}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=130)
    print(f"   chart written to {out}")


def section_speed(seed: int, starts: int) -> None:
    """5R PRBDM frequencies against the converged beam FE, measured side by side."""
    beam = random_beam(seed)
    truth = compute_truth(beam, 5)
    fit = fit_prbdm(beam, 5, 5, "combined", n_starts=starts, seed=seed, truth=truth)
    gamma, k = np.array(fit.link_fractions), np.array(fit.stiffness)
    chain = build_chain(beam, gamma, k)
    data = chain.model.createData()
    t_freq = best_time(lambda: chain_frequencies(chain, None, data), number=200)
    t_build = best_time(lambda: chain_frequencies(build_chain(beam, gamma, k)), number=50)
    t_fe = best_time(lambda: beam_frequencies(beam, 5), repeat=3)
    hz = chain_frequencies(chain)
    err = np.abs(hz / truth.modes.freq_hz - 1.0)
    print("== speed: 5R PRBDM (combined fit) vs converged beam FE, same run")
    print(f"   converged FE (3 meshes, Richardson, {truth.modes.n_elements} elements): "
          f"{t_fe * 1e3:.1f} ms")
    print(f"   PRBDM frequencies (CRBA + eigh): {t_freq * 1e6:.1f} us -> ratio "
          f"{t_fe / t_freq:.0f}x (target >= 100x)")
    print(f"   PRBDM built from its parameters + frequencies: {t_build * 1e6:.1f} us -> ratio "
          f"{t_fe / t_build:.0f}x")
    print(f"   PRBDM frequency errors on the fitted modes: {np.array2string(err, precision=2)} "
          f"(max {100 * err.max():.4f} %, target <= 0.05 %)")


def section_condition() -> None:
    """Condition number of M(theta) over poses and rank of the tip Jacobian at theta = 0."""
    beam = uniform_beam()
    ei = equivalent_bending_stiffness(beam)
    print("== paper 001's singular-mass-matrix claim at theta = 0")
    for n in (3, 5, 8):
        gamma = np.full(n + 1, 1.0 / (n + 1))
        chain = build_chain(beam, gamma, np.full(n, ei * n))
        angles = np.linspace(0.0, np.pi / 2 / n, 7)
        cond = mass_matrix_condition(chain, angles[:, None] * np.ones(n))
        sv = np.linalg.svd(tip_jacobian(chain, np.zeros(n)), compute_uv=False)
        print(f"   {n}R equal links: cond M over poses {np.array2string(cond, precision=1)}; "
              f"tip-Jacobian singular values at 0: {np.array2string(sv, precision=3)}")


RESULTS: dict = {}


def _load() -> str:
    load = os.getloadavg()
    return f"load average {load[0]:.1f} / {load[1]:.1f} / {load[2]:.1f} on {os.cpu_count()} cores"


def _x_of(fit) -> np.ndarray:
    return np.concatenate([fit.link_fractions, np.log(fit.correction_factors)])


def section_fitspeed(quick: bool, n_joints: int | None = None, rounds: int | None = None,
                     starts: int | None = None, seeds: list | None = None) -> None:
    """Analytic-Jacobian fits against the finite-difference path, interleaved per beam.

    Each round fits every beam with both paths, alternating which goes first. Timed by this
    thread's CPU time (``time.thread_time``; one BLAS thread, so all of the work), with wall
    time beside. Per beam: the ratio finite-difference / analytic of each round (median and
    range over the rounds), evaluations per fit (residual evaluations, finite differences
    included) and the optimum's combined loss on both paths.
    """
    seeds = seeds if seeds is not None else ([0] if quick else [0, 1, 2])
    n = n_joints or (3 if quick else 4)
    starts = starts or (4 if quick else 8)
    rounds = rounds or (3 if quick else 5)
    truths = {s: compute_truth(random_beam(s), 5) for s in seeds}
    kinds = ("analytic", "finite-difference")
    cpu: dict = {(k, s): [] for k in kinds for s in seeds}
    wall: dict = {(k, s): [] for k in kinds for s in seeds}
    evals: dict = {(k, s): [] for k in kinds for s in seeds}
    losses: dict = {(k, s): [] for k in kinds for s in seeds}
    load_before = _load()
    for r in range(rounds):
        for seed in seeds:
            for jac in (kinds if r % 2 == 0 else kinds[::-1]):
                t0, w0 = time.thread_time(), time.perf_counter()
                fit = fit_prbdm(random_beam(seed), n, n, "combined", n_starts=starts, seed=seed,
                                truth=truths[seed], jacobian=jac)
                cpu[jac, seed].append(time.thread_time() - t0)
                wall[jac, seed].append(time.perf_counter() - w0)
                evals[jac, seed].append(fit.n_evaluations)
                losses[jac, seed].append(fit.combined_error)
    print(f"== fit speed: {n}R combined fit, {starts} starts, beams {seeds}, {rounds} rounds "
          f"interleaved, thread CPU seconds per fit (wall beside), one BLAS thread "
          f"({load_before} before, {_load()} after)")
    per_beam = {}
    all_ratios = []
    for seed in seeds:
        a, f = np.array(cpu["analytic", seed]), np.array(cpu["finite-difference", seed])
        wa, wf = np.array(wall["analytic", seed]), np.array(wall["finite-difference", seed])
        ratio = f / a
        all_ratios.extend(ratio.tolist())
        la, lf = losses["analytic", seed][0], losses["finite-difference", seed][0]
        ea = int(np.median(evals["analytic", seed]))
        ef = int(np.median(evals["finite-difference", seed]))
        per_beam[seed] = {"analytic_cpu_s": a.tolist(), "fd_cpu_s": f.tolist(),
                          "analytic_wall_s": wa.tolist(), "fd_wall_s": wf.tolist(),
                          "ratio_median": float(np.median(ratio)),
                          "ratio_min": float(ratio.min()), "ratio_max": float(ratio.max()),
                          "wall_ratio_median": float(np.median(wf / wa)),
                          "analytic_evaluations": ea, "fd_evaluations": ef,
                          "analytic_loss": la, "fd_loss": lf}
        print(f"   beam {seed}: analytic {np.median(a):.2f} s CPU ({np.median(wa):.2f} s wall), "
              f"{ea} evaluations; finite differences {np.median(f):.2f} s CPU "
              f"({np.median(wf):.2f} s wall), {ef} evaluations")
        print(f"           ratio per beam median {np.median(ratio):.1f}x  range "
              f"{ratio.min():.1f}-{ratio.max():.1f}x (wall {np.median(wf / wa):.1f}x); "
              f"combined loss {la:.6e} / {lf:.6e} (rel. difference {abs(la - lf) / lf:.1e})")
    ratios = np.array(all_ratios)
    a_all = np.concatenate([cpu["analytic", s] for s in seeds])
    f_all = np.concatenate([cpu["finite-difference", s] for s in seeds])
    ev_a = np.concatenate([evals["analytic", s] for s in seeds])
    ev_f = np.concatenate([evals["finite-difference", s] for s in seeds])
    print(f"   all fits: analytic median {np.median(a_all):.2f} s, {np.median(ev_a):.0f} "
          f"evaluations ({np.median(a_all) / np.median(ev_a) * 1e3:.2f} ms each); finite "
          f"differences median {np.median(f_all):.2f} s, {np.median(ev_f):.0f} evaluations "
          f"({np.median(f_all) / np.median(ev_f) * 1e3:.2f} ms each)")
    print(f"   ratio per fit over all beams median {np.median(ratios):.1f}x  range "
          f"{ratios.min():.1f}-{ratios.max():.1f}x (target >= 10x per beam)")
    gap = max(abs(losses["analytic", s][i] - losses["finite-difference", s][i])
              / losses["finite-difference", s][i] for s in seeds for i in range(rounds))
    print(f"   same optimum: largest relative combined-loss difference {gap:.1e} "
          f"(optimiser tolerance 1e-9 on the cost; searches stopped by their evaluation "
          f"budget end a little apart)")
    RESULTS["fitspeed"] = {"n_joints": n, "starts": starts, "beams": seeds, "rounds": rounds,
                           "clock": "time.thread_time", "per_beam": per_beam,
                           "ratio_median": float(np.median(ratios)),
                           "ratio_min": float(ratios.min()), "ratio_max": float(ratios.max()),
                           "loss_gap_rel": float(gap), "load_before": load_before,
                           "load_after": _load()}


#: The random-beam study of docs/prbdm.md:
#: ``pinflex batch prbdm --beams 1000 --seed 15 --links 3 4 5 --starts 8``.
STUDY_SEED, STUDY_LINKS, STUDY_STARTS = 15, (3, 4, 5), 8


def section_fitspeed_study(quick: bool, links: tuple[int, ...] = STUDY_LINKS,
                           rounds: int | None = None, items: list | None = None) -> None:
    """Per-beam fit cost in the study setting, exact path against finite differences.

    A beam of the study costs one fit per link count (``pinflex batch prbdm --links 3 4 5``:
    beam ``i`` of study seed 15, combined objective, 8 starts, the beam's own seed for the
    start points, the study's truth settings). Each round fits every beam at every link count
    with both paths, alternating which goes first, timed by this thread's CPU time (one BLAS
    thread). Per beam: the ratio of the summed fit times (finite differences / exact) of each
    round, median and range over rounds; beside it, the ratio of each link count.
    """
    from pinflex.batch.tasks import PrbdmStudy, beam_seed
    from pinflex.prbdm.beams import Material

    items = items if items is not None else ([0] if quick else [0, 1, 2])
    rounds = rounds or (2 if quick else 5)
    study = PrbdmStudy(seed=STUDY_SEED, n_beams=max(items) + 1, links=tuple(links),
                       n_starts=STUDY_STARTS)
    beam_cfg, truth_cfg = study.beam_settings(), study.truth_settings()
    material = Material(E=beam_cfg["material"]["youngs_modulus_pa"],
                        density=beam_cfg["material"]["density_kg_m3"],
                        name=beam_cfg["material"]["name"])
    beams, truths, seeds = {}, {}, {}
    for i in items:
        seeds[i] = beam_seed(STUDY_SEED, i)
        beams[i] = random_beam(seeds[i], n_sections=beam_cfg["n_sections"],
                               length_m=beam_cfg["length_m"],
                               max_half_width_m=beam_cfg["max_half_width_m"],
                               thickness_m=beam_cfg["thickness_m"], material=material)
        truths[i] = compute_truth(beams[i], truth_cfg["n_modes"], tuple(truth_cfg["alphas"]))
    kinds = ("analytic", "finite-difference")
    cpu: dict = {(k, i, n): [] for k in kinds for i in items for n in links}
    evals: dict = {(k, i, n): [] for k in kinds for i in items for n in links}
    losses: dict = {(k, i, n): [] for k in kinds for i in items for n in links}
    load_before = _load()
    for r in range(rounds):
        for i in items:
            for n in links:
                for jac in (kinds if (r + n) % 2 == 0 else kinds[::-1]):
                    fit_cfg = next(c["fit"] for c in study.configs() if c["fit"]["n_joints"] == n)
                    t0 = time.thread_time()
                    fit = fit_prbdm(beams[i], n, fit_cfg["n_modes"],
                                    objective=fit_cfg["objective"],
                                    stiffness_law=fit_cfg["stiffness_law"],
                                    poses=fit_cfg["poses"], n_starts=fit_cfg["n_starts"],
                                    seed=seeds[i], truth=truths[i], jacobian=jac)
                    cpu[jac, i, n].append(time.thread_time() - t0)
                    evals[jac, i, n].append(fit.n_evaluations)
                    losses[jac, i, n].append(fit.combined_error)
    names = "+".join(f"{n}R" for n in links)
    print(f"== fit speed per beam, study setting (seed {STUDY_SEED}, {names}, combined, "
          f"{STUDY_STARTS} starts): beams {items}, {rounds} rounds interleaved, thread CPU "
          f"seconds, one BLAS thread ({load_before} before, {_load()} after)")
    per_beam = {}
    beam_ratios = []
    for i in items:
        a = np.sum([cpu["analytic", i, n] for n in links], axis=0)
        f = np.sum([cpu["finite-difference", i, n] for n in links], axis=0)
        ratio = f / a
        beam_ratios.extend(ratio.tolist())
        per_n = {}
        parts = []
        for n in links:
            rn = np.array(cpu["finite-difference", i, n]) / np.array(cpu["analytic", i, n])
            la, lf = losses["analytic", i, n][0], losses["finite-difference", i, n][0]
            per_n[n] = {"analytic_cpu_s": cpu["analytic", i, n],
                        "fd_cpu_s": cpu["finite-difference", i, n],
                        "ratio_median": float(np.median(rn)), "ratio_min": float(rn.min()),
                        "ratio_max": float(rn.max()),
                        "analytic_evaluations": int(np.median(evals["analytic", i, n])),
                        "fd_evaluations": int(np.median(evals["finite-difference", i, n])),
                        "analytic_loss": la, "fd_loss": lf}
            parts.append(f"{n}R {np.median(rn):.1f}x ({rn.min():.1f}-{rn.max():.1f}; "
                         f"{np.median(cpu['analytic', i, n]):.2f} / "
                         f"{np.median(cpu['finite-difference', i, n]):.2f} s; loss "
                         f"{la:.4e} / {lf:.4e})")
        per_beam[i] = {"beam_seed": seeds[i], "analytic_cpu_s": a.tolist(),
                       "fd_cpu_s": f.tolist(), "ratio_median": float(np.median(ratio)),
                       "ratio_min": float(ratio.min()), "ratio_max": float(ratio.max()),
                       "per_n": per_n}
        print(f"   beam {i}: exact {np.median(a):.2f} s, finite differences {np.median(f):.2f} s "
              f"per beam; ratio per beam median {np.median(ratio):.1f}x  range "
              f"{ratio.min():.1f}-{ratio.max():.1f}x")
        for part in parts:
            print(f"           {part}")
    br = np.array(beam_ratios)
    print(f"   ratio per beam over all beams and rounds median {np.median(br):.1f}x  range "
          f"{br.min():.1f}-{br.max():.1f}x (target >= 10x per beam)")
    RESULTS["fitspeed_study"] = {"study_seed": STUDY_SEED, "links": list(links),
                                 "starts": STUDY_STARTS, "beams": items, "rounds": rounds,
                                 "clock": "time.thread_time", "per_beam": per_beam,
                                 "ratio_median": float(np.median(br)),
                                 "ratio_min": float(br.min()), "ratio_max": float(br.max()),
                                 "load_before": load_before, "load_after": _load()}


def section_paper(seed: int, starts: int, quick: bool) -> None:
    """Every loss by the paper's definitions beside pinflex's own, and the paper's numbers."""
    from pinflex.cases.paper001 import PUBLISHED_LOSS_PERCENT as PAPER_PUBLISHED
    from pinflex.prbdm.paper import eq14_reference, paper_losses
    from pinflex.prbdm.problem import build_problem, reference_stiffness

    beam = random_beam(seed)
    truth = compute_truth(beam, 5)
    gamma = np.array([0.2, 0.3, 0.1, 0.25, 0.15])
    prob = build_problem(beam, 4, 4, "paper", "paper", truth)
    width_free = eq14_reference(beam, gamma[1:] * beam.length_m)
    print(f"== paper 001's definitions beside pinflex's, random beam seed {seed} (p = 10)")
    print("   eq. 14 sqrt(E I_j / m_j) against sqrt(E t^2 / (12 rho L_j)) (width-free): max rel "
          f"diff {np.max(np.abs(reference_stiffness(prob, gamma) / width_free - 1)):.1e}")
    print("   loads: dead transverse tip forces, alpha = PL^2/EI_eq = "
          + ", ".join(f"{a:g}" for a in truth.alphas) + " (the paper does not give its loads)")
    rows = []
    for n in ((3, 4) if quick else (3, 4, 5)):
        ours = fit_prbdm(beam, n, n, "combined", n_starts=starts, seed=seed, truth=truth)
        ours_prob = build_problem(beam, n, n, "straight", "segment", truth)
        pl_ours = paper_losses(ours_prob, _x_of(ours))
        # The text's method on our beam: eq. 14 as printed, the eq. 10-11 poses (eps 0.1),
        # eq. 15a, one factor per pose solved exactly, a global search over the fractions.
        pap = fit_prbdm(beam, n, n, "eigen", definitions="paper-text", truth=truth, seed=seed)
        pl_pap = pap.losses
        rows.append({"n": n, "ours_eigen": ours.eigen_error, "ours_defl": ours.deflection_error,
                     "ours_combined": ours.combined_error,
                     "ours_paper_defs": pl_ours.as_percent(),
                     "paper_method_defs": {k: 100 * v for k, v in pl_pap.items()},
                     "paper_method_per_mode_rms": pap.eigen_error,
                     "paper_method_disp_defl": pap.deflection_error,
                     "paper_method_starts": {"n": len(pap.start_values),
                                             "at_best": sum(v <= pap.start_values[0] * 1.001
                                                            for v in pap.start_values)},
                     "n_poses": pap.n_poses, "published": {
                         k: PAPER_PUBLISHED[k].get(n) for k in ("eigen", "combined")}})
    print("   all losses in %; 'sum' = eq. 15a literally (sum of eq. 16 over the m poses), "
          "'mean' = sum / m; eq. 19 RMS over our loads; eq. 27 = sqrt(eq.15a^2 + eq.19^2)")
    print("   model | pinflex fit (segment law, straight, combined): pinflex defs eigen/defl/"
          "combined | same fit by paper defs at the paper's poses (eps 0.1): 15a sum/mean, 19, 27"
          " | the text's method (paper-text: eq.14 law, eq.10-11 poses, eigen-only, global "
          "search): 15a sum/mean (starts at the best / polished) | paper published "
          "eigen / combined (by the code's definitions: not comparable with these columns)")
    for r in rows:
        o, q = r["ours_paper_defs"], r["paper_method_defs"]
        print(f"   {r['n']}R | {100 * r['ours_eigen']:.4f} / {100 * r['ours_defl']:.4f} / "
              f"{100 * r['ours_combined']:.4f} | {o['eq15a_sum']:.3f} / {o['eq15a_mean']:.3f}, "
              f"{o['eq19_rms']:.4f}, {o['eq27_sum']:.3f} | {q['eq15a_sum']:.4f} / "
              f"{q['eq15a_mean']:.4f} (m = {r['n_poses']}; "
              f"{r['paper_method_starts']['at_best']}/"
              f"{r['paper_method_starts']['n']}) | {r['published']['eigen']} / "
              f"{r['published']['combined']}")
    RESULTS["paper"] = {"seed": seed, "starts": starts, "rows": rows}


def section_classic(seed: int, starts: int, quick: bool) -> None:
    """Howell 1R and Su 3R on the same beams and loads as the fitted PRBDMs, one table."""
    from pinflex.prbdm.classic import CLASSIC_MODELS
    from pinflex.prbdm.problem import build_problem, evaluate, reference_stiffness

    beams = [("uniform", uniform_beam())] + ([] if quick else [(f"random seed {seed}",
                                                                 random_beam(seed))])
    table = []
    print("== classic PRBMs beside fitted PRBDMs (same beams, same loads alpha = 0.5 1 2 5);"
          " eigen = RMS per-mode relative error over the model's own n modes at theta = 0;"
          " defl = RMS tip error over the tip displacement; eq19 = over the tip position; %")
    for label, beam in beams:
        truth = compute_truth(beam, 5)
        models = []
        for model in CLASSIC_MODELS:
            n = len(model.stiffness_coefficients)
            prob = build_problem(beam, n, n, "straight", "segment", truth)
            chain = model.chain(beam)
            g = np.array(model.link_fractions)
            x = np.concatenate([g, np.log(chain.stiffness_nm_rad
                                          / reference_stiffness(prob, g))])
            models.append((model.name, evaluate(prob, x)))
        for n in ((3,) if quick else (1, 2, 3, 4, 5)):
            fit = fit_prbdm(beam, n, n, "combined", n_starts=starts, seed=seed, truth=truth)
            prob = build_problem(beam, n, n, "straight", "segment", truth)
            models.append((f"PRBDM {n}R (fitted, combined)", evaluate(prob, _x_of(fit))))
        print(f"   {label}:")
        for name, ev in models:
            mode1 = abs(ev.model_hz[0, 0] / truth.modes.freq_hz[0] - 1)
            print(f"     {name:30s} mode 1 {100 * mode1:8.4f}  eigen {100 * ev.eigen_error:8.4f}"
                  f"  defl {100 * ev.deflection_error:8.4f}  eq19 "
                  f"{100 * ev.deflection_error_position:8.4f}")
            table.append({"beam": label, "model": name, "mode1": float(mode1),
                          "eigen": ev.eigen_error, "defl": ev.deflection_error,
                          "eq19": ev.deflection_error_position})
    print("   no published 2R: neither Kimball-Tsai's (2002) nor Yu-Feng-Xu's (2012) 2R "
          "parameters were available to us; the 2R row is pinflex's own fitted 2R")
    RESULTS["classic"] = table


def section_pareto(seed: int, starts: int, quick: bool, outdir: str) -> None:
    """Epsilon-constraint Pareto front with its hypervolume beside the weighted sums."""
    from pinflex.prbdm.mapping import multistart, pareto_front
    from pinflex.prbdm.pareto import epsilon_constraint_front, hypervolume_2d, nondominated
    from pinflex.prbdm.problem import build_problem

    beam = random_beam(seed)
    truth = compute_truth(beam, 5)
    out = {}
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.6))
    for n in ((3,) if quick else (3, 4, 5)):
        prob = build_problem(beam, n, n, "straight", "segment", truth)
        eig = multistart(prob, "eigen", starts, seed, keep_all=True)
        x_c, ev_c = multistart(prob, "combined", starts=np.array([p[0] for p in sorted(
            eig, key=lambda p: p[1].combined_error)[: max(2, starts // 2)]]))
        x_d, _ = multistart(prob, "deflection", starts=np.array([x_c]))
        ws = pareto_front(prob, eig[0][0], x_d, 5 if quick else 9, extra=[(x_c, ev_c)])
        ws_pts = np.array([[p[1].eigen_error, p[1].deflection_error] for p in ws])
        d_lo, d_hi = ws_pts[:, 1].min(), ws_pts[:, 1].max()
        ladder = np.geomspace(max(d_lo, 1e-6), max(d_hi, 2 * d_lo), 6 if quick else 12)
        ec = epsilon_constraint_front(prob, [p[0] for p in ws], ladder)
        ec_pts = np.array([[p[1].eigen_error, p[1].deflection_error] for p in ec]
                          ).reshape(-1, 2)
        both = np.vstack([ws_pts, ec_pts])
        ref = (float(both[:, 0].max() * 1.1), float(both[:, 1].max() * 1.1))
        hv_ws = hypervolume_2d(ws_pts, ref)
        hv_all = hypervolume_2d(both[nondominated(both)], ref)
        try:
            from pymoo.indicators.hv import HV

            hv_check = float(HV(ref_point=np.array(ref))(both[nondominated(both)]))
        except ImportError:  # pragma: no cover - optional
            hv_check = float("nan")
        print(f"== Pareto {n}R: weighted sums {len(ws_pts)} points, epsilon-constraint "
              f"{len(ec_pts)} points; hypervolume up to {ref} : weighted sums {hv_ws:.3e}, "
              f"with the epsilon-constraint points {hv_all:.3e} (pymoo HV {hv_check:.3e})")
        out[n] = {"weighted": ws_pts.tolist(), "eps": ec_pts.tolist(), "ref": ref,
                  "hv_weighted": hv_ws, "hv_all": hv_all, "hv_pymoo": hv_check}
        line = ax.plot(100 * ws_pts[:, 0], 100 * ws_pts[:, 1], "o", mfc="none",
                       label=f"{n}R weighted sums")[0]
        if len(ec_pts):
            order = np.argsort(ec_pts[:, 1])
            ax.plot(100 * ec_pts[order, 0], 100 * ec_pts[order, 1], "-x",
                    color=line.get_color(), label=f"{n}R epsilon-constraint")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("frequency loss (RMS per-mode) [%]")
    ax.set_ylabel("deflection loss (over the tip displacement) [%]")
    ax.set_title(f"Pareto fronts, random beam seed {seed}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(outdir, "prbdm_pareto.png")
    fig.savefig(path, dpi=130)
    print(f"   chart written to {path}")
    RESULTS["pareto"] = out


def section_scf(seed: int, starts: int, quick: bool, outdir: str) -> None:
    """Paper Figs. 8/10: stiffness correction factor against deflection angle (eq. 25-26)."""
    from pinflex.prbdm.paper import paper_problem

    beam = random_beam(seed)
    truth = compute_truth(beam, 5)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax2 = ax.twinx()
    out = {}
    for n in ((4,) if quick else (4, 5)):
        prob = paper_problem(beam, n, truth)
        fit = fit_prbdm(beam, n, n, "eigen", "paper", prob.poses, n_starts=starts, seed=seed,
                        truth=truth, metrics="paper")
        k = np.array(fit.correction_factors)
        angle = np.degrees(prob.poses[:, 0])
        mean = k.mean()                                  # eq. 25
        pct = 100 * (k - mean) / mean                    # eq. 26
        slope, icept = np.polyfit(angle, k, 1)
        r = np.corrcoef(angle, k)[0, 1]
        print(f"== SCF {n}R (eq. 14 law, eps 0.1, {len(k)} poses): SCF_mean {mean:.4g}; "
              f"linear fit k = {icept:.4g} + {slope:.4g} * angle[deg], r = {r:.4f}; eq. 26 "
              f"range {pct.min():.2f} .. {pct.max():.2f} %")
        line = ax.plot(angle, k, "o-", label=f"{n}R SCF")[0]
        ax2.plot(angle, pct, ":", color=line.get_color())
        out[n] = {"angle_deg": angle.tolist(), "scf": k.tolist(), "mean": mean,
                  "slope": slope, "r": r}
    ax.set_xlabel("joint deflection angle xi + i eps [deg]")
    ax.set_ylabel("stiffness correction factor k_i")
    ax2.set_ylabel("(k_i - SCF_mean) / SCF_mean [%] (dotted)")
    ax.set_title(f"SCF trend (paper Figs. 8, 10), random beam seed {seed}")
    ax.legend(fontsize=7)
    fig.tight_layout()
    path = os.path.join(outdir, "prbdm_scf.png")
    fig.savefig(path, dpi=130)
    print(f"   chart written to {path}")
    RESULTS["scf"] = out


def section_equal(seed: int, starts: int, quick: bool) -> None:
    """Chain against the beam FE of equal accuracy, and the fit's cost amortised over uses."""
    beam = random_beam(seed)
    truth = compute_truth(beam, 5)
    out = []
    print(f"== speed at equal accuracy, random beam seed {seed} ({_load()})")
    for n in ((4,) if quick else (3, 4, 5)):
        t0 = time.process_time()
        fit = fit_prbdm(beam, n, n, "combined", n_starts=starts, seed=seed, truth=truth)
        t_fit = time.process_time() - t0
        chain = build_chain(beam, np.array(fit.link_fractions), np.array(fit.stiffness))
        data = chain.model.createData()
        err_chain = np.max(np.abs(chain_frequencies(chain, None, data)[:n]
                                  / truth.modes.freq_hz[:n] - 1))
        # The cheapest mesh of the family (element length L/count, EI ratio per element r)
        # whose frequency error over the chain's modes reaches the chain's.
        n_el, nodes = None, None
        for ratio in (1.5, 2.0, 4.0, 16.0, 1e3):
            for count in range(1, 200):
                trial = beam_mesh(beam, beam.length_m / count, max_stiffness_ratio=ratio)
                if n_el is not None and trial.size - 1 >= n_el:
                    break
                lam = fe_eigenvalues(beam, trial, n)
                err = np.max(np.abs(np.sqrt(lam) / (2 * np.pi) / truth.modes.freq_hz[:n] - 1))
                if err <= err_chain:
                    n_el, nodes = trial.size - 1, trial
                    break
        t_chain, t_fe = [], []
        for _ in range(5):
            t_chain.append(best_time(lambda: chain_frequencies(chain, None, data), number=200))
            t_fe.append(best_time(lambda: fe_eigenvalues(beam, nodes, n), number=5))
        tc, tf = float(np.median(t_chain)), float(np.median(t_fe))
        uses = t_fit / max(tf - tc, 1e-12)
        print(f"   {n}R: chain max error over {n} modes {100 * err_chain:.4f} %; coarsest FE "
              f"mesh at that error: {n_el} elements; chain {tc * 1e6:.0f} us, FE {tf * 1e3:.2f}"
              f" ms -> {tf / tc:.0f}x; fit {t_fit:.1f} CPU-s = {uses:.0f} FE evaluations "
              "(break-even uses)")
        out.append({"n": n, "err_chain": float(err_chain), "fe_elements": n_el,
                    "t_chain_s": tc, "t_fe_s": tf, "ratio": tf / tc, "fit_cpu_s": t_fit,
                    "break_even_uses": uses})
    RESULTS["equal"] = out


def section_study(store_path: str, outdir: str) -> None:
    """Loss statistics per nR of a ``pinflex batch prbdm`` store, box plots, per-beam cost."""
    import sqlite3

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    con = sqlite3.connect(f"file:{store_path}?mode=ro", uri=True)
    rows = con.execute("SELECT item, status, result, metrics, timings FROM results").fetchall()
    by_n: dict = {}
    cpu: dict = {}
    truth_cpu: dict = {}
    fit_cpu: dict = {}
    failed = 0
    for item, status, result, metrics, timings in rows:
        t = json.loads(timings)
        truth_cpu[item] = t.get("truth_cpu_s", 0.0)
        cpu.setdefault(item, t.get("truth_cpu_s", 0.0))
        cpu[item] += t.get("fit_cpu_s", 0.0)
        if status != "ok":
            failed += 1
            continue
        n = json.loads(result)["n_joints"]
        by_n.setdefault(n, []).append(json.loads(metrics))
        fit_cpu.setdefault(n, []).append(t.get("fit_cpu_s", 0.0))
    # Beams with every model stored (a beam's rows arrive together).
    beams = len(cpu)
    per_beam = float(np.mean(list(cpu.values()))) if cpu else float("nan")
    print(f"== study {store_path}: {beams} beams, {len(rows)} rows ({failed} failed); CPU per "
          f"beam (truth + all fits) {per_beam:.1f} s -> 1,000 beams "
          f"{per_beam * 1000 / 3600:.1f} core-h, 50,000 beams {per_beam * 50000 / 3600:.0f} "
          f"core-h ({_load()})")
    print(f"   CPU split per beam: truth {np.mean(list(truth_cpu.values())):.2f} s; fits "
          + ", ".join(f"{n}R {np.mean(v):.2f} s" for n, v in sorted(fit_cpu.items())))
    keys = ("eigen_error", "deflection_error", "combined_error", "eq15a_sum")
    out = {"beams": beams, "cpu_per_beam_s": per_beam, "failed_rows": failed,
           "truth_cpu_s": float(np.mean(list(truth_cpu.values()))) if truth_cpu else None,
           "fit_cpu_s": {n: float(np.mean(v)) for n, v in fit_cpu.items()}, "per_n": {}}
    fig, axes = plt.subplots(1, 3, figsize=(10, 3.6), sharey=True)
    for n in sorted(by_n):
        vals = {k: 100 * np.array([m[k] for m in by_n[n]]) for k in keys}
        stats = {k: {q: float(np.percentile(v, q)) for q in (5, 50, 95)} for k, v in vals.items()}
        out["per_n"][n] = {"count": len(by_n[n]), **stats}
        print(f"   {n}R ({len(by_n[n])} fits), % p5/p50/p95: " + "; ".join(
            f"{k} {stats[k][5]:.4f}/{stats[k][50]:.4f}/{stats[k][95]:.4f}" for k in keys))
    for ax, key in zip(axes, keys[:3]):
        ns = sorted(by_n)
        ax.boxplot([100 * np.array([m[key] for m in by_n[n]]) for n in ns],
                   tick_labels=[f"{n}R" for n in ns])
        ax.set_yscale("log")
        ax.set_title(key.replace("_", " ") + " [%]", fontsize=9)
    fig.suptitle(f"PRBDM study: {beams} random beams (p = 10), combined fits", fontsize=10)
    fig.tight_layout()
    path = os.path.join(outdir, "prbdm_study.png")
    fig.savefig(path, dpi=130)
    print(f"   chart written to {path}")
    RESULTS["study"] = out


def main() -> None:
    """Run the selected sections."""
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--sections", nargs="+",
                        default=["truth", "condition", "speed", "table", "chart", "fitspeed",
                                 "paper", "classic", "pareto", "scf", "equal"])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--starts", type=int, default=8)
    parser.add_argument("--out", default="prbdm_speed_accuracy.png")
    parser.add_argument("--outdir", default=".")
    parser.add_argument("--quick", action="store_true", help="small versions of the sections")
    parser.add_argument("--links", type=int, nargs="+", default=None,
                        help="joints of the fitspeed section (default 4; 3 with --quick); "
                             "several (e.g. 3 4 5) time a whole beam of the study setting")
    parser.add_argument("--beams", type=int, nargs="+", default=None,
                        help="study beams of the per-beam fitspeed run (default 0 1 2)")
    parser.add_argument("--rounds", type=int, default=None,
                        help="interleaved rounds of the fitspeed section (default 5; 3 quick)")
    parser.add_argument("--store", default=None,
                        help="SQLite store of a 'pinflex batch prbdm' run (section 'study')")
    parser.add_argument("--json", default=None, metavar="FILE",
                        help="write the new sections' numbers to FILE as JSON")
    args = parser.parse_args()
    if args.quick:
        args.starts = min(args.starts, 3)
    if args.outdir:
        os.makedirs(args.outdir, exist_ok=True)
    for name in args.sections:
        if name == "truth":
            section_truth()
        elif name == "table":
            section_table(args.seed, args.starts)
        elif name == "chart":
            print("== chart: speed against accuracy")
            section_chart(args.seed, args.starts, args.out)
        elif name == "speed":
            section_speed(args.seed, args.starts)
        elif name == "condition":
            section_condition()
        elif name == "fitspeed":
            if args.links is not None and len(args.links) > 1:
                section_fitspeed_study(args.quick, tuple(args.links), args.rounds, args.beams)
            else:
                section_fitspeed(args.quick, args.links[0] if args.links else None,
                                 args.rounds)
        elif name == "paper":
            section_paper(args.seed, args.starts, args.quick)
        elif name == "classic":
            section_classic(args.seed, args.starts, args.quick)
        elif name == "pareto":
            section_pareto(args.seed, args.starts, args.quick, args.outdir)
        elif name == "scf":
            section_scf(args.seed, args.starts, args.quick, args.outdir)
        elif name == "equal":
            section_equal(args.seed, args.starts, args.quick)
        elif name == "study":
            section_study(args.store, args.outdir)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(RESULTS, fh, indent=1, default=float)


if __name__ == "__main__":
    main()
