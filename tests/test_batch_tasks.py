"""Tests of pinflex/batch/tasks.py: random-beam study plan and the per-beam task."""

from __future__ import annotations

import numpy as np
import pytest

from pinflex.batch.tasks import PrbdmStudy, beam_seed, config_hash, run_prbdm_beam
from pinflex.exceptions import BatchError

TINY = dict(links=(2,), n_starts=2, n_sections=3, truth_modes=2, alphas=(1.0,))


def _run(study: PrbdmStudy, item: int, configs=None) -> list[dict]:
    configs = configs or [(config_hash(c), c) for c in study.configs()]
    shared = {"beam": study.beam_settings(), "truth": study.truth_settings()}
    return run_prbdm_beam(shared, study.seed, item, configs)


def test_beam_seeds_are_stable_distinct_and_fit_sqlite():
    """Beam seeds depend only on (seed, index), differ between beams and fit in int64."""
    seeds = [beam_seed(5, i) for i in range(200)] + [beam_seed(6, i) for i in range(200)]
    assert len(set(seeds)) == 400
    assert all(0 <= s < 2**63 for s in seeds)
    assert beam_seed(5, 17) == beam_seed(5, 17)
    with pytest.raises(BatchError, match="non-negative"):
        beam_seed(-1, 0)


def test_config_hash_covers_settings_but_not_study_size():
    """The hash changes with fit, truth and beam settings, not with the beam count."""
    base = PrbdmStudy(seed=1, n_beams=10, **TINY)
    (h,) = [config_hash(c) for c in base.configs()]
    assert config_hash(PrbdmStudy(seed=1, n_beams=500, **TINY).configs()[0]) == h
    assert config_hash(PrbdmStudy(seed=9, n_beams=10, **TINY).configs()[0]) == h
    for change in ({"n_starts": 3}, {"n_sections": 4}, {"alphas": (2.0,)},
                   {"truth_modes": 3}, {"objective": "eigen"}):
        other = PrbdmStudy(seed=1, n_beams=10, **dict(TINY, **change))
        assert config_hash(other.configs()[0]) != h, change


@pytest.mark.parametrize("kwargs, message", [
    ({"links": (2,), "modes": (3,)}, "2R model has 2 modes"),
    ({"links": (2, 3), "modes": (2, 2, 2)}, "one value per --links"),
    ({"links": (4,), "truth_modes": 3}, "--truth-modes 3"),
    ({"objective": "pareto", "alphas": ()}, "needs deflection loads"),
    ({"objective": "fast"}, "expected one of"),
])
def test_bad_studies_are_rejected(kwargs, message):
    """Inconsistent study settings raise BatchError naming the option to fix."""
    with pytest.raises(BatchError, match=message):
        PrbdmStudy(seed=0, n_beams=1, **kwargs)


def test_one_modes_value_is_capped_per_model():
    """A single --modes value applies to every model, capped at its joint count."""
    study = PrbdmStudy(seed=0, n_beams=1, links=(2, 3, 4), modes=(3,), truth_modes=3)
    assert study.modes == (2, 3, 3)


def test_task_row_matches_an_independent_rebuild():
    """The stored beam, truth and fit agree with the beam, beam FE and chain rebuilt here."""
    from pinflex.prbdm.beams import random_beam
    from pinflex.prbdm.chain import build_chain, chain_frequencies
    from pinflex.prbdm.truth import beam_frequencies

    study = PrbdmStudy(seed=11, n_beams=1, **dict(TINY, objective="eigen"))
    (row,) = _run(study, 0)
    assert row["status"] == "ok" and row["error"] is None
    assert row["params"]["beam_seed"] == beam_seed(11, 0)
    beam = random_beam(beam_seed(11, 0), n_sections=3)
    np.testing.assert_array_equal(row["params"]["x_m"], beam.x_m)
    np.testing.assert_array_equal(row["params"]["half_width_m"], beam.half_width_m)
    truth_hz = beam_frequencies(beam, 2).freq_hz
    np.testing.assert_allclose(row["truth"]["freq_hz"], truth_hz, rtol=1e-12)
    fit = row["result"]
    chain = build_chain(beam, np.array(fit["link_fractions"]), np.array(fit["stiffness"]))
    model_hz = chain_frequencies(chain, np.zeros(2))[:2]
    # the stored frequencies are those of the stored chain, rebuilt here from its design
    np.testing.assert_allclose(fit["model_hz"], model_hz, rtol=1e-10)
    # the stored metric is the RMS relative error (the mapping's definition) of those numbers
    rms = float(np.sqrt(np.mean((model_hz / truth_hz - 1.0) ** 2)))
    assert row["metrics"]["eigen_error"] == pytest.approx(rms, rel=1e-3, abs=1e-14)
    assert rms < 1e-6  # a 2R model matches two modes exactly
    assert 0.0 < row["metrics"]["deflection_error"] < 1.0
    assert set(row["timings"]) >= {"truth_s", "fit_s", "task_s"}


def test_a_failing_fit_is_a_row_not_an_exception():
    """A configuration the fit rejects yields a failed row with the error; others succeed."""
    study = PrbdmStudy(seed=11, n_beams=1, **dict(TINY, objective="eigen"))
    good = study.configs()[0]
    bad = {**good, "fit": {**good["fit"], "n_joints": 3, "n_modes": 3}}  # truth has 2 modes
    rows = _run(study, 0, [("bad", bad), ("good", good)])
    assert [r["status"] for r in rows] == ["failed", "ok"]
    assert rows[0]["error"].startswith("fit: InvalidChain:")
    assert "3 requested" in rows[0]["error"]
    assert rows[0]["truth"] == rows[1]["truth"]


def test_a_failing_beam_fails_every_configuration():
    """A planform that cannot be built fails all of the beam's rows at the 'beam' stage."""
    study = PrbdmStudy(seed=11, n_beams=1, thickness_m=-1.0, **TINY)
    rows = _run(study, 0, [(f"h{n}", c) for n, c in enumerate(study.configs() * 2)])
    assert [r["status"] for r in rows] == ["failed", "failed"]
    assert all(r["error"].startswith("beam: InvalidBeam:") for r in rows)
    assert all(r["params"] == {"beam_seed": beam_seed(11, 0)} for r in rows)
