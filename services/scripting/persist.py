"""A script's state in a saved run, written as Lua table constructors.

``--save-state`` keeps what a script holds so that running the saved file continues it
rather than starting it again: the data in its globals and in the file's local
variables its functions use (numbers, strings, booleans, tables of them, objects by
their scene ID), its pending ``after``/``every`` timers and the ``on`` handlers it
registered while running, named by the function they call. Functions themselves are
code: the file makes them again when it runs, so a timer or handler calling a function
with no name (``after(1, function() ... end)``) cannot be saved, and saying so is the
writer's job (:func:`services.scripting.runtime.ScriptRuntime.capture`).

The text is Lua (``{count = 3, target = object('crate1'), ratio = 0.1}``), exact for
every number (floats are written so they read back to the same bits), and is read back
by Lua in an empty environment that knows only ``object(id)``.

>>> lua_literal({"count": 3, "ratio": 0.1, "tags": ["a", "b'"], "big": float("inf")})
"{big = 1/0, count = 3, ratio = 0.1, tags = {'a', 'b\\\\039'}}"
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from typing import Any

#: The marker the kernel gives handles in captured data (see ``K.OBJECT``).
OBJECT_KEY = "\0object"
_NAME = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_LUA_KEYWORDS = frozenset((
    "and", "break", "do", "else", "elseif", "end", "false", "for", "function", "goto", "if",
    "in", "local", "nil", "not", "or", "repeat", "return", "then", "true", "until", "while"))
_PLAIN = frozenset(range(0x20, 0x7F)) - {ord("'"), ord("\\")}


def quote(text: str | bytes) -> str:
    """A Lua string literal in single quotes, every byte outside printable ASCII escaped
    (so the literal survives any file encoding)."""
    raw = text.encode("utf-8", "surrogateescape") if isinstance(text, str) else text
    return "'" + "".join(chr(b) if b in _PLAIN else f"\\{b:03d}" for b in raw) + "'"


def _number(x: int | float) -> str:
    if isinstance(x, int):
        return str(x)
    if math.isnan(x):
        return "0/0"
    if math.isinf(x):
        return "1/0" if x > 0 else "-1/0"
    return repr(x)  # the shortest text that reads back as the same double


def lua_literal(value: Any, object_name: Callable[[int], str | None] = lambda e: None) -> str:
    """``value`` (plain data from Lua, see :func:`~services.scripting.runtime.to_python`) as
    a Lua constructor; handles as ``object('ID')`` (``nil`` for an object that has none)."""
    if value is None:
        return "nil"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | float):
        return _number(value)
    if isinstance(value, str | bytes):
        return quote(value)
    if isinstance(value, list):
        return "{" + ", ".join(lua_literal(v, object_name) for v in value) + "}"
    if isinstance(value, dict):
        if OBJECT_KEY in value:
            name = object_name(int(value[OBJECT_KEY]))
            return "nil" if name is None else f"object({quote(name)})"
        items = []
        for key in sorted(value, key=lambda k: (not isinstance(k, str), str(k))):
            text = lua_literal(value[key], object_name)
            if isinstance(key, str) and _NAME.match(key) and key not in _LUA_KEYWORDS:
                items.append(f"{key} = {text}")
            else:
                items.append(f"[{lua_literal(key)}] = {text}")
        return "{" + ", ".join(items) + "}"
    raise TypeError(f"not data: {type(value).__name__}")
