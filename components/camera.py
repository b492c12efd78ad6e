"""Viewpoints."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(slots=True)
class Camera:
    """A viewpoint looking along its local +Y. ``follow`` names an entity to follow at
    ``offset``."""

    fov: float = 60.0
    near: float = 0.05
    far: float = 500.0
    active: bool = True
    follow: int | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    look_at: tuple[float, float, float] | None = None
    eye_separation: float = 0.0
