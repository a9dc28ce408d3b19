"""Rigid bodies (``<pinflex:body>``, kept URDF inertia) drawn in the meshcat previews.

A recording writer stands in for meshcat's scene; references: Pinocchio's forward kinematics
of the link frames (rest pose) and, in a deformed state, the drawn centreline at the body's
axial station plus its offset turned with the link frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

pytest.importorskip("meshcat")

ROOT = Path(__file__).resolve().parents[1]
Q = np.array([0.4, 1.1])


class _Recorder:
    """The SceneWriter calls RobotDrawing makes: objects with rest transforms, keyframes."""

    def __init__(self):
        self.objects, self.rest, self.keys = {}, {}, {}

    def add(self, path, geometry, material, T, scale=None):
        self.objects[path] = geometry
        self.rest[path] = np.asarray(T, dtype=float)

    def place(self, path, T, scale=None):
        self.rest[path] = np.asarray(T, dtype=float)

    def key(self, frame, path, T=None, scale=None, colour=None):
        if T is not None:
            self.keys[(frame, path)] = np.asarray(T, dtype=float)


def _arm(tmp_path):
    """Benchmark A's arm with a motor body off the axis of link1 and a tool body at link2's tip."""
    from pinflex import FlexibleModel

    text = (ROOT / "urdf" / "two_link.urdf").read_text().replace(
        "</robot>", '<pinflex:body name="motor" link="link1" xyz="0.35 0.03 0.01" mass="0.4" '
        'ixx="2e-4" iyy="3e-4" izz="3e-4"/>\n'
        '<pinflex:body name="tip" link="link2" xyz="0.45 0 0" mass="0.1"/></robot>')
    path = tmp_path / "arm.urdf"
    path.write_text(text)
    return FlexibleModel(path)


def test_bodies_are_drawn_at_their_centre_of_mass_with_their_link_frame(tmp_path):
    """Rest pose: one cube per body (volume = mass / 2000 kg/m³) at Pinocchio's placement of
    its link frame acting on the body's centre of mass, turned with that frame."""
    import meshcat.geometry as mg

    from pinflex.visualization.robot import MASS_SPHERE_DENSITY, RobotDrawing

    model = _arm(tmp_path)
    rec = _Recorder()
    RobotDrawing(rec, model, Q, ghosts=False)
    data = model.model.createData()
    pin.framesForwardKinematics(model.model, data, model.coord_map @ Q)
    expected = {"motor": ("link1", np.array([0.35, 0.03, 0.01]), 0.4),
                "tip": ("link2", np.array([0.45, 0.0, 0.0]), 0.1)}
    for name, (link, com, mass) in expected.items():
        path = f"bodies/{name}"
        box = rec.objects[path]
        assert isinstance(box, mg.Box)
        side = (mass / MASS_SPHERE_DENSITY) ** (1 / 3)
        assert box.lengths == pytest.approx([side] * 3, rel=1e-12)
        oMf = data.oMf[model.model.getFrameId(link)]
        np.testing.assert_allclose(rec.rest[path][:3, 3], oMf.act(com), atol=1e-12)
        np.testing.assert_allclose(rec.rest[path][:3, :3], oMf.rotation, atol=1e-12)


def test_bodies_move_with_the_deformed_beam(tmp_path):
    """In a mode's keyframes: a body on the axis at a beam's tip sits on the drawn tip station;
    one off the axis at the centreline's point of its station plus the offset turned with the
    link frame; both move when the beam deforms."""
    from pinflex.visualization.robot import RobotDrawing, stations_local

    model = _arm(tmp_path)
    rec = _Recorder()
    drawing = RobotDrawing(rec, model, Q, ghosts=False)
    result = model.modes(Q, n_modes=2)
    scale = 0.05 / np.abs(result.shapes[:, 0]).max()
    (state,) = drawing.mode_states(result, 1, [scale])
    drawing.key(7, state)
    tip = rec.keys[(7, "bodies/tip")][:3, 3]
    np.testing.assert_allclose(tip, state.beams["link2"][-1], atol=1e-12)
    assert np.linalg.norm(tip - rec.rest["bodies/tip"][:3, 3]) > 1e-3
    # the motor at axial station 0.35 m of link1 (0.6 m along x), 0.03 / 0.01 m off the axis
    axial = stations_local(model, "link1", drawing.spe)[:, 0]
    st = state.beams["link1"]
    on_axis = np.array([np.interp(0.35, axial, st[:, c]) for c in range(3)])
    R = state.links["link1"].rotation
    motor = rec.keys[(7, "bodies/motor")]
    np.testing.assert_allclose(motor[:3, 3], on_axis + R @ np.array([0.0, 0.03, 0.01]),
                               atol=1e-12)
    np.testing.assert_allclose(motor[:3, :3], R, atol=1e-12)


def test_kept_urdf_inertia_of_a_real_arm_is_drawn(tmp_path):
    """The UR3 overlay keeps its motors as bodies (keep-excess, the default): both are drawn;
    beam-only draws none."""
    from pinflex import FlexibleModel

    for inertia, n in (("keep-excess", 2), ("beam-only", 0)):
        text = (ROOT / "urdf" / "ur3_tubes.xml").read_text()
        text = text.replace('<pinflex:flexible link=',
                            f'<pinflex:flexible inertia="{inertia}" link=')
        path = tmp_path / f"ur3_{inertia}.xml"
        path.write_text(text)
        model = FlexibleModel(path)
        from pinflex.visualization.robot import RobotDrawing

        rec = _Recorder()
        RobotDrawing(rec, model, np.array([0, -1.2, 1.4, -1.8, -1.57, 0]), ghosts=False)
        bodies = sorted(p for p in rec.objects if p.startswith("bodies/"))
        assert len(bodies) == n, bodies
        if n:
            assert bodies == ["bodies/forearm_link.urdf", "bodies/upper_arm_link.urdf"]
