"""meshcat previews: the drawn geometry checked numerically, without a browser."""

from __future__ import annotations

import re
import subprocess
import sys
import urllib.request

import numpy as np
import pytest
from conftest import TWO_LINK, UR5, single_link_urdf

pytest.importorskip("meshcat", reason="previews need meshcat (pip install meshcat)")

from pinflex.description import parse  # noqa: E402
from pinflex.erls import FlexibleModel  # noqa: E402
from pinflex.visualization import (  # noqa: E402
    centrelines,
    mode_preview,
    mode_scale,
    prbdm_preview,
    trajectory_preview,
)
from pinflex.visualization.offline import viewer_js_path  # noqa: E402
from pinflex.visualization.shapes import link_twists  # noqa: E402

Q0 = np.array([1.817, 5.312])
Q_UR5 = np.array([0.3, -1.0, 1.2, -0.5, 0.4, 0.2])


@pytest.fixture(scope="module")
def ur5():
    """The UR5 overlay with flexible upper arm and forearm (spatial)."""
    return FlexibleModel(UR5)


def recorded_tracks(preview) -> dict[str, dict[str, list]]:
    """Keyframe values of the preview's animation: {node path: {track: [values by frame]}}."""
    import umsgpack

    data = umsgpack.unpackb(preview.viewer.window.animation)
    out = {}
    for anim in data["animations"]:
        clip = anim["clip"]
        out[anim["path"]] = {t["name"]: [k["value"] for k in t["keys"]] for t in clip["tracks"]}
    return out


def segment_ends(track: dict[str, list], frame: int) -> tuple[np.ndarray, np.ndarray]:
    """End points of a drawn unit cylinder (axis y) from its keyframe at ``frame``."""
    import meshcat.transformations as tf

    x, y, z, w = track[".quaternion"][frame]
    R = tf.quaternion_matrix([w, x, y, z])[:3, :3]
    half = 0.5 * track[".scale"][frame][1] * R[:, 1]
    p = np.asarray(track[".position"][frame])
    return p - half, p + half


@pytest.mark.parametrize("mode", [1, 2, 3])
def test_centreline_at_nodes_equals_nodal_mode_displacement_planar(two_link_planar, mode):
    """Benchmark A: drawn stations at the nodes are node positions + s · nodal translations."""
    r = two_link_planar.modes(Q0, n_modes=3)
    for link, c in centrelines(two_link_planar, r, mode).items():
        for s in (0.0, 0.03, -0.11):
            want = r.node_positions[link] + s * r.node_motion[link][mode - 1, :, :3]
            np.testing.assert_allclose(c.at(s)[c.node_index], want, rtol=0, atol=1e-14)


def test_centreline_at_nodes_equals_nodal_mode_displacement_spatial(ur5):
    """UR5 overlay (spatial, two flexible links): the same identity for the first 3 modes."""
    r = ur5.modes(Q_UR5, n_modes=3)
    for mode in (1, 2, 3):
        for link, c in centrelines(ur5, r, mode).items():
            want = r.node_positions[link] + 0.2 * r.node_motion[link][mode - 1, :, :3]
            np.testing.assert_allclose(c.at(0.2)[c.node_index], want, rtol=0, atol=1e-14)


def test_drawn_beam_segments_pass_through_the_displaced_nodes(two_link_planar):
    """The cylinders in the animation chain through node + s_j · motion at every keyframe."""
    frames = 8
    p = mode_preview(two_link_planar, Q0, 1, amplitude_m=0.05, frames=frames)
    r = two_link_planar.modes(Q0, n_modes=1)
    scale = p.info["scale"]
    tracks = recorded_tracks(p)
    n_st = 8
    for link, plan in two_link_planar.plan.beams.items():
        n_seg = plan.spec.elements * n_st
        for j in range(frames + 1):
            s = scale * np.sin(2 * np.pi * j / frames)
            ends = [segment_ends(tracks[f"/meshcat/pinflex/beams/{link}/{i}"], j)
                    for i in range(n_seg)]
            starts = np.array([a for a, _ in ends] + [ends[-1][1]])
            np.testing.assert_allclose(np.array([b for _, b in ends[:-1]]), starts[1:-1],
                                       atol=1e-12)  # a continuous chain
            want = r.node_positions[link] + s * r.node_motion[link][0, :, :3]
            np.testing.assert_allclose(starts[::n_st], want, atol=1e-12)


def test_peak_drawn_displacement_equals_the_amplitude(two_link_planar):
    """mode_scale makes the largest nodal translation exactly the requested amplitude."""
    r = two_link_planar.modes(Q0, n_modes=2)
    s = mode_scale(r, 2, 0.04)
    peak = max(np.linalg.norm(m[1, :, :3], axis=1).max() for m in r.node_motion.values())
    assert s * peak == pytest.approx(0.04, rel=1e-14)


def test_bad_preview_requests_raise_named_errors(two_link_planar):
    """Mode 0, a mode past the elastic dofs and a zero amplitude are refused with the range."""
    from pinflex.exceptions import ConfigurationError

    with pytest.raises(ConfigurationError, match=r"modes 1\.\.21"):
        mode_preview(two_link_planar, Q0, 0)
    with pytest.raises(ConfigurationError, match=r"modes 1\.\.21"):
        mode_preview(two_link_planar, Q0, 22)
    with pytest.raises(ConfigurationError, match="positive length"):
        mode_preview(two_link_planar, Q0, 1, amplitude_m=0.0)


def test_missing_mesh_falls_back_to_simple_shapes():
    """A URDF whose mesh cannot be found previews with simple shapes and a named warning."""
    from pinflex.exceptions import PinflexWarning

    xml = single_link_urdf().replace(
        '<link name="base"/>',
        '<link name="base"><visual><geometry><mesh filename="package://nowhere/base.stl"/>'
        "</geometry></visual></link>",
    )
    model = FlexibleModel(parse(xml))
    with pytest.warns(PinflexWarning, match="nowhere/base.stl"):
        p = mode_preview(model, [0.3], 1, frames=4)
    nodes = p.viewer.window.tree["meshcat"]["pinflex"]
    assert sorted(nodes) == ["beams", "joints", "markers"]
    assert "base" in nodes["markers"] and len(nodes["beams"]["bar"]) == 40 * 8


def test_hermite_drawing_is_closer_to_a_fine_mesh_than_straight_segments():
    """A 2-element cantilever drawn with shape functions is 50x closer to a 32-element mode."""
    def drawn(elements, stations):
        m = FlexibleModel(parse(single_link_urdf(joint="fixed", elements=elements)))
        r = m.modes(np.zeros(0), n_modes=1)
        c = centrelines(m, r, 1, stations)["bar"]
        d = mode_scale(r, 1, 0.1) * c.displacement_m
        return c, d * np.sign(d[-1, 1])

    coarse, d_coarse = drawn(2, 8)
    _, d_fine = drawn(32, 1)
    fine = d_fine[::2]  # same stations: x = k L / 16
    hermite = np.abs(d_coarse - fine).max()
    x = coarse.positions_m[:, 0]
    nodes = d_coarse[coarse.node_index]
    straight = np.column_stack(
        [np.interp(x, x[coarse.node_index], nodes[:, k]) for k in range(3)]
    )
    assert hermite < 2e-4  # 0.2 % of the 0.1 m amplitude
    assert hermite < np.abs(straight - fine).max() / 50


def test_link_twists_continue_the_beams(two_link_planar):
    """The elbow link's origin moves as link 1's tip node; the tool as link 2's tip node."""
    r = two_link_planar.modes(Q0, n_modes=3)
    tw = link_twists(two_link_planar, Q0, r.shapes)
    from pinflex.visualization.shapes import link_placements

    M = link_placements(two_link_planar, Q0)
    for link, node_link, node in (("link2", "link1", -1), ("link2", "link2", 0),
                                  ("tool", "link2", -1)):
        R = M[link].rotation
        world = np.concatenate([tw[link][:, :3] @ R.T, tw[link][:, 3:] @ R.T], axis=1)
        got = r.node_motion[node_link][:, node, :]
        if link == "link2" and node_link == "link1":
            got, world = got[:, :3], world[:, :3]  # the elbow joint adds a rotation
        np.testing.assert_allclose(world, got, atol=1e-12)


def test_rigid_visuals_follow_the_forearm_tip(ur5):
    """UR5: the wrist mesh's link origin moves with the forearm beam's tip in every frame."""
    p = mode_preview(ur5, Q_UR5, 1, amplitude_m=0.05, frames=4)
    tracks = recorded_tracks(p)
    r = ur5.modes(Q_UR5, n_modes=1)
    tw = link_twists(ur5, Q_UR5, r.shapes)
    names = [k for k in tracks if "/robot/visuals/" in k]
    assert any("wrist_1" in k for k in names), names
    # wrist_1_link sits on the forearm tip: its translation is the tip node's
    from pinflex.visualization.shapes import link_placements

    R = link_placements(ur5, Q_UR5)["wrist_1_link"].rotation
    np.testing.assert_allclose(tw["wrist_1_link"][0, :3] @ R.T,
                               r.node_motion["forearm_link"][0, -1, :3], atol=1e-12)


def test_static_html_is_self_contained(two_link_planar, tmp_path):
    """The page inlines meshcat's viewer and references nothing over the network."""
    path = mode_preview(two_link_planar, Q0, 1).write_html(tmp_path / "m.html")
    html = path.read_text()
    js = viewer_js_path().read_text()
    assert js in html
    assert not re.search(r"<(script|link|img)[^>]+(src|href)\s*=", html)
    assert "fetch(" not in html.replace(js, "")
    assert "193.11 Hz" in html  # the caption states the frequency


def test_trajectory_playback_colours_and_labels(two_link_planar):
    """Benchmark A playback: one keyframe per sample, colours ordered by frequency, labels."""
    from pinflex.assignment.study import user_trajectory

    traj = user_trajectory(two_link_planar, "benchmark_a")
    p = trajectory_preview(two_link_planar, traj.times_s, traj.q)
    f = two_link_planar.frequencies(traj.q, n_modes=1)[:, 0]
    np.testing.assert_allclose(p.info["freq_hz"], f, rtol=1e-12)
    tracks = recorded_tracks(p)
    colour = np.array(tracks["/meshcat/pinflex/beams/link1/0/<object>"][".material.color"])
    assert colour.shape == (152, 3)
    # viridis: blue falls and green rises with the frequency
    order = np.argsort(f)
    assert np.all(np.diff(colour[order, 1]) >= -1e-12)
    assert colour[np.argmax(f), 1] > 0.85 > 0.2 > colour[np.argmin(f), 1]
    timeline = p.viewer.window.timeline
    assert len(timeline["labels"]) == 152
    k = int(np.argmin(f))
    assert f"{f[k]:.2f} Hz" in timeline["labels"][k]
    assert timeline["times"][-1] == pytest.approx(4.0 * traj.times_s[-1], abs=1 / 60)


def test_assignment_preview_shows_the_assigned_design(two_link_planar, tmp_path):
    """Benchmark A assignment: the page plays the assigned design, labels quote the target."""
    from pinflex.assignment import Target, assign_frequencies
    from pinflex.assignment.study import user_trajectory
    from pinflex.visualization import assignment_preview_html

    traj = user_trajectory(two_link_planar, "benchmark_a")
    result = assign_frequencies(two_link_planar, traj, [Target(1, 190.0)], q0=Q0)
    path = assignment_preview_html(two_link_planar, traj, result, tmp_path / "a.html")
    html = path.read_text()
    assert "target 190.00 Hz" in html
    assert f"{result.freq_after_hz[0, 0]:.2f} Hz" in html
    assert f"m1 = {result.design['m1']:.4g} kg" in html


def test_prbdm_preview_moves_links_along_a_chain_mode(tmp_path):
    """4R chain over a random beam: keyframes are Pinocchio placements at θ₀ + s sin φ."""
    from pinflex.prbdm.beams import random_beam
    from pinflex.prbdm.chain import build_chain, mass_matrix
    from pinflex.visualization.prbdm import chain_frames, planform_piece

    beam = random_beam(3)
    chain = build_chain(beam, np.array([0.1, 0.3, 0.3, 0.2, 0.1]), np.array([4e4, 3e4, 2e4, 1e4]))
    p = prbdm_preview(beam, chain, mode=2, amplitude_m=0.05, frames=8)
    phi = p.info["shape"]
    w2 = (2 * np.pi * p.info["freq_hz"]) ** 2
    M = mass_matrix(chain, np.zeros(4))
    np.testing.assert_allclose(chain.stiffness_matrix @ phi, w2 * M @ phi, rtol=1e-10,
                               atol=1e-10 * np.abs(chain.stiffness_matrix @ phi).max())
    tracks = recorded_tracks(p)
    s = p.info["scale"] * np.sin(2 * np.pi * 2 / 8)
    frames = chain_frames(chain, s * phi)
    for j, F in enumerate(frames, start=1):
        np.testing.assert_allclose(tracks[f"/meshcat/pinflex/links/{j}"][".position"][2],
                                   F.translation, atol=1e-12)
    # the pieces tile the planform: their volumes add up to the beam's
    v, f = planform_piece(beam, 0.0, beam.length_m)
    a, b, c = v[f[:, 0]], v[f[:, 1]], v[f[:, 2]]
    volume = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6  # > 0: normals point out
    area = np.trapezoid(2 * beam.half_width_m, beam.x_m)
    assert volume == pytest.approx(area * beam.thickness_m, rel=1e-12)
    assert set(np.round(v[:, 0], 12)) == set(np.round(beam.x_m, 12))


def test_view_cli_writes_html(tmp_path, capsys):
    """``pinflex view URDF --q ... --mode 2 --html FILE`` writes the page and quotes mode 2."""
    from pinflex.cli import main

    out = tmp_path / "v.html"
    code = main(["view", str(TWO_LINK), "--planar", "--q", "1.817", "5.312", "--mode", "2",
                 "--set", "m1=0.2", "--amplitude", "0.03", "--html", str(out)])
    assert code == 0
    model = FlexibleModel(TWO_LINK, planar=True, values={"m1": 0.2})
    f2 = model.frequencies(Q0, n_modes=2)[1]
    printed = capsys.readouterr().out
    assert f"mode 2 at {f2:.2f} Hz" in printed and "30 mm" in printed
    assert out.is_file() and f"{f2:.2f} Hz" in out.read_text()
    assert main(["view", str(TWO_LINK), "--planar", "--mode", "30", "--html", str(out)]) == 2
    assert "modes 1..21" in capsys.readouterr().err


def test_served_viewer_answers_over_http(two_link_planar):
    """Without --html the scene goes to meshcat's local server, whose page is reachable."""
    from pinflex.visualization import served_visualizer

    vis = served_visualizer()
    try:
        p = mode_preview(two_link_planar, Q0, 1, viewer=vis, frames=4)
        assert vis.url().startswith("http://127.0.0.1:")
        with urllib.request.urlopen(vis.url(), timeout=10) as page:
            assert page.status == 200 and b"MeshCat" in page.read()
        assert p.info["freq_hz"] == pytest.approx(193.113, abs=1e-3)
    finally:
        vis.window.server_proc.terminate()
        vis.window.server_proc.wait(timeout=10)


def test_import_pinflex_does_not_need_meshcat():
    """With meshcat hidden, pinflex imports and the preview package names the pip command."""
    code = (
        "import sys; sys.modules['meshcat'] = None\n"
        "import pinflex\n"
        "try:\n"
        "    import pinflex.visualization\n"
        "except ImportError as exc:\n"
        "    print(type(exc).__name__, exc)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout
    assert out.startswith("MissingDependency")
    assert "pip install meshcat" in out


def test_previews_report_progress_when_asked(two_link_planar, capsys):
    """The playback and the modes page draw a progress bar on stderr that ends at 100 %."""
    from pinflex.assignment.study import user_trajectory
    from pinflex.visualization.modes_page import modes_preview

    traj = user_trajectory(two_link_planar, "benchmark_a")
    trajectory_preview(two_link_planar, traj.times_s, traj.q, progress=True)
    modes_preview(two_link_planar, Q0, 3, progress=True)
    err = capsys.readouterr().err.splitlines()
    playback = [line for line in err if line.startswith("playback")]
    modes = [line for line in err if line.startswith("modes preview")]
    assert re.match(r"playback \[#+\] (\d+)/\1 100%", playback[-1]), playback
    assert re.match(r"modes preview \[#+\] 3/3 100%", modes[-1]), modes
    trajectory_preview(two_link_planar, traj.times_s, traj.q)
    assert capsys.readouterr().err == ""
