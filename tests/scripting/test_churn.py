"""Objects coming and going under load: a script that keeps 400 boxes alive by spawning
and deleting 40 a frame holds nothing of what it deleted (the process does not grow),
what it deleted is gone from every table that could find it, and a spawn or a delete
costs the same among 5,000 bodies as among 100."""

from __future__ import annotations

import gc
import os
import statistics
from pathlib import Path

import pytest

from app.bench.scripting import churn_round, churn_world
from components import Name, Script, Transform
from engine.app import Engine, EngineConfig
from engine.scene import SceneIds, instantiate, spec_from_text
from systems import RegistryPlugin, load_plugin
from systems.scripting import ScriptingPlugin

#: Bytes the process may grow by per churned object (the issue's bound).
MAX_BYTES_PER_OBJECT = 30

CHURN = """
live, head, tail = {}, 1, 0
function onUpdate(dt)
  local rows = {}
  for i = 1, PER do  -- apart, so they never touch: the churn is what is measured
    rows[i] = 'Object { ID "box' .. i .. '" Position [' .. ((tail + i) % KEEP) * 3
              .. ' 0 1] PhysicalAttributes { } }'
  end
  for _, obj in ipairs(spawn(table.concat(rows, '\\n'))) do
    tail = tail + 1
    live[tail] = obj
  end
  while tail - head + 1 > KEEP do
    live[head]:delete()
    live[head] = nil
    head = head + 1
  end
end
"""


def _resident_bytes() -> int:
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def _churning_engine(backend: str, per: int, keep: int, content: Path) -> Engine:
    config = EngineConfig(backend=backend, fast=True, content_dir=content, dt=1 / 60)
    engine = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                     ScriptingPlugin()])
    instantiate(engine, spec_from_text('Object { ID "still" Position [0 -5 1] }', content))
    script = CHURN.replace("PER", str(per)).replace("KEEP", str(keep))
    engine.spawn(Name("churner"), Transform(), Script(source=script))
    return engine


@pytest.mark.skipif(not os.path.exists("/proc/self/statm"), reason="reads /proc")
@pytest.mark.parametrize(("backend", "objects"), [("ode", 40_000), ("pymunk", 20_000)])
def test_spawning_and_deleting_retains_nothing_per_object(tmp_path, backend, objects) -> None:
    per, keep = 40, 400
    engine = _churning_engine(backend, per, keep, tmp_path)
    try:
        engine.run(frames=300)  # warm-up: tables, caches and pools at their working size
        gc.collect()
        before = _resident_bytes()
        engine.run(frames=objects // per)
        gc.collect()
        grown = _resident_bytes() - before
        scene = engine.resource(SceneIds)
        assert len(scene.spawned) == keep // per  # the records of the live boxes, no more
        assert sum(1 for _ in engine.world.entities()) == keep + 2  # boxes, "still", churner
    finally:
        engine.close()
    assert grown / objects <= MAX_BYTES_PER_OBJECT, (
        f"{backend}: the process grew {grown} bytes over {objects} churned objects")


PILE = """
live, head, tail, hits = {}, 1, 0, 0
function onUpdate(dt)
  for _, obj in ipairs(spawn('Object { ID "box" Position [' .. (tail % 3) * 0.3 .. ' 0 1] '
                             .. 'Size [0.4 0.4 0.4] PhysicalAttributes { } }')) do
    tail = tail + 1
    live[tail] = obj
  end
  while tail - head + 1 > 30 do  -- the oldest go, from under the newer ones on the pile
    live[head]:delete()
    live[head] = nil
    head = head + 1
  end
end
function onCollision(a, b, impulse) hits = hits + 1 end
"""


def test_contacts_told_after_their_boxes_were_deleted_leave_nothing_in_lua(tmp_path) -> None:
    """Threaded, a box a script deletes while it touches the pile may still be in the
    contacts of the step under way, told to onCollision after the box is gone: the Lua
    handle made for it then must go too (it stayed, one per such box: a soak's Lua heap
    grew without end). The heap after a full collection stays where it was: over three
    stretches of 400 frames, a leak grows it in each, while tables reaching a loaded
    machine's working size (more steps a frame, more contacts a callback) grow it in
    some and then stop."""
    from services.scripting.runtime import ScriptRuntime

    config = EngineConfig(backend="ode", fast=True, content_dir=tmp_path, mode="threaded")
    engine = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                     ScriptingPlugin()])
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "pile.lua").write_text(PILE)
    instantiate(engine, spec_from_text(
        'Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" '
        '} } }\nScript "scripts/pile.lua"\n', tmp_path))
    try:
        engine.run(frames=400)  # warm-up: the script's tables at their working size
        kernel = engine.resource(ScriptRuntime).kernel
        heap = [kernel.collect()]  # KB, after a full collection
        for _ in range(3):
            engine.run(frames=400)
            heap.append(kernel.collect())
        hits = next(s for s in engine.resource(ScriptRuntime).scripts).env.hits
    finally:
        engine.close()
    assert hits > 1000  # the pile was touched all along
    grown = [b - a for a, b in zip(heap, heap[1:], strict=False)]
    assert min(grown) < 8, f"the Lua heap grew {grown} KB in each 400 boxes"


def test_a_deleted_object_is_gone_from_every_lookup_and_still_named(tmp_path) -> None:
    script = """
first = spawn('Object { ID "crate" Position [0 0 1] PhysicalAttributes { } }')[1]
function onStart()
  first:delete()
end
function onUpdate(dt)
  if time() > 0.05 and not checked then
    checked = true
    found = find("crate")
    ok, err = pcall(first.setPosition, first, 1, 2, 3)
    again = spawn('Object { ID "crate" Position [0 0 2] PhysicalAttributes { } }')[1]
    refound = find("crate")
  end
end
"""
    config = EngineConfig(backend="ode", fast=True, content_dir=tmp_path)
    engine = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                     ScriptingPlugin()])
    instantiate(engine, spec_from_text('Object { ID "still" }', tmp_path))
    owner = engine.spawn(Name("owner"), Transform(), Script(source=script))
    try:
        engine.run(frames=10)
        from services.scripting.runtime import ScriptRuntime

        env = next(s for s in engine.resource(ScriptRuntime).scripts if s.entity == owner).env
        assert env.found is None  # deleted: find no longer sees it
        assert env.ok is False and 'object "crate" no longer exists' in str(env.err)
        assert env.refound is not None and env.refound.id == env.again.id
    finally:
        engine.close()


def test_a_spawn_and_a_delete_cost_the_same_among_5000_bodies_as_among_100() -> None:
    """The issue's bound (at most 1.5 times), measured so a loaded machine cannot fake
    it: the same Lua spawns and deletes in a world of 100 and one of 5,000 dynamic boxes
    resting on the ground (settled: asleep, as resting crates are with the default
    sleeping), rounds alternating between the two worlds, the main thread's CPU time,
    the median round of each. Other work on the machine only adds noise either way, so
    a measurement is taken again (three at most) before the bound counts as broken; the
    29 times it was cannot pass. (The 0.3 ms a spawn's wall time is held to is a
    benchmark figure: colosseum bench scripting.)"""
    worlds = {n: churn_world(n) for n in (100, 5000)}
    ratios: list[tuple[float, float]] = []
    try:
        big = worlds[5000][0].physics.backend
        assert big.body_count() == 5001 and big.sleeping_count() == 5000  # (and the ground)
        while len(ratios) < 3 and not (ratios and max(ratios[-1]) <= 1.5):
            rounds: dict[int, list[tuple[float, ...]]] = {100: [], 5000: []}
            for _ in range(5):
                for n, (engine, runtime, script) in worlds.items():
                    rounds[n].append(churn_round(engine, runtime, script, 50))
            spawn, delete = (statistics.median(r[column] for r in rounds[5000]) /
                             statistics.median(r[column] for r in rounds[100])
                             for column in (0, 2))
            ratios.append((spawn, delete))
    finally:
        for engine, _, _ in worlds.values():
            engine.close()
    assert max(ratios[-1]) <= 1.5, f"(spawn, delete) cost these times as much: {ratios}"
