"""PRBDM benchmark: truth validation, loss table against paper 001, speed against accuracy.

Run ``python benchmarks/bench_prbdm.py`` (all sections) or pick sections with
``--sections truth table chart speed condition``. Prints plain text; the chart is written as a
PNG (``--out``, default ``prbdm_speed_accuracy.png`` in the working directory).
"""

from __future__ import annotations

import argparse

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


def main() -> None:
    """Run the selected sections."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--sections", nargs="+",
                        default=["truth", "condition", "speed", "table", "chart"])
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--starts", type=int, default=8)
    parser.add_argument("--out", default="prbdm_speed_accuracy.png")
    args = parser.parse_args()
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


if __name__ == "__main__":
    main()
