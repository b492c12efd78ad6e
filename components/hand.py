"""A virtual hand: what drives it, and where it stands (paper section 5)."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any

from components.blocks import (
    BlockDeclaration,
    BuildContext,
    Key,
    KeyDeclaration,
    declare,
    declare_key,
)
from components.physical import Physical


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


def build_graspable(graspable: int, ctx: BuildContext) -> list[Any]:
    """An object's ``Graspable``: 0 marks it as one no hand may hold."""
    return [] if graspable else [Graspable(False)]


GRASPABLE_KEY = declare_key(KeyDeclaration(
    Key("Graspable", "bool", 1, "0: hands cannot hold it (dynamic bodies can by default)"),
    build_graspable))


#: A hand's body where the author gives it no size or mass: a hand-sized box (m) of a
#: hand's weight (kg).
HAND_SIZE = (0.09, 0.18, 0.03)
HAND_MASS = 0.45
#: A fingered hand's palm (``Hand { Fingers 1 }``): the box round the metacarpals (m;
#: +x along the fingers), its fingers' phalanges being bodies of their own.
PALM_SIZE = (0.075, 0.085, 0.028)
#: The drive's bounds and response reach the backend: each must be positive (or, with a
#: least value of 0, at least that).
_DRIVE = (("MaxForce", 0.0), ("MaxTorque", 0.0), ("TimeConstant", 0.0), ("MaxSpeed", None),
          ("MaxSpin", None), ("DeviationDistance", None), ("BreakForce", None))
_MODELS = ("NeutralModel", "ContactModel", "GraspModel")


def build_hand(h: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Hand`` block: the hand and its standing. A hand is a body (an object without
    one is told); it floats, never sleeps and weighs a hand's unless told otherwise; its
    tracker and glove are checked against the scene's Input; its Frame is linked."""
    who = f"hand '{ctx.owner}'"
    if not ctx.has_body:
        ctx.error(None, f"object '{ctx.owner}' has a Hand but no PhysicalAttributes: a "
                  "virtual hand is a body (leave both Visual- and PhysicalAttributes out for "
                  "the default hand box)")
        return []
    _hand_body(ctx.component(Physical), h, ctx)
    for key, least in _DRIVE:
        value = h[key]
        if value is not None and not (value > 0 or value == least):
            ctx.error(key, f"{who}: {key} must be "
                      f"{'positive' if least is None else '>= 0'}, got {value:g}")
    if not h["Fingers"]:  # a fingered hand's Tracker is an input hand (HandJoints),
        ctx.input_name("Tracker", "tracker", who)  # which no Input block declares
    ctx.input_name("Glove", "glove", who)
    models = {key: ctx.model_file(key) for key in _MODELS}
    hand = Hand(tracker=h["Tracker"], glove=h["Glove"], button=h["Button"],
                max_force=float(h["MaxForce"]), max_torque=float(h["MaxTorque"]),
                time_constant=float(h["TimeConstant"]), max_speed=float(h["MaxSpeed"]),
                max_spin=math.radians(float(h["MaxSpin"])),
                deviation_distance=float(h["DeviationDistance"]),
                break_force=None if h["BreakForce"] is None else float(h["BreakForce"]),
                marker=bool(h["Marker"]), neutral_model=models["NeutralModel"],
                contact_model=models["ContactModel"], grasp_model=models["GraspModel"],
                holding=tuple(h["Holding"] or ()), fingers=bool(h["Fingers"]))
    if ctx.given("Frame"):
        ctx.link(hand, "frame", h["Frame"])
    return [hand, HandState()]


def _hand_body(body: Physical, h: Mapping[str, Any], ctx: BuildContext) -> None:
    """A hand floats (its drive holds it up) and never sleeps; it weighs a hand's 0.45 kg
    unless the author gave it a mass: the Hand's ``Mass``, or its PhysicalAttributes'
    Mass or Density (one of them; both is an error)."""
    beside = ctx.beside("PhysicalAttributes")
    phys, at = beside if beside is not None else ({}, None)
    if at is not None and at.given("Gravity") and phys["Gravity"]:
        at.warning("Gravity", f"object '{ctx.owner}' is a hand: hands float, so Gravity 1 "
                   "is ignored")
    body.gravity = False
    body.can_sleep = False
    own = next((k for k in ("Mass", "Density") if at is not None and at.given(k)), None)
    if not ctx.given("Mass"):
        if own is None:
            body.mass = HAND_MASS
    elif own is not None:
        ctx.error("Mass", f"hand '{ctx.owner}': Mass {h['Mass']:g} kg here and {own} "
                  f"{phys[own]:g} in its PhysicalAttributes: give the hand's weight once")
    else:
        ctx.check_mass("Mass")
        body.mass = float(h["Mass"])


HAND_BLOCK = declare(BlockDeclaration(
    "Hand", build=build_hand, doc="makes the object a virtual hand: a body driven toward a "
    "tracker's pose with bounded force, grasping on a glove's button", keys=(
        Key("Tracker", "string", None, "the input tracker whose pose the hand follows (Input "
            "{ Tracker { ID } }, or hand_l/hand_r of the desktop device)", required=True,
            example='"glove"'),
        Key("Glove", "string", "", "the input device whose Button holds what the hand "
            "touches (glove_l/glove_r: the desktop device's mouse button)"),
        Key("Button", "string", "pinch", "the glove's button that grasps while down"),
        Key("Mass", "float", None, "the hand's body weighs (default 0.45; give it here or as "
            "PhysicalAttributes' Mass or Density, not both)", unit="kg"),
        Key("MaxForce", "float", 300.0, "the drive may push with: a heavier load lags, a wall "
            "stops the hand", unit="N"),
        Key("MaxTorque", "float", 30.0, "the drive may turn with", unit="N*m"),
        Key("TimeConstant", "float", 0.0, "the hand's distance to its tracker closes with; 0: "
            "max(2 TimeStep, 0.03 s)", unit="s"),
        Key("MaxSpeed", "float", 10.0, "the drive's correction is capped at (a tracker's own "
            "speed comes on top)", unit="m/s"),
        Key("MaxSpin", "float", 1146.0, "the drive's turning correction is capped at (20 "
            "rad/s)", unit="deg/s"),
        Key("DeviationDistance", "float", 0.3, "(D): farther from its tracker the hand passes "
            "through things and snaps back; it collides again under 0.1 D, and is drawn "
            "see-through, on top, from 0.1 D to 0.7 D", unit="m"),
        Key("BreakForce", "float", None, "a grip carries before it lets go: the pull toward "
            "the hand and any shear beyond what pressing the object against the palm holds "
            "(none: never)", unit="N"),
        Key("Marker", "bool", 1, "show a ball where the real hand (the tracker) is"),
        Key("Fingers", "bool", 0, "1: the palm and each finger's phalanges are bodies driven "
            "toward the 26 tracked joints of input hand Tracker (ODE; on pymunk a 2D hand in "
            "the plane), and what the thumb and "
            "an opposing finger or the palm press is held; 0: the palm only (the paper's "
            "hand)"),
        Key("NeutralModel", "asset", None, "model drawn while the hand touches nothing it "
            "could grasp (a relaxed hand); default: the object's own look"),
        Key("ContactModel", "asset", None, "model drawn while the hand touches something it "
            "could grasp (an open hand); default: the object's own look"),
        Key("GraspModel", "asset", None, "model drawn while it holds something (a closed "
            "hand)"),
        Key("Frame", "ref", None, "the object the tracker is calibrated relative to (a "
            "wheelchair): the hand follows it", ref="Object"),
        Key("Holding", "stringvector", None, "objects held when this state was saved "
            "(written by --save-state; they are held again on load)"),
    )))
