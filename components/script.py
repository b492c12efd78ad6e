"""A Lua script an entity (or the scene) runs, and the state a saved run left it in."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from components.blocks import BuildContext, Key, KeyDeclaration, declare_key


@dataclass(frozen=True, slots=True)
class ScriptTimer:
    """A pending ``after``/``every`` timer of a saved script: the name of its function,
    the simulated time it fires at (s) and its period (s; 0 fires once)."""

    function: str
    due: float
    period: float = 0.0


@dataclass(frozen=True, slots=True)
class ScriptHandler:
    """An ``on(event, fn)`` handler a saved script registered while running."""

    event: str
    function: str


@dataclass(frozen=True, slots=True)
class SavedScript:
    """Where a script stood when a state was saved: its globals and the file's local
    variables (Lua table constructors, data only), its pending timers and the handlers
    it registered while running. A script given one resumes instead of starting."""

    globals: str = "{}"
    locals: str = "{}"
    timers: tuple[ScriptTimer, ...] = ()
    handlers: tuple[ScriptHandler, ...] = ()


@dataclass(slots=True)
class Script:
    """A Lua script attached to an entity (or to the scene when on the scene entity)."""

    file: str = ""
    source: str | None = None
    enabled: bool = True
    #: The state to resume from (a loaded saved state); None starts the script afresh.
    saved: SavedScript | None = None


def build_script(file: str | None, ctx: BuildContext) -> list[Any]:
    """An object's (or the scene's) ``Script``: the script it runs, resuming where a saved
    state left it."""
    return [] if file is None else [Script(file=file, saved=ctx.saved_script(ctx.owner))]


OBJECT_SCRIPT_KEY = declare_key(KeyDeclaration(
    Key("Script", "asset", None, "Lua script attached to this object",
        example='"scripts/ball.lua"'), build_script))
SCENE_SCRIPT_KEY = declare_key(KeyDeclaration(
    Key("Script", "asset", None, "a Lua script run for the whole scene", repeat=True,
        example='"scripts/scene.lua"'), build_script, inside=("Scene",)))

