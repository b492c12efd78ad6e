"""The author's name for an entity."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Name:
    """The author's ID for an entity (``ID "a sphere object"`` in a scene file)."""

    id: str
