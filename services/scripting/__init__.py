"""Lua scripting: a sandboxed Lua 5.4 runtime (lupa), its kernel and the scripting API.

See :mod:`services.scripting.api` for what scripts can call and
:mod:`services.scripting.sandbox` for what they cannot.
"""

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
