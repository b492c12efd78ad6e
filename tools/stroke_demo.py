"""Makes content/stroke/demo.input: a recorded session that sets the breakfast table.

A scripted user drives the real chair's wheels and moves the right hand's tracker and
glove, and the input layer's own recorder writes what they send, so ``colosseum run
content/stroke --replay content/stroke/demo.input`` plays it back exactly as any
recorded session (and ``colosseum score content/stroke/demo.input`` scores it). The
user is closed-loop on the simulation it records: it steers the wheels by where the
chair is, and places each thing by where the hand holds it. In order: the chair rolls
from the hall through the kitchen doorway (over its threshold) to the table's near side,
then the right hand takes the plate, the bowl, the cup, the spoon and the cereal from
the counter and puts each on its place on the table (scripts/tasks.lua then reports the
breakfast task done). The left hand rests on the lap.

Trackers are sent relative to the chair (the hands' ``Frame``), the right one at 20 Hz
while it moves (with its velocity, which the hand's target moves on with between
poses) and both four times a second at rest, the wheel counters every frame while they
turn, times to the microsecond: a small file. Run: ``python -m tools.stroke_demo [--out
FILE]``.
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from engine.content import REPO_ROOT
from tools.recordings import record_session

CONTENT = REPO_ROOT / "content" / "stroke"
#: Where the chair parks: the floor under its rear axle, at the table's near side.
PARK_Y = 3.62
#: The right hand's rest on the lap, the left one's (chair frame, m).
REST_R, REST_L = (0.26, 0.38, 0.72), (-0.26, 0.38, 0.72)
CARRY = 1.45  # m: things are carried this high above the floor
PRESS = 0.008  # m the tracker goes into what the palm rests on: a firm touch
PALM = 0.015  # half the palm's thickness
#: The breakfast things in the order they are set, and their places (tasks.lua's marks).
ITEMS = ("plate", "bowl", "cup", "spoon", "cereal")
WHEEL_RATE = 3.0  # rad/s: the wheels' top speed (0.9 m/s)
COUNTS_PER_TURN, WRAP = 1024, 65536
DIGITS = 6  # device times to the microsecond: shorter numbers, a smaller file


@dataclass(slots=True)
class Move:
    """The right tracker goes to ``target()`` (world) in ``seconds``; then ``then`` runs."""

    target: Callable[[], np.ndarray]
    seconds: float
    then: Callable[[], None] | None = None


class User:
    """The scripted user: drives to the table, then sets it, one thing at a time."""

    def __init__(self, engine: Any) -> None:
        from components import Name, Physical, Transform

        self.engine = engine
        world = engine.world
        self.ids = {n.id: e for e, n in world.get_component(Name)}
        self.transform = lambda name: world.component_for_entity(self.ids[name], Transform)
        self.half_height = {name: _half_height(world.component_for_entity(self.ids[name],
                                                                          Physical))
                            for name in ITEMS}
        self.places = {name: self.transform(f"mark {name}").position.copy() for name in ITEMS}
        self.counts = [0.0, 0.0]
        self.pinch = False
        self.right = np.array(REST_R, float)  # chair frame
        self.moves: list[Move] = []
        self.move_start: tuple[float, np.ndarray] | None = None
        self.parked = False
        self.done = False
        self.grip = 0.0  # hand centre above the held thing's centre (m), measured at grasp

    # -- the chair ----------------------------------------------------------------------
    def chair(self) -> tuple[np.ndarray, np.ndarray]:
        from engine.rotation import quat_to_matrix

        t = self.transform("wheelchair")
        return t.position.copy(), quat_to_matrix(t.orientation)

    def wheel_rates(self) -> tuple[float, float]:
        """Roll north along x = the doorway's middle to the parking line, keeping straight."""
        position, rotation = self.chair()
        heading = math.atan2(-rotation[0, 1], rotation[1, 1])  # 0: facing +Y
        left_of_line = position[0] - 8.7
        togo = PARK_Y - position[1]
        if togo <= 0.002:
            self.parked = True
            return 0.0, 0.0
        speed = min(WHEEL_RATE, 0.5 + 6.0 * togo, 1.0 + 3.0 * self.engine.time)
        turn = -2.0 * heading - 1.5 * left_of_line  # rad/s difference, right minus left
        return speed - turn, speed + turn

    # -- the hand -----------------------------------------------------------------------
    def to_chair(self, world_point: np.ndarray) -> np.ndarray:
        position, rotation = self.chair()
        return rotation.T @ (np.asarray(world_point, float) - position)

    def plan(self) -> None:
        """The moves that set the table: for each thing, reach, take, carry, put, lift."""
        for name in ITEMS:
            self.moves += self._set(name)
        self.moves.append(Move(lambda: self.to_world(REST_R), 1.0, self._finish))

    def to_world(self, local: tuple[float, float, float]) -> np.ndarray:
        position, rotation = self.chair()
        return position + rotation @ np.asarray(local, float)

    def _set(self, name: str) -> list[Move]:
        item = lambda: self.transform(name).position  # noqa: E731 - read when moving
        top = lambda: item()[2] + self.half_height[name]  # noqa: E731
        above = lambda: np.array([*item()[:2], CARRY])  # noqa: E731
        place = self.places[name]
        over_place = lambda: np.array([*place[:2], CARRY])  # noqa: E731
        # the held thing's bottom 3 mm over the table: its centre half a height up
        put = lambda: np.array([*place[:2], place[2] + self.half_height[name] + 0.003  # noqa: E731
                                + self.grip])
        on_top = lambda: np.array([*item()[:2], top() + PALM - PRESS])  # noqa: E731
        return [
            Move(above, 0.9),
            Move(on_top, 0.5),
            Move(on_top, 0.15, lambda: self._take(name)),
            Move(on_top, 0.2),
            Move(above, 0.5),
            Move(over_place, 0.8),
            Move(put, 0.6),
            Move(put, 0.15, self._let_go),
            Move(put, 0.2),
            Move(over_place, 0.4),
        ]

    def _take(self, name: str) -> None:
        self.pinch = True
        hand = self.transform("right hand").position
        self.grip = float(hand[2] - self.transform(name).position[2])

    def _let_go(self) -> None:
        self.pinch = False

    def _finish(self) -> None:
        self.done = True

    def step_hand(self) -> bool:
        """Advance the right tracker along its moves; whether it moved this frame."""
        if not self.moves:
            return False
        now = self.engine.time
        move = self.moves[0]
        if self.move_start is None:
            self.move_start = (now, self.right.copy())
        t0, start = self.move_start
        share = min((now - t0) / move.seconds, 1.0)
        goal = self.to_chair(move.target())
        ease = 0.5 - 0.5 * math.cos(math.pi * share)
        before = self.right.copy()
        self.right = start + (goal - start) * ease
        if share >= 1.0:
            self.moves.pop(0)
            self.move_start = None
            if move.then is not None:
                move.then()
        return bool(np.any(np.abs(self.right - before) > 1e-6))


def _half_height(physical: Any) -> float:
    """Half the height of a thing's first shape (a box's or a cylinder's, upright)."""
    shape = physical.shapes[0]
    return float(shape.size[2] / 2 if shape.kind == "box" else shape.size[1] / 2)


def record(out: Path, seconds: float = 60.0) -> Path:
    """Run the content folder with the user's input fed in, the input layer recording it,
    until the table is set (or ``seconds`` pass)."""
    from engine import Phase, system
    from services.input.events import Button, TrackerPose, WheelCount

    def feeder(engine: Any, hub: Any) -> Any:
        user = User(engine)
        pressed = [False]
        last_velocity = [np.zeros(3)]

        @system(Phase.INPUT, before=("InputSystem",))
        def session(e: Any, dt: float) -> None:
            t = round(e.time, DIGITS)
            if not user.parked:
                rates = user.wheel_rates()
                if user.parked:
                    user.plan()
            else:
                rates = (0.0, 0.0)
            for i, name in enumerate(("left", "right")):
                user.counts[i] += rates[i] / (2 * math.pi) * COUNTS_PER_TURN * dt
                if rates[i] or e.frame % 15 == 0:
                    hub.inject(WheelCount(name, int(round(user.counts[i])) % WRAP, t))
            before = user.right.copy()
            moved = user.parked and user.step_hand()
            velocity = (user.right - before) / dt if dt > 0 else np.zeros(3)
            if (moved and e.frame % 3 == 0) or e.frame % 15 == 0 or (
                    not moved and np.any(last_velocity[0])):
                last_velocity[0] = velocity if moved else np.zeros(3)
                hub.inject(TrackerPose("hand_r", _rounded(user.right), (1.0, 0.0, 0.0, 0.0),
                                       _rounded(last_velocity[0]), t))
            if e.frame % 15 == 0:
                hub.inject(TrackerPose("hand_l", REST_L, (1.0, 0.0, 0.0, 0.0), None, t))
            if user.pinch != pressed[0]:
                pressed[0] = user.pinch
                hub.inject(Button("glove_r", "pinch", user.pinch, t))
            if user.done:
                e.request_quit()

        return session

    return record_session(CONTENT, out, feeder, seconds, digits=DIGITS)


def _rounded(v: np.ndarray) -> tuple[float, float, float]:
    """Positions to 0.1 mm (a tracker's precision): a smaller file."""
    return (round(float(v[0]), 4), round(float(v[1]), 4), round(float(v[2]), 4))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=CONTENT / "demo.input")
    print(record(parser.parse_args().out))


if __name__ == "__main__":
    main()
