"""The all-modes page: user viewers, the grid, the selector data, `view --trajectory`."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("meshcat", reason="previews need meshcat (pip install meshcat)")

from conftest import TWO_LINK  # noqa: E402

from pinflex.exceptions import ConfigurationError  # noqa: E402
from pinflex.visualization import offline_visualizer  # noqa: E402
from pinflex.visualization.modes_page import modes_preview, nice_spacing  # noqa: E402

Q0 = np.array([1.817, 5.312])


def test_grid_spacing_is_round():
    """1, 2 or 5 times a power of ten, at least a tenth of the size."""
    assert [nice_spacing(s) for s in (0.83, 1.0, 2.4, 12.0, 0.031)] == pytest.approx(
        [0.1, 0.1, 0.5, 2.0, 0.005])


def test_draws_into_a_users_pinocchio_meshcat_visualizer(two_link_planar):
    """A Pinocchio MeshcatVisualizer's viewer receives the scene; select() swaps the clip."""
    import pinocchio as pin
    from pinocchio.visualize import MeshcatVisualizer

    viz = MeshcatVisualizer(two_link_planar.model, pin.GeometryModel(), pin.GeometryModel())
    viz.initViewer(viewer=offline_visualizer(), open=False)
    page = modes_preview(two_link_planar, Q0, 3, viewer=viz, frames=4)
    window = viz.viewer.window
    assert window.tree["meshcat"]["pinflex"]["grid"].object is not None
    f = two_link_planar.frequencies(Q0, n_modes=3)
    np.testing.assert_allclose(page.freq_hz, f, rtol=1e-10)  # two eigensolvers
    assert page.modes == (1, 2, 3) and f"mode 2 at {f[1]:.2f} Hz" in page.captions[1]
    first = window.animation
    page.select(3)
    assert window.animation != first and window.caption == page.captions[2]
    html = page.html(initial=2)
    assert html.count("<option value=") == 3 and "indexOf(m ? parseInt(m[1], 10) : 2)" in html
    with pytest.raises(ConfigurationError):
        page.select(7)
    with pytest.raises(ConfigurationError, match="viewer must be"):
        modes_preview(two_link_planar, Q0, 2, viewer=object())
    with pytest.raises(ConfigurationError, match="must lie in"):
        modes_preview(two_link_planar, Q0, [0, 1])


def test_view_cli_trajectory_and_modes_page(tmp_path, capsys):
    """`pinflex view --trajectory CSV --html` plays the motion; without it the modes page."""
    from pinflex.cli import main
    from pinflex.erls import FlexibleModel
    from pinflex.trajectory import Trajectory

    model = FlexibleModel(TWO_LINK, planar=True)
    q = np.linspace(Q0, Q0 + [0.2, -0.3], 5)
    Trajectory(np.linspace(0, 1, 5), q, model.joint_names).to_csv(tmp_path / "t.csv")
    out = tmp_path / "traj.html"
    assert main(["view", str(TWO_LINK), "--planar", "--trajectory", str(tmp_path / "t.csv"),
                 "--html", str(out)]) == 0
    f1 = model.frequencies(q, n_modes=1)[:, 0]
    printed = capsys.readouterr().out
    assert f"from {f1.min():.2f} to {f1.max():.2f} Hz" in printed and out.is_file()
    page = tmp_path / "modes.html"
    assert main(["view", str(TWO_LINK), "--planar", "--q", *map(str, Q0), "--modes", "3",
                 "--html", str(page)]) == 0
    text = page.read_text()
    assert text.count("<option value=") == 3 and "pinflex-mode-select" in text
