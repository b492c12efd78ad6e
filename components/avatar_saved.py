"""What a saved state holds of an avatar (:class:`SavedAvatar`: its clips, queue, path,
ground following, held objects and driven bones), apart from the component, so reading
or running a scene that resumes no avatar does not make these records' classes.
"""

from __future__ import annotations

from dataclasses import dataclass

from components.avatar import Hold

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
