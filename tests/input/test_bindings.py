"""What reads the input layer, fed by a real OSC client on loopback: Lua's input table and
callbacks, a Controller moving a kinematic body in the physics step of the same frame,
and a headset's tracker turning the camera."""

from __future__ import annotations

import math
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from input_helpers import input_engine, run_until
from pythonosc.udp_client import SimpleUDPClient

from components import Camera, Transform
from engine import Phase, system
from engine.rotation import quat_to_matrix
from engine.scene import instantiate, load_spec
from services.input import InputHub, InputState
from services.input.osc import OscDevice
from services.render.camera import camera_from_component
from services.scripting.runtime import ScriptRuntime
from systems import load_plugin

SCRIPT = """
seen = {}
function onTracker(name, x, y, z, qw) seen.tracker = name .. " " .. x .. " " .. z end
function onButton(device, name, pressed)
  seen.button = device .. "/" .. name .. " " .. tostring(pressed)
end
function onUpdate(dt)
  local x, y, z, qw, qx, qy, qz, tracked = input.tracker("hand_r")
  if x then seen.polled = {x, y, z, qw, tracked} end
  seen.wheel = input.wheel("left")
  seen.pinch = input.button("glove_r", "index")
end
"""


def osc_port(engine) -> int:
    engine.start()
    hub = engine.resource(InputHub)
    hub.start()
    return next(d for d in hub.devices if isinstance(d, OscDevice)).port


def test_lua_reads_trackers_wheels_and_buttons_a_device_sent(tmp_path: Path):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "s.lua").write_text(SCRIPT)
    (tmp_path / "main.scene").write_text("""
Input { Device { Kind "osc" Port 0 } Tracker { ID "hand_r" Offset [0 0 1] }
        Wheel { ID "left" CountsPerTurn 100 Window 0.2 } }
Script "scripts/s.lua"
""")
    from engine import Engine, EngineConfig

    config = EngineConfig(backend="ballistic", fast=True, content_dir=tmp_path)
    with Engine(config, plugins=[load_plugin("scripting"), load_plugin("input")]) as engine:
        instantiate(engine, load_spec(tmp_path / "main.scene", engine.rng))
        client = SimpleUDPClient("127.0.0.1", osc_port(engine))
        engine.step()  # the scripts load in the first frame
        turns_per_second = 5.0

        pose = [0.25, 0.5, 0.125, 1.0, 0.0, 0.0, 0.0]

        def turn() -> None:
            """Counts from elapsed time, as an encoder counts; the tracker streams beside
            them, as a tracker does (sent once, it would be lost after its timeout)."""
            start = time.monotonic()
            while (now := time.monotonic()) - start < 0.5:
                client.send_message("/colosseum/wheel/left",
                                    round(turns_per_second * 100 * (now - start)))
                client.send_message("/colosseum/tracker/hand_r", pose)
                time.sleep(0.005)

        client.send_message("/colosseum/tracker/hand_r", pose)
        sender = threading.Thread(target=turn)
        sender.start()
        client.send_message("/colosseum/button/glove_r/index", 1)
        env = engine.resource(ScriptRuntime).scripts[0].env
        run_until(engine, lambda: env.seen.polled is not None and env.seen.button is not None)
        while sender.is_alive():
            engine.step()
            time.sleep(0.005)
        sender.join()
        seen = env.seen
        assert seen.tracker == "hand_r 0.25 1.125"  # calibrated: lifted by the Offset
        assert list(seen.polled.values()) == [0.25, 0.5, 1.125, 1.0, True]
        assert seen.button == "glove_r/index true" and seen.pinch is True
        # from the counts and their receive times, not from frames
        assert seen.wheel == pytest.approx(2 * math.pi * turns_per_second, rel=0.15)


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_tracker_controller_moves_a_kinematic_body_in_the_same_frame(tmp_path: Path,
                                                                       backend: str):
    """The pose delivered in frame N's INPUT phase is where the physics step of frame N
    takes the body (pymunk simulates the X-Z plane: the pose keeps y = 0)."""
    scene = """
Input { Device { Kind "osc" Port 0 } Tracker { ID "hand" Offset [0 0 1] Scale 0.01 } }
Object { ID "paddle" Kinematic 1 PhysicalAttributes { Gravity 0
         Geometry { Primitive "box" Size [0.1 0.1 0.1] } } }
Controller { Input "tracker:hand" Target "kinematic:paddle" }
"""
    delivered: list[int] = []
    moved: list[tuple[int, np.ndarray]] = []

    @system(Phase.POST_PHYSICS, reads=(Transform,))
    def watch(engine, dt):
        if engine.resource(InputState).tracker("hand") is not None and not delivered:
            delivered.append(engine.frame)
        paddle = next(t for _, t in engine.world.get_component(Transform))
        moved.append((engine.frame, paddle.position.copy()))

    with input_engine(scene, tmp_path, extra_plugins=(load_plugin("physics"),
                                                       load_plugin("controllers")),
                      backend=backend) as engine:
        engine.add_system(watch)
        client = SimpleUDPClient("127.0.0.1", osc_port(engine))
        engine.step()
        client.send_message("/colosseum/tracker/hand", [30.0, 0.0, -40.0, 1.0, 0.0, 0.0, 0.0])
        run_until(engine, lambda: bool(delivered))
        frame, position = moved[-1]
        assert frame == delivered[0]
        np.testing.assert_allclose(position, [0.3, 0.0, 0.6], atol=1e-6)
        assert np.linalg.norm(moved[-2][1] - [0.3, 0.0, 0.6]) > 0.5  # it was elsewhere


def test_a_headset_tracker_in_openxr_axes_turns_the_camera(tmp_path: Path):
    """A y-up, -z-forward pose (OpenXR's frame, as a bridge sends it) read through
    ``Axes "x -z y"`` places and turns the camera it is bound to."""
    scene = """
Camera { ID "eye" Position [0 -5 1.5] LookAt [0 0 1.5] }
Input { Device { Kind "osc" Port 0 } Tracker { ID "hmd" Axes "x -z y" Camera "eye" } }
"""
    with input_engine(scene, tmp_path) as engine:
        client = SimpleUDPClient("127.0.0.1", osc_port(engine))
        half = math.sqrt(0.5)  # 1.6 m up, 2 m ahead, turned 90 degrees left about up
        client.send_message("/colosseum/tracker/hmd", [0.0, 1.6, -2.0, half, 0.0, half, 0.0])
        run_until(engine, lambda: engine.resource(InputState).tracker("hmd") is not None)
        entity, camera = next(iter(engine.world.get_component(Camera)))
        transform = engine.world.component_for_entity(entity, Transform)
        view = camera_from_component(camera, transform.position, transform.orientation)
        np.testing.assert_allclose(view.position, [0.0, 2.0, 1.6], atol=1e-6)
        axes = quat_to_matrix(np.asarray(view.orientation))  # columns: right, forward, up
        np.testing.assert_allclose(axes[:, 1], [-1.0, 0.0, 0.0], atol=1e-6)  # looks left
        np.testing.assert_allclose(axes[:, 2], [0.0, 0.0, 1.0], atol=1e-6)  # up stays up
