"""What an entity looks like."""

from __future__ import annotations

from dataclasses import dataclass, field

from components.shape import Shape


@dataclass(slots=True)
class Visual:
    """A primitive or a model file, and how to shade it. ``overlay`` draws it after
    everything else, blended by its colour's alpha and never hidden behind other objects
    (a virtual hand pushed into a table shows through it)."""

    shapes: list[Shape] = field(default_factory=list)
    model: str | None = None
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    color: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)
    texture: str | None = None
    shader_state: str | None = None
    shadower: bool = True
    shadowed: bool = True
    visible: bool = True
    overlay: bool = False
