"""A user's wheelchair driven from their node: the wheel counters of eve's rig reach her
node over OSC, go to the server as eve/left and eve/right, and turn the stroke content's
chair there (velocity mode: the chair rolls at the wheels' rate times their radius)."""

from __future__ import annotations

import math
import shutil
import time
from pathlib import Path

import numpy as np
import pytest
from pythonosc.udp_client import SimpleUDPClient

from components import Transform
from engine.scene import SceneIds
from services.input import InputState
from tests.net.net_helpers import free_port, join_args, local_server, processes
from tests.stroke.chair_helpers import CONTENT, COUNTS_PER_TURN, chair_scene, ground_flat

RATE = math.pi  # rad/s: half a turn a second
RADIUS = 0.305  # m, as wheelchair.scene says


@pytest.mark.slow
def test_a_nodes_wheels_drive_its_users_chair_on_the_server(tmp_path: Path) -> None:
    folder = tmp_path / "chair"
    (folder / "models").mkdir(parents=True)
    shutil.copy(CONTENT / "models" / "wheel.obj", folder / "models")
    shutil.copytree(CONTENT / "sounds", folder / "sounds")
    (folder / "wheelchair.scene").write_text((CONTENT / "wheelchair.scene").read_text()
                                             .replace('Wheels ["left" "right"]',
                                                      'Wheels ["eve/left" "eve/right"]'))
    (folder / "main.scene").write_text(chair_scene(ground_flat()))
    port, osc = free_port(), free_port()
    with local_server(port, content=folder) as server, processes(tmp_path) as procs:
        node = procs.start("eve", *join_args(port, "eve", "--seconds", 30, "--input",
                                             f"osc:{osc}", path=folder))
        server.step_until(lambda e: server.server.peers, 30, "eve joining")
        engine = server.engine
        chassis = engine.world.component_for_entity(
            engine.resource(SceneIds).entities["wheelchair"], Transform)
        start_y = float(chassis.position[1])
        rig = SimpleUDPClient("127.0.0.1", osc)
        state = engine.resource(InputState)
        began = time.monotonic()
        turning_since: list[float] = []  # when the server first had eve's wheels
        speeds: list[float] = []

        def turning(_: object) -> bool:
            t = time.monotonic() - began
            count = int(RATE * t / (2 * math.pi) * COUNTS_PER_TURN)
            for wheel in ("left", "right"):
                rig.send_message(f"/colosseum/wheel/{wheel}", [count])
            if not turning_since:  # the node still starting: nothing reaches the server
                if "eve/left" in state.wheels:
                    turning_since.append(t)
                return False
            if t > turning_since[0] + 1.0:  # under way: the chair's speed, each frame
                speeds.append(float(np.linalg.norm(chassis.linear_velocity)))
            return t > turning_since[0] + 2.5

        server.step_until(turning, 25, "eve's wheels turning for 2.5 s")
        procs.signal(node, 9)
    assert chassis.position[1] - start_y > 0.8 * RATE * RADIUS * 1.5, chassis.position  # +Y
    assert len(speeds) > 30
    assert float(np.mean(speeds)) == pytest.approx(RATE * RADIUS, rel=0.05), speeds
