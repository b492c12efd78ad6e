"""A skinned, animated figure: what it is made of, what it plays and how it moves.

The entity also has a ``Transform`` (where its root stands: its feet, facing +Y) and a
``Visual`` naming the same model file (colour, shader state, shadows). The avatars plugin
animates it; the renderer skins it. What a saved state holds of it is in
:mod:`components.avatar_saved`, loaded with a saved state.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from components.avatar_saved import SavedAvatar


@dataclass(slots=True)
class ClipSpec:
    """How one clip plays unless a call says otherwise. ``ground_speed`` (m/s at speed 1)
    overrides the speed measured from the clip's root motion (None: measured)."""

    name: str
    speed: float = 1.0
    loop: bool = True
    ground_speed: float | None = None


@dataclass(slots=True)
class Hold:
    """An object carried by a bone: ``target`` is its scene ID (or entity id), placed at
    ``offset`` (m) and ``rotation`` (quaternion) in the bone's frame."""

    bone: str
    target: str | int
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)


@dataclass(slots=True)
class Avatar:
    """A glTF model with a skin, animated by the avatars plugin.

    ``clip`` (or ``blend``, clip -> weight) plays first, at ``speed`` and ``loop`` (None:
    as its ``clips`` entry says), then ``queue`` one after another; ``fade`` is the default
    crossfade in seconds. ``path`` is a list of world points walked
    in turn (``path_loop``: back to the first), turning at ``turn_rate`` (rad/s) and moving
    at the clips' ground speed. With ``ground_follow`` the root is kept on the ground below
    it (rays cast down from ``step_height`` above it; steps are smoothed over
    ``smoothing`` seconds); ``foot_ik`` lists (hip, knee, ankle) bone names whose feet meet
    the ground. ``capsule`` (radius, length; m) gives the figure a kinematic body.
    ``saved`` (a loaded saved state) replaces the start with where a saved run stood.
    """

    model: str
    scale: float = 1.0
    clip: str | None = None
    loop: bool | None = None
    speed: float | None = None
    blend: dict[str, float] = field(default_factory=dict)
    queue: list[str] = field(default_factory=list)
    fade: float = 0.2
    clips: list[ClipSpec] = field(default_factory=list)
    ground_follow: bool = False
    step_height: float = 0.5
    smoothing: float = 0.1
    foot_ik: list[tuple[str, str, str]] = field(default_factory=list)
    path: list[tuple[float, float, float]] = field(default_factory=list)
    path_loop: bool = True
    turn_rate: float = 3.14159
    capsule: tuple[float, float] | None = None
    holds: list[Hold] = field(default_factory=list)
    #: The state to resume from (a loaded saved state); None starts as above.
    saved: SavedAvatar | None = None
