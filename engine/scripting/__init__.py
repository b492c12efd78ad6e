"""Lua scripting: a sandboxed Lua 5.4 runtime (lupa), its kernel and the scripting API.

See :mod:`engine.scripting.api` for what scripts can call and
:mod:`engine.scripting.sandbox` for what they cannot.
"""

from engine.scripting.api import ScriptAPI, ScriptAPIError
from engine.scripting.runtime import Script, ScriptLimits, ScriptLoadError, ScriptRuntime

__all__ = [
    "Script",
    "ScriptAPI",
    "ScriptAPIError",
    "ScriptLimits",
    "ScriptLoadError",
    "ScriptRuntime",
]
