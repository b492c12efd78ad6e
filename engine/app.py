"""The Engine: one world, its systems, resources, events and physics driver.

>>> from engine.system import Phase, system
>>> with Engine(EngineConfig(backend="ballistic", fast=True), plugins=()) as eng:
...     seen = []
...     _ = eng.add_system(system(Phase.SCRIPT)(lambda e, dt: seen.append(e.frame)))
...     eng.run(frames=3)
>>> seen
[0, 1, 2]
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable
from typing import Any, TypeVar

import numpy as np

from components import Transform
from engine.config import EngineConfig
from engine.events import Despawned, EventBus, Spawned
from engine.memory import paused_gc
from engine.physics.driver import DetachedPhysics, PhysicsPort
from engine.realtime import CostLog, RealTimeController, Tick, advance
from engine.system import (
    ANY_COMPONENT,
    Phase,
    Plugin,
    System,
    SystemFailure,
    UndeclaredAccess,
    order_systems,
)
from engine.world import AccessAudit, World

log = logging.getLogger("colosseum")

R = TypeVar("R")
PHASES = tuple(Phase)
#: A frame that takes no physics step (a headset's frame between two steps, see
#: services.xr.timing) reads input and draws; the simulation's phases wait for a step.
DISPLAY_PHASES = (Phase.INPUT, Phase.RENDER)


class MissingResource(KeyError):
    """A resource no plugin provided: the message names it and what there is (a KeyError,
    so code that asked the dict before still catches it)."""

    def __init__(self, kind: type, known: list[str]) -> None:
        super().__init__(f"no {kind.__name__} resource: the plugin that provides it is not "
                         f"loaded (resources: {', '.join(known) or 'none'})")

    def __str__(self) -> str:
        return str(self.args[0])


class Engine:
    """Owns one private ECS world and runs systems phase by phase, frame after frame.

    The engine itself simulates nothing: plugins bring the systems, physics included
    (``systems.create_engine`` assembles the default set). Without a physics plugin,
    ``physics`` is a :class:`~engine.physics.driver.DetachedPhysics` that keeps the
    commands pushed to it.
    """

    def __init__(self, config: EngineConfig | None = None,
                 plugins: Iterable[Plugin] = (),
                 clock: Callable[[], float] = time.perf_counter,
                 sleep: Callable[[float], None] = time.sleep) -> None:
        self.config = config or EngineConfig()
        cfg = self.config
        self.world = World()
        self.events = EventBus()
        self.rng = np.random.default_rng(cfg.seed)
        self.resources: dict[type, Any] = {}
        self.systems: dict[Phase, list[System]] = {phase: [] for phase in Phase}
        self.plugins: dict[str, Plugin] = {}
        self.plugin_factories: dict[str, Callable[[], Plugin]] = {}
        #: Extra sections for ``--stats`` (e.g. the sound manager's counters).
        self.stat_sources: dict[str, Callable[[], Any]] = {}
        self.frame = 0
        self.time = 0.0
        self.frame_costs = CostLog()
        self.tick = Tick(self.config.dt, self.config.substeps)
        #: Wall seconds the dynamics system spent stepping this frame (serial mode).
        self.physics_seconds: float | None = None
        self._deferred: list[Callable[[], None]] = []
        self._started = False
        self._closed = False
        self._quit = False
        #: The wall clock every controller of this engine reads (injectable for tests).
        self.clock = clock
        self.physics: PhysicsPort = DetachedPhysics(cfg.world.limits)
        self.controller = RealTimeController(cfg.pacing(), clock=clock, sleep=sleep)
        for plugin in plugins:
            self.add_plugin(plugin)

    # -- composition --------------------------------------------------------
    def add_system(self, system: System) -> System:
        """Add a system to its phase, ordered by its ``before``/``after`` declarations."""
        self.systems[system.phase] = order_systems([*self.systems[system.phase], system])
        if self._started:
            system.setup(self)
        return system

    def attach_physics(self, physics: PhysicsPort) -> None:
        """Make ``physics`` the engine's (the physics plugin's job); commands already
        pushed to a detached port are handed over in order."""
        previous = self.physics
        if isinstance(previous, DetachedPhysics):
            for command in previous.outbox:
                physics.push(command)
        self.physics = physics

    def add_plugin(self, plugin: Plugin) -> Plugin:
        """Build a plugin once; a second plugin of the same name is ignored."""
        name = str(plugin.name)  # a PluginName is kept as its plain text
        if name in self.plugins:
            return self.plugins[name]
        self.plugins[name] = plugin
        plugin.build(self)
        return plugin

    def register_plugin(self, name: str, factory: Callable[[], Plugin],
                        aliases: Iterable[str] = ()) -> None:
        """Make a plugin loadable by name (``requestPlugin`` in Lua)."""
        for key in (name, *aliases):
            self.plugin_factories[str(key)] = factory

    def request_plugin(self, name: str) -> Plugin:
        factory = self.plugin_factories.get(name)
        if factory is None:
            known = ", ".join(sorted(self.plugin_factories)) or "none"
            raise KeyError(f"unknown plugin {name!r} (known: {known})")
        plugin = factory()
        return self.add_plugin(plugin)

    def insert_resource(self, resource: Any, as_type: type | None = None) -> None:
        self.resources[as_type or type(resource)] = resource

    def resource(self, kind: type[R]) -> R:
        """The one ``kind`` a plugin provides (the input plugin's ``InputState``, the
        render plugin's ``Renderer``); :class:`MissingResource` names it when none did."""
        try:
            return self.resources[kind]
        except KeyError:
            raise MissingResource(kind, sorted(t.__name__ for t in self.resources)) from None

    def try_resource(self, kind: type[R]) -> R | None:
        return self.resources.get(kind)

    # -- structural changes ---------------------------------------------------
    def spawn(self, *components: Any) -> int:
        """Create an entity now (main thread); physics learns of it through the queue."""
        entity = self.world.create_entity(*components)
        self.events.emit(Spawned(entity))
        return entity

    def spawn_many(self, component_lists: Iterable[Iterable[Any]]) -> list[int]:
        """:meth:`spawn` for many entities at once (a scene load): cheaper per entity."""
        entities = self.world.create_entities(component_lists)
        for entity in entities:
            self.events.emit(Spawned(entity))
        return entities

    def despawn(self, entity: int) -> None:
        """Delete an entity at the end of the current phase."""
        self.defer(lambda: self._despawn_now(entity))

    def _despawn_now(self, entity: int) -> None:
        if self.world.entity_exists(entity):
            self.world.delete_entity(entity)
            self.events.emit(Despawned(entity))

    def defer(self, action: Callable[[], None]) -> None:
        """Run ``action`` on the main thread at the next phase boundary."""
        self._deferred.append(action)

    def flush(self) -> None:
        """Apply what was deferred (despawns) and deliver the events emitted, as at a phase
        boundary (a tool measuring a deletion calls it outside a frame)."""
        while self._deferred:
            actions, self._deferred = self._deferred, []
            for action in actions:
                action()
        self.events.dispatch()

    # -- running ------------------------------------------------------------
    def start(self) -> None:
        if self._started:
            return
        self._started = True
        with paused_gc():  # setups make what lives as long as the world: a scene's worth
            for phase in Phase:
                for system in self.systems[phase]:
                    system.setup(self)
        self.flush()

    def step(self) -> None:
        """Run one frame: every phase in order."""
        self.start()
        self.physics.check()
        tick = self.controller.begin()
        t0 = self.controller.clock()
        self.tick = tick
        self.physics_seconds = None
        self.physics.frame = self.frame
        audited = self.config.debug
        for phase in PHASES if tick.substeps > 0 else DISPLAY_PHASES:
            for system in self.systems[phase]:
                try:
                    if audited:
                        self._run_audited(system, tick.dt)
                    else:
                        system.run(self, tick.dt)
                except Exception as exc:
                    raise SystemFailure(system.name, exc) from exc
            self.flush()
        self.frame += 1
        if self.config.mode == "threaded":
            self.time = self.physics.time
        elif tick.substeps > 0:
            self.time = advance(self.time, tick.dt)
        self.events.end_frame()
        self.frame_costs.add(self.controller.clock() - t0)
        self.controller.end(tick, self.physics_seconds)
        if self.config.mode == "threaded" and self.config.fast:
            time.sleep(0)  # unpaced: still let the physics thread take the GIL

    def _run_audited(self, system: System, dt: float) -> None:
        """Run ``system`` and check it touched only the component types it declares.

        Reads are the queries it made; writes the components it added or removed, and
        for Transforms (the pose table, which physics and rendering trust) any value it
        changed: the table is compared bit for bit before and after. Changes to other
        components' fields are not seen.
        """
        readable, writable = {*system.reads, *system.writes}, set(system.writes)
        poses = self.world.poses
        before = None if Transform in writable or ANY_COMPONENT in writable else \
            poses.table.copy()
        audit = self.world.audit = AccessAudit()
        try:
            system.run(self, dt)
        finally:
            self.world.audit = None
        undeclared = set() if ANY_COMPONENT in readable else audit.read - readable
        if ANY_COMPONENT not in writable:
            undeclared |= audit.written - writable
        if before is not None and _changed(before, poses.table):
            undeclared.add(Transform)
        if undeclared:
            raise UndeclaredAccess(system, sorted(t.__name__ for t in undeclared))

    def run(self, frames: int | None = None, seconds: float | None = None,
            until: Callable[[Engine], bool] | None = None) -> None:
        """Run frames until a frame count, a simulated time, a predicate or a quit request.

        In threaded mode the physics thread stops by itself at the end time and one
        last frame picks up its final state.
        """
        self.start()
        threaded = self.config.mode == "threaded"
        self.physics.stop_at = None if seconds is None else self.time + seconds
        end_time = None if seconds is None else self.time + seconds - 1e-9
        end_frame = None if frames is None else self.frame + frames
        while end_frame is None or self.frame < end_frame:
            if self._quit or (until is not None and until(self)):
                break
            if end_time is not None and threaded and self.physics.time >= end_time:
                self.step()
                break
            if end_time is not None and not threaded and self.time >= end_time:
                break
            self.step()

    @property
    def real_time_factor(self) -> float:
        """Simulated seconds per wall second since the first frame (physics time, either mode)."""
        wall = self.controller.wall_time
        return self.physics.time / wall if wall > 0 else 0.0

    def request_quit(self) -> None:
        """Ask the run loop to stop after this frame (a closed window, a script's quit)."""
        self._quit = True

    def close(self) -> None:
        """Stop physics, shut every system down; safe to call twice, also after errors."""
        if self._closed:
            return
        self._closed = True
        self.physics.close()
        for phase in reversed(Phase):
            for system in reversed(self.systems[phase]):
                try:
                    system.shutdown(self)
                except Exception:
                    log.exception("system %s failed to shut down", system.name)
        self.world.close()

    def __enter__(self) -> Engine:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def _changed(before: np.ndarray, after: np.ndarray) -> bool:
    """Whether a pose table's rows changed (bit for bit: NaN equals NaN); a table that
    grew was changed by adding Transforms, which the audit counts on its own."""
    rows = min(len(before), len(after))
    return not np.array_equal(before[:rows].view(np.int64), after[:rows].view(np.int64))
