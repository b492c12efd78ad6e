"""A Lua script an entity (or the scene) runs."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Script:
    """A Lua script attached to an entity (or to the scene when on the scene entity)."""

    file: str = ""
    source: str | None = None
    enabled: bool = True
