"""A wheelchair driven by counters on a real chair's wheels (paper sections 5.5 and 6)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare


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


_POSITIVE = ("WheelRadius", "MaxSpeed", "MaxTorque", "RimInertia", "MaxPush")
_SAVED = "(written by --save-state)"


def _pair(value: Any) -> tuple[float, float]:
    left, right = value or (0.0, 0.0)
    return float(left), float(right)


def build_wheelchair(w: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """The ``Wheelchair`` block's component: a chassis, so its object needs a body, and
    settings that must be positive (each told at its line)."""
    if not ctx.has_body:
        ctx.error(None, f"object '{ctx.owner}' has a Wheelchair but no PhysicalAttributes: "
                  "the chassis is a body the wheels are jointed to")
        return []
    for key in _POSITIVE:
        if not w[key] > 0 or not math.isfinite(w[key]):
            ctx.error(key, f"{key} must be positive, got {w[key]}")
    wheels, axles = w["Wheels"], w["Axles"]
    mode = NavigationMode.FEEDBACK if w["Feedback"] else NavigationMode.VELOCITY
    return [Wheelchair(mode=mode, wheels=(wheels[0], wheels[1]), axles=(axles[0], axles[1]),
                       wheel_radius=float(w["WheelRadius"]), max_speed=float(w["MaxSpeed"]),
                       max_torque=float(w["MaxTorque"]), rim_inertia=float(w["RimInertia"]),
                       max_push=float(w["MaxPush"]), lag=_pair(w["Lag"]),
                       measured=_pair(w["Measured"]), pending=_pair(w["Pending"]),
                       still=max(float(w["Still"]), 0.0))]


def save_wheelchair(chair: Wheelchair) -> dict[str, Any]:
    """What a saved state writes back: the mode now and the plugin's memory (the servo's
    lag, the last rates, pushes still due, how long it has stood still)."""
    return {"Feedback": chair.mode == NavigationMode.FEEDBACK, "Lag": chair.lag,
            "Measured": chair.measured, "Pending": chair.pending, "Still": chair.still}


WHEELCHAIR_BLOCK = declare(BlockDeclaration(
    "Wheelchair", doc="makes the object a wheelchair's chassis: input wheel counters drive "
    "its rear axle joints (the wheelchair plugin)", build=build_wheelchair,
    saves=Wheelchair, save=save_wheelchair, keys=(
        Key("Feedback", "bool", 0, "0: velocity mode (the paper's): the wheels turn only as "
            "the real ones do and the chair never rolls by itself; 1: feedback mode: a "
            "change of the real wheel's speed pushes the free simulated wheel, gravity and "
            "walls act, and each wheel's speed and push are published (Output values "
            "wheelchair:ID/left/speed, wheelchair:ID/left/torque, and right)"),
        Key("Wheels", "stringvector", ("left", "right"), "the input wheel counters (Input { "
            "Wheel { ID } }, or the desktop device's left and right) of the left and right "
            "rear wheel", lengths=(2,)),
        Key("Axles", "stringvector", ("axle_l", "axle_r"), "the left and right rear wheels' "
            "hinge joints, their axes pointing so that turning forward is a positive rate",
            ref="Joint", lengths=(2,)),
        Key("WheelRadius", "float", 0.305, "the rear wheels' radius (rim speed = rate * "
            "radius)", unit="m"),
        Key("MaxSpeed", "float", 3.0, "at the rim: faster wheel input is clamped (told "
            "once)", unit="m/s"),
        Key("MaxTorque", "float", 30.0, "each velocity-mode motor turns and holds its wheel "
            "with (a user's arm: 2 m/s^2 for a 90 kg chair, enough to hold it on a 1:12 "
            "ramp)", unit="N*m"),
        Key("RimInertia", "float", 4.29, "the real wheel's moment of inertia: its measured "
            "change of speed times this is the push in feedback mode (a rig that feels like "
            "the chair: its rolling inertia (M + sum I/r^2) r^2 shared by two wheels; 4.29 "
            "for 90 kg on 0.305 m wheels)", unit="kg*m^2"),
        Key("MaxPush", "float", 30.0, "the largest torque a push applies in feedback mode; "
            "a harder push (a key pressed) is spread over the next frames", unit="N*m"),
        Key("Lag", "vector", None, "each simulated wheel [left right] was behind its real "
            f"one, which velocity mode makes up {_SAVED}", unit="rad", lengths=(2,),
            example="[0.0012 -0.0004]"),
        Key("Measured", "vector", None, "the real wheels [left right] turned at in the last "
            f"frame, which feedback mode's pushes are changes of {_SAVED}", unit="rad/s",
            lengths=(2,), example="[2.1 2.05]"),
        Key("Pending", "vector", None, "of pushes [left right] beyond MaxPush, still to be "
            f"applied {_SAVED}", unit="N*m*s", lengths=(2,), example="[0.6 0.6]"),
        Key("Still", "float", 0.0, "the chair has stood still in velocity mode with its real "
            f"wheels still; at the world's SleepTime it sleeps {_SAVED}", unit="s",
            example="0.3"),
    )))
