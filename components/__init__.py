"""Components: plain data attached to entities. No behaviour, no heavy imports.

Units and axes everywhere: metres, kilograms, seconds; angles in degrees where an
author writes them (the scene format), radians inside the engine; Z is up.
Orientations are unit quaternions ``(w, x, y, z)``.

A :class:`Transform` added to a world is *adopted*: its ``position`` and
``orientation`` arrays become views into the world's pose table, so systems can
update every pose with one numpy assignment (see ``engine.world.PoseTable``).
"""

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
    """Where an entity is: position (m) and orientation quaternion (w, x, y, z)."""

    position: np.ndarray = field(default_factory=_vec3)
    orientation: np.ndarray = field(default_factory=_quat)
    linear_velocity: np.ndarray = field(default_factory=_vec3)
    angular_velocity: np.ndarray = field(default_factory=_vec3)

    def __post_init__(self) -> None:
        self.position = _vec3(self.position)
        self.orientation = _quat(self.orientation)
        self.linear_velocity = _vec3(self.linear_velocity)
        self.angular_velocity = _vec3(self.angular_velocity)


@dataclass(slots=True)
class Name:
    """The author's ID for an entity (``ID "a sphere object"`` in a scene file)."""

    id: str


@dataclass(slots=True)
class Shape:
    """One collision or visual primitive, in the body's frame.

    ``kind`` is sphere, box, capsule, cylinder, plane, mesh or hull.
    ``size`` is the full extents for a box, ``(radius,)`` for a sphere,
    ``(radius, length)`` for a capsule or cylinder (along local Z), and the
    plane's normal and offset ``(nx, ny, nz, d)`` for a plane.
    """

    kind: str = "sphere"
    size: tuple[float, ...] = (0.5,)
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    vertices: np.ndarray | None = None
    faces: np.ndarray | None = None


@dataclass(slots=True)
class MaterialProps:
    """Surface response of a body: Coulomb friction, restitution, softness."""

    name: str = "default"
    friction: float = 0.5
    bounce: float = 0.0
    bounce_velocity: float = 0.1
    softness: float = 0.0
    density: float = 1000.0
    contact_sound: str | None = None


@dataclass(slots=True)
class Physical:
    """The body an entity has in the dynamics backend.

    ``kind`` is dynamic, static or kinematic. ``mass`` wins over the material
    density when both are given. ``category``/``mask`` filter collisions as bit
    sets: two bodies collide when each one's category meets the other's mask.
    """

    kind: str = "dynamic"
    mass: float | None = 1.0
    shapes: list[Shape] = field(default_factory=lambda: [Shape()])
    material: MaterialProps = field(default_factory=MaterialProps)
    linear_damping: float = 0.0
    angular_damping: float = 0.0
    can_sleep: bool = True
    category: int = 1
    mask: int = 0xFFFFFFFF
    gravity: bool = True


@dataclass(slots=True)
class Joint:
    """A constraint between two bodies (``body_b`` None means the static world).

    kind: hinge, motorized_hinge, ball, slider, universal, hinge2, fixed,
    angular_motor, linear_motor, six_dof. ``anchor``/``axis`` are in world
    coordinates at creation. Limits are in radians (angular) or metres (slider).
    A motor drives ``motor_velocity`` (rad/s or m/s) with at most
    ``motor_max_force`` (N·m or N). For six_dof, ``body_b`` is the tracked target
    (or None: the target is set with ``set_joint_target``) and ``motor_max_force``
    caps both force and torque until ``set_drive_limits`` changes them.

    ``reference`` is the pose (x, y, z, qw, qx, qy, qz) of ``body_a`` and of
    ``body_b`` (None for the world) when the joint was first made, with ``anchor``
    and ``axis`` as they were then; a backend makes the joint as if the bodies
    were there, which re-creates a saved joint exactly. None: where they are now.
    """

    kind: str = "hinge"
    body_a: int = -1
    body_b: int | None = None
    anchor: tuple[float, float, float] = (0.0, 0.0, 0.0)
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    axis2: tuple[float, float, float] = (0.0, 1.0, 0.0)
    low: float | None = None
    high: float | None = None
    motor_velocity: float = 0.0
    motor_max_force: float = 0.0
    id: str = ""
    broken: bool = False
    reference: tuple[tuple[float, ...], tuple[float, ...] | None] | None = None


@dataclass(slots=True)
class Visual:
    """What an entity looks like: a primitive or a model file, and how to shade it."""

    shapes: list[Shape] = field(default_factory=list)
    model: str | None = None
    scale: tuple[float, float, float] = (1.0, 1.0, 1.0)
    color: tuple[float, float, float, float] = (0.8, 0.8, 0.8, 1.0)
    texture: str | None = None
    shader_state: str | None = None
    shadower: bool = True
    shadowed: bool = True
    visible: bool = True


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


@dataclass(slots=True)
class Hand:
    """A physically simulated virtual hand driven toward a tracked target pose."""

    tracker: str = ""
    target_position: tuple[float, float, float] = (0.0, 0.0, 0.0)
    target_orientation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
    max_force: float = 200.0
    max_torque: float = 20.0
    deviation_distance: float = 0.3
    grasping: bool = False
    touching: tuple[int, ...] = ()
    held: tuple[int, ...] = ()


@dataclass(slots=True)
class Script:
    """A Lua script attached to an entity (or to the scene when on the scene entity)."""

    file: str = ""
    source: str | None = None
    enabled: bool = True


@dataclass(slots=True)
class Camera:
    """A viewpoint. ``follow`` names an entity to follow at ``offset``."""

    fov: float = 60.0
    near: float = 0.05
    far: float = 500.0
    active: bool = True
    follow: int | None = None
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    look_at: tuple[float, float, float] | None = None
    eye_separation: float = 0.0


@dataclass(slots=True)
class Light:
    """A light source: directional, point or spot."""

    kind: str = "directional"
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    direction: tuple[float, float, float] = (0.3, 0.5, -1.0)
    cutoff: float = 30.0
    shadows: bool = True


@dataclass(slots=True)
class Controller:
    """A continuous binding from an input to an actuator, with gain and limits.

    ``input`` names a key pair ``"key:Up/Down"``, an axis ``"axis:0"``, a tracked
    device ``"tracker:hand_r"`` or a wheel counter ``"wheel:left"``; ``target``
    names the actuator: ``"motor:<joint id>"``, ``"force:<object id>"`` or
    ``"kinematic:<object id>"``.
    """

    input: str = ""
    target: str = ""
    gain: float = 1.0
    low: float = float("-inf")
    high: float = float("inf")
    value: float = 0.0


__all__ = [
    "Camera",
    "Controller",
    "Hand",
    "Joint",
    "Light",
    "MaterialProps",
    "Name",
    "Physical",
    "Script",
    "Shape",
    "Sound",
    "Transform",
    "Visual",
]
