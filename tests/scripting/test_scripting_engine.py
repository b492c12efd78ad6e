"""Scripts inside a running engine: the paper's Listing 2, collisions counted against the
physics, spawning in both scheduler modes, the API checked against the dynamics, reload."""

from __future__ import annotations

import math
import os
import shutil
from pathlib import Path

import numpy as np
import pytest
from script_helpers import backends, runtime_of, script_named, scripted_engine, write_content

from components import Joint, Name, Physical, Transform
from engine.events import Contacts, KeyEvent
from engine.scene import SceneIds

DATA = Path(__file__).parent / "data"
G = 9.81

GROUND = ('Object { ID "ground" Position [0 0 -0.5] Dynamic 0\n'
          '  PhysicalAttributes { Geometry { Primitive "box" Size [20 20 1] } } }\n')


def test_listing2_runs_as_printed(tmp_path: Path) -> None:
    """Paper section 4.2, Listing 2: curly quotes, ``requrestPlugin`` and the OSG/OpenAL++ names."""
    from systems.sound import SoundPlugin

    write_content(tmp_path, 'Script "scripts/listing2.lua"\n', {})
    shutil.copy(DATA / "listing2.lua", tmp_path / "scripts" / "listing2.lua")
    with scripted_engine(tmp_path) as engine:
        engine.register_plugin("sound", lambda: SoundPlugin("null"))
        engine.run(frames=2)
        runtime = runtime_of(engine)
        assert [s.name for s in runtime.scripts] == ["scripts/listing2.lua"]
        assert not any("error" in m or "stopped" in m for m in runtime.messages)
        assert "physics" in engine.plugins
        assert "sound" in engine.plugins  # requrestPlugin("openalpp") loaded it


def test_unknown_plugin_is_an_error_with_a_suggestion(tmp_path: Path) -> None:
    write_content(tmp_path, 'Script "scripts/p.lua"\n', {"p.lua": 'requestPlugin("phisics")\n'})
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=1)
        message = runtime_of(engine).messages[0]
        assert message.startswith("scripts/p.lua:1: requestPlugin: unknown plugin 'phisics'; "
                                  "did you mean 'physics'?")


@pytest.mark.parametrize("backend", backends())
def test_collision_scripts_count_real_contacts(tmp_path: Path, backend: str) -> None:
    height, radius = 2.0, 0.25
    scene = GROUND + (f'Object {{ ID "ball" Position [0 0 {height}] Script "scripts/ball.lua"\n'
                      '  PhysicalAttributes { Mass 2 Geometry { Primitive "sphere" '
                      f'Size [{2 * radius}] }} }} }}\n'
                      'Script "scripts/scene.lua"\n')
    ball = ("hits, first_t, first_j, first_other = 0, nil, nil, nil\n"
            "function onCollision(other, impulse)\n"
            "  hits = hits + 1\n"
            "  if not first_t then first_t, first_j, first_other = time(), impulse, "
            "other:getName() end\n"
            "end\n")
    scene_script = "pairs_seen = 0\nfunction onCollision(a, b, j) pairs_seen = pairs_seen + 1 end\n"
    write_content(tmp_path, scene, {"ball.lua": ball, "scene.lua": scene_script})
    with scripted_engine(tmp_path, backend) as engine:
        ball_id = engine.world.entities_named("ball") if hasattr(engine.world, "entities_named") \
            else None
        frames_with_contact = []
        engine.events.subscribe(Contacts, lambda ev: frames_with_contact.append(ev.batch))
        engine.run(seconds=1.5)
        env = script_named(engine, "scripts/ball.lua").env
        scene_env = script_named(engine, "scripts/scene.lua").env
        del ball_id
        # one onCollision per frame in which the backend reported a contact of the ball
        assert env.hits == len(frames_with_contact) > 10
        assert scene_env.pairs_seen == env.hits  # only one pair in this scene
        assert env.first_other == "ground"
        fall = math.sqrt(2 * (height - radius) / G)
        assert env.first_t == pytest.approx(fall, abs=3 * engine.config.dt)
        # the first contact stops the fall: impulse ~ m * v (within restitution/penetration)
        assert env.first_j == pytest.approx(2 * G * fall, rel=0.25)


SPAWN_SCENE = GROUND + 'Script "scripts/spawner.lua"\n'
SPAWNER = """
spawned = {}
function onStart()
  for i = 1, 3 do
    local objs = spawn(string.format([[
      Object { ID "ball%d" Position [%d 0 1] Script "scripts/counter.lua"
        PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.5] } } }
    ]], i, 2 * i))
    spawned[i] = objs[1]
  end
end
"""
COUNTER = "touches = 0\nfunction onCollision(other) touches = touches + 1 end\n"


@pytest.mark.parametrize("mode", ["serial", "threaded"])
@pytest.mark.parametrize("backend", backends())
def test_spawn_from_script(tmp_path: Path, backend: str, mode: str) -> None:
    write_content(tmp_path, SPAWN_SCENE, {"spawner.lua": SPAWNER, "counter.lua": COUNTER})
    with scripted_engine(tmp_path, backend, mode) as engine:
        engine.run(seconds=1.5)
        spawner = script_named(engine, "scripts/spawner.lua").env
        ids = [spawner.spawned[i].id for i in (1, 2, 3)]
        for i, entity in enumerate(ids, start=1):
            t = engine.world.component_for_entity(entity, Transform)
            # fell under gravity and came to rest on the ground: the backend has the body
            assert t.position[2] == pytest.approx(0.25, abs=0.03)
            assert t.position[0] == pytest.approx(2 * i, abs=0.05)
        counters = [s for s in runtime_of(engine).scripts if s.name == "scripts/counter.lua"]
        assert len(counters) == 3
        assert all(c.env.touches > 0 for c in counters)


@pytest.mark.parametrize("backend", backends())
def test_impulse_and_velocity_match_the_dynamics(tmp_path: Path, backend: str) -> None:
    scene = ('Object { ID "puck" Position [0 0 5] Script "scripts/puck.lua"\n'
             '  PhysicalAttributes { Mass 4 Gravity 0 Geometry { Primitive "sphere" '
             'Size [0.2] } } }\n')
    puck = ("function onStart() self:addImpulse(8, 0, 0) end\n"  # 8 N s on 4 kg: 2 m/s
            "function onKey(key, pressed)\n"
            "  if key == 'r' then self:setPosition(0, 0, 5); self:setVelocity(0, 0, 1) end\n"
            "end\n")
    write_content(tmp_path, scene, {"puck.lua": puck})
    with scripted_engine(tmp_path, backend) as engine:
        engine.run(seconds=1.0)
        t = engine.world.component_for_entity(script_named(engine, "scripts/puck.lua").entity,
                                              Transform)
        assert t.linear_velocity[0] == pytest.approx(2.0, rel=1e-6)
        assert t.position[0] == pytest.approx(2.0, abs=2.0 * 2 * engine.config.dt)
        engine.events.emit(KeyEvent("r", True))
        engine.run(seconds=1.0)
        assert t.position[0] == pytest.approx(0.0, abs=1e-6)
        assert t.position[2] == pytest.approx(6.0, abs=2 * engine.config.dt)


def test_broken_script_never_stops_the_simulation(tmp_path: Path) -> None:
    scene = GROUND + 'Script "scripts/bad.lua"\nScript "scripts/good.lua"\n'
    write_content(tmp_path, scene, {
        "bad.lua": "function onUpdate(dt)\n  local x = nil\n  return x.y\nend\n",
        "good.lua": "n = 0\nfunction onUpdate(dt) n = n + 1 end\n",
    })
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=20)
        runtime = runtime_of(engine)
        assert script_named(engine, "scripts/good.lua").env.n == 20
        assert len(runtime.messages) == 3
        assert runtime.messages[0].startswith("scripts/bad.lua:3: attempt to index a nil value")
        assert runtime.messages[-1].endswith("onUpdate disabled after 3 errors")


def _touch(path: Path, text: str) -> None:
    before = path.stat().st_mtime
    path.write_text(text)
    os.utime(path, (before + 1, before + 1))  # an edit within the clock's resolution


def test_hot_reload_good_and_bad_edits(tmp_path: Path) -> None:
    write_content(tmp_path, 'Script "scripts/live.lua"\n',
                  {"live.lua": "step = step or 1\nn = n or 0\n"
                               "function onUpdate() n = n + step end\n"})
    path = tmp_path / "scripts" / "live.lua"
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=5)
        env = lambda: script_named(engine, "scripts/live.lua").env  # noqa: E731
        assert env().n == 5
        _touch(path, "step = 100\nn = n or 0\nfunction onUpdate() n = n + step end\n")
        engine.run(frames=5)  # reloaded at the next frame: state kept, new code runs
        assert env().n == 5 + 5 * 100
        _touch(path, "function onUpdate( n = 0 end\n")  # does not compile
        engine.run(frames=2)
        assert env().n == 505 + 2 * 100  # the old version keeps running
        assert "scripts/live.lua:1:" in runtime_of(engine).messages[-1]
        assert "previous version keeps running" in runtime_of(engine).messages[-1]


def test_script_that_failed_to_load_is_retried_when_fixed(tmp_path: Path) -> None:
    write_content(tmp_path, 'Script "scripts/late.lua"\n', {"late.lua": "x = = 1\n"})
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=2)
        runtime = runtime_of(engine)
        assert runtime.scripts == []
        assert runtime.messages[0].startswith("scripts/late.lua:1:")
        _touch(tmp_path / "scripts" / "late.lua", "started = false\n"
                                                 "function onStart() started = true end\n")
        engine.run(frames=2)
        assert script_named(engine, "scripts/late.lua").env.started is True


def test_collision_filter_only_reaches_involved_scripts(tmp_path: Path) -> None:
    scene = GROUND + ''.join(
        f'Object {{ ID "b{i}" Position [{3 * i} 0 {0.5 + i}] Script "scripts/c.lua"\n'
        '  PhysicalAttributes { Geometry { Primitive "sphere" Size [0.5] } } }\n'
        for i in range(3))
    write_content(tmp_path, scene, {"c.lua": "others = {}\nfunction onCollision(o) "
                                             "others[o:getName()] = true end\n"})
    with scripted_engine(tmp_path) as engine:
        engine.run(seconds=1.5)
        for script in runtime_of(engine).scripts:
            assert list(script.env.others.keys()) == ["ground"]
        assert np.all([s.env.others["ground"] for s in runtime_of(engine).scripts])


def test_input_timer_and_custom_events_reach_scripts(tmp_path: Path) -> None:
    from engine.events import CustomEvent, TimerEvent
    from services.input.events import Axis, Button, TrackerPose

    script = """
seen = {}
local function note(s) seen[#seen + 1] = s end
function onKey(key, pressed) note("key " .. key .. " " .. tostring(pressed)) end
function onButton(device, name, pressed)
  note("button " .. device .. "/" .. name .. " " .. tostring(pressed))
end
function onTracker(name, x, y, z, qw) note("tracker " .. name .. " " .. x .. "," .. qw) end
function onInput(device, value)
  if type(value) == "table" then value = table.concat(value, ",") end
  note("input " .. device .. " " .. tostring(value))
end
function onTimer(name) note("timer " .. name) end
on("door", function(data) note("door " .. data.state); emit("ack", {n = 1}) end)
"""
    write_content(tmp_path, 'Script "scripts/s.lua"\n', {"s.lua": script})
    acks = []
    with scripted_engine(tmp_path) as engine:
        engine.events.subscribe(CustomEvent, lambda ev: ev.name == "ack" and acks.append(ev.data))
        engine.run(frames=1)
        for event in (KeyEvent("space", True), Button("glove", "trigger", True),
                      Axis("pad", "x", 0.5), TrackerPose("hand", (1.0, 2.0, 3.0),
                                                         (1.0, 0.0, 0.0, 0.0)),
                      TimerEvent("bell"), CustomEvent("door", {"state": "open"})):
            engine.events.emit(event)
        engine.run(frames=2)
        seen = list(script_named(engine, "scripts/s.lua").env.seen.values())
    assert seen == ["key space true", "button glove/trigger true", "input axis:pad/x 0.5",
                    "timer bell", "door open", "tracker hand 1.0,1.0"]
    assert acks == [{"n": 1}]


@pytest.mark.parametrize("backend", backends())
def test_joints_from_scripts(tmp_path: Path, backend: str) -> None:
    """createJoint + setMotor spin a wheel at the commanded rate; breakJoint frees it."""
    scene = ('Object { ID "wheel" Position [0 0 1] Script "scripts/w.lua"\n'
             '  PhysicalAttributes { Mass 1 Gravity 0 Geometry { Primitive "sphere" '
             'Size [0.5] } } }\n')
    wheel = """
function onStart()
  axle = createJoint{kind = "hinge", a = self, anchor = {0, 0, 1}, axis = {0, 1, 0},
                     id = "axle"}
  setMotor("axle", 2.0, 50)
end
function onKey(key) if key == "b" then breakJoint("axle") end end
"""
    write_content(tmp_path, scene, {"w.lua": wheel})
    with scripted_engine(tmp_path, backend) as engine:
        engine.run(seconds=1.0)
        entity = script_named(engine, "scripts/w.lua").env.axle
        rate = engine.physics.request(lambda b: b.joint_state(entity)).result()[1]
        assert abs(rate) == pytest.approx(2.0, rel=0.02)
        engine.events.emit(KeyEvent("b", True))
        engine.run(frames=3)
        assert not engine.world.entity_exists(entity)
        with pytest.raises(KeyError):
            engine.physics.request(lambda b: b.joint_state(entity)).result()


@pytest.mark.parametrize("backend", backends())
def test_a_spring_from_a_script_swings_at_the_root_of_k_over_i(tmp_path: Path,
                                                               backend: str) -> None:
    """createJoint's spring (engine units: N·m/rad, rad) on a hinge through a sphere's
    centre: released at the joint's zero toward a target of 0.3 rad, it swings to 0.6 rad
    and back with period 2π√(I/k) (I = 2/5 m r²)."""
    mass, radius, stiffness, target = 1.0, 0.25, 0.4, 0.3
    scene = (f'Object {{ ID "wheel" Position [0 0 1] Script "scripts/w.lua"\n'
             f'  PhysicalAttributes {{ Mass {mass} Gravity 0 Geometry {{ Primitive "sphere" '
             f'Size [{2 * radius}] }} }} }}\n')  # a sphere's Size is its diameter
    wheel = f"""
function onStart()
  axle = createJoint{{kind = "hinge", a = self, anchor = {{0, 0, 1}}, axis = {{0, 1, 0}},
                     spring = {{stiffness = {stiffness}, target = {target}}}}}
end
"""
    write_content(tmp_path, scene, {"w.lua": wheel})
    period = 2 * math.pi * math.sqrt(0.4 * mass * radius**2 / stiffness)
    with scripted_engine(tmp_path, backend) as engine:
        engine.run(frames=1)
        entity = script_named(engine, "scripts/w.lua").env.axle
        angles, times = [], []
        start = engine.physics.time
        while engine.physics.time - start < period:
            engine.run(frames=1)
            angles.append(engine.physics.request(lambda b: b.joint_state(entity)).result()[0])
            times.append(engine.physics.time - start)
    swing = int(np.argmax(np.abs(angles)))
    assert abs(angles[swing]) == pytest.approx(2 * target, rel=0.02)
    assert times[swing] == pytest.approx(period / 2, abs=0.02)


def test_delete_and_optional_subsystems(tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    scene = GROUND + 'Script "scripts/d.lua"\n'
    script = """
function onStart()
  playSound(find("ground")); playSound(find("ground"))
  setUniform("toon", "Phong", {1, 2, 3})
  find("ground"):delete()
end
function onUpdate() gone = find("ground") == nil end
"""
    write_content(tmp_path, scene, {"d.lua": script})
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=3)
        assert script_named(engine, "scripts/d.lua").env.gone is True
        assert runtime_of(engine).messages == type(runtime_of(engine).messages)()
    assert caplog.text.count("playSound: the sound plugin is not loaded") == 1
    # headless, loading the render plugin would draw for no one: say what would show it
    assert caplog.text.count("setUniform: nothing is drawn in this run (headless, without "
                             "--screenshot or --record-frames)") == 1
    assert "requestPlugin('render')" not in caplog.text
    caplog.clear()
    with scripted_engine(tmp_path) as engine:
        engine.config.headless = False  # a display, but no render plugin
        engine.run(frames=3)
    assert caplog.text.count("setUniform: the render plugin is not loaded; the call does "
                             "nothing (requestPlugin('render') loads it)") == 1


@pytest.mark.parametrize("mode", ["serial", "threaded"])
def test_runaway_script_is_stopped_and_the_engine_runs_on(tmp_path: Path, mode: str) -> None:
    scene = GROUND + ('Object { ID "ball" Position [0 0 2]\n'
                      '  PhysicalAttributes { Geometry { Primitive "sphere" Size [0.5] } } }\n'
                      'Script "scripts/evil.lua"\nScript "scripts/good.lua"\n')
    write_content(tmp_path, scene, {
        "evil.lua": "function onUpdate(dt)\n  while true do pcall(function() end) end\nend\n",
        "good.lua": "n = 0\nfunction onUpdate(dt) n = n + 1 end\n",
    })
    with scripted_engine(tmp_path, mode=mode) as engine:
        engine.run(seconds=1.0)
        runtime = runtime_of(engine)
        assert script_named(engine, "scripts/evil.lua").stopped
        assert script_named(engine, "scripts/good.lua").env.n == engine.frame
        assert [m.split(";")[0] for m in runtime.messages] == [
            "scripts/evil.lua:2: script exceeded its instruction budget (2000000 instructions "
            "per callback) in onUpdate"]
        ball = engine.world.component_for_entity(
            next(e for e, n in engine.world.get_component(Name) if n.id == "ball"), Transform)
        assert ball.position[2] < 1.0  # physics went on


def test_spawned_snippets_use_the_scene_materials_and_objects(tmp_path: Path) -> None:
    scene = ('Material { ID "ice" Friction 0.02 Bounce 0.3 }\n'
             'Object { ID "post" Dynamic 0 Position [0 0 1]\n'
             '  PhysicalAttributes { Geometry { Primitive "box" Size [0.2 0.2 2] } } }\n'
             'Script "scripts/maker.lua"\n')
    maker = ('function onStart()\n'
             '  made = spawn([[\n'
             '    Object { ID "puck" Position [1 0 0.1]\n'
             '      PhysicalAttributes { Material "ice" Geometry { Primitive "sphere" } } }\n'
             '    Joint { ID "tether" Type "Ball" Bodies ["puck" "post"] Anchor [0 0 1] }\n'
             '  ]])\n'
             'end\n')
    write_content(tmp_path, scene, {"maker.lua": maker})
    with scripted_engine(tmp_path) as engine:
        engine.run(frames=2)
        made = script_named(engine, "scripts/maker.lua").env.made
        puck = engine.world.component_for_entity(made[1].id, Physical)
        assert (puck.material.name, puck.material.friction) == ("ice", 0.02)
        tether = engine.world.component_for_entity(made[2].id, Joint)
        assert tether.body_b == engine.resource(SceneIds).entities["post"]
