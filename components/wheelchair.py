"""A wheelchair driven by counters on a real chair's wheels (paper sections 5.5 and 6)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum


class NavigationMode(StrEnum):
    """How the real wheels move the simulated ones.

    ``velocity`` (the paper's): each simulated wheel turns at the real one's measured
    speed, held by a strong motor, so the chair moves only when the real wheels do and
    never rolls down a slope by itself. ``feedback`` (the paper's future work): the
    wheels are free; a change of the real wheel's speed is a push, a torque on the
    simulated wheel (the rim's inertia times its angular acceleration), and gravity and
    collisions act on the chair; the simulated wheel's speed and the push go out for a
    motorized rig."""

    VELOCITY = "velocity"
    FEEDBACK = "feedback"


@dataclass(slots=True)
class Wheelchair:
    """The chassis of a wheelchair: which input wheels drive which axle joints, and how.

    ``wheels`` are the input layer's wheel counters (left, right), ``axles`` the scene IDs
    of the rear wheels' hinge joints (left, right; their axis points so that a positive
    angle rate rolls the chair forward). ``max_speed`` (m/s at the rim) bounds what a
    counter can ask; ``max_torque`` (N·m) is what the velocity-mode motors hold with;
    ``rim_inertia`` (kg·m²) is the real wheel's moment of inertia, which turns its
    measured change of speed into a push in feedback mode, applied as a torque of at most
    ``max_push`` (N·m). ``lag`` (rad: how far each simulated wheel is behind its real
    one, what the velocity mode's servo makes up), ``measured`` (rad/s: the real wheels'
    rates last frame, from which feedback mode's pushes are changes) and ``pending``
    (N·m·s: what pushes hold beyond MaxPush, applied next) and ``still`` (s the chair has
    stood still in velocity mode, real wheels still: at the world's SleepTime it is put to
    sleep) are the plugin's memory, kept here so a saved state continues it.
    """

    mode: str = NavigationMode.VELOCITY
    wheels: tuple[str, str] = ("left", "right")
    axles: tuple[str, str] = ("axle_l", "axle_r")
    wheel_radius: float = 0.305
    max_speed: float = 3.0
    max_torque: float = 30.0
    rim_inertia: float = 4.29
    max_push: float = 30.0
    lag: tuple[float, float] = (0.0, 0.0)
    measured: tuple[float, float] = (0.0, 0.0)
    pending: tuple[float, float] = (0.0, 0.0)
    still: float = 0.0
