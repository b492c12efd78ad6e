"""Makes content/hands/demo.input: a recorded session of two tracked hands and gloves.

The session is written as a tracker and glove would send it (poses at every frame with
their velocities, button presses), through the input layer's own recorder, so
``colosseum run content/hands --replay content/hands/demo.input`` plays it back exactly
as any recorded session. What it shows, in order: the right hand touches a cup, grasps
it, lifts and carries it, lets go; both hands lift the plank and carry it; the right
hand alone grasps the 50 kg crate and cannot lift it, then both hands lift it; the left
hand pulls the drawer open; the right hand is pushed down through the table top (it
stops on the top, then passes through once 0.3 m from its tracker: the rule of section
5.4) and comes back up.

Run: ``python -m tools.hands_demo [--out FILE]``.
"""

from __future__ import annotations

import argparse
from collections.abc import Callable
from pathlib import Path

import numpy as np

from engine.content import REPO_ROOT
from tools.recordings import record_session

CONTENT = REPO_ROOT / "content" / "hands"
TOP = 0.75  # the table top
PRESS = 0.008  # how far a hand's tracker goes into what it rests on: a firm touch
REST_R, REST_L = (0.25, -0.45, 1.0), (-0.25, -0.45, 1.0)


def on(z_top: float) -> float:
    """A hand's tracker height resting on a surface at ``z_top`` (the palm 3 cm thick)."""
    return z_top + 0.015 - PRESS


#: (time s, position) waypoints of each hand; between them the tracker moves in a line.
RIGHT = [
    (0.0, REST_R), (1.0, REST_R),
    (2.0, (0.3, -0.15, TOP + 0.2)), (2.6, (0.3, -0.15, on(TOP + 0.1))),  # onto cup1
    (3.0, (0.3, -0.15, on(TOP + 0.1))), (4.0, (0.1, -0.25, TOP + 0.35)),  # lift, carry
    (4.6, (0.1, -0.25, TOP + 0.35)),  # (lets go at 4.4)
    (5.4, (0.5, 0.2, TOP + 0.15)), (6.0, (0.45, 0.2, on(TOP + 0.05))),  # plank's end
    (6.4, (0.45, 0.2, on(TOP + 0.05))), (7.6, (0.45, 0.0, TOP + 0.35)),
    (8.4, (0.45, 0.0, TOP + 0.35)), (9.0, (0.45, 0.0, TOP + 0.25)),  # (lets go at 8.6)
    (9.5, (0.45, 0.0, 1.1)), (10.0, (1.4, 0.2, 0.7)),
    (10.6, (1.4, 0.2, on(0.5))),  # onto the crate
    (11.0, (1.4, 0.2, on(0.5))), (12.0, (1.4, 0.2, on(0.5) + 0.2)),  # one hand: no
    (12.6, (1.4, 0.2, on(0.5) + 0.2)), (13.2, (1.4, 0.2, 0.7)),
    (13.8, (1.42, 0.2, on(0.5))), (14.2, (1.42, 0.2, on(0.5))),
    (15.4, (1.42, 0.2, on(0.5) + 0.2)), (16.4, (1.42, 0.2, on(0.5) + 0.2)),  # two: up
    (17.0, (1.42, 0.2, on(0.5) + 0.2)), (17.4, (1.42, 0.2, 1.1)),  # up, clear of things
    (18.0, (0.3, -0.3, TOP + 0.25)),
    (19.5, (0.3, -0.3, TOP - 0.45)), (21.0, (0.3, -0.3, TOP - 0.45)),  # through the top
    (22.5, (0.3, -0.3, TOP + 0.45)), (23.5, REST_R), (24.0, REST_R),
]
LEFT = [
    (0.0, REST_L), (5.0, REST_L),
    (5.4, (-0.5, 0.2, TOP + 0.15)), (6.0, (-0.45, 0.2, on(TOP + 0.05))),  # plank's end
    (6.4, (-0.45, 0.2, on(TOP + 0.05))), (7.6, (-0.45, 0.0, TOP + 0.35)),
    (8.4, (-0.45, 0.0, TOP + 0.35)), (9.0, (-0.45, 0.0, TOP + 0.25)),
    (9.6, (-0.45, 0.0, 1.1)), (10.5, (0.9, 0.0, 1.1)), (13.0, (1.18, 0.2, 0.7)),
    (13.8, (1.18, 0.2, on(0.5))), (14.2, (1.18, 0.2, on(0.5))),  # the crate's other end
    (15.4, (1.18, 0.2, on(0.5) + 0.2)), (16.4, (1.18, 0.2, on(0.5) + 0.2)),
    (17.0, (1.18, 0.2, on(0.5) + 0.2)), (17.4, (1.18, 0.2, 1.1)),
    (18.0, (-0.9, -0.2, 1.1)),
    (19.0, (-1.2, 0.12, on(0.8))), (19.4, (-1.2, 0.12, on(0.8))),  # onto the drawer
    (20.6, (-1.2, -0.13, on(0.8) + 0.005)), (21.2, (-1.2, -0.13, on(0.8) + 0.005)),
    (22.0, REST_L), (24.0, REST_L),
]
#: When each glove's pinch is down (start, end).
PINCHES = {"glove_r": [(2.8, 4.4), (6.2, 8.6), (10.8, 12.4), (14.0, 16.8)],
           "glove_l": [(6.2, 8.6), (14.0, 16.8), (19.2, 21.0)]}
SECONDS = 24.0


def path(points: list[tuple[float, tuple[float, float, float]]]
         ) -> Callable[[float], np.ndarray]:
    times = np.array([p[0] for p in points])
    spots = np.array([p[1] for p in points], float)
    return lambda t: np.array([np.interp(t, times, spots[:, k]) for k in range(3)])


def record(out: Path, seconds: float = SECONDS) -> Path:
    """Run the content folder with the session fed in, the input layer recording it."""
    from engine import Phase, system
    from services.input.events import Button, TrackerPose

    trackers = {"hand_r": path(RIGHT), "hand_l": path(LEFT)}

    def feeder(engine, hub):
        pressed: dict[str, bool] = {}

        @system(Phase.INPUT, before=("InputSystem",))
        def session(e, dt):
            t = e.time
            for name, move in trackers.items():
                velocity = (move(t + 1e-3) - move(t - 1e-3)) / 2e-3
                hub.inject(TrackerPose(name, tuple(move(t)), (1.0, 0.0, 0.0, 0.0),
                                       tuple(velocity), t))
            for glove, spans in PINCHES.items():
                down = any(a <= t < b for a, b in spans)
                if down != pressed.get(glove, False):
                    pressed[glove] = down
                    hub.inject(Button(glove, "pinch", down, t))

        return session

    return record_session(CONTENT, out, feeder, seconds)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=CONTENT / "demo.input")
    print(record(parser.parse_args().out))


if __name__ == "__main__":
    main()
