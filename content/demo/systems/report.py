"""A custom Python system: logs the tallest crate's height every simulated second."""

from components import Name, Transform
from engine import Phase, system


@system(Phase.POST_PHYSICS, reads=(Name, Transform))
def tower_report(engine, dt):
    if engine.frame % 100 == 0:
        heights = [t.position[2] for _, (n, t) in engine.world.get_components(Name, Transform)
                   if n.id.startswith("crate")]
        if heights:
            print(f"t={engine.time:5.2f} s  tower top at {max(heights):.2f} m")


def build(engine):
    engine.add_system(tower_report)
