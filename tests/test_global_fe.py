"""ERLS frequencies equal an independent global FE model of the same mesh (round-off level)."""

import numpy as np
import pytest
from arms import spatial_reference, spatial_urdf
from conftest import TWO_LINK
from reference_fe import planar_two_link_frequencies

from pinflex.description import parse
from pinflex.erls import FlexibleModel


def test_benchmark_a_matches_global_frame_model_at_random_poses_and_masses():
    """At 24 random poses and point masses benchmark A equals the hinged global frame to 1e-9."""
    model = FlexibleModel(TWO_LINK, planar=True)
    rng = np.random.default_rng(2021)
    worst = 0.0
    for _ in range(24):
        q_abs = rng.uniform(-np.pi, 2 * np.pi, size=2)
        y = rng.uniform(0.0, 0.25, size=2)
        ours = model.frequencies(q_abs, y)
        _, ref = planar_two_link_frequencies(q_abs, y[0], y[1])
        worst = max(worst, np.max(np.abs(ours / ref - 1)))
    assert worst < 1e-9


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_spatial_two_link_matches_global_frame_model(seed):
    """A skewed spatial 2-link arm with unequal sections equals the global 3D frame to 1e-9."""
    rng = np.random.default_rng(seed)
    m1, m2 = rng.uniform(0, 0.5, size=2)
    model = FlexibleModel(parse(spatial_urdf(m1, m2)))
    for q in rng.uniform(-np.pi, np.pi, size=(3, 2)):
        _, ref = spatial_reference(q, m1, m2)
        ours = model.frequencies(q)
        assert ours.shape == ref.shape
        np.testing.assert_allclose(ours, ref, rtol=1e-9)
