"""A sound an entity makes."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Sound:
    """A sound source attached to the entity it sits on."""

    file: str = ""
    loop: bool = False
    gain: float = 1.0
    pitch: float = 1.0
    ref_distance: float = 1.0
    rolloff: float = 1.0
    max_distance: float = 1000.0
    auto_play: bool = False
    priority: int = 0
    id: str = ""
