"""Light sources."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Light:
    """A light source: directional, point or spot."""

    kind: str = "directional"
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    direction: tuple[float, float, float] = (0.3, 0.5, -1.0)
    cutoff: float = 30.0
    shadows: bool = True
