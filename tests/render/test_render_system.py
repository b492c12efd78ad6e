"""The render plugin inside an Engine: entities drawn, scene shaders, camera follow, output."""

from __future__ import annotations

import numpy as np
from PIL import Image
from render_helpers import CONTENT, H, W

from components import Camera, Shape, Transform, Visual
from engine.app import Engine, EngineConfig
from engine.scene.factory import instantiate
from engine.scene.loader import spec_from_text
from engine.services import SwapGate
from services.render.math3d import look_at_orientation
from systems.render import RenderOptions, RenderPlugin, RenderSystem

LISTING_3 = """
VertexShader { ID "toon_vertex" File "shaders/toon.vert" }
FragmentShader { ID "toon_fragment" File "shaders/toon.frag" }
ShaderProgram { ID "toon" VertexShader "toon_vertex" FragmentShader "toon_fragment" Enable 1 }
ShaderState { ID "toon" ShaderProgram "toon"
  Uniform { ID "DiffuseColor" Value [0 0.25 1] }
  Uniform { ID "PhongColor" Value [0.75 0.75 1] }
  Uniform { ID "Edge" Value 0.3 }
  Uniform { ID "Phong" Value 0.98 }
}
Object { ID "ball" Position [0 0 0.6] Dynamic 0
  VisualAttributes { Shadower 1 Geometry { Primitive "sphere" } ShaderState "toon" } }
Camera { ID "cam" Position [0 -6 0.6] LookAt [0 0 0.6] }
"""


def _engine(**options) -> Engine:
    opts = RenderOptions(backend="headless", size=(W, H), **options)
    return Engine(EngineConfig(backend="ballistic", fast=True, content_dir=CONTENT),
                  plugins=[RenderPlugin(opts)])


def _centre(engine: Engine) -> np.ndarray:
    return engine.resource(RenderSystem).renderer.read_pixels()[H // 2, W // 2 + 4].astype(float)


def test_scene_file_shader_state_and_uniform_from_a_script():
    with _engine() as eng:
        instantiate(eng, spec_from_text(LISTING_3, CONTENT))
        eng.run(frames=2)
        assert np.allclose(_centre(eng), (0, 64, 255), atol=3)  # DiffuseColor [0 0.25 1]
        eng.resource(RenderSystem).set_uniform("toon", "DiffuseColor", (1.0, 0.5, 0.0))
        eng.run(frames=1)
        assert np.allclose(_centre(eng), (255, 128, 0), atol=3)
        assert eng.resource(RenderSystem).renderer.errors == []


def test_screenshot_at_the_end_and_recorded_frames(tmp_path):
    shot = tmp_path / "end.png"
    frames = tmp_path / "frames"
    with _engine(screenshot=shot, record_frames=frames, record_every=2) as eng:
        eng.spawn(Transform((0.0, 0.0, 0.5)), Visual(shapes=[Shape("box", (1, 1, 1))]))
        eng.run(frames=5)
    with Image.open(shot) as img:
        assert img.size == (W, H)
    assert sorted(p.name for p in frames.iterdir()) == [
        "frame_000000.png", "frame_000002.png", "frame_000004.png"]


def test_camera_follows_its_entity_and_visual_changes_show():
    with _engine() as eng:
        target = Transform((0.0, 0.0, 0.5))
        visual = Visual(shapes=[Shape("sphere", (0.4,))], color=(1.0, 0.0, 0.0, 1.0))
        entity = eng.spawn(target, visual)
        eng.spawn(Transform(), Camera(follow=entity, offset=(0.0, -4.0, 0.0),
                                      look_at=(0.0, 0.0, 0.0)))
        eng.run(frames=1)
        rs = eng.resource(RenderSystem)
        centre = rs.renderer.read_pixels()[H // 2, W // 2].astype(float)
        assert centre[0] > 100 and centre[1] < 40
        target.position[:] = (7.0, -3.0, 2.0)  # the camera goes along
        eng.world.component_for_entity(entity, Visual).color = (0.0, 0.0, 1.0, 1.0)
        eng.run(frames=1)
        centre = rs.renderer.read_pixels()[H // 2, W // 2].astype(float)
        assert centre[2] > 100 and centre[0] < 40
        eng.despawn(entity)
        eng.run(frames=1)
        assert entity not in rs.renderer


def test_default_camera_and_light_show_an_object_in_an_empty_scene():
    with _engine() as eng:
        eng.spawn(Transform((0.0, 0.0, 0.5)), Visual(shapes=[Shape("box", (1, 1, 1))],
                                                     color=(1, 0, 0, 1)))
        eng.run(frames=1)
        centre = eng.resource(RenderSystem).renderer.read_pixels()[H // 2, W // 2]
        assert centre[0] > 120 and centre[1] < 40  # lit from over the camera's shoulder


def test_options_from_the_command_line_config(tmp_path):
    config = EngineConfig(headless=True, options={
        "screenshot": tmp_path / "a.png", "record_frames": None, "record_every": 3,
        "interpolate": True, "hud": True, "size": "320x200"})
    opts = RenderOptions.from_config(config)
    assert opts.backend == "headless" and opts.size == (320, 200) and opts.hud
    assert opts.screenshot == tmp_path / "a.png" and opts.record_every == 3 and opts.interpolate


def test_look_at_orientation_points_the_camera_axis():
    q = look_at_orientation((0.0, -4.0, 0.0), (0.0, 0.0, 0.0))
    assert np.allclose(q, (1.0, 0.0, 0.0, 0.0), atol=1e-9)  # already looking along +Y


def test_f1_toggles_the_hud():
    from engine.events import KeyEvent

    with _engine(hud=False) as eng:
        eng.run(frames=1)
        hud = eng.resource(RenderSystem).renderer.hud
        assert not hud.enabled
        eng.events.emit(KeyEvent("f1", True))
        eng.run(frames=1)
        assert hud.enabled and "fps" in hud.text and "real-time" in hud.text


def test_threaded_mode_draws_interpolated_physics_states():
    from components import Physical
    from systems.dynamics import DynamicsPlugin

    opts = RenderOptions(backend="headless", size=(W, H), interpolate=True)
    config = EngineConfig(backend="ballistic", mode="threaded", fast=True, content_dir=CONTENT)
    with Engine(config, plugins=[DynamicsPlugin(), RenderPlugin(opts)]) as eng:
        ball = eng.spawn(Transform((0.0, 0.0, 3.0)), Physical(),
                         Visual(shapes=[Shape("sphere", (0.3,))]))
        eng.run(frames=20)
        rs = eng.resource(RenderSystem)
        assert ball in rs.renderer and rs.renderer.errors == []
        assert rs.renderer.pose(ball)[0][2] < 3.0  # it is falling, and drawn where physics has it


class _Gate:
    """A swap gate that notes, each time it is passed, the frame as drawn so far and how
    many frames the target had been asked to show."""

    def __init__(self, system: RenderSystem) -> None:
        self.system = system
        self.seen: list[tuple[np.ndarray, int]] = []
        self.presents = 0

    def before_swap(self) -> None:
        self.seen.append((self.system.renderer.read_pixels(), self.presents))


def test_a_swap_gate_is_passed_between_the_finished_frame_and_its_swap(tmp_path):
    with _engine() as eng:
        eng.spawn(Transform((0.0, 0.0, 0.6)), Visual(shapes=[Shape("sphere", (0.5,))],
                                                   color=(1.0, 0.0, 0.0, 1.0)))
        eng.spawn(Transform((0.0, -6.0, 0.6)), Camera(look_at=(0.0, 0.0, 0.6)))
        eng.run(frames=1)
        system = eng.resource(RenderSystem)
        gate = _Gate(system)
        eng.insert_resource(gate, as_type=SwapGate)
        shown = system._target.present

        def present() -> None:
            gate.presents += 1
            shown()

        system._target.present = present
        eng.run(frames=2)
    # passed once a frame, with the frame drawn (the red sphere in the middle) and not yet
    # swapped: one swap after each pass
    assert [presents for _, presents in gate.seen] == [0, 1] and gate.presents == 2
    for pixels, _ in gate.seen:
        assert pixels[H // 2, W // 2, 0] > 100 and pixels[H // 2, W // 2, 1] < 40


def test_the_frame_drawn_for_a_screenshot_at_the_end_passes_no_gate(tmp_path):
    with _engine(screenshot=tmp_path / "end.png", draw_every_frame=False) as eng:
        eng.spawn(Transform((0.0, 0.0, 0.5)), Visual(shapes=[Shape("box", (1, 1, 1))]))
        gate = _Gate(None)  # type: ignore[arg-type]
        eng.insert_resource(gate, as_type=SwapGate)
        eng.run(frames=3)
    assert (tmp_path / "end.png").is_file() and gate.seen == []
