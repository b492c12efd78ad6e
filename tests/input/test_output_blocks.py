"""Output blocks: engine values and task markers sent over OSC, caught by a loopback receiver."""

from __future__ import annotations

import time
from pathlib import Path

import pytest
from input_helpers import input_engine, osc_receiver, received

from components import Transform
from engine.events import CustomEvent
from systems import load_plugin
from systems.input import Outputs


@pytest.fixture
def receiver():
    with osc_receiver() as sock:
        yield sock


def test_values_and_markers_go_out_every_frame(tmp_path: Path, receiver):
    port = receiver.getsockname()[1]
    scene = f"""
Object {{ ID "ball" Position [0 0 10] PhysicalAttributes {{ Mass 1 }} }}
Output {{ Kind "osc" Port {port} Value "position:ball" Value "velocity:ball"
          Value "wheel_torque" Value "wheel:left" }}
"""
    with input_engine(scene, tmp_path, extra_plugins=(load_plugin("physics"),)) as engine:
        engine.start()
        engine.resource(Outputs).set("wheel_torque", 2.5)
        engine.events.emit(CustomEvent("marker", "anomaly on"))
        frames = 30
        engine.run(frames=frames)
        time.sleep(0.05)
        got = received(receiver)
        ball = next(t for _, t in engine.world.get_component(Transform))
        final_z, final_vz = float(ball.position[2]), float(ball.linear_velocity[2])
    positions = [args for address, args in got if address == "/colosseum/out/position/ball"]
    velocities = [args for address, args in got if address == "/colosseum/out/velocity/ball"]
    assert len(positions) == frames  # one per frame, none lost on loopback
    # falling freely: what was sent each frame is the body's state then (float32 on the wire)
    assert positions[-1][2] == pytest.approx(final_z, rel=1e-6)
    assert velocities[-1][2] == pytest.approx(final_vz, rel=1e-6)
    assert velocities[-1][2] < velocities[0][2] < 0.0
    assert [args for address, args in got if address == "/colosseum/out/wheel_torque"][0] == \
        [2.5]
    assert ("/colosseum/marker", ["anomaly on"]) in got
    assert not [a for a, _ in got if a.startswith("/colosseum/out/wheel/")]  # no wheel yet
