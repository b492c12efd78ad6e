"""A custom Python system: logs the tallest crate's height each time the simulated clock
passes a whole second (whatever the time step)."""

import math

from components import Name, Transform
from engine import Phase, system


@system(Phase.POST_PHYSICS, reads=(Name, Transform))
def tower_report(engine, dt):
    # this frame took the clock from engine.time - dt to engine.time (POST_PHYSICS runs
    # before the engine advances it, so engine.time is still the frame's start)
    start, end = engine.time + 1e-9, engine.time + dt + 1e-9
    if math.floor(end) == math.floor(start):
        return
    heights = [t.position[2] for _, (n, t) in engine.world.get_components(Name, Transform)
               if n.id.startswith("crate")]
    if heights:
        print(f"t={math.floor(end):3d} s  tower top at {max(heights):.2f} m")


def build(engine):
    engine.add_system(tower_report)
