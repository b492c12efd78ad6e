"""``colosseum bench hands``, the 2D fingered hand's rows (pymunk: the X–Z plane).

The ODE rows of :mod:`app.bench.fingers` in the side view, with hands the plane can hold:
unturned or turned only about Y (their fingers bend in X–Z), so a pinch closes the thumb
and index round an object along X. Each row is measured at the physics rate it is given
(the bench runs 200 and 100 Hz frames):

* ``fingertips``: :func:`app.bench.fingers.fingertips`' swinging, curling hand; each tip's
  distance from its tracked one in the plane (the thumb, whose projection shortens as it
  bends out of the plane, shown but not held to the goal), and the palm's at 1 m/s.
* ``penetration``: contact depths of the bones in a ball pinched off the table and
  lifted, and in a box a pointing index pushes along the table.
* ``held still``, ``shake``, ``hand-over``, ``swipe``: as on ODE, in the plane (the left
  hand comes down onto the ball the right holds and pinches it as the right does: seen
  from the side the two pinches are one, and hands pass through hands; the swiping
  hand's palm leads, its fingers up).

Seen in the plane the pinch gesture's other fingers lie across what it pinches, so every
pinching hand comes down onto its object (:func:`approach`) rather than being made round
it. The pinch is placed for the grip it has (:func:`side_pinch`), so the hand comes down a
few millimetres as it closes: placed for the object's width and closed by the fingers
alone it takes no hold in the plane (the thumb closes mostly across the plane, and its
rigid chain's tip stays about a centimetre short of the object). The right hand of the
hand-over opens where it holds, or opening would pull the ball down with it.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from app.bench.fingers import (
    PLATE,
    PUSHED_BOX,
    SQUEEZE,
    TABLE,
    TOP,
    ball,
    bones_of,
    depths,
    hand,
    held_ball_run,
    lift,
    physical_tips,
    run,
    shaken_cup,
)

BACKEND = "pymunk"


@cache
def _side_pinch_gaps() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pinch gesture's scales, the gap between its thumb and index tips seen in the
    plane (X–Z) at each, and their midpoints (the hand unturned: it bends in the plane)."""
    from app.bench.hand_grips import curls
    from services.input.events import HAND_JOINTS
    from services.input.hand_pose import local_hand

    thumb, index = HAND_JOINTS.index("thumb_tip"), HAND_JOINTS.index("index_tip")
    scales = np.linspace(0.0, 1.0, 101)
    gaps, mids = [], []
    for s in scales:
        p = local_hand(curls(float(s)))[0]
        gaps.append(float(np.hypot(*(p[index] - p[thumb])[[0, 2]])))
        mids.append((p[index] + p[thumb]) / 2)
    return scales, np.array(gaps), np.array(mids)


def side_pinch(device: str, centre: Any, grip: float, timestamp: float = 0.0, *,
               spread: float | None = None, left: bool = False) -> Any:
    """A tracked hand pinching in the plane, as the 2D hand sees it: the pinch gesture
    (unturned, so its fingers bend about Y) closed until its thumb and index tips are
    ``grip`` apart in X–Z, put where their midpoint would be ``centre`` at a grip of
    ``spread`` (default ``grip``): with a fixed ``spread`` opening and closing moves the
    fingers, not the hand (the tips' midpoint drops 2.5 cm as the pinch closes)."""
    from app.bench.hand_grips import curls
    from services.input.hand_pose import pose_hand

    scales, gaps, mids = _side_pinch_gaps()
    order = np.argsort(gaps)
    s, fit = (float(np.interp(g, gaps[order], scales[order]))
              for g in (grip, grip if spread is None else spread))
    mid = np.array([np.interp(fit, scales, mids[:, k]) for k in range(3)])
    at = np.asarray(centre, dtype=float) - mid
    at[1] = centre[1]
    return pose_hand(device, tuple(at.tolist()), (1.0, 0.0, 0.0, 0.0), curls(s), left=left,
                     timestamp=timestamp)


def fingertips_2d(folder: Path, seconds: float, rate: float = 120.0, speed: float = 0.5
                  ) -> dict[str, Any]:
    """:func:`app.bench.fingers.fingertips`' hand (swinging along X at ``speed`` peak,
    curling and opening) on pymunk, unturned (its fingers bend in the plane): each
    physical tip's distance from its tracked one seen in the plane (X and Z), RMS (mm),
    the four fingers' worst; the thumb's shown; the palm's."""
    from components import Transform
    from services.input.events import HAND_JOINTS
    from services.input.hand_pose import pose_hand
    from systems.hand_fingers2d import tip_error

    omega, names = 5.0, ("thumb", "index", "middle", "ring", "little")
    tips = [HAND_JOINTS.index(f"{f}_tip") for f in names]

    def sample(t: float) -> Any:
        curl = 0.3 + 0.2 * np.sin(2.0 * t)
        return pose_hand("right", (speed / omega * np.sin(omega * t), 0.0, 1.0),
                         (1.0, 0.0, 0.0, 0.0), dict.fromkeys(names, curl), timestamp=t)

    err: list[np.ndarray] = []
    palm: list[float] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        if bones_of(e, ids["hand_r"]):
            tracked = np.asarray(sample(e.time + 1.0 / rate).positions)
            err.append(tip_error(tracked[tips], physical_tips(e, ids["hand_r"])))
            at = e.world.component_for_entity(ids["hand_r"], Transform).position
            palm.append(float(np.hypot(*(at - tracked[0])[[0, 2]])))

    run(hand("hand_r", "right"), folder, {"right": sample}, seconds, note, rate,
        backend=BACKEND)
    rms = np.sqrt(np.mean(np.square(err), axis=0)) * 1e3
    return {"error_rms_mm": float(rms[1:].max()), "tips_rms_mm": rms,
            "palm_rms_mm": float(np.sqrt(np.mean(np.square(palm)))) * 1e3}


def approach(motion: Callable[[float], np.ndarray], height: float = 0.1
             ) -> Callable[[float], np.ndarray]:
    """``motion`` after coming down ``height`` onto the grip in the first 0.3 s: in the
    plane the fingers a pinch curls beside the object (middle, ring, little) lie across
    it, so a hand made at the grip would start inside it."""
    return lambda t: motion(t) + np.array([0.0, 0.0, float(np.interp(t, [0.0, 0.3],
                                                                     [height, 0.0]))])


def held_ball_2d(folder: Path, rate: float) -> dict[str, Any]:
    """A ball on the table pinched in the plane, lifted 15 cm and held still: the bones'
    contact depths in it throughout, its jitter (RMS from its mean, mm) after 2 s."""
    width = 0.06
    centre = np.array([0.0, 0.0, TOP + width / 2])
    up = approach(lift())

    def feed(t: float) -> Any:
        grip = float(np.interp(t, [0.3, 0.7], [width + 0.03, width - SQUEEZE]))
        return side_pinch("right", centre + up(t), grip, t)

    return held_ball_run(TABLE + ball("ball", width, centre, 0.1) + hand("hand_r", "right"),
                         folder, feed, centre, rate, backend=BACKEND)


def pushed_box_2d(folder: Path, rate: float) -> dict[str, Any]:
    """A pointing index pushes a 0.5 kg box along the table, in the plane."""
    from services.input.hand_pose import GESTURES, pose_hand


    def feed(t: float) -> Any:
        x = float(np.interp(t, [0.0, 0.4, 2.0], [-0.22, -0.22, 0.05]))
        return pose_hand("right", (x, 0.0, TOP + 0.04), (1.0, 0.0, 0.0, 0.0),
                         GESTURES["point"], timestamp=t)

    deep: list[float] = []
    run(TABLE + PUSHED_BOX + hand("hand_r", "right", (-0.15, 0.0, 0.8)), folder, {"right": feed},
        2.0, lambda e, ids: deep.extend(depths(e, set(bones_of(e, ids["hand_r"])),
                                               ids["box"])), rate, settle=0.0,
        backend=BACKEND)
    return {"depths": deep}


def shake_2d(folder: Path, rate: float) -> dict[str, Any]:
    """A 0.3 kg cup pinched in the plane, lifted, shaken up and down (Z) at 3 Hz ±10 cm
    for 2 s: held throughout, and how far it got from the tracked grip's centre (the
    plane keeps the cup at the grip's Y, so that is its distance in X–Z)."""
    def pinching(centre: np.ndarray, width: float,
                 motion: Callable[[float], np.ndarray]) -> Callable[[float], Any]:
        def feed(t: float) -> Any:
            grip = float(np.interp(t, [0.3, 0.7], [width + 0.03, width - SQUEEZE]))
            return side_pinch("right", centre + motion(t), grip, t)
        return feed

    return shaken_cup(folder, rate, pinching, backend=BACKEND)


def hand_over_2d(folder: Path, rate: float) -> dict[str, Any]:
    """The right hand holds a ball up; the left comes down onto it where it is and
    pinches it (in the plane the left hand's pinch is the right's mirror image, the same
    seen from the side: hands pass through hands); the right lets go. How far the ball
    moved (mm) from before the left came down to after the right let go."""
    from components import Transform

    width = 0.06
    centre = np.array([0.0, 0.0, TOP + width / 2])
    seen: dict[str, np.ndarray] = {}
    up = approach(lift())

    def right(t: float) -> Any:
        grip = float(np.interp(t, [0.3, 0.7, 2.6, 2.9], [width + 0.03, width - SQUEEZE,
                                                          width - SQUEEZE, width + 0.04]))
        # it opens where it holds (not placed for its grip as it closes): the hand stays
        return side_pinch("right", centre + up(t), grip, t,
                          spread=width - SQUEEZE if t > 2.6 else None)

    def left(t: float) -> Any:
        at = seen.get("ball", centre) + np.array([0.0, 0.0, np.interp(t, [1.6, 1.8],
                                                                          [0.1, 0.0])])
        grip = float(np.interp(t, [1.8, 2.2], [width + 0.03, width - SQUEEZE]))
        return side_pinch("left", at, grip, t, left=True)

    def note(e: Any, ids: dict[str, int]) -> None:
        spot = e.world.component_for_entity(ids["ball"], Transform).position.copy()
        if e.time < 1.6:
            seen["ball"] = spot  # where the left hand comes down to
        seen["last"] = spot

    scene = TABLE + ball("ball", width, centre, 0.1) + hand("hand_r", "right") + \
        hand("hand_l", "left", (0.0, 0.3, 1.0))
    run(scene, folder, {"right": right, "left": left}, 3.6, note, rate, settle=0.0,
        backend=BACKEND)
    moved = float(np.linalg.norm((seen["last"] - seen["ball"])[[0, 2]])) * 1e3
    return {"moved_mm": moved, "held": bool(seen["last"][2] > centre[2] + 0.1)}


def swipe_2d(folder: Path, rate: float) -> dict[str, Any]:
    """The open hand, its fingers up and its palm leading (turned a quarter about Y: it
    still bends in the plane), swept at 3 m/s along X at a fixed 5 mm plate at x = 0
    (its bottom 0.1 m below the wrist, its top past the fingertips): the farthest any of
    its bodies' centres got (mm)."""
    from components import Transform
    from services.input.hand_pose import GESTURES, pose_hand

    up = (np.cos(-np.pi / 4), 0.0, np.sin(-np.pi / 4), 0.0)  # fingers +Z, palm facing +X

    def feed(t: float) -> Any:
        x = float(np.interp(t, [0.0, 0.3, 0.4], [-0.12, -0.12, 0.18]))  # 3 m/s
        return pose_hand("right", (x, 0.0, 0.9), up, GESTURES["open"], timestamp=t)

    farthest = [-1.0]

    def note(e: Any, ids: dict[str, int]) -> None:
        for body in [ids["hand_r"], *bones_of(e, ids["hand_r"])]:
            x = float(e.world.component_for_entity(body, Transform).position[0])
            farthest[0] = max(farthest[0], x)

    run(PLATE + hand("hand_r", "right", (-0.12, 0.0, 0.9)), folder, {"right": feed}, 0.6,
        note, rate, settle=0.0, backend=BACKEND)
    return {"farthest_centre_mm": farthest[0] * 1e3}
