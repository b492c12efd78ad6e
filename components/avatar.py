"""A skinned, animated figure: what it is made of, what it plays and how it moves.

The entity also has a ``Transform`` (where its root stands: its feet, facing +Y) and a
``Visual`` naming the same model file (colour, shader state, shadows). The avatars plugin
animates it; the renderer skins it.
"""

from __future__ import annotations

from dataclasses import dataclass, field


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


Point = tuple[float, float, float]
Quaternion = tuple[float, float, float, float]


@dataclass(frozen=True, slots=True)
class SavedLayer:
    """One clip of a saved group: its playback rate, its weight now and the fade it is in
    (from ``fade_from`` to ``fade_to`` over ``fade_length`` s, ``fade_time`` s gone)."""

    clip: str
    speed: float = 1.0
    weight: float = 1.0
    fade_from: float = 1.0
    fade_to: float = 1.0
    fade_time: float = 0.0
    fade_length: float = 0.0


@dataclass(frozen=True, slots=True)
class SavedGroup:
    """Clips started together (one play, queue or blend), sharing one ``phase`` (0..1
    through them). ``ended``: it reached its end and said so (``onAnimationEnd``);
    ``current``: what the avatar plays now (the other groups are fading out)."""

    layers: tuple[SavedLayer, ...]
    phase: float = 0.0
    loop: bool = True
    ended: bool = False
    current: bool = False


@dataclass(frozen=True, slots=True)
class SavedRequest:
    """A queued start: clips and weights, fade (s), speed and looping (None: the clip's)."""

    weights: tuple[tuple[str, float], ...]
    fade: float = 0.0
    speed: float | None = None
    loop: bool | None = None


@dataclass(frozen=True, slots=True)
class SavedHold:
    """A held object of a saved state; ``last``: where it was put last frame (a dynamic one
    moves on at the hand's velocity)."""

    hold: Hold
    last: Point | None = None


@dataclass(frozen=True, slots=True)
class SavedDrive:
    """A bone held at a world pose (a tracked hand) when the state was saved."""

    bone: str
    position: Point
    orientation: Quaternion


@dataclass(frozen=True, slots=True)
class SavedAvatar:
    """Where an avatar stood when a state was saved, besides its root pose: its clips
    (``groups``, oldest first) and ``queue``, the path it walks and the point it walks to
    (``waypoint``), ground following (the ground height under its root last frame,
    where that was, the step height still to be smoothed away), what it holds and which
    bones are driven, and its capsule's pose. An avatar given one resumes from it instead
    of starting its ``clip``, ``path`` and ``holds``."""

    groups: tuple[SavedGroup, ...] = ()
    queue: tuple[SavedRequest, ...] = ()
    path: tuple[Point, ...] = ()
    path_loop: bool = True
    waypoint: int = 0
    ground: float | None = None
    ground_at: tuple[float, float] | None = None
    step_offset: float = 0.0
    holds: tuple[SavedHold, ...] = ()
    drives: tuple[SavedDrive, ...] = ()
    capsule: tuple[Point, Quaternion] | None = None


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
