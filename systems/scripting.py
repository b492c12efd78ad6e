"""The scripting system: Script components run as sandboxed Lua, fed with engine events.

A Script on an entity with a Transform is an *object script* (``self`` is the
object; ``onCollision(other, impulse)``); a Script on an entity without one is a
*scene script* (``onCollision(a, b, impulse)`` for every colliding pair). The
frame's Contacts batch is reduced in numpy to one event per colliding pair with
the summed impulse, and only pairs involving scripted entities reach Lua.
Scripts run in the SCRIPT phase on the main thread; what they do to physics
goes through the command queue. Script files are watched (a stat at most every
``RELOAD_INTERVAL`` seconds) and reloaded when they change.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from components import HandState, Name, Script, Transform
from components.script import SavedScript
from engine.events import (
    ContactBegan,
    ContactEnded,
    Contacts,
    CustomEvent,
    Despawned,
    HandGrasped,
    HandReleased,
    HandTouched,
    KeyEvent,
    TimerEvent,
)
from engine.services import ScriptStates
from engine.system import ANY_COMPONENT, Phase, PluginName, System
from services.input.events import Axis, Button, DeviceFound, DeviceLost, TrackerPose, WheelCount

if TYPE_CHECKING:
    from engine.app import Engine
    from engine.world import World
    from services.scripting.api import ScriptAPI
    from services.scripting.runtime import Script as LoadedScript
    from services.scripting.runtime import ScriptLimits, ScriptRuntime

log = logging.getLogger("colosseum.script")

#: Seconds between two checks of the script files' modification times.
RELOAD_INTERVAL = 0.25


@dataclass(eq=False, slots=True)
class _Broken:
    """A script file that failed to load; retried when the file changes."""

    entity: int
    path: Path
    mtime: float


class ScriptingSystem(System):
    phase = Phase.SCRIPT
    # scripts find, spawn, move and delete objects of every kind
    reads = (ANY_COMPONENT,)
    writes = (ANY_COMPONENT,)

    def __init__(self, limits: ScriptLimits | None = None,
                 reload_interval: float = RELOAD_INTERVAL) -> None:
        self.limits = limits
        self.reload_interval = reload_interval
        self.runtime: ScriptRuntime | None = None
        self._api: ScriptAPI | None = None
        self._pending: list[tuple[int, Script]] = []
        self._started: list[LoadedScript] = []
        self._by_entity: dict[int, list[LoadedScript]] = {}
        self._scene: list[LoadedScript] = []
        self._scripted = np.zeros(0, np.int64)
        self._lookup = np.zeros(1, bool)
        self._broken: list[_Broken] = []
        self._owners: dict[int, list[LoadedScript]] = {}
        self._next_check = 0.0
        self.contact_events = 0
        #: This frame's newest pose per tracker: scripts hear each tracker once a frame.
        self._poses: dict[str, TrackerPose] = {}
        self._exists: Callable[[int], bool] = lambda entity: True
        #: (hand, object) -> the fingers its grasp was told with: onRelease names them
        #: (by then the hand's grip has opened).
        self._grips: dict[tuple[int, int], tuple[str, ...]] = {}
        self._world: World | None = None
        self._engine: Engine | None = None

    # -- setup ------------------------------------------------------------------
    def setup(self, engine: Engine) -> None:
        self._engine = engine
        engine.insert_resource(self)
        engine.insert_resource(self, as_type=ScriptStates)
        world = engine.world
        self._exists = world.entity_exists
        self._world = world
        world.on_add(Script, self._added)
        world.on_remove(Script, lambda e, c: self._unload(e))
        for entity, script in world.get_component(Script):
            self._added(entity, script)
        events = engine.events
        events.subscribe(Contacts, self._on_contacts)
        events.subscribe(ContactBegan, lambda ev: self._on_touch(
            "onCollisionBegin", ev.a, ev.b, (ev.impulse,)))
        events.subscribe(ContactEnded, lambda ev: self._on_touch("onCollisionEnd", ev.a, ev.b, ()))
        events.subscribe(HandTouched, lambda ev: self._on_hand("onTouch", ev.hand, ev.object))
        events.subscribe(HandGrasped, lambda ev: self._on_grip("onGrasp", ev.hand, ev.object))
        events.subscribe(HandReleased, lambda ev: self._on_grip("onRelease", ev.hand,
                                                                ev.object))
        self._subscribe_broadcasts(engine)

    def _added(self, entity: int, script: Script) -> None:
        """A Script component came: it loads at the next frame, in a runtime started now
        if this is the first (a scene without scripts never starts Lua)."""
        if self.runtime is None:
            self._start_runtime()
        self._pending.append((entity, script))

    @property
    def api(self) -> ScriptAPI:
        """The scripting API (what Lua calls, and Python may call as Lua would), made when
        first asked for: at the first script, or by a tool spawning as a script does."""
        if self._api is None:
            from services.scripting.api import ScriptAPI

            assert self._engine is not None, "the scripting system is not set up yet"
            self._api = ScriptAPI(self._engine)
        return self._api

    def _start_runtime(self) -> ScriptRuntime:
        """The Lua runtime with the API installed, made a resource of the engine; both are
        loaded here, at the first script (a scene without scripts loads neither)."""
        from services.scripting.runtime import ScriptLimits, ScriptRuntime

        engine = self._engine
        assert engine is not None
        content = engine.config.content_dir
        scripts_dir = Path(content) / "scripts" if content is not None else None
        limits = self.limits or engine.config.options.get("script_limits") or ScriptLimits()
        runtime = ScriptRuntime(limits, scripts_dir, api=self.api.install,
                                seed=engine.config.seed)
        runtime.emit_hook = lambda name, data: engine.events.emit(CustomEvent(name, data))
        self.runtime = runtime
        engine.insert_resource(runtime)
        return runtime

    def _subscribe_broadcasts(self, engine: Engine) -> None:
        """Input, timer, custom and despawn events for the scripts, once a runtime runs
        (before it, no script is there to hear them)."""
        def broadcast(callback: str, *args: object) -> None:
            if self.runtime is not None:
                self.runtime.broadcast(callback, *args)

        def deliver(ev: CustomEvent) -> None:
            if self.runtime is not None:
                self.runtime.deliver(ev.name, ev.data)

        def forget(ev: Despawned) -> None:
            if self.runtime is not None:
                self.runtime.kernel.forget(ev.entity)

        events = engine.events
        events.subscribe(KeyEvent, lambda ev: broadcast("onKey", ev.key, ev.pressed))
        events.subscribe(Button, lambda ev: broadcast("onButton", ev.device, ev.name,
                                                      ev.pressed))
        events.subscribe(Axis, lambda ev: broadcast(
            "onInput", f"axis:{ev.device}/{ev.name}", ev.value))
        events.subscribe(WheelCount, lambda ev: broadcast("onInput", f"wheel:{ev.device}",
                                                          ev.count))
        events.subscribe(TrackerPose, lambda ev: self._poses.__setitem__(ev.device, ev))
        events.subscribe(DeviceLost, lambda ev: broadcast("onDeviceLost", ev.device))
        events.subscribe(DeviceFound, lambda ev: broadcast("onDeviceFound", ev.device))
        events.subscribe(TimerEvent, lambda ev: broadcast("onTimer", ev.name))
        events.subscribe(CustomEvent, deliver)
        events.subscribe(Despawned, forget)

    # -- per frame --------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        runtime = self.runtime
        if runtime is None:  # no script yet: nothing to run, no Lua started
            self._poses.clear()
            return
        runtime.time = engine.time  # timers run on the simulation's clock (a saved one too)
        if self._pending:
            self._load_pending(engine)
        now = time.monotonic()
        if now >= self._next_check:
            self._next_check = now + self.reload_interval
            self._check_files(engine)
        if self._poses:
            self._deliver_poses(runtime)
        runtime.update(dt)

    def _load_pending(self, engine: Engine) -> None:
        runtime = self.runtime
        assert runtime is not None
        pending, self._pending = self._pending, []
        started: list[tuple[LoadedScript, str]] = []
        for entity, component in pending:
            if not component.enabled or not engine.world.entity_exists(entity):
                continue
            loaded = self._load(engine, entity, component)
            if loaded is not None:
                saved, component.saved = component.saved, None
                resumed = saved is not None and runtime.resume(loaded, saved, self._find)
                started.append((loaded, "onResume" if resumed else "onStart"))
                self._owners.setdefault(entity, []).append(loaded)
        self._reindex(engine)
        for loaded, callback in started:
            runtime.call(loaded, callback)

    def _find(self, name: str) -> int:
        return self.api.find(name)

    def _load(self, engine: Engine, entity: int, component: Script) -> LoadedScript | None:
        from services.scripting.runtime import ScriptLoadError

        runtime = self.runtime
        assert runtime is not None
        is_object = engine.world.has_component(entity, Transform)
        owner = entity if is_object else None
        try:
            if component.source is not None:
                named = engine.world.try_component(entity, Name)
                label = f"{named.id if named else entity}.lua"
                return runtime.load(label, component.source, owner)
            path = self._resolve(engine, component.file)
            try:
                return runtime.load_file(path, owner)
            except OSError as exc:
                runtime.report(f"{component.file}: cannot read script: {exc.strerror or exc}")
                return None
        except ScriptLoadError as exc:
            runtime.report(f"{exc}\n(script not started; fix the file and it is reloaded)")
            if component.source is None:
                path = self._resolve(engine, component.file)
                if path.exists():
                    self._broken.append(_Broken(entity, path, path.stat().st_mtime))
            return None

    @staticmethod
    def _resolve(engine: Engine, file: str) -> Path:
        path = Path(file)
        content = engine.config.content_dir
        if not path.is_absolute() and content is not None:
            path = Path(content) / path
        return path

    def _reindex(self, engine: Engine) -> None:
        runtime = self.runtime
        assert runtime is not None
        self._by_entity = {}
        self._scene = []
        for script in runtime.scripts:
            if script.entity is None:
                self._scene.append(script)
            else:
                self._by_entity.setdefault(script.entity, []).append(script)
        self._scripted = np.array(sorted(self._by_entity), dtype=np.int64)
        self._update_lookup()

    def _update_lookup(self) -> None:
        """Boolean table entity id -> has an object script, plus a final False slot."""
        size = int(self._scripted.max()) + 2 if len(self._scripted) else 1
        self._lookup = np.zeros(size, bool)
        self._lookup[self._scripted] = True

    def _unload(self, entity: int) -> None:
        runtime = self.runtime
        if runtime is None:
            return
        for script in self._owners.pop(entity, ()):
            runtime.unload(script)
        self._pending = [(e, c) for e, c in self._pending if e != entity]
        self._broken = [b for b in self._broken if b.entity != entity]
        self._by_entity.pop(entity, None)
        self._scene = [s for s in self._scene if s in runtime.scripts]
        self._scripted = self._scripted[self._scripted != entity]
        self._update_lookup()

    def _check_files(self, engine: Engine) -> None:
        runtime = self.runtime
        assert runtime is not None
        for script in list(runtime.scripts):
            path = script.path
            if path is None:
                continue
            try:
                mtime = path.stat().st_mtime
            except OSError:
                continue
            if mtime != script.mtime:
                script.mtime = mtime
                try:
                    source = path.read_text(encoding="utf-8")
                except (OSError, UnicodeDecodeError) as exc:
                    runtime.report(f"{script.name}: cannot read the changed file: {exc}")
                    continue
                if runtime.reload(script, source):
                    log.info("%s: reloaded", script.name)
        for broken in list(self._broken):
            try:
                mtime = broken.path.stat().st_mtime
            except OSError:
                continue
            if mtime != broken.mtime:
                self._broken.remove(broken)
                if engine.world.entity_exists(broken.entity):
                    component = engine.world.try_component(broken.entity, Script)
                    if component is not None:
                        self._pending.append((broken.entity, component))
        if self._pending:
            self._load_pending(engine)

    # -- events -----------------------------------------------------------------
    def _on_contacts(self, event: Contacts) -> None:
        runtime = self.runtime
        batch = event.batch
        if runtime is None or not len(batch) or not (len(self._scripted) or self._scene):
            return
        a, b = batch["a"], batch["b"]
        impulse = batch["impulse"]
        if not self._scene:
            lut = self._lookup
            last = len(lut) - 1  # lut[last] (= lut[-1]) is False: the world (-1), unscripted ids
            mask = lut[np.clip(a, -1, last)] | lut[np.clip(b, -1, last)]
            if not mask.any():
                return
            a, b, impulse = a[mask], b[mask], impulse[mask]
        # one event per colliding pair, impulses summed over contacts and steps
        key = (a.astype(np.int64) << 32) | (b.astype(np.int64) & 0xFFFFFFFF)
        pairs, first, inverse = np.unique(key, return_index=True, return_inverse=True)
        total = np.bincount(inverse.reshape(-1), weights=impulse, minlength=len(pairs))
        pa, pb = a[first].tolist(), b[first].tolist()
        totals = total.tolist()
        by_entity, scene = self._by_entity, self._scene
        self.contact_events += len(totals)
        owners: list[LoadedScript] = []
        others: list[int] = []
        impulses: list[float] = []
        for ea, eb, j in zip(pa, pb, totals, strict=True):
            for mine, other in ((ea, eb), (eb, ea)):  # each side's scripts hear the other
                for script in by_entity.get(mine, ()):
                    owners.append(script)
                    others.append(other)
                    impulses.append(j)
        if owners:
            runtime.collide_many(owners, others, impulses)
        for script in scene:
            for ea, eb, j in zip(pa, pb, totals, strict=True):
                runtime.collide_scene(script, ea, eb, j)
        self._forget_gone({*pa, *pb})

    def _forget_gone(self, entities: Iterable[int]) -> None:
        """Drop the Lua handles the callbacks just made for objects already deleted: a
        contact of a step under way when a script deleted its body (threaded) or a touch
        ending with a deleted object is told after the Despawned event that dropped the
        handle, and the handle made for it would stay for good (a soak's handle table
        grew by one per churned box)."""
        assert self.runtime is not None
        forget, exists = self.runtime.kernel.forget, self._exists
        for entity in entities:
            if entity >= 0 and not exists(entity):
                forget(entity)

    def _deliver_poses(self, runtime: ScriptRuntime) -> None:
        poses, self._poses = self._poses, {}
        for name, pose in poses.items():
            runtime.broadcast("onTracker", name, *pose.position, *pose.orientation)

    def _on_hand(self, callback: str, hand: int, obj: int,
                 fingers: tuple[str, ...] | None = None) -> None:
        """``callback(hand, object)`` for the hand's scripts, the object's and the scene's;
        ``callback(hand, object, fingers)`` (a table of finger names) when given."""
        runtime = self.runtime
        if runtime is None:
            return
        for script in (*self._by_entity.get(hand, ()), *self._by_entity.get(obj, ()),
                       *self._scene):
            if fingers is None:
                runtime.call_objects(script, callback, (hand, obj))
            else:  # a table each: a script changing its copy changes no other's
                runtime.call_objects(script, callback, (hand, obj),
                                     runtime.lua.table_from(list(fingers)))
        self._forget_gone((hand, obj))

    def _on_grip(self, callback: str, hand: int, obj: int) -> None:
        """onGrasp and onRelease with the fingers that hold (HandState.grip, thumb first,
        "palm" included; empty for a palm-only hand): a release names those its grasp
        was told with, or the grip of the moment if the grasp came before this plugin."""
        world = self._world
        state = world.try_component(hand, HandState) \
            if world is not None and self._exists(hand) else None
        grip = tuple(state.grip) if state is not None else ()
        if callback == "onGrasp":
            self._grips[(hand, obj)] = grip
        else:
            grip = self._grips.pop((hand, obj), grip)
        self._on_hand(callback, hand, obj, grip)

    def _on_touch(self, callback: str, a: int, b: int, extra: tuple[float, ...]) -> None:
        """A pair began or stopped touching: each side's object scripts hear the other
        (``callback(other, ...)``), scene scripts hear both (``callback(a, b, ...)``)."""
        runtime = self.runtime
        if runtime is None:
            return
        for mine, other in ((a, b), (b, a)):
            for script in self._by_entity.get(mine, ()):
                runtime.call_objects(script, callback, (other,), *extra)
        for script in self._scene:
            runtime.call_objects(script, callback, (a, b), *extra)
        self._forget_gone((a, b))


    def saved_scripts(self, object_name: Callable[[int], str | None]
                      ) -> dict[int, SavedScript]:
        """Each running script's state, by the entity it runs on (see
        :mod:`services.scripting.persist`); what cannot be saved is told, once per save."""
        runtime = self.runtime
        if runtime is None:
            return {}
        states: dict[int, SavedScript] = {}
        if runtime.kernel.random_calls():
            log.warning("saved state: scripts drew from math.random, whose position in its "
                        "sequence cannot be saved; the resumed run draws other numbers (seed "
                        "it in onResume with math.randomseed(n) for a repeatable continuation)")
        for entity, scripts in self._owners.items():
            for script in scripts:
                if script.stopped or script not in runtime.scripts:
                    continue
                saved, told = runtime.capture(script, object_name)
                for message in told:
                    log.warning("saved state: %s", message)
                if saved is not None:
                    states[entity] = saved
        return states

    def shutdown(self, engine: Engine) -> None:
        if self._api is not None:
            self._api.flush()  # how often each repeated message came again
        self._pending.clear()
        self._broken.clear()


class ScriptingPlugin:
    """Runs the scene's Lua scripts (``requestPlugin("scripting")``)."""

    name = PluginName.SCRIPTING

    def __init__(self, limits: ScriptLimits | None = None,
                 reload_interval: float = RELOAD_INTERVAL) -> None:
        self.limits = limits
        self.reload_interval = reload_interval

    def build(self, engine: Engine) -> None:
        engine.add_system(ScriptingSystem(self.limits, self.reload_interval))
