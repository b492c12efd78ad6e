"""A virtual hand: what drives it, and where it stands (paper section 5)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class HandMode(StrEnum):
    """What a hand is doing (paper figure 5): touching nothing, touching something it
    could grasp (drawn open), or holding what it touched."""

    NEUTRAL = "neutral"
    CONTACT = "contact"
    GRASP = "grasp"


@dataclass(slots=True)
class Hand:
    """A physically simulated hand: its own body (the entity's Physical) is driven toward
    the pose of input tracker ``tracker`` with force and torque bounded (N, N·m), its
    pose error closing with ``time_constant`` (s; 0: max(2 Δt, 0.03 s)) and the
    correction capped at ``max_speed`` (m/s) and ``max_spin`` (rad/s). While button
    ``button`` of device ``glove`` is down, what it touches is held. Farther than
    ``deviation_distance`` (m) from the tracker it passes through things (section 5.4).
    ``frame`` is the entity the tracker is calibrated relative to (a wheelchair), or None
    for the world; ``holding`` the scene IDs held when a saved state was written. The
    ``*_model`` files are drawn in each mode (None: the object's own look, tinted).
    ``fingers``: the palm and each finger's phalanges are bodies driven toward the 26
    tracked joints of input hand ``tracker`` (palm only, the paper's hand, when False)."""

    tracker: str = ""
    glove: str = ""
    button: str = "pinch"
    max_force: float = 300.0
    max_torque: float = 30.0
    time_constant: float = 0.0
    max_speed: float = 10.0
    max_spin: float = 20.0
    deviation_distance: float = 0.3
    break_force: float | None = None
    marker: bool = True
    neutral_model: str | None = None
    contact_model: str | None = None
    grasp_model: str | None = None
    frame: int | None = None
    holding: tuple[str, ...] = ()
    fingers: bool = False


@dataclass(slots=True)
class HandState:
    """A hand's standing, kept by the hands system: its mode, whether its tracker is seen,
    whether it collides, how far it is from the tracker (m), what it touches and holds
    (entities), and the force its contacts pushed with last frame (N). A fingered hand
    also says which fingers grip what it holds (``grip``, thumb first, "palm" included)
    and how far each finger's tip is from its tracked tip (``finger_deviation``, m,
    thumb to little): a blocked finger is drawn as a ghost where it is tracked."""

    mode: str = HandMode.NEUTRAL
    tracked: bool = False
    colliding: bool = True
    deviation: float = 0.0
    touching: tuple[int, ...] = ()
    held: tuple[int, ...] = ()
    contact_force: float = 0.0
    grip: tuple[str, ...] = ()
    finger_deviation: tuple[float, ...] = ()


@dataclass(slots=True)
class Graspable:
    """Whether hands may hold this object (dynamic bodies may, unless this says no)."""

    enabled: bool = True
