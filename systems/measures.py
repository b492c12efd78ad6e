"""The measures plugin: a run's final values, for ``--stats`` and ``colosseum sweep``.

``Measure`` blocks name an object and a quantity; scripts call ``measure(name, value)``.
The plugin registers the ``measures`` section of the statistics, read when the run ends:
every Measure block's quantity then, and every value a script gave (its last one).
A Measure whose object is gone (deleted) is told once and left out.
"""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING

from components import Transform
from engine.measures import Measures, quantity
from engine.scene import SceneIds
from engine.system import Phase, PluginName, System

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.measures")


def final_values(engine: Engine) -> dict[str, float]:
    """The run's measures now: the scene's Measure blocks, then what scripts reported."""
    out: dict[str, float] = {}
    ids = engine.try_resource(SceneIds)
    for spec in [] if ids is None else ids.spec.measures:
        entity = ids.entities.get(spec.object)  # type: ignore[union-attr]
        t = None if entity is None or not engine.world.entity_exists(entity) else \
            engine.world.try_component(entity, Transform)
        if t is None:
            log.warning("measure %r: object %r is gone; it is not reported", spec.id,
                        spec.object)
            continue
        out[spec.id] = quantity(spec.value, tuple(t.position), tuple(t.linear_velocity))
    reported = engine.try_resource(Measures)
    if reported is not None:
        out.update(reported.values)
    return out


class MeasuresSystem(System):
    """Keeps the values as they stand when the engine closes (its world is emptied then;
    the statistics are read again after)."""

    phase = Phase.POST_PHYSICS
    reads = (Transform,)

    def __init__(self) -> None:
        self.final: dict[str, float] | None = None

    def run(self, engine: Engine, dt: float) -> None:
        """Nothing each frame: the values are read when asked."""

    def shutdown(self, engine: Engine) -> None:
        self.final = final_values(engine)

    def values(self, engine: Engine) -> dict[str, float]:
        return final_values(engine) if self.final is None else self.final


class MeasuresPlugin:
    """Adds the ``measures`` section to the run's statistics."""

    name = PluginName.MEASURES

    def build(self, engine: Engine) -> None:
        if engine.try_resource(Measures) is None:
            engine.insert_resource(Measures())
        system = MeasuresSystem()
        engine.add_system(system)
        engine.stat_sources["measures"] = lambda: system.values(engine)
