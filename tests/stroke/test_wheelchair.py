"""The stroke content's wheelchair on real ODE, driven by wheel counts as a rig sends them,
checked against the physics of a rolling chair (at two time steps where it matters)."""

from __future__ import annotations

import logging
import math

import numpy as np
import pytest
from chair_helpers import PARTS, ChairRun, G, chair_scene, ground_flat, ground_ramp

from app.scene_loading import content_engine
from components import Wheelchair
from components.wheelchair import NavigationMode
from engine import Phase, system
from engine.events import CustomEvent
from engine.rotation import quat_to_matrix
from engine.scene import check, write_state
from systems.input import Outputs
from tools.stroke_scene import CHASSIS, TRACK, WHEEL_DIAMETER

pytest.importorskip("engine.physics.ode3d")

R = WHEEL_DIAMETER / 2
STEPS = (1.0 / 60.0, 1.0 / 100.0)
RAMP = math.degrees(math.atan(1.0 / 12.0))  # the apartment's ramp: 1:12


def speed(track: np.ndarray, after: float) -> float:
    rows = track[track[:, 0] > after]
    return float(np.hypot(rows[:, 8], rows[:, 9]).mean())


@pytest.mark.parametrize("dt", STEPS)
@pytest.mark.parametrize("rate", [2.0, 4.0])
def test_the_chair_rolls_at_the_wheels_rate_times_their_radius(dt: float, rate: float):
    with ChairRun(chair_scene(ground_flat(), dt), rates=lambda t: (rate, rate)) as run:
        track = run.run(3.5)
    v = speed(track, 2.0)
    assert v == pytest.approx(rate * R, rel=0.01)  # the brief asks 3 %
    assert track[-1, 2] > 0.5 * rate * R  # forward is +Y: the way the chair faces
    assert abs(track[-1, 1]) < 0.02 * track[-1, 2]  # and straight (casters settling: < 1°)


@pytest.mark.parametrize("dt", STEPS)
def test_opposite_wheel_rates_turn_the_chair_in_place(dt: float):
    """Yaw rate (v_r - v_l) / track; the casters swivel round and the chair stays put."""
    rate = 1.5
    with ChairRun(chair_scene(ground_flat(), dt), rates=lambda t: (-rate, rate)) as run:
        track = run.run(4.0)
    rows = track[track[:, 0] > 2.0]
    assert rows[:, 13].mean() == pytest.approx(2 * rate * R / TRACK, rel=0.02)  # brief: 5 %
    assert np.hypot(*track[-1, 1:3]) < 0.3  # the rear axle's middle wanders little


def test_at_two_metres_a_second_the_chair_stops_at_a_wall():
    """No tunnelling: the chair's front (the user's feet) never passes the wall's face,
    and the chair is stopped there while the wheels still push."""
    face = 3.0
    wall = ('Object { ID "wall" Dynamic 0 Position [0 %r 1] Size [3 0.1 2] '
            'PhysicalAttributes { Material "ground" } }\n' % (face + 0.05))
    rate = 2.0 / R
    front = max(centre[1] + size[1] / 2 for _, size, centre in CHASSIS)
    with ChairRun(chair_scene(ground_flat(), extra=wall), rates=lambda t: (rate, rate)) as run:
        reach: list[float] = []

        @system(Phase.POST_PHYSICS)
        def front_reach(e, dt):
            rows = run.track
            if rows:
                p, q = rows[-1][1:4], rows[-1][4:8]
                reach.append(float((p + quat_to_matrix(q) @ np.array([0, front, 0.15]))[1]))

        run.engine.add_system(front_reach)
        track = run.run(4.0)
        parts = run.parts_positions()
    assert track[:, 8:10].max() > 1.95  # it got up to 2 m/s
    impact = track[np.argmax(np.array(reach) > face - 0.02), 0]
    assert 1.0 < impact < 2.5
    assert max(reach) < face + 0.01  # pressed into the wall at most 1 cm, never through
    assert all(p[1] < face for p in parts.values())
    assert np.linalg.norm(track[-1, 8:11]) < 0.05  # stopped there


@pytest.mark.parametrize("dt", STEPS)
def test_on_the_ramp_velocity_mode_holds_the_chair(dt: float):
    """The paper's mode: the wheels turn only when the real ones do, so with the counters
    still the chair stays where it stands, 1:12 down the ramp or not."""
    scene = chair_scene(ground_ramp(RAMP), dt, pitch=-RAMP)
    with ChairRun(scene) as run:
        track = run.run(3.0)
    settled = track[track[:, 0] > 0.5]
    assert np.linalg.norm(settled[-1, 1:4] - settled[0, 1:4]) < 0.004
    assert np.linalg.norm(settled[-60:, 8:10].mean(axis=0)) < 0.002  # not rolling away


@pytest.mark.parametrize("dt", STEPS)
@pytest.mark.parametrize("degrees", [RAMP, 8.0])
def test_on_the_ramp_feedback_mode_rolls_at_the_rolling_chairs_acceleration(
        dt: float, degrees: float):
    """Free wheels: a = g sin(theta) M / (M + sum I/r^2), the wheels' and casters' spin
    taking its share (2.4 % here, so g sin(theta) alone would fail)."""
    scene = chair_scene(ground_ramp(degrees), dt, pitch=-degrees, feedback=True)
    with ChairRun(scene) as run:
        mass, spin = run.rolling_mass()
        track = run.run(2.0)
    th = math.radians(degrees)
    along = track[:, 9] * math.cos(th) - track[:, 10] * math.sin(th)  # down the slope
    rows = track[:, 0] > 0.3
    a = np.polyfit(track[rows, 0], along[rows], 1)[0]
    expected = G * math.sin(th) * mass / (mass + spin)
    assert a == pytest.approx(expected, rel=0.006)
    assert abs(a / (G * math.sin(th)) - 1) > 0.015


def test_a_push_in_feedback_mode_moves_the_chair_by_its_impulse():
    """The real wheels spun up by dw: each push is the rim's inertia times dw, an angular
    impulse (applied at most MaxPush at a time) that sets the rolling chair going at
    2 I dw / (r (M + sum I/r^2)); then it rolls free. The push and the simulated wheels'
    speed go out for a rig."""
    dw = 2.0
    scene = chair_scene(ground_flat(), feedback=True)
    with ChairRun(scene, rates=lambda t: (dw, dw) if t >= 0.5 else (0.0, 0.0)) as run:
        chair = run.engine.world.component_for_entity(run.ids["wheelchair"], Wheelchair)
        mass, spin = run.rolling_mass()
        pushes: list[float] = []
        spins: list[float] = []

        @system(Phase.POST_PHYSICS)
        def published(e, dt):
            values = e.resource(Outputs).values
            pushes.append(values["wheelchair:wheelchair/left/torque"][0])
            spins.append(values["wheelchair:wheelchair/left/speed"][0])

        run.engine.add_system(published)
        track = run.run(2.5)
    assert chair.mode == NavigationMode.FEEDBACK
    expected = 2 * chair.rim_inertia * dw / (R * (mass + spin))
    assert speed(track, 1.5) == pytest.approx(expected, rel=0.02)
    impulse = sum(pushes) / 60.0  # N·m over the frames: the rim's I dw
    assert impulse == pytest.approx(chair.rim_inertia * dw, rel=0.02)
    assert max(pushes) == pytest.approx(chair.max_push)  # spread, not lost
    # the counts' rate over its 0.1 s window steps by a count now and then: small pushes
    # back and forth, which cancel; the wheel turns at the chair's speed over r on average
    assert np.mean(spins[-60:]) == pytest.approx(expected / R, rel=0.02)


def test_lua_switches_the_mode_and_the_wheels_go_free():
    """In velocity mode the chair holds on the ramp, and falls asleep there, braked by the
    still real wheels; emit("wheelchair", {mode = "feedback"}) frees the wheels, wakes it,
    and it rolls."""
    scene = chair_scene(ground_ramp(RAMP), pitch=-RAMP)
    with ChairRun(scene) as run:
        held = run.run(2.5)[-1, 1:4]
        assert run.engine.physics.backend.is_sleeping(run.ids["wheelchair"])
        run.engine.events.emit(CustomEvent("wheelchair", {"mode": "feedback"}))
        track = run.run(1.0)
    assert np.linalg.norm(track[-1, 1:4] - held) > 0.2


def test_counts_that_wrap_are_motion_and_jumps_are_told_and_ignored(caplog):
    """A 16-bit counter wrapping at 65536 drives the chair as any other count; a jump (a
    counter reset) is a message, not a lurch; a rate over MaxSpeed is clamped, told."""
    rate = 3.0
    near_wrap = WRAP_START = 65536 - 600  # the counters wrap within the first turn

    def shift(wheel: int, t: float) -> int:
        return near_wrap + (20000 if t >= 2.0 else 0)  # at 2 s both counters jump

    with caplog.at_level(logging.WARNING), ChairRun(
            chair_scene(ground_flat()), rates=lambda t: (rate, rate), shift=shift) as run:
        track = run.run(3.0)
    assert WRAP_START + rate / (2 * math.pi) * 1024 * 3.0 > 65536  # it did wrap
    assert speed(track, 1.0) == pytest.approx(rate * R, rel=0.02)
    jump = (track[:, 0] > 1.9) & (track[:, 0] < 2.6)  # 20000 counts are not 19.5 turns:
    assert np.hypot(track[jump, 8], track[jump, 9]).max() < rate * R * 1.02  # no lurch
    assert any("counter reset" in r.getMessage() for r in caplog.records)

    caplog.clear()
    fast = 20.0  # rad/s: 6 m/s at the rim, twice MaxSpeed
    with caplog.at_level(logging.WARNING), ChairRun(
            chair_scene(ground_flat()), rates=lambda t: (fast, fast)) as run:
        track = run.run(3.0)
        limit = run.engine.world.component_for_entity(run.ids["wheelchair"],
                                                      Wheelchair).max_speed
    assert speed(track, 2.5) == pytest.approx(limit, rel=0.03)
    told = [r.getMessage() for r in caplog.records if "MaxSpeed" in r.getMessage()]
    assert len(told) == 2 and all("clamped" in m for m in told)  # once a wheel, then counted


def test_a_counter_that_falls_silent_stands_its_wheel_and_is_told(caplog):
    """Both counters unplugged at 1.5 s while turning: their rates fall to nothing within
    the rate's window, the chair stops where it is (velocity mode holds it) and the input
    layer tells each counter lost."""
    rate = 3.0
    with caplog.at_level(logging.WARNING), ChairRun(
            chair_scene(ground_flat()), rates=lambda t: (rate, rate),
            sends=lambda wheel, t: t < 1.5) as run:
        track = run.run(3.5)
    assert speed(track[track[:, 0] < 1.5], 1.0) == pytest.approx(rate * R, rel=0.02)
    stopped = track[track[:, 0] > 2.2]  # (the servo makes up its last few mm by then)
    assert np.hypot(stopped[:, 8], stopped[:, 9]).max() < 0.03
    assert np.hypot(*stopped[-30:, 8:10].mean(axis=0)) < 0.003
    assert np.linalg.norm(stopped[-1, 1:3] - stopped[0, 1:3]) < 0.01
    lost = [r.getMessage() for r in caplog.records if "lost" in r.getMessage()]
    assert any("'left'" in m for m in lost) and any("'right'" in m for m in lost)


BAD_CHAIR = """World { TimeStep 0.01 }
Object { ID "floor" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "base" Position [0 0 0.3] Size [0.5 0.5 0.1] PhysicalAttributes { Mass 10 }
  Wheelchair { Axles ["a1" "AXLE"] RimInertia RIM } }
Object { ID "w" Position [0.3 0 0.3] Size [0.1] PhysicalAttributes { Mass 1 } }
Joint { ID "a1" Type "Ball" Bodies ["w" "base"] }
"""


def test_a_wheelchair_block_that_cannot_work_is_told(tmp_path, caplog):
    """Mistakes in the block are told at their line before anything runs; axles that are
    not hinges on the chassis are told when the run starts, and the run goes on."""
    scene = tmp_path / "bad.scene"
    scene.write_text(BAD_CHAIR.replace("AXLE", "nope").replace("RIM", "4"))
    told = [(d.line, d.message) for d in check(scene) if d.is_error]
    assert told == [(4, "unknown Joint 'nope'")]
    scene.write_text(BAD_CHAIR.replace("AXLE", "a1").replace("RIM", "-1"))
    told = [(d.line, d.message) for d in check(scene) if d.is_error]
    assert told == [(4, "RimInertia must be positive, got -1")]

    scene.write_text(BAD_CHAIR.replace("AXLE", "a1").replace("RIM", "4"))
    assert [d for d in check(scene) if d.is_error] == []
    with caplog.at_level(logging.ERROR), content_engine(scene) as engine:
        engine.run(frames=10)
        assert engine.frame == 10
    assert "wheelchair 'base': its left axle 'a1' must be a hinge" in caplog.text


def test_a_chair_whose_real_wheels_stand_still_sleeps_where_it_stands_and_wakes_to_roll():
    """Velocity mode on flat ground, no input: awake, the iterative solver let the chair
    creep sideways about 1 mm/s (11 mm in 10 s) while its casters' jitter kept it from
    the engine's sleep rule; braked by the still real wheels it sleeps, and moves not at
    all. When the real wheels turn, it wakes and rolls at their rate."""
    rate = 2.0
    with ChairRun(chair_scene(ground_flat()),
                  rates=lambda t: (rate, rate) if t >= 3.0 else (0.0, 0.0)) as run:
        backend = run.engine.physics.backend
        track = run.run(3.0)
        assert all(backend.is_sleeping(run.ids[part]) for part in PARTS)
        settled = track[track[:, 0] > 1.5]
        assert np.linalg.norm(settled[-1, 1:4] - settled[0, 1:4]) < 0.0005
        track = run.run(2.0)
    assert speed(track, 4.0) == pytest.approx(rate * R, rel=0.01)


def test_a_saved_state_continues_the_chair_exactly():
    """The plugin's memory (the servo's lag, how long the chair has stood still) is in the
    saved state: a run loaded from it at 0.3 s falls asleep on the same frame as the run
    that went on, and stands where that one stands."""
    def asleep_from(track: np.ndarray) -> float:
        return float(track[np.all(track[:, 8:14] == 0.0, axis=1), 0][0])

    with ChairRun(chair_scene(ground_flat())) as whole:
        straight = whole.run(2.0)
    with ChairRun(chair_scene(ground_flat())) as first:
        first.run(0.3)
        saved = write_state(first.engine)
    assert "Still 0." in saved and "Still 0\n" not in saved  # mid-way to sleep
    with ChairRun(saved) as second:
        continued = second.run(1.7)
    assert 0.3 < asleep_from(straight) == asleep_from(continued) < 2.0
    assert np.allclose(straight[-1, 1:8], continued[-1, 1:8], rtol=0, atol=1e-12)


@pytest.mark.parametrize("yaw", [90.0, -135.0])
def test_the_included_chair_placed_anywhere_rolls_along_its_heading(yaw: float):
    """wheelchair.scene placed by its variables (here at (2, -1), turned): it stands where
    it was put and rolls the way it faces at the wheels' rate times their radius."""
    scene = chair_scene(ground_flat()).replace("chair_yaw 0", f"chair_yaw {yaw!r}").replace(
        "chair_x 0 chair_y 0", "chair_x 2 chair_y -1")
    with ChairRun(scene, rates=lambda t: (2.0, 2.0)) as run:
        track = run.run(2.5)
    assert np.allclose(track[0, 1:3], (2.0, -1.0), atol=0.005)
    heading = np.radians(yaw)
    velocity = track[track[:, 0] > 2.0, 8:10].mean(axis=0)
    assert velocity == pytest.approx(2.0 * R * np.array([-np.sin(heading), np.cos(heading)]),
                                     abs=0.01)
