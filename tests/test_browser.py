"""Previews opened in headless Chromium: the robot is on screen and the animation moves it.

The static HTML is loaded from a file with the network blocked (an unreachable proxy and no
name resolution), so a page that needed anything online would render empty. ``#t=SECONDS``
pauses the animation at that time (see :mod:`pinflex.visualization.offline`), which makes the
screenshots deterministic; one pair of screenshots also lets the animation play on its own.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("meshcat", reason="previews need meshcat (pip install meshcat)")
Image = pytest.importorskip("PIL.Image", reason="reading screenshots needs Pillow")

from chromium import (  # noqa: E402
    CAPTION_ROWS,
    HEIGHT,
    WIDTH,
    draw_time_ms,
    find_browser,
    foreground,
    near,
    orange,
    screenshots,
)

from pinflex.visualization import centrelines, mode_preview, prbdm_preview  # noqa: E402

Q0 = np.array([1.817, 5.312])


@pytest.fixture(scope="module")
def browser():
    """Path of a Chromium executable, or skip."""
    return find_browser()




def test_mode_preview_shows_the_arm_and_its_oscillation(browser, two_link_planar, tmp_path):
    """Benchmark A mode 1: beam pixels lie on the projected deformed centreline at both peaks.

    The two peaks differ where the beam swings.
    """
    preview = mode_preview(two_link_planar, Q0, 1, amplitude_m=0.06)
    html = preview.write_html(tmp_path / "mode.html")
    shots = screenshots(browser, tmp_path, html, ["t=0.5&gui=0", "t=1.5&gui=0"])
    result = two_link_planar.modes(Q0, n_modes=1)
    lines = centrelines(two_link_planar, result, 1)
    scale = preview.info["scale"]
    visible = slice(0, HEIGHT - CAPTION_ROWS)
    for img, s in zip(shots, (scale, -scale)):
        fg = foreground(img)
        assert 2000 < fg[visible].sum() < 0.25 * WIDTH * HEIGHT
        beam = orange(img)
        for c in lines.values():
            px = preview.camera.project(c.at(s), WIDTH, HEIGHT)
            assert np.all(px[:, 1] < HEIGHT - CAPTION_ROWS)
            # the beam's ends hide under joint and mass spheres; the rest is orange
            missing = [p for p in px[1:-1] if not near(beam, p)]
            assert not missing, f"no beam pixels at {np.round(missing)}"
            assert near(fg, px[0]) and near(fg, px[-1])
        # nothing is drawn far from the robot
        rows, cols = np.nonzero(fg[visible])
        box = preview.camera.project(np.vstack([c.at(s) for c in lines.values()]), WIDTH, HEIGHT)
        assert cols.min() > box[:, 0].min() - 40 and cols.max() < box[:, 0].max() + 40
        assert rows.min() > box[:, 1].min() - 40
    a, b = shots
    changed = np.abs(a - b).sum(axis=2) > 60
    assert changed[visible].sum() > 1500
    # where the first link swings most, the beam is on one side at one peak only
    c = lines["link1"]
    k = int(np.argmax(np.linalg.norm(c.displacement_m, axis=1)))
    pa = preview.camera.project(c.at(scale)[k], WIDTH, HEIGHT)[0]
    pb = preview.camera.project(c.at(-scale)[k], WIDTH, HEIGHT)[0]
    assert np.linalg.norm(pa - pb) > 15
    assert near(orange(a), pa) and not near(orange(b), pa, radius=1)
    assert near(orange(b), pb) and not near(orange(a), pb, radius=1)


def test_trajectory_playback_runs_by_itself(browser, two_link_planar, tmp_path):
    """Benchmark A playback: colours follow the frequency (yellow high, purple low).

    Without a ``#t=`` fragment the animation advances on its own with the browser's clock.
    """
    from pinflex.assignment.study import user_trajectory
    from pinflex.visualization import trajectory_preview

    traj = user_trajectory(two_link_planar, "benchmark_a")
    preview = trajectory_preview(two_link_planar, traj.times_s, traj.q)
    html = preview.write_html(tmp_path / "traj.html")
    f = preview.info["freq_hz"]
    hi, lo = int(np.argmax(f)), int(np.argmin(f))
    t_hi, t_lo = 4.0 * traj.times_s[hi], 4.0 * traj.times_s[lo]
    shots = screenshots(browser, tmp_path, html,
                        [f"t={t_hi:.4f}&gui=0", f"t={t_lo:.4f}&gui=0", "gui=0", "gui=0"],
                        budget_ms=(1000, 1000, 1500, 4000))
    from pinflex.visualization.robot import pose_state

    for img, k, yellow in ((shots[0], hi, True), (shots[1], lo, False)):
        st = pose_state(two_link_planar, traj.q[k], 1)
        mid = 0.5 * (st.beams["link1"][0] + st.beams["link1"][-1])
        c, r = np.round(preview.camera.project(mid, WIDTH, HEIGHT)[0]).astype(int)
        patch = img[r - 1: r + 2, c - 1: c + 2].reshape(-1, 3).mean(axis=0)
        if yellow:
            assert patch[0] > 150 and patch[1] > 150 and patch[2] < 100, patch
        else:  # viridis' dark purple end
            assert patch.max() < 130 and patch[1] < 40 and patch[2] > patch[0], patch
    changed = np.abs(shots[2] - shots[3]).sum(axis=2) > 60
    assert changed[: HEIGHT - CAPTION_ROWS].sum() > 1000


def test_prbdm_preview_shows_the_chain_over_its_beam(browser, tmp_path):
    """A 4R chain over a random beam: drawn in the framed region, and it moves."""
    from pinflex.prbdm.beams import random_beam
    from pinflex.prbdm.chain import build_chain
    from pinflex.visualization.prbdm import chain_frames

    beam = random_beam(3)
    chain = build_chain(beam, np.array([0.1, 0.3, 0.3, 0.2, 0.1]), np.array([4e4, 3e4, 2e4, 1e4]))
    preview = prbdm_preview(beam, chain, amplitude_m=0.15)
    html = preview.write_html(tmp_path / "prbdm.html")
    shots = screenshots(browser, tmp_path, html, ["t=0.5&gui=0", "t=1.5&gui=0"])
    s = preview.info["scale"]
    for img, sign in zip(shots, (1.0, -1.0)):
        fg = foreground(img)
        joints = [F.translation for F in chain_frames(chain, sign * s * preview.info["shape"])]
        for p in preview.camera.project(np.array(joints), WIDTH, HEIGHT):
            assert near(fg, p, radius=3)
        assert fg[: HEIGHT - CAPTION_ROWS].sum() > 5000
    changed = np.abs(shots[0] - shots[1]).sum(axis=2) > 60
    assert changed[: HEIGHT - CAPTION_ROWS].sum() > 1000


SHIPPED_DIR = Path(__file__).resolve().parents[1] / "urdf"
#: Every shipped description; poses other than zero where the paper or an example uses one.
SHIPPED = {path.name: (path.name == "two_link.urdf", None)
           for path in sorted(SHIPPED_DIR.iterdir()) if path.suffix in (".urdf", ".xml")}
SHIPPED["two_link.urdf"] = (True, [1.817, 5.312])
SHIPPED["ur5_flexible.xml"] = (False, [0.0, -1.0, 1.2, 0.3, 0.5, 0.0])


@pytest.mark.parametrize("name", sorted(SHIPPED))
def test_mode_pages_of_the_shipped_arms_are_small_and_render(browser, name, tmp_path):
    """Six modes of each shipped arm (every file of urdf/): at most 5 MB, drawn offline.

    The time from the page's start to its first drawn frame of the scene (decoding, scene
    building, drawing; measured by the page itself, in real time) is printed, not asserted: it
    depends on the machine's load (`pytest -s -k shipped_arms` shows it).
    """
    from pinflex import FlexibleModel
    from pinflex.description.builtin import builtin_path
    from pinflex.visualization import modes_preview

    planar, q = SHIPPED[name]
    model = FlexibleModel(builtin_path(name), planar=planar)
    q = np.zeros(model.nv) if q is None else np.array(q)
    page = modes_preview(model, q, 6).write_html(tmp_path / "modes.html")
    size_mb = page.stat().st_size / 1e6
    assert size_mb <= 5.0, f"{name}: {size_mb:.2f} MB"
    drawn_ms = draw_time_ms(browser, page, tmp_path / "timing-profile")
    print(f"\n{name}: six modes, {size_mb:.2f} MB, drawn {drawn_ms / 1000:.1f} s after the "
          "page started")
    (shot,) = screenshots(browser, tmp_path, page, ["t=0.5&gui=0"])
    fg = foreground(shot)[: HEIGHT - CAPTION_ROWS]
    assert fg.sum() > 5000
    assert orange(shot)[: HEIGHT - CAPTION_ROWS].sum() > 500  # the beams are drawn
