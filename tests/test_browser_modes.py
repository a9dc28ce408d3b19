"""The all-modes page in headless Chromium: the selector switches mode shape and caption."""

from __future__ import annotations

import subprocess

import numpy as np
import pytest

pytest.importorskip("meshcat", reason="previews need meshcat (pip install meshcat)")
pytest.importorskip("PIL.Image", reason="reading screenshots needs Pillow")

from chromium import (  # noqa: E402
    CAPTION_ROWS,
    HEIGHT,
    WIDTH,
    find_browser,
    near,
    orange,
    screenshots,
)

from pinflex.visualization import centrelines  # noqa: E402
from pinflex.visualization.modes_page import modes_preview  # noqa: E402

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def chromium():
    """Path of a Chromium executable, or skip."""
    return find_browser()


@pytest.fixture(scope="module")
def page(two_link_planar, tmp_path_factory):
    """Benchmark A, modes 1-4 on one page."""
    preview = modes_preview(two_link_planar, Q0, 4, amplitude_m=0.06)
    html = preview.write_html(tmp_path_factory.mktemp("modes") / "modes.html")
    return preview, html


def test_selector_lists_every_mode_with_its_frequency(page, two_link_planar, chromium, tmp_path):
    """The options name modes 1-4 and their frequencies; #mode=K selects K (caption, DOM)."""
    preview, html = page
    f = two_link_planar.frequencies(Q0, n_modes=4)
    text = html.read_text()
    for k in range(4):
        assert f'<option value="{k}">{k + 1}: {f[k]:.2f} Hz</option>' in text
    out = subprocess.run(
        [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--enable-unsafe-swiftshader",
         f"--user-data-dir={tmp_path / 'p'}", "--virtual-time-budget=1000", "--dump-dom",
         f"{html.as_uri()}#mode=3&t=0.5"],
        capture_output=True, text=True, timeout=120,
    ).stdout
    assert f"mode 3 at {f[2]:.2f} Hz" in out
    assert f"<title>{preview.captions[2]}" in out or preview.captions[2] in out


def test_selected_mode_is_the_one_drawn(page, two_link_planar, chromium, tmp_path):
    """At t = 0.5 s (peak) the beams lie on mode 1's centreline, then on mode 3's."""
    preview, html = page
    shots = screenshots(chromium, tmp_path, html, ["mode=1&t=0.5&gui=0", "mode=3&t=0.5&gui=0"])
    result = two_link_planar.modes(Q0, n_modes=4)
    for img, mode in zip(shots, (1, 3)):
        beam = orange(img)
        s = preview.info["scales"][mode]
        for c in centrelines(two_link_planar, result, mode).values():
            px = preview.camera.project(c.at(s), WIDTH, HEIGHT)
            assert np.all(px[:, 1] < HEIGHT - CAPTION_ROWS)
            missing = [p for p in px[1:-1] if not near(beam, p)]
            assert not missing, f"mode {mode}: no beam pixels at {np.round(missing)}"
    # and the two pictures differ: the selection changed the animation, not only the caption
    changed = np.abs(shots[0] - shots[1]).sum(axis=2) > 60
    assert changed[: HEIGHT - CAPTION_ROWS].sum() > 1000
