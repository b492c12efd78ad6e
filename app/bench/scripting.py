"""``colosseum bench scripting``: the cost of calling into sandboxed Lua.

Rows, each beside a reference measured in the same run:

- onUpdate dispatch: one frame calls ``onUpdate(dt)`` on 100 scripts through the
  runtime (fresh instruction budget, error capture, disabled-callback checks).
- collision events: 10,000 events per second (167 colliding pairs per 60 Hz
  frame, 4 contacts each) from a Contacts batch through the scripting system's
  numpy filter and pair reduction into ``onCollision(other, impulse)``.

The reference of those two is a bare lupa call of an equivalent Lua function from
Python (no sandbox, no budget, no handle lookup); ``ratio`` is ours over it.
Target: under 5 µs per collision event.

- churn: a script spawns boxes from scene text (``spawn``) and deletes them
  (``obj:delete()``, the deletion done at the phase's end) among 100 and among 5,000
  dynamic boxes resting on the ground on ODE (settled, and so asleep, as resting crates
  are with the default sleeping), the physics commands included. The reference of the
  5,000-body rows is the same among 100 bodies: the ratio says how much a big world costs
  each call (target ≤ 1.5); a spawn's target is 0.3 ms. Beside each, what the frame that
  applies them costs more than a frame with nothing to apply (the bodies made or
  removed in the backend and every table laid out again, once a frame however many
  came or went), per box. Times are the main thread's CPU time, the fastest round.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

SCRIPT = """
n, hits = 0, 0
function onUpdate(dt) n = n + 1 end
function onCollision(other, impulse) hits = hits + impulse end
"""


def _bare_reference(calls_per_round: int, rounds: int, args: tuple) -> float:
    """µs per call of a trivial Lua function from Python, lupa without any sandbox."""
    import lupa.lua54 as lua54

    lua = lua54.LuaRuntime()
    fns = [lua.eval("function(a, b) return nil end") for _ in range(calls_per_round)]
    t0 = time.perf_counter()
    for _ in range(rounds):
        for fn in fns:
            fn(*args)
    return (time.perf_counter() - t0) / (rounds * calls_per_round) * 1e6


def run_bench(quick: bool = False) -> list[dict[str, Any]]:
    from components import Script, Transform
    from engine.app import Engine, EngineConfig
    from services.scripting.runtime import ScriptRuntime
    from systems import RegistryPlugin, load_plugin
    from systems.scripting import ScriptingPlugin, ScriptingSystem

    scripts = 100
    frames = 120 if quick else 1200
    pairs_per_frame = 167  # 10,000 events/s at 60 Hz
    rows: list[dict[str, Any]] = []
    config = EngineConfig(backend="ballistic", fast=True)
    with Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                 ScriptingPlugin()]) as engine:
        entities = [engine.spawn(Transform(), Script(source=SCRIPT)) for _ in range(scripts)]
        engine.run(frames=1)
        runtime = engine.resource(ScriptRuntime)
        system = engine.resource(ScriptingSystem)
        assert len(runtime.scripts) == scripts

        # -- onUpdate to 100 scripts -------------------------------------------
        dt = 1 / 60
        runtime.update(dt)
        t0 = time.perf_counter()
        for _ in range(frames):
            runtime.update(dt)
        ours = (time.perf_counter() - t0) / (frames * scripts) * 1e6
        bare = _bare_reference(scripts, frames, (dt, None))
        rows.append({"kind": CALLS_KIND, "benchmark": "onUpdate dispatch (100 scripts)",
                     "calls": frames * scripts,
                     "us_per_call": ours, "us_per_frame": ours * scripts,
                     "bare_lupa_us": bare, "ratio": ours / bare})

        rows.append(_collision_row(system, entities, frames, pairs_per_frame))
        assert all(s.env.hits > 0 for s in runtime.scripts)
    rows.extend(churn_rows(quick))
    return rows


def _collision_row(system: Any, entities: list[int], frames: int,
                   pairs_per_frame: int) -> dict[str, Any]:
    """Collision events to scripts through the scripting system's Contacts path, beside
    bare lupa calls of the same count."""
    from engine.events import Contacts
    from engine.physics.backend import CONTACT_DTYPE

    rng = np.random.default_rng(0)
    batches = []
    for _ in range(min(frames, 60)):
        batch = np.zeros(pairs_per_frame * 4, CONTACT_DTYPE)
        a = np.repeat(rng.choice(entities, pairs_per_frame), 4)
        b = np.repeat(np.arange(10_000, 10_000 + pairs_per_frame), 4)  # unscripted
        batch["a"], batch["b"] = a, b
        batch["impulse"] = rng.random(len(batch))
        batches.append(Contacts(batch))
    before = system.contact_events
    t0 = time.perf_counter()
    for i in range(frames):
        system._on_contacts(batches[i % len(batches)])
    elapsed = time.perf_counter() - t0
    events = system.contact_events - before
    ours = elapsed / events * 1e6
    bare = _bare_reference(pairs_per_frame, frames, (None, 0.5))
    return {"kind": CALLS_KIND, "benchmark": "collision event (10k/s, via Contacts)",
            "calls": events, "us_per_call": ours, "us_per_frame": ours * pairs_per_frame,
            "bare_lupa_us": bare, "ratio": ours / bare, "target_us": 5.0, "ok": ours < 5.0}


CHURN = """
made = {}
function spawnMany(k)
  for i = 1, k do
    local box = spawn('Object { ID "box" Position [' .. (i % 50) * 3 .. ' 400 1] '
                      .. 'PhysicalAttributes { } }')
    made[#made + 1] = box[1]
  end
end
function deleteAll()
  for i = 1, #made do made[i]:delete() end
  made = {}
end
"""


#: Frames a churn world runs before it is measured: its boxes settle and fall asleep.
SETTLE_FRAMES = 45


def churn_world(bodies: int) -> tuple[Any, Any, Any]:
    """An ODE world of ``bodies`` named dynamic boxes resting on the ground, 2 m apart,
    settled (asleep), and a script that churns."""
    from components import Name, Script, Transform
    from engine.app import Engine, EngineConfig
    from engine.scene import instantiate, spec_from_text
    from services.scripting.runtime import ScriptRuntime
    from systems import RegistryPlugin, load_plugin
    from systems.scripting import ScriptingPlugin

    engine = Engine(EngineConfig(backend="ode", fast=True, dt=1 / 60),
                    plugins=[RegistryPlugin(), load_plugin("physics"), ScriptingPlugin()])
    text = "\n".join([
        'Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" '
        "} } }",
        *(f'Object {{ ID "b{i}" Position [{i % 70 * 2} {i // 70 * 2} 0.5] '
          "PhysicalAttributes { } }" for i in range(bodies))])
    instantiate(engine, spec_from_text(text, "."))
    owner = engine.spawn(Name("churner"), Transform(), Script(source=CHURN))
    engine.run(frames=SETTLE_FRAMES)
    runtime = engine.resource(ScriptRuntime)
    return engine, runtime, next(s for s in runtime.scripts if s.entity == owner)


def churn_round(engine: Any, runtime: Any, script: Any, boxes: int) -> tuple[float, ...]:
    """One round in a churn world, in the main thread's CPU seconds: a frame with nothing
    to apply, ``boxes`` Lua spawns, the frame applying them, as many Lua deletes (the
    deletion done), the frame applying those."""
    clock = time.thread_time
    t0 = clock()
    engine.step()
    t1 = clock()
    runtime.kernel.dispatch(script.env.spawnMany, boxes)
    t2 = clock()
    engine.step()
    t3 = clock()
    runtime.kernel.dispatch(script.env.deleteAll)
    engine.flush()
    t4 = clock()
    engine.step()
    t5 = clock()
    quiet = t1 - t0
    return t2 - t1, t3 - t2 - quiet, t4 - t3, t5 - t4 - quiet


def _churn_costs(bodies: int, boxes: int, rounds: int) -> tuple[float, ...]:
    """Best ms per box over ``rounds``: a Lua spawn, the frame applying spawns beyond a
    quiet frame, a Lua delete with the deletion it defers, the frame applying deletes."""
    engine, runtime, script = churn_world(bodies)
    try:
        best = [min(costs) for costs in zip(*(churn_round(engine, runtime, script, boxes)
                                              for _ in range(rounds)), strict=True)]
    finally:
        engine.close()
    return tuple(max(cost, 0.0) / boxes * 1e3 for cost in best)


#: The two tables' titles: units and references.
CALLS_KIND = "calls into Lua, us/call; reference: a bare lupa call of the same function"
CHURN_KIND = ("spawning and deleting from Lua, ms/box; reference (5000 bodies): the same "
              "among 100 bodies, in the same run")


def churn_rows(quick: bool) -> list[dict[str, Any]]:
    """Spawn and delete among 100 and 5,000 bodies; the 5,000-body rows' reference is
    the 100-body world measured in the same run."""
    boxes, rounds = (50, 2) if quick else (100, 5)
    small = _churn_costs(100, boxes, rounds)
    large = _churn_costs(5000, boxes, rounds)
    rows = []
    for i, what in enumerate(("spawn a box", "delete a box")):
        target = 0.3 if i == 0 else None
        call, frame = 2 * i, 2 * i + 1
        for bodies, ours in ((100, small), (5000, large)):
            row: dict[str, Any] = {"kind": CHURN_KIND,
                                   "benchmark": f"{what} from Lua ({bodies} resting bodies)",
                                   "calls": boxes * rounds, "ms_per_box": ours[call],
                                   "frame_ms_per_box": ours[frame]}
            if bodies == 5000:
                ratio = ours[call] / small[call]
                row |= {"ms_100_bodies": small[call], "ratio": ratio,
                        "ok": ratio <= 1.5 and (target is None or ours[call] <= target)}
            elif target is not None:
                row |= {"target_ms": target, "ok": ours[call] <= target}
            rows.append(row)
    return rows


if __name__ == "__main__":
    from app.bench import print_table

    print_table(run_bench())
