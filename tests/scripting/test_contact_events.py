"""Contacts begin and end (issue 20): one event when a pair starts touching and one when
it stops, instead of only the per-frame ``onCollision``; times checked against free fall,
on both backends and at two time steps; bodies asleep on each other still touch."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from script_helpers import backends, scripted_engine, write_content

from components import Name
from engine.app import EngineConfig
from engine.events import ContactBegan, ContactEnded, Contacts
from engine.physics.commands import SetVelocity
from engine.scene import instantiate, spec_from_text
from services.scripting.runtime import ScriptRuntime
from systems import create_engine
from systems.contacts import pair_keys, split

G = 9.81
DROP = 0.8  # m the box falls before it touches
LAUNCH = 4.0  # m/s upward, after it has come to rest

SCENE = """\
World {{ Dynamics "{backend}" TimeStep {dt} Gravity [0 0 -9.81] }}
Material {{ ID "dead" Bounce 0 Friction 0.8 }}
Object {{ ID "ground" Dynamic 0 PhysicalAttributes {{ Material "dead"
  Geometry {{ Primitive "plane" }} }} }}
Object {{ ID "box" Position [0 0 {z}] PhysicalAttributes {{ Mass 1 Material "dead" }} }}
"""


def test_pair_keys_are_one_per_pair_in_either_order() -> None:
    keys = pair_keys(np.array([3, 7, 5, 9]), np.array([7, 3, -1, 2]))
    assert keys[0] == keys[1] and len(set(keys.tolist())) == 3
    assert [split(k) for k in keys.tolist()] == [(7, 3), (7, 3), (5, -1), (9, 2)]


@pytest.mark.parametrize("dt", [0.01, 0.005])
@pytest.mark.parametrize("backend", backends())
def test_a_landing_box_begins_once_stays_through_sleep_and_ends_when_launched(
        backend: str, dt: float, tmp_path: Path) -> None:
    text = SCENE.format(backend=backend, dt=dt, z=0.5 + DROP)
    spec = spec_from_text(text, tmp_path)
    events: list[tuple[float, str, tuple[int, int]]] = []
    config = EngineConfig(backend=backend, dt=dt, fast=True, world=spec.world)
    with create_engine(config) as engine:
        ids = instantiate(engine, spec)
        box = ids["box"]
        engine.events.subscribe(ContactBegan, lambda ev: events.append(
            (engine.time, "began", (ev.a, ev.b))))
        engine.events.subscribe(ContactEnded, lambda ev: events.append(
            (engine.time, "ended", (ev.a, ev.b))))
        reported: list[float] = []
        engine.events.subscribe(Contacts, lambda ev: reported.append(engine.time))
        engine.run(seconds=1.0)  # lands (a penetration may kick it into a hop) and settles
        landed = events[0][0] + dt  # the frame's step ends dt after the frame's time
        assert events[0][1] == "began" and events[-1][1] == "began"
        assert landed == pytest.approx(math.sqrt(2 * DROP / G), abs=2 * dt)
        assert events[0][2] in ((box, -1), (box, ids["ground"]))
        settled = len(events)
        engine.run(seconds=3.0)  # falls asleep on the ground
        assert reported[-1] < 3.5  # asleep: the backend reports its contacts no more
        assert len(events) == settled  # and it still touches: no end
        launched = engine.time
        engine.physics.push(SetVelocity(box, (0.0, 0.0, LAUNCH), (0.0, 0.0, 0.0)))
        engine.run(seconds=1.5)
    kinds = [kind for _, kind, _ in events[settled:]]
    assert kinds[:2] == ["ended", "began"]
    left, back = events[settled][0], events[settled + 1][0]
    assert left - launched <= 2 * dt  # it leaves at once
    assert back - left == pytest.approx(2 * LAUNCH / G, abs=3 * dt)  # up and down again


OBSERVER = """\
begins, ends, frames = 0, 0, 0
function onCollisionBegin(other, impulse)
  begins = begins + 1
  log(string.format("begin %s %.3f", other and other:getName() or "world", impulse))
end
function onCollisionEnd(other) ends = ends + 1 end
function onCollision(other, impulse) frames = frames + 1 end
"""
SCENE_OBSERVER = """\
pairs = {}
function onCollisionBegin(a, b, impulse)
  pairs[#pairs + 1] = a:getName() .. "+" .. tostring(b and b:getName())
end
function onCollisionEnd(a, b) pairs[#pairs + 1] = "end " .. a:getName() end
"""


@pytest.mark.parametrize("backend", backends())
def test_lua_hears_begin_and_end_once_and_oncollision_every_frame(
        backend: str, tmp_path: Path) -> None:
    scene = SCENE.format(backend=backend, dt=0.01, z=0.5 + DROP).replace(
        'PhysicalAttributes { Mass 1 Material "dead" } }',
        'Script "scripts/box.lua" PhysicalAttributes { Mass 1 Material "dead" } }') + \
        'Script "scripts/scene.lua"\n'
    write_content(tmp_path, scene, {"box.lua": OBSERVER, "scene.lua": SCENE_OBSERVER})
    with scripted_engine(tmp_path, backend) as engine:
        engine.run(seconds=1.0)
        scripts = {s.name: s for s in engine.resource(ScriptRuntime).scripts}
        box = scripts["scripts/box.lua"]
        assert box.env.begins == 1 and box.env.ends == 0
        assert box.env.frames > 20  # onCollision: every frame it touches (until asleep)
        pairs = list(scripts["scripts/scene.lua"].env.pairs.values())
        assert pairs in (["box+nil"], ["box+ground"])
        entity = next(e for e, n in engine.world.get_component(Name) if n.id == "box")
        engine.physics.push(SetVelocity(entity, (0.0, 0.0, LAUNCH), (0.0, 0.0, 0.0)))
        engine.run(frames=5)
        assert box.env.ends == 1
