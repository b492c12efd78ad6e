"""A screen of a projection wall or CAVE, in world coordinates."""

from __future__ import annotations

from dataclasses import dataclass

Vec3 = tuple[float, ...]  # three numbers


@dataclass(slots=True)
class Display:
    """A flat screen given by three corners (m, world frame), drawn off-axis from the
    viewer's eye: the position of ``head`` (an entity a head tracker moves), else of this
    node's tracker ``tracker``, else ``eye``."""

    lower_left: Vec3 = (-1.0, 0.0, 0.0)
    lower_right: Vec3 = (1.0, 0.0, 0.0)
    upper_left: Vec3 = (-1.0, 0.0, 1.5)
    head: int | None = None
    tracker: str | None = None
    eye: Vec3 = (0.0, -2.0, 0.75)
    near: float = 0.05
    far: float = 500.0
