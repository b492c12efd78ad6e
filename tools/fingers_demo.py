"""Makes content/hands/fingers.input: a recorded session of two tracked 26-joint hands.

The hands are made by :func:`services.input.hand_pose.pose_hand` (the pinch gesture opened
and closed, :mod:`app.bench.hand_grips` placing it round each object) and recorded through
the input layer's own recorder, so ``colosseum run content/hands/fingers.scene --replay
content/hands/fingers.input`` plays them back as any recorded session. What it shows,
in order: the right hand pinches the cup, lifts it and sets it down; the mug by its
handle; the pen off the table; the ball; then both hands lift the long box by its ends.
No button: every grasp is the thumb and index pressing from both sides, every release
the grip opening.

Run: ``python -m tools.fingers_demo [--out FILE]``.
"""

from __future__ import annotations

import argparse
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from app.bench.hand_grips import curls, grip_wrist, scale_for
from engine.content import REPO_ROOT
from engine.rotation import slerp
from services.input.hand_pose import pose_hand
from tools.recordings import record_session

CONTENT = REPO_ROOT / "content" / "hands"
TOP = 0.75
SECONDS = 24.5
#: Samples per second a hand sends (a camera tracker's rate; the file stays small), and
#: when the left hand, idle before it, starts sending.
RATE = 30.0
LEFT_FROM = 18.0
REST = {"right": ((0.3, -0.4, 1.0), 1.0), "left": ((-0.3, -0.4, 1.0), 1.0)}
UP = 0.12  # how high above an object the hand comes and goes
LIFT = 0.15


@dataclass(frozen=True, slots=True)
class Grip:
    """One object the hand takes: its centre, width across the pinch and direction."""

    centre: tuple[float, float, float]
    width: float
    across: tuple[float, float, float] = (0.0, 1.0, 0.0)
    opening: float = 0.04  # how much wider than it the hand comes down open


#: What each hand takes and when (s): the scene's objects.
RIGHT = [(1.0, Grip((0.35, -0.1, TOP + 0.05), 0.07)),  # the cup
         (5.5, Grip((0.18, -0.1, TOP + 0.05), 0.02, (0.0, 1.0, 0.0), 0.025)),  # mug handle
         (10.0, Grip((-0.15, -0.1, TOP + 0.008), 0.012, (1.0, 0.0, 0.0))),  # the pen
         (14.5, Grip((-0.4, -0.1, TOP + 0.03), 0.06)),  # the ball
         (19.5, Grip((0.14, 0.2, TOP + 0.03), 0.06))]  # the long box's right end
LEFT = [(19.5, Grip((-0.14, 0.2, TOP + 0.03), 0.06))]  # its left end


def keyframes(grips: list[tuple[float, Grip]], left: bool
              ) -> list[tuple[float, np.ndarray, np.ndarray, float]]:
    """(time, wrist position, wrist orientation, pinch scale) of a hand taking each of
    ``grips`` in turn: over it, down open, close, lift, hold, down, open, up."""
    first = grip_wrist((0.0, 0.0, 1.0), (0.0, 1.0, 0.0), 0.08, left)[1]
    rest = np.array(REST["left" if left else "right"][0])
    frames = [(0.0, rest, first, 0.0)]
    for start, g in grips:
        c = np.array(g.centre)
        wrist, quat = grip_wrist(c, g.across, g.width, left)
        up, lift = np.array([0, 0, UP]), np.array([0, 0, LIFT])
        opened, closed = scale_for(g.width + g.opening), scale_for(g.width - 0.012)
        frames += [(start + 0.9, wrist + up, quat, opened), (start + 1.4, wrist, quat, opened),
                   (start + 1.9, wrist, quat, closed), (start + 2.7, wrist + lift, quat, closed),
                   (start + 3.2, wrist + lift, quat, closed),
                   (start + 3.8, wrist + [0, 0, 0.004], quat, closed),
                   (start + 4.1, wrist + [0, 0, 0.004], quat, scale_for(g.width + 0.05)),
                   (start + 4.5, wrist + up, quat, scale_for(g.width + 0.05))]
    return frames


def sample(frames: list[tuple[float, np.ndarray, np.ndarray, float]], t: float
           ) -> tuple[np.ndarray, np.ndarray, float]:
    """The keyframes at ``t``: positions and scales in a line, turns by slerp."""
    times = [f[0] for f in frames]
    k = int(np.clip(np.searchsorted(times, t) - 1, 0, len(frames) - 2))
    t0, p0, q0, s0 = frames[k]
    t1, p1, q1, s1 = frames[k + 1]
    u = float(np.clip((t - t0) / (t1 - t0), 0.0, 1.0))
    return p0 + u * (p1 - p0), slerp(q0, q1, u), s0 + u * (s1 - s0)


def feeder(engine: Any, hub: Any) -> Any:
    from engine import Phase, system

    plans = {"right": (keyframes(RIGHT, False), False), "left": (keyframes(LEFT, True), True)}

    sent = [-1]

    @system(Phase.INPUT, before=("InputSystem",))
    def hands(e: Any, dt: float) -> None:
        t = round(e.time, 4)
        tick = int(t * RATE + 1e-6)
        if tick == sent[0]:
            return
        sent[0] = tick
        for name, (frames, left) in plans.items():
            if left and t < LEFT_FROM:
                continue
            p, q, s = sample(frames, t)
            hub.inject(_rounded(pose_hand(name, p, q, curls(s), left=left, timestamp=t)))

    return hands


def _rounded(h: Any) -> Any:
    """The sample to 0.1 mm and 1e-4 (a smaller file; the same motion)."""
    from services.input.events import HandJoints

    return HandJoints(h.device, tuple(tuple(round(x, 4) for x in p) for p in h.positions),
                      tuple(tuple(round(x, 4) for x in q) for q in h.orientations),
                      tuple(round(r, 4) for r in h.radii), h.valid, h.timestamp)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=CONTENT / "fingers.input")
    args = parser.parse_args(argv)
    out = record_session(CONTENT, args.out, feeder, SECONDS, digits=4,
                         scene_file="fingers.scene")
    print(f"wrote {out} ({out.stat().st_size // 1024} KiB)")


if __name__ == "__main__":
    main()
