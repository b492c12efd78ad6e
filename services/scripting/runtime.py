"""One sandboxed Lua 5.4 runtime per engine, running many scripts side by side.

Lua 5.4 is imported explicitly (``lupa.lua54``), never LuaJIT: the JIT skips
the instruction-count hook the budget relies on. Every script lives in its own
environment table; the runtime calls into them only through the kernel's
dispatcher (see :mod:`services.scripting.sandbox`), so each callback runs under a
fresh instruction budget and its errors come back as ``file:line: message``
plus a traceback instead of exceptions. A callback that keeps failing is
disabled with one message; a script that blows its budget or the memory cap is
stopped; the engine and every other script carry on.
"""

from __future__ import annotations

import logging
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from components.script import SavedScript, ScriptHandler, ScriptTimer
from services.scripting.persist import lua_literal
from services.scripting.sandbox import (
    BUDGET_MESSAGE,
    HOOK_STEP,
    INSTRUCTIONS_PER_SECOND,
    KERNEL,
    MEMORY_MESSAGE,
    normalise_quotes,
    resolve_module,
)

log = logging.getLogger("colosseum.script")

#: ``lupa.lua54``, imported when the first runtime starts (:func:`load_lua`): a run whose
#: scene has no script loads no Lua.
lua54: Any = None


class _NoLuaYet(Exception):
    """Stands for lupa's ``LuaError`` until Lua is loaded; nothing raises it (every
    ``except LuaError`` is in a runtime's method, and a runtime loads Lua first)."""


LuaError: type[Exception] = _NoLuaYet


def load_lua() -> Any:
    """``lupa.lua54``, imported once, on first use; ``LuaError`` is then lupa's."""
    global lua54, LuaError
    if lua54 is None:
        import lupa.lua54 as module

        lua54, LuaError = module, module.LuaError
    return lua54


@dataclass(slots=True)
class ScriptLimits:
    """How much one callback and the whole runtime may use."""

    #: VM instructions per callback (about 10-20 ms of pure Lua on one core).
    instructions: int = 10_000_000
    #: Bytes for the whole runtime (all scripts together).
    memory: int = 256 * 1024 * 1024
    #: Errors of one callback before it is disabled.
    max_failures: int = 3


@dataclass(eq=False, slots=True)
class Script:
    """One loaded script: its environment and health."""

    sid: int
    name: str
    entity: int | None
    path: Path | None
    env: Any
    source: str = ""
    stopped: bool = False
    failures: dict[str, int] = field(default_factory=dict)
    disabled: set[str] = field(default_factory=set)
    mtime: float | None = None
    #: Names the environment started with (the API): not the script's own (Lua set).
    base: Any = None
    #: The script's global functions as its file made them (Lua table name -> function).
    loaded: Any = None

    @property
    def active(self) -> bool:
        return not self.stopped


@dataclass(eq=False, slots=True)
class _Timer:
    script: Script
    due: float
    period: float
    fn: Any
    tid: int


@dataclass(eq=False, slots=True)
class _Handler:
    script: Script
    fn: Any
    #: Registered by the file's top level (made again when the file runs).
    at_load: bool


class ScriptLoadError(RuntimeError):
    """A script failed to compile or its top-level code failed."""


def _refuse_attribute(obj: object, name: object, is_setting: bool) -> str:
    raise AttributeError("scripts cannot access attributes of Python objects")


#: Per-script globals: print, log, timers, custom events, require.
_SCRIPT_GLOBALS = r"""
local K, P, API = ...
local select, tostring, type, concat, pairs = select, tostring, type, table.concat, pairs
local function text(...)
  local n = select("#", ...)
  local parts = {}
  for i = 1, n do parts[i] = tostring((select(i, ...))) end
  return concat(parts, "\t")
end
local function number(v, what)
  if type(v) ~= "number" then error(what .. ": expected a number, got " .. type(v), 3) end
  if v ~= v or v == math.huge or v == -math.huge then
    error(what .. ": expected a finite number of seconds, got " .. tostring(v), 3)
  end
  return v
end
local function fn(v, what)
  if type(v) ~= "function" then error(what .. ": expected a function, got " .. type(v), 3) end
  return v
end
local module_globals = K.copy(API)
module_globals.print = function(...) P.log(0, "info", text(...)) end
module_globals.log = module_globals.print
local require = K.require_with(P.read_module, module_globals)
module_globals.require = require
return function(sid, self_id)
  local g = {}
  for k, v in pairs(API) do g[k] = v end
  local c = K.copy(API.colosseum or {})
  g.colosseum = c
  g.self = K.handle(self_id)
  g.print = function(...) P.log(sid, "info", text(...)) end
  c.log = function(...) P.log(sid, "info", text(...)) end
  c.warn = function(...) P.log(sid, "warning", text(...)) end
  c.after = function(sec, f) return P.timer(sid, number(sec, "after"), fn(f, "after"), 0.0) end
  c.every = function(sec, f)
    sec = number(sec, "every")
    if sec <= 0 then error("every: the period must be positive", 2) end
    return P.timer(sid, sec, fn(f, "every"), sec)
  end
  c.cancel = function(t) P.cancel(sid, t) end
  c.on = function(name, f) P.on(sid, tostring(name), fn(f, "on")) end
  c.emit = function(name, data) P.emit(sid, tostring(name), K.plain(data)) end
  for _, k in pairs({"log", "warn", "after", "every", "cancel", "on", "emit"}) do g[k] = c[k] end
  g.require = require
  return K.new_env(g)
end
"""


class ScriptRuntime:
    """A Lua 5.4 state with the sandbox kernel, an API and the scripts loaded into it."""

    def __init__(self, limits: ScriptLimits | None = None, scripts_dir: Path | None = None,
                 api: Callable[[ScriptRuntime], Any] | None = None,
                 seed: int | None = None) -> None:
        self.limits = limits or ScriptLimits()
        self.scripts_dir = scripts_dir
        self.lua = load_lua().LuaRuntime(register_eval=False, register_builtins=False,
                                         attribute_filter=_refuse_attribute,
                                         unpack_returned_tuples=True,
                                         max_memory=self.limits.memory)
        ticks = max(1, self.limits.instructions // HOOK_STEP)
        k = self.lua.execute(KERNEL, HOOK_STEP, ticks, BUDGET_MESSAGE, INSTRUCTIONS_PER_SECOND,
                             name="=colosseum")
        self.kernel = k
        self._call = k.call
        self._dispatch = k.dispatch
        self._collide = k.collide
        self._collide_scene = k.collide_scene
        self._collide_batch = k.collide_batch
        self._call_batch = k.call_batch
        self._call_handles = k.call_handles
        #: scripts that get onUpdate and their environments as a Lua array; None: rebuild
        self._update_batch: tuple[list[Script], Any] | None = None
        self._collect_pending = False
        self.scripts: list[Script] = []
        self._by_sid: dict[int, Script] = {}
        self._timers: list[_Timer] = []
        self._handlers: dict[str, list[_Handler]] = {}
        #: The script whose file is running (its top level), if any.
        self._loading: Script | None = None
        self._next_tid = 1
        self.time = 0.0
        #: Every message reported (also logged), newest last; for tools and tests.
        self.messages: deque[str] = deque(maxlen=200)
        #: Called with (name, python data) when a script emits a custom event.
        self.emit_hook: Callable[[str, Any], None] | None = None
        P = self.lua.table_from({
            "log": self._lua_log, "timer": self._lua_timer, "cancel": self._lua_cancel,
            "on": self._lua_on, "emit": self._lua_emit, "read_module": self._read_module,
        })
        api_globals = api(self) if api is not None else self.lua.table()
        self._make_globals = self.lua.execute(_SCRIPT_GLOBALS, k, P, api_globals,
                                              name="=colosseum")
        #: object(id) for reading saved variables: the handle of the object of that ID.
        self._object = self.lua.execute(
            "local K = ...; return function(find) return function(name) "
            "return K.handle(find(name)) end end", k, name="=colosseum")
        k.lockdown()
        if seed is not None:  # math.random follows the run's seed (serial runs repeat)
            self.lua.execute("local s = ...; math.randomseed(s)", int(seed) & 0x7FFFFFFF)

    # -- loading --------------------------------------------------------------
    def load(self, name: str, source: str, entity: int | None = None,
             path: Path | None = None) -> Script:
        """Compile ``source`` and run its top level in a new environment.

        Raises :class:`ScriptLoadError` (message ``name:line: ...``) when it does
        not compile or its top level fails; nothing is left loaded then.
        """
        sid = len(self._by_sid) + 1
        while sid in self._by_sid:
            sid += 1
        try:
            env = self._make_globals(sid, entity if entity is not None else -1)
        except LuaError as exc:  # the memory cap is reached
            self.kernel.collect()
            raise ScriptLoadError(f"{name}: {exc or MEMORY_MESSAGE}") from None
        script = Script(sid, name, entity, path, env, source, base=self.kernel.names(env))
        self._by_sid[sid] = script
        error = self._run_chunk(script, source)
        if error is not None:
            self._drop(script)
            raise ScriptLoadError(error)
        script.loaded = self.kernel.functions(env)
        self.scripts.append(script)
        self._update_batch = None
        return script

    def load_file(self, path: Path, entity: int | None = None) -> Script:
        name = self.display_name(path)
        text = path.read_text(encoding="utf-8")
        script = self.load(name, text, entity, path)
        script.mtime = path.stat().st_mtime
        return script

    def display_name(self, path: Path) -> str:
        """``scripts/door.lua``: relative to the content folder where possible."""
        base = self.scripts_dir.parent if self.scripts_dir is not None else None
        if base is not None:
            try:
                return str(path.resolve().relative_to(base.resolve()))
            except ValueError:
                pass
        return path.name

    def _compile(self, script: Script, source: str) -> tuple[Any, str | None]:
        source = normalise_quotes(source, script.name)
        try:
            fn, err = self.kernel.compile(source, "@" + script.name, script.env)
        except LuaError as exc:  # out of memory while compiling
            return None, f"{script.name}: {exc}"
        return fn, err

    def _run_chunk(self, script: Script, source: str) -> str | None:
        fn, err = self._compile(script, source)
        if fn is None:
            return err
        self._loading = script
        try:
            err = self._safe(self._dispatch, fn)
        finally:
            self._loading = None
        if err is not None and self._fatal(err):
            self.kernel.collect()
        return err

    def reload(self, script: Script, source: str) -> bool:
        """Re-run changed source in the script's environment (its globals survive).

        A version that does not compile is refused and the old one keeps running.
        A stopped script restarts in a fresh environment. ``onReload`` is called
        when defined.
        """
        fresh = script.stopped
        if fresh:
            try:
                script.env = self._make_globals(script.sid, script.entity
                                                if script.entity is not None else -1)
                script.base = self.kernel.names(script.env)
            except LuaError as exc:
                self.kernel.collect()
                self.report(f"{script.name}: {exc or MEMORY_MESSAGE} (reload failed)")
                return False
        fn, err = self._compile(script, source)
        if fn is None:
            self.report(f"{err}\n(reload of {script.name} failed; the previous version keeps "
                        "running)" if not fresh else f"{err}\n(reload of {script.name} failed)")
            return False
        self._update_batch = None
        script.stopped = False
        script.failures.clear()
        script.disabled.clear()
        script.source = source
        self._drop_registrations(script)
        if script not in self.scripts:
            self.scripts.append(script)
        self._loading = script
        try:
            err = self._safe(self._dispatch, fn)
        finally:
            self._loading = None
        script.loaded = self.kernel.functions(script.env)
        if err is not None:
            self._failed(script, "<reload>", err)
            return False
        self.call(script, "onStart" if fresh else "onReload")
        return True

    # -- calling --------------------------------------------------------------
    def _safe(self, fn: Any, *args: Any) -> str | None:
        try:
            return fn(*args)
        except LuaError as exc:  # allocation failure outside the protected call
            self.kernel.collect()
            return str(exc) or MEMORY_MESSAGE

    def call(self, script: Script, callback: str, *args: Any) -> bool:
        """Call ``callback(*args)`` if the script defines it; False when it failed."""
        if script.stopped or callback in script.disabled:
            return True
        try:
            err = self._call(script.env, callback, *args)
        except LuaError as exc:
            err = str(exc) or MEMORY_MESSAGE
        if err is None:
            return True
        self._failed(script, callback, err)
        return False

    def call_function(self, script: Script, fn: Any, what: str, *args: Any) -> bool:
        """Call a Lua function a script registered (timer, event handler)."""
        if script.stopped or what in script.disabled:
            return True
        err = self._safe(self._dispatch, fn, *args)
        if err is None:
            return True
        self._failed(script, what, err)
        return False

    def update(self, dt: float) -> None:
        """``onUpdate(dt)`` on every script (one call into Lua for all), then due timers."""
        if self._update_batch is None:
            scripts = [s for s in self.scripts
                       if not s.stopped and "onUpdate" not in s.disabled]
            self._update_batch = (scripts, self.lua.table_from([s.env for s in scripts]))
        scripts, envs = self._update_batch
        start = 1
        while start <= len(scripts):
            try:
                result = self._call_batch(envs, "onUpdate", len(scripts), start, dt)
            except LuaError as exc:
                self.kernel.collect()
                self.report(f"onUpdate dispatch failed: {exc or MEMORY_MESSAGE}")
                break
            if result is None:
                break
            index, err = result
            self._failed(scripts[index - 1], "onUpdate", err)
            start = index + 1
        if self._collect_pending:  # a script was stopped: free what it held, now unreferenced
            del scripts, envs
            self._collect_pending = False
            self.kernel.collect()
        self.advance_timers(dt)

    def broadcast(self, callback: str, *args: Any) -> None:
        for script in self.scripts:
            self.call(script, callback, *args)

    def collide(self, script: Script, other: int, impulse: float) -> None:
        """``onCollision(other, impulse)`` on an object script."""
        if script.stopped or "onCollision" in script.disabled:
            return
        try:
            err = self._collide(script.env, other, impulse)
        except LuaError as exc:
            err = str(exc) or MEMORY_MESSAGE
        if err is not None:
            self._failed(script, "onCollision", err)

    def collide_many(self, scripts: list[Script], others: list[int],
                     impulses: list[float]) -> None:
        """``onCollision(others[i], impulses[i])`` on ``scripts[i]``, in one call into Lua."""
        while scripts:
            keep = [i for i, s in enumerate(scripts)
                    if not s.stopped and "onCollision" not in s.disabled]
            if len(keep) != len(scripts):
                scripts = [scripts[i] for i in keep]
                others = [others[i] for i in keep]
                impulses = [impulses[i] for i in keep]
                if not scripts:
                    return
            table = self.lua.table_from
            try:
                result = self._collide_batch(table([s.env for s in scripts]), table(others),
                                             table(impulses), len(scripts), 1)
            except LuaError as exc:
                self.kernel.collect()
                self.report(f"collision dispatch failed: {exc or MEMORY_MESSAGE}")
                return
            if result is None:
                return
            index, err = result
            self._failed(scripts[index - 1], "onCollision", err)
            scripts, others, impulses = scripts[index:], others[index:], impulses[index:]

    def call_objects(self, script: Script, callback: str, objects: tuple[int, ...],
                     *args: Any) -> None:
        """``callback(objects..., args...)`` with the entities as handles (-1: nil)."""
        if script.stopped or callback in script.disabled:
            return
        try:
            err = self._call_handles(script.env, callback, len(objects), *objects, *args)
        except LuaError as exc:
            err = str(exc) or MEMORY_MESSAGE
        if err is not None:
            self._failed(script, callback, err)

    def collide_scene(self, script: Script, a: int, b: int, impulse: float) -> None:
        """``onCollision(a, b, impulse)`` on a scene script."""
        if script.stopped or "onCollision" in script.disabled:
            return
        try:
            err = self._collide_scene(script.env, a, b, impulse)
        except LuaError as exc:
            err = str(exc) or MEMORY_MESSAGE
        if err is not None:
            self._failed(script, "onCollision", err)

    # -- failures -------------------------------------------------------------
    @staticmethod
    def _fatal(err: str) -> bool:
        return BUDGET_MESSAGE in err or err.startswith(MEMORY_MESSAGE) or \
            err.endswith(MEMORY_MESSAGE)

    def _failed(self, script: Script, callback: str, err: str) -> None:
        if self._fatal(err):
            first = err.splitlines()[0] if err else MEMORY_MESSAGE
            if first == MEMORY_MESSAGE:
                first = f"{script.name}: {first} (the scripts' memory cap of " \
                        f"{self.limits.memory // (1024 * 1024)} MiB was reached)"
            self.stop(script, f"{first} in {callback}")
            return
        count = script.failures.get(callback, 0) + 1
        script.failures[callback] = count
        if count < self.limits.max_failures:
            self.report(err)
        else:
            script.disabled.add(callback)
            self._update_batch = None
            self.report(f"{err}\n{script.name}: {callback} disabled after {count} errors")

    def stop(self, script: Script, reason: str) -> None:
        """Stop a script for good (until it is reloaded); one message."""
        if script.stopped:
            return
        script.stopped = True
        self._update_batch = None
        self.report(f"{reason}; script {script.name} stopped (the engine and other scripts "
                    "continue)")
        self._drop_registrations(script)
        script.env = self.lua.table()  # release what the script held (a memory hoard)
        script.loaded = None
        self._collect_pending = True
        self.kernel.collect()

    def report(self, message: str) -> None:
        self.messages.append(message)
        log.error("%s", message)

    def unload(self, script: Script) -> None:
        """Remove a script (its entity was deleted)."""
        self._drop(script)
        if script in self.scripts:
            self.scripts.remove(script)
        self._update_batch = None

    def _drop(self, script: Script) -> None:
        self._drop_registrations(script)
        self._by_sid.pop(script.sid, None)

    def _drop_registrations(self, script: Script) -> None:
        self._timers = [t for t in self._timers if t.script is not script]
        for name, handlers in self._handlers.items():
            self._handlers[name] = [h for h in handlers if h.script is not script]

    # -- timers and custom events -----------------------------------------------
    def advance_timers(self, dt: float) -> None:
        self.time += dt
        now = self.time
        if not self._timers:
            return
        due = [t for t in self._timers if t.due <= now + 1e-12]
        for timer in sorted(due, key=lambda t: (t.due, t.tid)):
            if timer not in self._timers:  # cancelled by an earlier timer
                continue
            if timer.period > 0:
                timer.due += timer.period * max(1, math.floor((now - timer.due) / timer.period)
                                                + 1)
            else:
                self._timers.remove(timer)
            self.call_function(timer.script, timer.fn, "timer")

    def deliver(self, name: str, data: Any) -> None:
        """Call every ``on(name, fn)`` handler with ``data``."""
        handlers = tuple(self._handlers.get(name, ()))
        if not handlers:
            return
        try:
            value = self.to_lua(data)
        except TypeError as exc:
            self.report(f"event {name!r}: {exc}; not delivered to scripts")
            return
        for h in handlers:
            self.call_function(h.script, h.fn, f"on({name!r})", value, name)

    # -- saved states (see services.scripting.persist) -----------------------------
    def capture(self, script: Script, object_name: Callable[[int], str | None]
                ) -> tuple[SavedScript | None, list[str]]:
        """The script's state for a saved run, and what of it could not be saved (each a
        message naming the script); None when nothing could be taken."""
        timers = sorted((t for t in self._timers if t.script is script),
                        key=lambda t: (t.due, t.tid))
        handlers = [(event, h) for event, hs in self._handlers.items() for h in hs
                    if h.script is script and not h.at_load]
        fns = self.lua.table_from([t.fn for t in timers] + [h.fn for _, h in handlers])
        out = self.lua.table()
        err = self._safe(self._dispatch, self.kernel.capture, script.env, script.base,
                         script.loaded, "@" + script.name, fns, out)
        if err is not None:
            return None, [f"{script.name}: its state cannot be saved: {err}; "
                          "it starts afresh when the saved state runs"]
        told = [f"{script.name}: {what}; not saved" for what in out.skipped.values()]
        names = list(out.fn_names.values())
        lines = list(out.fn_lines.values())
        saved_timers: list[ScriptTimer] = []
        for timer, name, line in zip(timers, names, lines, strict=False):
            if name:
                saved_timers.append(ScriptTimer(name, timer.due, timer.period))
            else:
                kind = "every" if timer.period > 0 else "after"
                told.append(f"{script.name}:{line}: a pending {kind}() timer (due at "
                            f"t = {timer.due:.6g} s) calls a function with no name, so it "
                            "is not saved; give the function a name (local function tick() "
                            f"... end, then {kind}(sec, tick)) and it is")
        saved_handlers: list[ScriptHandler] = []
        for (event, _), name, line in zip(handlers, names[len(timers):],
                                          lines[len(timers):], strict=False):
            if name:
                saved_handlers.append(ScriptHandler(event, name))
            else:
                told.append(f"{script.name}:{line}: the on({event!r}) handler calls a function "
                            "with no name, so it is not saved; name the function (or register "
                            "it at the file's top level, which runs again) and it is")
        try:
            saved = SavedScript(lua_literal(to_python(out.globals), object_name),
                                lua_literal(to_python(out.locals), object_name),
                                tuple(saved_timers), tuple(saved_handlers))
        except (TypeError, ValueError) as exc:
            return None, [f"{script.name}: its state cannot be saved: {exc}; "
                          "it starts afresh when the saved state runs"]
        return saved, told

    def resume(self, script: Script, saved: SavedScript, find: Callable[[str], int]) -> bool:
        """Put a freshly loaded script back where a saved run left it: its variables, then
        its timers (replacing those its file's top level started) and handlers. False,
        with a message, when the saved values do not read back (the script then starts)."""
        where = f"{script.name} (saved state)"
        values = []
        for text in (saved.globals, saved.locals):
            fn, err = self.kernel.compile("local out = ...; out.value = " + text, "=" + where,
                                          self.lua.table_from({"object": self._object(find)}))
            out = self.lua.table()
            if fn is not None:
                err = self._safe(self._dispatch, fn, out)
            if err is not None or lua54.lua_type(out.value) != "table":
                self.report(f"{where}: its variables do not read back as a Lua table "
                            f"({err or 'not a table'}); the script starts afresh")
                return False
            values.append(out.value)
        err = self._safe(self._dispatch, self.kernel.restore, script.env, script.base,
                         "@" + script.name, *values)
        if err is not None:
            self.report(f"{where}: {err}; the script starts afresh")
            return False
        self._timers = [t for t in self._timers if t.script is not script]
        source = "@" + script.name
        for timer in saved.timers:
            fn = self.kernel.named(script.env, script.base, source, timer.function)
            if fn is None:
                self.report(f"{where}: a saved timer calls {timer.function!r}, which the file "
                            "no longer defines; the timer is dropped")
                continue
            self._timers.append(_Timer(script, timer.due, timer.period, fn, self._next_tid))
            self._next_tid += 1
        for handler in saved.handlers:
            fn = self.kernel.named(script.env, script.base, source, handler.function)
            if fn is None:
                self.report(f"{where}: a saved on({handler.event!r}) handler calls "
                            f"{handler.function!r}, which the file no longer defines; dropped")
                continue
            self._handlers.setdefault(handler.event, []).append(_Handler(script, fn, False))
        return True

    def to_lua(self, value: Any) -> Any:
        """Plain Python data (numbers, strings, lists, dicts, arrays) as Lua values."""
        if isinstance(value, dict):
            return self.lua.table_from({k: self.to_lua(v) for k, v in value.items()})
        if hasattr(value, "tolist"):  # numpy arrays and scalars
            value = value.tolist()
        if isinstance(value, list | tuple):
            return self.lua.table_from([self.to_lua(v) for v in value])
        if value is None or isinstance(value, bool | int | float | str):
            return value
        raise TypeError(f"cannot pass a {type(value).__name__} to Lua (plain data only)")

    def _script(self, sid: int) -> Script:
        return self._by_sid[sid]

    def _lua_log(self, sid: int, level: str, text: str) -> None:
        script = self._by_sid.get(sid)
        name = script.name if script is not None else "module"
        getattr(log, level if level in ("info", "warning") else "info")("%s: %s", name, text)
        self.messages.append(f"{name}: {text}")

    def _lua_timer(self, sid: int, delay: float, fn: Any, period: float) -> int:
        tid = self._next_tid
        self._next_tid += 1
        self._timers.append(_Timer(self._script(sid), self.time + max(0.0, delay), period, fn,
                                   tid))
        return tid

    def _lua_cancel(self, sid: int, tid: Any) -> None:
        self._timers = [t for t in self._timers if not (t.tid == tid and t.script.sid == sid)]

    def _lua_on(self, sid: int, name: str, fn: Any) -> None:
        script = self._script(sid)
        self._handlers.setdefault(name, []).append(_Handler(script, fn,
                                                            self._loading is script))

    def _lua_emit(self, sid: int, name: str, data: Any) -> None:
        value = to_python(data)
        if self.emit_hook is not None:
            self.emit_hook(name, value)
        else:
            self.deliver(name, value)

    def _read_module(self, name: Any) -> tuple[str, str]:
        path = resolve_module(self.scripts_dir, name)
        chunk = self.display_name(path)
        return "@" + chunk, normalise_quotes(path.read_text(encoding="utf-8"), chunk)

    def memory_kib(self) -> float:
        return float(self.kernel.memory())


def to_python(value: Any, depth: int = 0) -> Any:
    """A Lua value as plain Python data (tables become lists or dicts), bounded in size."""
    lua_type = load_lua().lua_type
    if lua_type(value) == "table":
        if depth > 16:
            raise ValueError("event data nested too deeply (more than 16 levels)")
        items = list(value.items())
        if len(items) > 100_000:
            raise ValueError("event data too large (more than 100000 entries)")
        keys = [k for k, _ in items]
        if keys == list(range(1, len(keys) + 1)):
            return [to_python(v, depth + 1) for _, v in items]
        return {k: to_python(v, depth + 1) for k, v in items}
    if lua_type(value) is not None:  # functions, coroutines: not data
        raise TypeError(f"cannot send a Lua {lua_type(value)} as event data")
    return value
