"""Threaded mode: physics on its own thread, immutable snapshots, clean shutdown."""

from __future__ import annotations

import threading

import numpy as np

from components import Physical, Transform
from engine import Engine, EngineConfig, Phase, system
from engine.physics.backend import WorldSettings
from engine.physics.commands import SetVelocity
from systems import create_engine
from systems.dynamics import DynamicsSystem


def drifting_engine(n: int) -> tuple[Engine, list[int]]:
    """Bodies without gravity, body i moving at (i + 1) m/s along X from x = 0."""
    cfg = EngineConfig(backend="ballistic", mode="threaded", fast=True, dt=1 / 60,
                       world=WorldSettings(gravity=(0.0, 0.0, 0.0)))
    eng = create_engine(cfg)
    ids = [eng.spawn(Transform(linear_velocity=(i + 1.0, 0, 0)), Physical()) for i in range(n)]
    return eng, ids


def test_no_torn_snapshot_over_thousands_of_frames():
    eng, ids = drifting_engine(200)
    speeds = np.arange(1.0, 201.0)
    checked = {"snapshots": 0, "frames": 0, "steps": set()}

    @system(Phase.POST_PHYSICS, reads=(Transform,))
    def verify(e, dt):
        snap = e.resource(DynamicsSystem).snapshot
        if snap.step == 0:
            return
        order = np.argsort(snap.bodies.keys)
        x = snap.bodies.position[order, 0]
        # every pose in one snapshot comes from the same step
        np.testing.assert_allclose(x / speeds, snap.time, rtol=1e-9)
        assert not snap.bodies.position.flags.writeable
        rows = e.world.poses.rows(ids)
        np.testing.assert_allclose(e.world.poses.position[rows, 0] / speeds, snap.time, rtol=1e-9)
        checked["snapshots"] += 1
        checked["steps"].add(snap.step)

    eng.add_system(verify)
    try:
        eng.run(frames=200_000, until=lambda e: e.physics.steps >= 3000)
        assert eng.physics.running
        assert checked["snapshots"] > 1000
        assert len(checked["steps"]) > 300  # physics really advanced beside the main thread
    finally:
        eng.close()
    assert not eng.physics.running
    assert "colosseum-physics" not in [t.name for t in threading.enumerate()]


def test_commands_from_the_main_thread_are_applied_between_steps():
    eng, ids = drifting_engine(3)
    try:
        eng.run(frames=5)
        late = eng.spawn(Transform(position=(0, 5, 0)), Physical())
        eng.physics.push(SetVelocity(ids[0], (0, 0, 0), (0, 0, 0)))
        eng.run(frames=100_000, until=lambda e: late in e.physics.snapshot.bodies.keys)
        assert late in eng.physics.snapshot.bodies.keys
        x0 = eng.world.component_for_entity(ids[0], Transform).position[0]
        step = eng.physics.steps
        eng.run(frames=100_000, until=lambda e: e.physics.steps > step + 20)
        assert eng.world.component_for_entity(ids[0], Transform).position[0] == x0
        assert eng.world.component_for_entity(ids[1], Transform).position[0] > 2 * x0
    finally:
        eng.close()


def test_threaded_seconds_stops_physics_at_the_requested_time():
    cfg = EngineConfig(backend="ballistic", mode="threaded", fast=True, dt=1 / 60)
    with create_engine(cfg) as eng:
        ball = eng.spawn(Transform(position=(0, 0, 10)), Physical())
        eng.run(seconds=0.5)
        assert eng.physics.steps == 30
        z = eng.world.component_for_entity(ball, Transform).position[2]
        assert z == eng.physics.snapshot.bodies.position[0, 2]
        assert 10 - 9.81 * 0.5**2 / 2 - 0.1 < z < 10 - 9.81 * 0.5**2 / 2


def test_physics_thread_error_stops_the_run_cleanly():
    cfg = EngineConfig(backend="ballistic", mode="threaded", fast=True)
    eng = create_engine(cfg)
    eng.spawn(Transform(), Physical())
    eng.run(frames=2)

    def explode(dt):
        raise RuntimeError("solver exploded")

    eng.physics.request(lambda b: setattr(b, "step", explode))
    try:
        import pytest

        with pytest.raises(Exception, match="solver exploded"):
            eng.run(frames=10_000)
    finally:
        eng.close()
    assert not eng.physics.running
