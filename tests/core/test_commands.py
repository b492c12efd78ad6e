"""Physics commands are data: checked when made, serialisable, replayable bit for bit."""

from __future__ import annotations

import json
import logging
from pathlib import Path

import numpy as np
import pytest

from components import Joint, Name, Physical, Shape, Transform
from engine import EngineConfig, Phase, system
from engine.physics import commands as cmd
from engine.physics import create_backend
from engine.physics.backend import MaterialPair, SleepState, WorldSettings
from engine.physics.driver import WAIT_STEPS, DetachedPhysics, apply
from systems import create_engine
from systems.dynamics import DynamicsPlugin

NAN, INF = float("nan"), float("inf")


@pytest.mark.parametrize("make, message", [
    (lambda: cmd.ApplyForce(1, (NAN, 0, 0)), "force must be 3 finite numbers"),
    (lambda: cmd.ApplyImpulse(1, (0, INF, 0)), "impulse must be 3 finite numbers"),
    (lambda: cmd.SetPose(1, (0, 0, 0), (0, 0, 0, 0)), "non-zero quaternion"),
    (lambda: cmd.SetPose(1, (0, 0), (1, 0, 0, 0)), "position must be 3"),
    (lambda: cmd.SetVelocity(1, "fast", (0, 0, 0)), "linear velocity must be 3 numbers"),
    (lambda: cmd.SetMotor(1, 2.0, -5.0), "maxForce must be a finite number >= 0"),
    (lambda: cmd.SetKinematicTarget(1, (0, 0, 0), (1, 0, 0, 0), 0.0), "dt must be positive"),
    (lambda: cmd.AddBody(1, Physical(mass=-1.0)), "mass must be a positive number"),
    (lambda: cmd.AddJoint(2, Joint(body_a=1, body_b=1)), "two different bodies"),
    (lambda: cmd.AddJoint(2, Joint(kind="hinge", body_a=1, axis=(0, 0, 0))), "axis must not"),
    (lambda: cmd.AddJoint(2, Joint(kind="wormhole", body_a=1)), "unknown kind 'wormhole'"),
    (lambda: cmd.RemoveBody("crate"), "target must be an entity id"),
    (lambda: cmd.SetPoses([3, 4], np.zeros((2, 13))), "body 3's orientation must be a "
                                                      "non-zero quaternion"),
    (lambda: cmd.SetPoses([3, 4], [[0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0],
                                   [NAN, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0]]),
     "body 4's row is not 13 finite numbers"),
    (lambda: cmd.SetPoses([3], np.zeros((1, 7))), r"1 keys need a table of shape \(1, 13\)"),
    (lambda: cmd.SetServos([3, 4], [[0, 0, 0, 0, 1, 0.03, 30], [0, 0, 0, 0, -1, 0.03, 30]]),
     "joint 4's row must be 7 finite numbers, its torque bound, time constant"),
    (lambda: cmd.SetServos([3], [[NAN, 0, 0, 0, 1, 0.03, 30]]), "joint 3's row must be 7"),
    (lambda: cmd.SetServos([3], np.zeros((1, 13))), r"1 keys need a table of shape \(1, 7\)"),
])
def test_bad_values_are_refused_when_the_command_is_made(make, message):
    with pytest.raises(cmd.CommandError, match=message):
        make()


def test_a_ball_joint_needs_no_axis_and_quaternions_are_normalised():
    cmd.AddJoint(2, Joint(kind="ball", body_a=1, axis=(0, 0, 0)))
    assert cmd.SetPose(1, (0, 0, 0), (0, 0, 0, 3)).orientation == (0.0, 0.0, 0.0, 1.0)
    rows = np.zeros((2, 13))
    rows[:, 3] = (1.0 + 1e-17, 2.0)  # unit to rounding, and not
    poses = cmd.SetPoses([1, 2], rows)
    assert poses.table[:, 3].tolist() == [1.0, 1.0] and rows[1, 3] == 2.0  # a copy
    assert poses.key == 1


def test_servos_faster_than_the_world_s_limit_are_refused_by_their_joint():
    rows = np.zeros((2, 7))
    rows[1, 3] = 2e5
    with pytest.raises(cmd.CommandError, match="SetServos: joint 8: rate 200000 rad/s is "
                                               "over the limit"):
        DetachedPhysics().push(cmd.SetServos([7, 8], rows))


@pytest.mark.parametrize("column, value, message", [
    (1, 2e6, r"SetPoses: body 8: y = 2e\+06 is outside the world"),
    (8, 3e5, r"SetPoses: body 8: linear velocity 300000 m/s is over the limit"),
    (12, -2e5, r"SetPoses: body 8: angular velocity 200000 rad/s is over the limit"),
])
def test_poses_set_together_are_checked_against_the_world_row_by_row(column, value, message):
    rows = np.zeros((2, 13))
    rows[:, 3] = 1.0
    rows[1, column] = value
    with pytest.raises(cmd.CommandError, match=message):
        DetachedPhysics().push(cmd.SetPoses([7, 8], rows))


def every_command() -> list[cmd.Command | cmd.Step]:
    hull = Shape("hull", (), vertices=np.random.default_rng(1).normal(size=(12, 3)))
    body = Physical(mass=2.5, shapes=[Shape("box", (1, 2, 3), (0.1, 0, 0)), hull])
    joint = Joint(kind="six_dof", body_a=4, body_b=5, low=-0.5, id="grip",
                  reference=((0, 0, 1, 1, 0, 0, 0), None))
    sleep = SleepState(True, 3, np.arange(12.0).reshape(2, 6))
    return [cmd.AddBody(4, body, (1, 2, 3), (1, 0, 0, 0), (0, 0, -1), (0, 1, 0)),
            cmd.RemoveBody(4), cmd.AddJoint(9, joint), cmd.RemoveJoint(9),
            cmd.SetMotor(9, 1.5, 20), cmd.SetServos([9, 10], np.ones((2, 7))),
            cmd.ApplyForce(4, (1, 0, 0), (0, 0, 1)),
            cmd.ApplyTorque(4, (0, 0, 2)), cmd.ApplyImpulse(4, (0, 1, 0)),
            cmd.SetPose(4, (0, 0, 5), (0, 1, 0, 0)), cmd.SetVelocity(4, (1, 1, 1), (0, 0, 0)),
            cmd.SetPoses([4, 5], np.arange(26.0).reshape(2, 13)),
            cmd.SetKinematicTarget(4, (0, 0, 1), (1, 0, 0, 0), 0.01),
            cmd.SetCollisionEnabled(4, False), cmd.SetGravityEnabled(4, False),
            cmd.SetSleeping(4, True), cmd.SetSleepState(4, sleep),
            cmd.SetJointTarget(9, (0, 0, 1), (1, 0, 0, 0), 300.0, None),
            cmd.SetDriveLimits(9, 300, 30),
            cmd.ConfigureWorld(WorldSettings(iterations=40, material_pairs=[
                MaterialPair("wood", "ice", friction=0.05)])),
            cmd.Step(1 / 120)]


def test_every_command_type_round_trips_through_json():
    made = every_command()
    assert {type(c).__name__ for c in made} == set(cmd.COMMANDS)
    for command in made:
        back = cmd.from_dict(json.loads(json.dumps(cmd.to_dict(command))))
        assert type(back) is type(command)
        assert json.dumps(cmd.to_dict(back)) == json.dumps(cmd.to_dict(command))
    body = cmd.from_dict(json.loads(json.dumps(cmd.to_dict(made[0])))).body
    assert isinstance(body.shapes, list) and body.shapes[1].vertices.dtype == np.float64
    np.testing.assert_array_equal(body.shapes[1].vertices, made[0].body.shapes[1].vertices)


def test_a_dict_that_is_no_command_is_refused():
    with pytest.raises(cmd.CommandError, match="not a physics command"):
        cmd.from_dict({"command": "Explode", "key": 1})


def jointed_run(backend: str, log: cmd.CommandLog) -> np.ndarray:
    """A pendulum, a motorised wheel and falling boxes, pushed and driven from a system."""
    config = EngineConfig(backend=backend, fast=True, dt=1 / 120)
    with create_engine(config) as eng:
        eng.physics.log = log
        eng.spawn(Transform(), Physical(kind="static", mass=None,
                                        shapes=[Shape("plane", (0, 0, 1, 0))]))
        bob = eng.spawn(Name("bob"), Transform(position=(1, 0, 3)), Physical(mass=2.0))
        eng.spawn(Name("rod"), Joint(kind="ball", body_a=bob, anchor=(0, 0, 3)))
        wheel = eng.spawn(Transform(position=(3, 0, 1)),
                          Physical(shapes=[Shape("cylinder", (0.4, 0.2))], gravity=False))
        axle = eng.spawn(Joint(kind="hinge", body_a=wheel, anchor=(3, 0, 1), axis=(0, 1, 0)))
        boxes = [eng.spawn(Transform(position=(-2 + 0.1 * i, 0, 0.6 + 1.1 * i)),
                           Physical(shapes=[Shape("box", (1, 1, 1))])) for i in range(4)]

        @system(Phase.SCRIPT)
        def drive(e, dt):
            if e.frame % 40 == 5:
                e.physics.push(cmd.ApplyImpulse(boxes[e.frame % 4], (1.5, 0, 2.0)))
            if e.frame == 30:
                e.physics.push(cmd.SetMotor(axle, 4.0, 10.0))
            if e.frame == 90:
                e.physics.set_pose(boxes[0], (-3, 0, 2), (1, 0, 0, 0))
            if e.frame == 120:  # two boxes put back up, turned, moving (as hands' controls)
                e.physics.push(cmd.SetPoses(boxes[1:3], [
                    [-1, 0, 3, 0.96, 0, 0.28, 0, 0.5, 0, 0, 0, 1.0, 0],
                    [1, 0, 4, 1, 0, 0, 0, 0, 0, -1.0, 0, 0, 0]]))

        eng.add_system(drive)
        eng.run(frames=240)
        return eng.physics.snapshot.bodies.table.copy()


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_recorded_command_stream_replays_bit_identically(backend):
    log = cmd.CommandLog()
    live = jointed_run(backend, log)
    entries = json.loads(json.dumps(log.entries))  # what a file or a socket would carry
    assert sum(e["command"] == "Step" for e in entries) == 240
    assert {"AddBody", "AddJoint", "ApplyImpulse", "SetMotor", "SetPose", "SetPoses"} <= {
        e["command"] for e in entries}
    fresh = create_backend(backend)
    fresh.configure(EngineConfig().world)
    cmd.CommandLog(entries).replay(lambda c: apply(c, fresh), fresh.step)
    replayed = fresh.read_state()
    assert replayed.table.tobytes() == live.tobytes()
    fresh.close()


def test_a_command_for_a_body_that_never_comes_is_dropped_with_its_scene_id(caplog):
    with create_engine(EngineConfig(backend="ballistic", fast=True)) as eng:
        ghost = eng.spawn(Name("ghost"), Transform())  # no Physical: no body
        ball = eng.spawn(Name("ball"), Transform(position=(0, 0, 5)), Physical())
        eng.run(frames=2)
        with caplog.at_level(logging.WARNING, "colosseum.physics"):
            eng.physics.push(cmd.ApplyImpulse(ghost, (1, 0, 0)))
            eng.run(frames=10)
        assert "ApplyImpulse dropped: no object 'ghost' in the physics world" in caplog.text
        assert f"frame {2 + WAIT_STEPS - 1}:" in caplog.text  # after waiting a few steps
        assert eng.world.component_for_entity(ball, Transform).position[2] < 5  # runs on


@pytest.mark.parametrize("mode", ["serial", "threaded"])
def test_a_command_for_a_removed_body_is_dropped_with_its_scene_id(mode, caplog):
    with create_engine(EngineConfig(backend="ode", mode=mode, fast=True)) as eng:
        crate = eng.spawn(Name("crate"), Transform(position=(0, 0, 5)), Physical())
        ball = eng.spawn(Name("ball"), Transform(position=(3, 0, 5)), Physical())
        eng.run(frames=3)
        eng.despawn(crate)
        eng.run(frames=2)
        with caplog.at_level(logging.WARNING, "colosseum.physics"):
            eng.physics.push(cmd.ApplyImpulse(crate, (1, 0, 0)))
            eng.run(frames=10)
        assert "ApplyImpulse dropped: no object 'crate' in the physics world" in caplog.text
        assert "removed" in caplog.text
        assert eng.world.component_for_entity(ball, Transform).position[2] < 5  # runs on


def test_a_command_waits_for_a_body_that_reaches_the_backend_later():
    with create_engine(EngineConfig(backend="ballistic", fast=True, dt=1 / 60)) as eng:
        late = eng.spawn(Physical(gravity=False))  # its Transform comes after the spawn
        eng.physics.push(cmd.SetVelocity(late, (2, 0, 0), (0, 0, 0)))
        eng.world.add_component(late, Transform())
        eng.run(frames=60)
        assert eng.world.component_for_entity(late, Transform).position[0] > 1.5


def test_an_engine_without_physics_keeps_commands_for_a_plugin_that_comes_later():
    from engine.app import Engine

    with Engine(EngineConfig(backend="ballistic", fast=True, dt=1 / 60)) as eng:
        assert isinstance(eng.physics, DetachedPhysics)
        ball = eng.spawn(Transform(position=(0, 0, 1)), Physical(gravity=False))
        eng.physics.set_velocity(ball, (0, 3, 0), (0, 0, 0))
        eng.run(frames=5)  # ECS, events and systems run; nothing simulates
        assert eng.world.component_for_entity(ball, Transform).position.tolist() == [0, 0, 1]
        assert [type(c).__name__ for c in eng.physics.outbox] == ["SetVelocity"]
        assert eng.physics.request(lambda b: b.body_count()).exception() is not None
        eng.add_plugin(DynamicsPlugin())
        eng.run(frames=60)
        assert eng.world.component_for_entity(ball, Transform).position[1] == pytest.approx(
            3.0, rel=0.02)


def test_the_architecture_document_lists_every_command():
    text = (Path(__file__).resolve().parents[2] / "docs" / "ARCHITECTURE.md").read_text()
    missing = [name for name in cmd.COMMANDS if f"`{name}`" not in text]
    assert missing == []
