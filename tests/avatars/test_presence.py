"""Physics presence and scripting: capsules that dynamic bodies bump into, objects carried
by bones, bones driven by a tracked pose, and the Lua avatar methods with their errors."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import GROUND, avatar_engine, avatars, content, entity, position

from engine.rotation import euler_to_quat, quat_to_matrix
from services.scripting.runtime import ScriptRuntime

WALKER = ('Avatar {{ ID "w" Model "models/walker.glb" Position [0 0 0] {extra} }}')


def test_a_capsule_pushes_a_ball_aside_without_launching_it(tmp_path: Path, backend_name: str):
    if backend_name == "ballistic":
        pytest.skip("ballistic particles do not collide")
    along = "x" if backend_name == "pymunk" else "y"
    start, ball, end = ("[0 0 0]", "[1.5 0 0.25]", "[6 0 0]") if along == "x" else (
        "[0 0 0]", "[0 1.5 0.25]", "[0 6 0]")
    heading = "-90" if along == "x" else "0"
    folder = content(tmp_path, "\n".join([
        GROUND,
        f'Object {{ ID "ball" Position {ball} Size [0.5] '
        'PhysicalAttributes { Mass 0.5 Geometry { Primitive "sphere" } } }',
        f'Avatar {{ ID "w" Model "models/walker.glb" Position {start} Orientation [0 0 '
        f'{heading}] Animation "Walk" Path [{start[1:-1]}  {end[1:-1]}] PathLoop 0 '
        'GroundFollow 1 Capsule [0.4 1.0] }']))
    axis = 0 if along == "x" else 1
    with avatar_engine(folder, backend=backend_name, dt=1 / 60) as engine:
        highest = 0.0
        for _ in range(150):  # 2.5 s: the walker reaches the ball after about 1 s
            engine.step()
            highest = max(highest, float(position(engine, "ball")[2]))
        moved = float(position(engine, "ball")[axis]) - 1.5
        walker_at = float(position(engine, "w")[axis])
    assert moved > 0.5  # pushed on ahead of the walker
    assert walker_at < 1.5 + moved  # still behind it
    assert highest < 0.6  # rolled or slid, never thrown into the air


def test_a_capsule_waits_at_its_avatar_however_many_steps_physics_takes(
        tmp_path: Path, backend_name: str):
    """In threaded mode the physics thread may take several steps while a frame takes one:
    the capsule reaches where its avatar stands in the frame's time and waits there (it
    used to keep the target's velocity and walk on ahead, alone)."""
    folder = content(tmp_path, "\n".join([GROUND, WALKER.format(
        extra='Animation "Walk" Path [0 0 0  4 3 0] PathLoop 0 Capsule [0.4 1.0]')]))
    dt = 1 / 60
    with avatar_engine(folder, backend=backend_name, dt=dt) as engine:
        engine.step()
        capsule = entity(engine, "w:capsule")
        for _ in range(30):
            engine.step()
            for _ in range(3):  # the physics thread's steps before the next frame's target
                engine.physics.step(dt)
            state = engine.physics.request(lambda b: b.read_state()).result(1.0)
            (row,) = np.flatnonzero(state.keys == capsule)
            np.testing.assert_allclose(state.position[row], position(engine, "w"), rtol=0,
                                       atol=1e-9)
            assert not state.linear_velocity[row].any()
        assert position(engine, "w")[0] > 0.3  # it walked (across the 2D backend's plane too)


def test_a_carried_crate_follows_the_hand_and_falls_when_let_go(tmp_path: Path):
    folder = content(tmp_path, "\n".join([
        GROUND,
        'Object { ID "crate" Position [2 0 1] Size [0.3 0.3 0.3] '
        'PhysicalAttributes { Mass 2 Geometry { Primitive "box" } } }',
        WALKER.format(extra='Animation "CarryWalk" Path [0 0 0  0 5 0] PathLoop 0 '
                            'GroundFollow 1 Hold { Object "crate" Bone "hand.R" '
                            'Offset [0 -0.15 0] }')]))
    dt = 1 / 60
    with avatar_engine(folder, dt=dt) as engine:
        system = avatars(engine)
        w, crate = entity(engine, "w"), entity(engine, "crate")
        for _ in range(90):
            engine.step()
            hand, turn = system.bone_pose(w, "hand.R")
            want = hand + quat_to_matrix(turn) @ np.array([0.0, -0.15, 0.0])
            # put on the hand before each step, moving with it: off by less than a step
            assert np.linalg.norm(position(engine, "crate") - want) < 1.4 * dt + 0.005
        system.release(w, crate)
        engine.run(frames=90)
        assert position(engine, "crate")[2] == pytest.approx(0.15, abs=0.02)  # on the ground


def test_a_hand_posed_out_of_reach_of_physics_lets_go_with_a_message_and_the_run_goes_on(
        tmp_path: Path, caplog: pytest.LogCaptureFixture):
    """A giant (Scale 1e6) swings its hand at over 100 km/s: the crate it holds cannot be
    moved there. It used to stop the run with a traceback; now the avatar lets go."""
    folder = content(tmp_path, "\n".join([
        GROUND,
        'Object { ID "crate" Position [2 0 1] Size [0.3 0.3 0.3] '
        'PhysicalAttributes { Mass 2 Geometry { Primitive "box" } } }',
        WALKER.format(extra='Scale 1000000 Animation "Walk" Hold { Object "crate" '
                            'Bone "hand.R" }')]))
    with avatar_engine(folder, dt=1 / 60) as engine:
        engine.run(frames=30)
        assert not avatars(engine).figures[entity(engine, "w")].held
        assert engine.frame == 30
    assert any("avatar 'w' lets go of 'crate'" in r.getMessage() for r in caplog.records)


def test_a_driven_bone_reaches_the_tracked_pose_with_its_arm_bent(tmp_path: Path):
    folder = content(tmp_path, "\n".join([GROUND, WALKER.format(extra='Animation "Idle"')]))
    with avatar_engine(folder, dt=1 / 60) as engine:
        engine.run(frames=2)
        system = avatars(engine)
        w = entity(engine, "w")
        shoulder = system.bone_pose(w, "upper_arm.R")[0]
        target = shoulder + np.array([0.15, 0.3, 0.1])  # in front, within reach
        grip = np.array(euler_to_quat((0.0, 20.0, 30.0)))
        system.drive_bone(w, "hand.R", target, grip)
        engine.run(frames=2)
        at, turn = system.bone_pose(w, "hand.R")
        shoulder = system.bone_pose(w, "upper_arm.R")[0]  # the chest sways with Idle
        assert np.linalg.norm(at - target) < 0.01
        assert abs(abs(float(np.dot(turn, grip))) - 1.0) < 1e-6
        elbow = system.bone_pose(w, "forearm.R")[0]
        # the bones kept their lengths: 0.28 m upper arm, 0.26 m forearm
        assert np.linalg.norm(elbow - shoulder) == pytest.approx(0.28, abs=1e-6)
        assert np.linalg.norm(at - elbow) == pytest.approx(0.26, abs=1e-6)
        system.release_bone(w, "hand.R")
        engine.run(frames=2)
        assert np.linalg.norm(system.bone_pose(w, "hand.R")[0] - target) > 0.05


LUA = """
log_lines = {}
function say(...) log_lines[#log_lines + 1] = table.concat({...}, " ") end
function onStart()
  local clips = self:clips()
  say("clips", table.concat(clips, ","))
  self:play("Walk", {fade = 0.2, speed = 1.5})
  self:queue("Idle")
end
function onUpdate(dt)
  if time() > 0.5 and not blended then
    blended = true
    self:blend({Walk = 0.25, Run = 0.75}, {fade = 0})
    local clip, t = self:animation()
    say("now", clip)
    local x, y, z, qw = self:bonePose("head")
    say("head", string.format("%.2f", z))
  end
end
"""


def test_lua_drives_an_avatar_with_play_queue_blend_and_reads_it_back(tmp_path: Path):
    folder = content(tmp_path, "\n".join([GROUND, WALKER.format(extra='Script "scripts/w.lua"')]),
                     {"w.lua": LUA})
    with avatar_engine(folder, dt=1 / 60) as engine:
        engine.run(frames=40)
        (script,) = [s for s in engine.resource(ScriptRuntime).scripts]
        lines = list(script.env.log_lines.values())
        w = entity(engine, "w")
        playing = {n: round(weight, 6) for n, _, weight in avatars(engine).mixer.playing(w)}
    assert lines[0] == "clips Idle,Walk,Run,CarryWalk,Wave"
    assert lines[1] == "now Run"
    assert lines[2].startswith("head ") and 1.6 < float(lines[2].split()[1]) < 1.8
    assert playing == {"Walk": 0.25, "Run": 0.75}


@pytest.mark.parametrize("call,message", [
    ('self:play("Jog")', "w.lua:2: play: model 'walker.glb' has no clip 'Jog' (its clips: "
                         "Idle, Walk, Run, CarryWalk, Wave)"),
    ('self:blend("Walk")', "w.lua:2: blend: expected a table of weights"),
    ('self:play("Walk", {fade = -1})', "w.lua:2: play: fade must be a number >= 0, got -1"),
    ('self:hold(find("ground"), "hand.X")', "w.lua:2: hold: model 'models/walker.glb' has no "
                                            "bone 'hand.X'; did you mean 'hand.R'?"),
    ('find("ground"):play("Walk")', "w.lua:2: play: object 'ground' is not an avatar"),
    ('self:play("Walk", {fade = 1, sped = 2})', "w.lua:2: play: unknown option 'sped'"),
    ('self:play("Walk", "fast")', "w.lua:2: play: options are a table {fade=s, speed=x, "
                                  "loop=bool}, got 'fast'"),
    ('self:play("Walk", {loop = "yes"})', "w.lua:2: play: loop must be true or false"),
    ('self:stopAnimation({fade = -1})', "w.lua:2: stopAnimation: fade must be a number >= 0"),
    ('self:hold(self, "hand.R")', "w.lua:2: hold: avatar 'w' cannot hold itself"),
    ('self:driveBone("spine", {0, 0, 1}, {1, 0, 0, 0})',
     "w.lua:2: driveBone: bone 'spine' has no parent and grandparent to bend"),
    ('self:hold(find("ground"), "hand.R", {offset = {0/0, 0, 0}})',
     "w.lua:2: hold: offset must be 3 finite numbers"),
    ('self:hold(find("ground"), "hand.R", {orientation = "x"})',
     "w.lua:2: hold: orientation is 3 finite numbers (degrees), got 'x'"),
])
def test_bad_avatar_calls_fail_at_the_script_line_naming_what_exists(tmp_path: Path, call: str,
                                                                     message: str):
    source = f"function onStart()\n  {call}\nend\n"
    folder = content(tmp_path, "\n".join([GROUND, WALKER.format(extra='Script "scripts/w.lua"')]),
                     {"w.lua": source})
    with avatar_engine(folder) as engine:
        engine.run(frames=3)
        messages = list(engine.resource(ScriptRuntime).messages)
        assert engine.world.entity_exists(entity(engine, "w"))  # the run goes on
    assert any(message in m for m in messages), messages


def test_bone_poses_compose_the_avatar_pose_scale_and_axes(tmp_path: Path):
    """The head of a walker turned 90 degrees and scaled 2: (0, 0, 2 x 1.67 m) from its
    root; turned to face -X, its right shoulder is on the world's +Y side."""
    folder = content(tmp_path, "\n".join([GROUND, WALKER.format(
        extra='Orientation [0 0 90] Scale 2 Animation "Idle" Speed 0')]))
    with avatar_engine(folder) as engine:
        engine.run(frames=1)
        system = avatars(engine)
        w = entity(engine, "w")
        head = system.bone_pose(w, "head")[0]
        right = system.bone_pose(w, "upper_arm.R")[0]
    np.testing.assert_allclose(head, [0.0, 0.0, 2 * (0.95 + 0.15 + 0.25 + 0.22 + 0.1)],
                               atol=1e-9)
    assert right[1] > 0.3  # facing -X, the right hand side is +Y
