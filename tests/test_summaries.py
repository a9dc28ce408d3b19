"""Short summaries of models and results: what they hold, never an array dump."""

from __future__ import annotations

import dataclasses

import numpy as np

from pinflex.summaries import array_summary, dataclass_summary, model_summary, taylor_summary


def test_small_arrays_are_shown_and_large_ones_summarised():
    """Up to six values appear rounded; a larger array becomes shape, dtype and range."""
    assert array_summary(np.array([1.817, 5.312])) == "[1.817, 5.312]"
    big = np.linspace(-2.0, 3.0, 152 * 2).reshape(152, 2)
    assert array_summary(big) == "<152×2 float64, -2 .. 3>"
    assert "1 not finite" in array_summary(np.array([1.0, np.nan, 2.0, 3.0, 4.0, 5.0, 6.0]))


def test_dataclass_summary_has_no_array_dump():
    """A result with a 1000-sample array prints in a few lines, naming each field."""

    @dataclasses.dataclass
    class Result:
        found: bool
        freq_hz: np.ndarray
        design: dict
        hidden: np.ndarray = dataclasses.field(default=None, repr=False)

    text = dataclass_summary(Result(True, np.arange(1000.0), {"m1": 0.237}))
    assert text == "Result(found=True, freq_hz=<1000 float64, 0 .. 999>, design={m1: 0.237})"


def test_flexible_model_summary_names_what_matters(two_link_planar):
    """Robot, dof, flexible links, joint conditions and design, on a few lines."""
    text = model_summary(two_link_planar)
    for part in ("'two_link'", "23 (21 elastic + 2 joints, planar)", "link1 (4 elements, 0.6 m)",
                 "link2 (3 elements, 0.45 m)", "all free (2)", "{m1: 0.125, m2: 0.125}", "absolute"):
        assert part in text, part
    assert len(text.splitlines()) <= 10


def test_taylor_summary_names_order_variables_modes_and_radius(two_link_planar):
    """Order, the expanded variables, the modes and each mode's radius per variable."""
    import pinflex

    tm = pinflex.expand(two_link_planar, [1.817, 5.312], order=4, modes=(1, 2))
    text = taylor_summary(tm)
    assert "order=4" in text and "variables=4 (joints q[0], q[1]; design y[0], y[1])" in text
    assert "modes=(1, 2)" in text and "q0=[1.817, 5.312]" in text
    r = np.asarray(tm.radius)
    assert f"mode 2: {array_summary(r[:, 1])}" in text
    assert "array(" not in text and len(text) < 600
    assert repr(tm) == text


def test_flexible_model_prints_its_summary_and_lists_its_public_surface(two_link_planar):
    """repr is the summary; dir() lists the public names, not the helpers other layers call."""
    from pinflex.erls.model import PUBLIC

    assert repr(two_link_planar) == model_summary(two_link_planar)
    public = [n for n in dir(two_link_planar) if not n.startswith("_")]
    assert public == sorted(PUBLIC)
    assert "check_q" not in public and "pose_terms_one" not in public
    assert all(hasattr(two_link_planar, n) for n in PUBLIC)


def test_result_reprs_summarise(two_link_planar):
    """An assignment result prints its fields with arrays summarised, in under 40 lines."""
    import pinflex
    from pinflex.assignment.study import user_trajectory

    traj = user_trajectory(two_link_planar, "benchmark_a")
    result = pinflex.assign_frequencies(two_link_planar, traj, [pinflex.Target(1, 190.0)],
                                        q0=[1.817, 5.312])
    text = repr(result)
    assert "array(" not in text and len(text.splitlines()) < 40
    assert f"max_error_after={result.max_error_after:.6g}" in text
    assert "freq_after_hz=<152×1 float64" in text
