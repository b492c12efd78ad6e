"""Lua scripting: a sandboxed Lua 5.4 runtime (lupa), its kernel and the scripting API.

See :mod:`services.scripting.api` for what scripts can call and
:mod:`services.scripting.sandbox` for what they cannot.

Its names load on first use (:mod:`engine.lazy`): the scripting plugin of a scene
without scripts loads neither the runtime nor the API.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from engine.lazy import lazy_exports

if TYPE_CHECKING:
    from services.scripting.api import ScriptAPI, ScriptAPIError
    from services.scripting.runtime import Script, ScriptLimits, ScriptLoadError, ScriptRuntime

__all__ = [
    "Script",
    "ScriptAPI",
    "ScriptAPIError",
    "ScriptLimits",
    "ScriptLoadError",
    "ScriptRuntime",
]

__getattr__, __dir__ = lazy_exports(__name__, {
    "services.scripting.api": ("ScriptAPI", "ScriptAPIError"),
    "services.scripting.runtime": ("Script", "ScriptLimits", "ScriptLoadError",
                                   "ScriptRuntime")})
