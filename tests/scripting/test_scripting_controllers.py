"""Controllers bind an input to an actuator with gain and limits, with no script."""

from __future__ import annotations

import math
from pathlib import Path

import pytest
from script_helpers import backends, scripted_engine, write_content

from components import Controller, Joint, Name, Transform
from engine.events import KeyEvent
from services.input import InputHub
from services.input.events import Axis, WheelCount

WHEEL = """
Object { ID "wheel" Position [0 0 1]
  PhysicalAttributes { Mass 1 Gravity 0 Geometry { Primitive "sphere" Size [0.5] } } }
Joint { ID "axle" Type "Hinge" Bodies ["wheel"] Anchor [0 0 1] Axis [0 1 0]
        MotorMaxForce 50 }
Controller { ID "drive" Input "key:Up/Down" Target "motor:axle" Gain 2 Low -1 High 1.5 }
"""


def joint_rate(engine, name: str) -> float:
    entity = next(e for e, n in engine.world.get_component(Name) if n.id == name)
    assert engine.world.has_component(entity, Joint)
    return engine.physics.request(lambda b: b.joint_state(entity)).result()[1]


@pytest.mark.parametrize("backend", backends())
def test_key_controller_drives_a_motor_within_limits(tmp_path: Path, backend: str) -> None:
    write_content(tmp_path, WHEEL, {})
    with scripted_engine(tmp_path, backend) as engine:
        engine.run(seconds=0.5)
        assert joint_rate(engine, "axle") == pytest.approx(0.0, abs=1e-6)
        engine.resource(InputHub).inject(KeyEvent("Up", True))
        engine.run(seconds=0.5)
        # gain 2 * (+1) = 2 rad/s, clamped to the High limit 1.5
        assert abs(joint_rate(engine, "axle")) == pytest.approx(1.5, rel=0.02)
        up_sign = 1.0 if joint_rate(engine, "axle") > 0 else -1.0
        controller = next(c for _, c in engine.world.get_component(Controller))
        assert controller.value == 1.5
        engine.resource(InputHub).inject(KeyEvent("Up", False))
        engine.resource(InputHub).inject(KeyEvent("Down", True))
        engine.run(seconds=0.5)
        assert joint_rate(engine, "axle") == pytest.approx(-1.0 * up_sign, rel=0.02)


def test_axis_controller_pushes_a_body(tmp_path: Path) -> None:
    scene = """
Object { ID "sled" Position [0 0 3]
  PhysicalAttributes { Mass 2 Gravity 0 Geometry { Primitive "sphere" Size [0.5] } } }
Controller { Input "axis:pad/throttle" Target "force:sled" Gain 10 High 4 }
"""
    write_content(tmp_path, scene, {})
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=2)
        engine.resource(InputHub).inject(Axis("pad", "throttle", 0.8))  # 8 N asked, 4 N allowed
        # along the sled's forward axis (local +X; the sled is not turned)
        frames = 60
        engine.run(frames=frames)
        sled = next(e for e, n in engine.world.get_component(Name) if n.id == "sled")
        v = engine.world.component_for_entity(sled, Transform).linear_velocity[0]
        # a = F / m = 2 m/s^2 for the steps that had the force
        steps = round(v / (2.0 * engine.config.dt))
        assert frames - 2 <= steps <= frames
        assert v == pytest.approx(2.0 * steps * engine.config.dt, rel=1e-6)


def test_bad_controller_is_reported_once(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """Scene files are checked when loaded; controllers added at run time are checked here."""
    write_content(tmp_path, "", {})
    with scripted_engine(tmp_path) as engine:
        engine.spawn(Controller(input="key:a", target="motor:nowhere"))
        engine.spawn(Controller(input="glove:left", target="force:x"))
        engine.run(frames=5)
    assert caplog.text.count("no joint 'nowhere'") == 1
    assert caplog.text.count("unknown input 'glove:left'") == 1


def test_wheel_counter_rate_drives_a_motor(tmp_path: Path) -> None:
    """A wheel encoder's angular velocity (2π counts / CountsPerTurn per second, from the
    device timestamps), times the gain, becomes the motor's velocity."""
    from engine.system import Phase, system

    scene = WHEEL.replace('Input "key:Up/Down" Target "motor:axle" Gain 2 Low -1 High 1.5',
                          'Input "wheel:left" Target "motor:axle" Gain 0.5')
    scene += 'Input { Wheel { ID "left" CountsPerTurn 1024 } }\n'
    write_content(tmp_path, scene, {})
    with scripted_engine(tmp_path) as engine:
        engine.start()  # the input hub is made from the scene's Input block at start
        hub = engine.resource(InputHub)
        hub.clock = lambda: engine.time  # the device's clock: simulated time, in a fast run

        @system(Phase.INPUT)
        def encoder(eng, dt):  # half a turn per second, stamped when they were read
            hub.inject(WheelCount("left", round(512 * eng.time), eng.time))

        engine.add_system(encoder)
        engine.run(seconds=1.0)
        # 512 counts/s of 1024 per turn: π rad/s; times the gain 0.5
        assert abs(joint_rate(engine, "axle")) == pytest.approx(0.5 * math.pi, rel=0.03)
