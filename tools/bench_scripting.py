"""``colosseum bench scripting``: the cost of calling into sandboxed Lua.

Two rows, each beside a reference measured in the same run:

- onUpdate dispatch: one frame calls ``onUpdate(dt)`` on 100 scripts through the
  runtime (fresh instruction budget, error capture, disabled-callback checks).
- collision events: 10,000 events per second (167 colliding pairs per 60 Hz
  frame, 4 contacts each) from a Contacts batch through the scripting system's
  numpy filter and pair reduction into ``onCollision(other, impulse)``.

The reference is a bare lupa call of an equivalent Lua function from Python
(no sandbox, no budget, no handle lookup); ``ratio`` is ours over it.
Target: under 5 µs per collision event.
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
    from engine.events import Contacts
    from engine.physics.backend import CONTACT_DTYPE
    from engine.scripting.runtime import ScriptRuntime
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
        rows.append({"benchmark": "onUpdate dispatch (100 scripts)", "calls": frames * scripts,
                     "us_per_call": ours, "us_per_frame": ours * scripts,
                     "bare_lupa_us": bare, "ratio": ours / bare})

        # -- collision events ---------------------------------------------------
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
        rows.append({"benchmark": "collision event (10k/s, via Contacts)", "calls": events,
                     "us_per_call": ours, "us_per_frame": ours * pairs_per_frame,
                     "bare_lupa_us": bare, "ratio": ours / bare,
                     "target_us": 5.0, "ok": ours < 5.0})
        assert all(s.env.hits > 0 for s in runtime.scripts)
    return rows


if __name__ == "__main__":
    from tools.bench import print_table

    print_table(run_bench())
