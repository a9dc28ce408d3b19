"""Random-beam PRBDM study: plan, keys and the per-beam task (paper 001, Sec. 2.1).

A study is a seed, a number of beams and one or more PRBDM model configurations (n joints,
matched modes, objective, multistarts). Beam ``i`` of study seed ``S`` is
:func:`~pinflex.prbdm.beams.random_beam` with the 63-bit seed
``SeedSequence([S, i]).generate_state(1, uint64) >> 1`` (stored in each row as
``params.beam_seed``, so any beam is rebuilt alone). The same number also seeds the fit's
multistart points, which makes every row a pure function of its key.

Timings are wall-clock (``*_s``) and CPU time of the worker process (``*_cpu_s``); on a
shared machine the CPU times are the ones to size a study with.

One task handles one beam: it builds the planform, computes the reference ("truth") once, and
fits every configuration still missing for that beam. Exceptions never leave a task: each
failed stage becomes a row with ``status = 'failed'`` and its error text, so a bad beam is
recorded once instead of being retried forever.

A configuration's hash covers everything that changes a row: the beam generator settings, the
truth settings (modes, load levels) and the fit settings. Runs that differ only in
``--beams``, ``--workers`` or the scheduler share keys, so a study can be extended or resumed.
"""

from __future__ import annotations

import hashlib
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from pinflex.batch.store import canonical_json
from pinflex.exceptions import BatchError
from pinflex.prbdm.options import DEFAULT_ALPHAS, OBJECTIVES

KIND = "prbdm"


def config_hash(config: dict) -> str:
    """Short stable hash (16 hex digits of SHA-256) of a configuration's canonical JSON."""
    return hashlib.sha256(canonical_json(config).encode()).hexdigest()[:16]


def beam_seed(seed: int, index: int) -> int:
    """Seed of beam ``index`` in study ``seed``: a non-negative 63-bit integer.

    Nearby studies and beams get unrelated streams (``numpy.random.SeedSequence``), and the
    value fits a signed 64-bit SQLite integer.
    """
    if seed < 0 or index < 0:
        raise BatchError(f"seed = {seed} and beam index = {index} must be non-negative")
    state = np.random.SeedSequence([int(seed), int(index)]).generate_state(1, np.uint64)
    return int(state[0]) >> 1


#: Most beams of one ``pinflex batch prbdm`` study (rows of the store).
MAX_BEAMS = 1_000_000
#: Most multistart points per search.
MAX_STARTS = 1000
#: Most random interior planform vertices.
MAX_SECTIONS = 1000
#: Most joints of an nR model (and reference modes).
MAX_LINKS = 64


@dataclass(frozen=True)
class PrbdmStudy:
    """Settings of a random-beam PRBDM study.

    Attributes:
        seed: Study seed (non-negative).
        n_beams: Number of beams; beam indices are 0 .. n_beams - 1.
        links: Joint counts n of the fitted nR models, one configuration each.
        modes: Matched modes per configuration (same length as ``links``); default n.
        objective: ``"eigen"``, ``"deflection"``, ``"combined"`` or ``"pareto"``.
        n_starts: Multistart points per search.
        stiffness_law: ``"segment"`` or ``"paper"``.
        poses: ``"straight"`` or ``"paper"`` comparison poses.
        n_sections: Random interior vertices p of each planform (the paper uses 10).
        length_m: Beam length [m].
        max_half_width_m: Scale of the random half-widths [m].
        thickness_m: Uniform thickness [m].
        truth_modes: Bending modes of the reference (>= every ``modes`` entry).
        alphas: Load levels of the deflection reference; empty skips the elastica.
    """

    seed: int
    n_beams: int
    links: tuple[int, ...] = (3,)
    modes: tuple[int, ...] | None = None
    objective: str = "combined"
    n_starts: int = 16
    stiffness_law: str = "segment"
    poses: str = "straight"
    n_sections: int = 10
    length_m: float = 1.0
    max_half_width_m: float = 0.5
    thickness_m: float = 0.040532
    truth_modes: int = 5
    alphas: tuple[float, ...] = field(default=DEFAULT_ALPHAS)

    def __post_init__(self) -> None:
        links = tuple(int(n) for n in self.links)
        modes = links if self.modes is None else tuple(int(m) for m in self.modes)
        if len(modes) == 1 and len(links) > 1:
            modes = tuple(min(modes[0], n) for n in links)
        object.__setattr__(self, "links", links)
        object.__setattr__(self, "modes", modes)
        object.__setattr__(self, "alphas", tuple(float(a) for a in self.alphas))
        if self.seed < 0:
            raise BatchError(f"--seed {self.seed} must be >= 0")
        for value, name, top in ((self.n_beams, "--beams", MAX_BEAMS),
                                 (self.n_starts, "--starts", MAX_STARTS),
                                 (self.n_sections, "--sections", MAX_SECTIONS),
                                 (max(links, default=1), "--links", MAX_LINKS),
                                 (self.truth_modes, "--truth-modes", MAX_LINKS)):
            low = 0 if name == "--sections" else 1
            if not low <= value <= top:  # counted before any work: each unit is a full fit
                raise BatchError(f"{name} {value} must be between {low} and {top}")
        if not links or min(links) < 1:
            raise BatchError(f"--links {list(links)}: give one or more joint counts >= 1")
        if len(modes) != len(links):
            raise BatchError(f"--modes {list(modes)} needs one value per --links entry "
                             f"{list(links)} (or a single value)")
        for n, m in zip(links, modes):
            if not 1 <= m <= n:
                raise BatchError(f"the {n}R model has {n} modes; --modes asks for {m}")
        if max(modes) > self.truth_modes:
            raise BatchError(f"--truth-modes {self.truth_modes} is below the {max(modes)} "
                             "matched modes; raise it")
        if self.objective not in OBJECTIVES:
            raise BatchError(f"--objective {self.objective!r}: expected one of {OBJECTIVES}")
        if self.objective != "eigen" and not self.alphas:
            raise BatchError(f"the {self.objective!r} objective needs deflection loads; "
                             "give --alphas")
        if self.n_starts < 1:
            raise BatchError(f"--starts {self.n_starts} must be >= 1")

    def beam_settings(self) -> dict:
        """Settings of the random planform generator."""
        return {"n_sections": self.n_sections, "length_m": self.length_m,
                "max_half_width_m": self.max_half_width_m, "thickness_m": self.thickness_m,
                "material": {"name": "steel", "youngs_modulus_pa": 205e9,
                             "density_kg_m3": 7850.0}}

    def truth_settings(self) -> dict:
        """Settings of the reference solution."""
        return {"n_modes": self.truth_modes, "alphas": list(self.alphas)}

    def configs(self) -> list[dict]:
        """One model configuration per ``links`` entry (what the hash covers)."""
        return [{"kind": KIND, "beam": self.beam_settings(), "truth": self.truth_settings(),
                 "fit": {"n_joints": n, "n_modes": m, "objective": self.objective,
                         "n_starts": self.n_starts, "stiffness_law": self.stiffness_law,
                         "poses": self.poses}}
                for n, m in zip(self.links, self.modes or self.links)]

    def to_dict(self) -> dict:
        """Plain dictionary of the settings."""
        return asdict(self)


def planform_params(planform, seed: int) -> dict:
    """Row parameters of a planform: its seed, vertices and thickness."""
    return {"beam_seed": seed, "x_m": planform.x_m.tolist(),
            "half_width_m": planform.half_width_m.tolist(),
            "thickness_m": float(planform.thickness_m), "length_m": planform.length_m}


def _error_text(stage: str, exc: BaseException) -> str:
    return f"{stage}: {type(exc).__name__}: {exc}"


def _worker_address() -> str | None:
    try:
        from distributed import get_worker

        return get_worker().address
    except (ImportError, ValueError):
        return None


def run_prbdm_beam(study: dict, seed: int, item: int,
                   configs: list[tuple[str, dict]]) -> list[dict]:
    """Build beam ``item`` of study ``seed``, compute its truth and fit each configuration.

    Runs on a Dask worker; inputs and outputs are plain data. Never raises for a failing beam.

    Args:
        study: :meth:`PrbdmStudy.beam_settings` and :meth:`PrbdmStudy.truth_settings` under
            the keys ``"beam"`` and ``"truth"``.
        seed: Study seed.
        item: Beam index.
        configs: ``(config_hash, config)`` pairs to fit (see :meth:`PrbdmStudy.configs`).

    Returns:
        One row (a dictionary with the fields of :class:`~pinflex.batch.store.Row`) per
        configuration.
    """
    from pinflex.prbdm.beams import Material, random_beam
    from pinflex.prbdm.mapping import fit_prbdm
    from pinflex.prbdm.problem import compute_truth

    t_task, cpu_task = time.perf_counter(), time.process_time()
    worker = _worker_address()
    bseed = beam_seed(seed, item)
    beam, truth_cfg = study["beam"], study["truth"]
    params: dict = {"beam_seed": bseed}
    truth_json = None
    error = None
    timings = {"beam_s": 0.0, "truth_s": 0.0, "truth_cpu_s": 0.0}
    stage = "beam"
    try:
        t0 = time.perf_counter()
        material = Material(E=beam["material"]["youngs_modulus_pa"],
                            density=beam["material"]["density_kg_m3"],
                            name=beam["material"]["name"])
        planform = random_beam(bseed, n_sections=beam["n_sections"], length_m=beam["length_m"],
                               max_half_width_m=beam["max_half_width_m"],
                               thickness_m=beam["thickness_m"], material=material)
        params = planform_params(planform, bseed)
        timings["beam_s"] = time.perf_counter() - t0
        stage = "truth"
        t0, c0 = time.perf_counter(), time.process_time()
        try:
            truth = compute_truth(planform, truth_cfg["n_modes"], tuple(truth_cfg["alphas"]))
        finally:
            timings["truth_s"] = time.perf_counter() - t0
            timings["truth_cpu_s"] = time.process_time() - c0
        truth_json = {
            "freq_hz": truth.modes.freq_hz.tolist(),
            "rel_error_estimate": truth.modes.rel_error_estimate.tolist(),
            "n_elements": list(truth.modes.n_elements),
            "alphas": truth.alphas.tolist(),
            "forces_n": truth.forces_n.tolist(),
            "tips_m": truth.tips_m.tolist(),
        }
    except Exception as exc:  # noqa: BLE001 - recorded in the row, never re-raised
        error = _error_text(stage, exc)

    rows = []
    for chash, config in configs:
        fit_cfg = config["fit"]
        row: dict[str, Any] = {"seed": seed, "item": item, "config_hash": chash, "kind": KIND,
               "params": params, "truth": truth_json, "result": None, "metrics": {},
               "worker": worker, "status": "failed", "error": error}
        t0, c0 = time.perf_counter(), time.process_time()
        if error is None:
            try:
                fit = fit_prbdm(planform, fit_cfg["n_joints"], fit_cfg["n_modes"],
                                objective=fit_cfg["objective"],
                                stiffness_law=fit_cfg["stiffness_law"], poses=fit_cfg["poses"],
                                n_starts=fit_cfg["n_starts"], seed=bseed, truth=truth)
                row["result"] = fit.to_dict()
                row["metrics"] = {"eigen_error": fit.eigen_error,
                                  "deflection_error": fit.deflection_error,
                                  "deflection_error_position": fit.deflection_error_position,
                                  "combined_error": fit.combined_error,
                                  "eq15a_sum": fit.eq15a_sum,
                                  "exactly_determined": float(fit.exactly_determined)}
                row["status"], row["error"] = "ok", None
            except Exception as exc:  # noqa: BLE001 - recorded in the row
                row["error"] = _error_text("fit", exc)
        row["timings"] = dict(timings, fit_s=time.perf_counter() - t0,
                              fit_cpu_s=time.process_time() - c0)
        rows.append(row)
    for row in rows:
        row["timings"]["task_s"] = time.perf_counter() - t_task
        row["timings"]["task_cpu_s"] = time.process_time() - cpu_task
    return rows
