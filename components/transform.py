"""Where an entity is: its pose and velocity."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np


def _vec3(value: Any = (0.0, 0.0, 0.0)) -> np.ndarray:
    a = np.array(value, dtype=np.float64)
    return a if a.shape == (3,) else a.reshape(3)


def _quat(value: Any = (1.0, 0.0, 0.0, 0.0)) -> np.ndarray:
    a = np.array(value, dtype=np.float64)
    return a if a.shape == (4,) else a.reshape(4)


@dataclass(slots=True, eq=False)
class Transform:
    """Position (m), orientation quaternion (w, x, y, z) and velocities (m/s, rad/s).

    Added to a world, its arrays become views into the world's pose table. On a
    dynamic body physics owns them: a write is turned into a teleport (see
    ``engine.physics.set_pose``), never silently overwritten.
    """

    position: np.ndarray = field(default_factory=_vec3)
    orientation: np.ndarray = field(default_factory=_quat)
    linear_velocity: np.ndarray = field(default_factory=_vec3)
    angular_velocity: np.ndarray = field(default_factory=_vec3)

    def __post_init__(self) -> None:
        self.position = _vec3(self.position)
        self.orientation = _quat(self.orientation)
        self.linear_velocity = _vec3(self.linear_velocity)
        self.angular_velocity = _vec3(self.angular_velocity)
