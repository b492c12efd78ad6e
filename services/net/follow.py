"""What a node shows: the server's frames, interpolated, or one frame exactly.

:class:`Follower` keeps the last few frames a node decoded (every replicated body's
pose in each, as :class:`~services.net.codec.PoseDecoder` holds them) with the server
time they stand for. A node drawing on its own clock shows :meth:`Follower.at` a time
a little behind the newest frame (``delay``, so there is a frame on each side to
interpolate between: positions linearly, orientations by slerp); a display of a wall
shows one frame exactly (:meth:`Follower.frame`), the one every display draws.

>>> import numpy as np
>>> f = Follower(delay=0.0)
>>> ids = np.array([1], np.uint32)
>>> f.push(1, 0.0, ids, np.array([[0.0, 0, 0, 1, 0, 0, 0]]), wall=10.0)
>>> f.push(2, 0.1, ids, np.array([[1.0, 0, 0, 1, 0, 0, 0]]), wall=10.1)
>>> ids, rows, shown = f.at(0.05)
>>> float(rows[0, 0]), float(rows[0, 7]), shown      # x, its velocity (m/s), the time
(0.5, 10.0, 0.05)
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from engine.rotation import rotation_vector_between, slerp


@dataclass(frozen=True, slots=True)
class Shown:
    """One decoded frame: every replicated body (``ids`` sorted) and its pose."""

    frame: int
    time: float
    ids: np.ndarray
    poses: np.ndarray


class Follower:
    """The frames a node holds and the server time it shows."""

    #: Frames kept (a display may be asked for one a few frames old).
    KEEP = 16

    def __init__(self, delay: float) -> None:
        self.delay = delay
        self.frames: deque[Shown] = deque(maxlen=self.KEEP)
        #: (server time, wall time it arrived) of the newest frame, for the clock.
        self._anchor: tuple[float, float] | None = None

    def reset(self) -> None:
        self.frames.clear()
        self._anchor = None

    def push(self, frame: int, time: float, ids: np.ndarray, poses: np.ndarray,
             wall: float) -> None:
        """A decoded frame (``poses`` is copied)."""
        self.frames.append(Shown(frame, time, ids, poses.copy()))
        if self._anchor is None or time >= self._anchor[0]:
            self._anchor = (time, wall)

    def server_time(self, wall: float) -> float | None:
        """The server time now, by the newest frame and the wall clock since it came,
        held back by ``delay``; never past the newest frame."""
        if self._anchor is None:
            return None
        time, arrived = self._anchor
        return min(time, time - self.delay + max(wall - arrived, 0.0))

    def at(self, time: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(ids, rows, time shown) at server ``time``: between the two frames around it,
        or the nearest frame when ``time`` is outside those held. A row is a pose and the
        velocities that take the frame before to the frame after (zero where the bodies
        changed between them), ``x y z qw qx qy qz vx vy vz wx wy wz`` as a pose table's."""
        frames = self.frames
        after = next((i for i, f in enumerate(frames) if f.time > time), len(frames) - 1)
        b = frames[after]
        a = frames[after - 1] if after > 0 else b
        rows = np.zeros((len(b.ids), 13))
        if a is b or len(a.ids) != len(b.ids) or (a.ids != b.ids).any() or b.time <= a.time:
            rows[:, :7] = b.poses
            return b.ids, rows, b.time
        span = b.time - a.time
        alpha = min(max((time - a.time) / span, 0.0), 1.0)
        rows[:, :3] = a.poses[:, :3] + (b.poses[:, :3] - a.poses[:, :3]) * alpha
        rows[:, 3:7] = slerp(a.poses[:, 3:], b.poses[:, 3:], alpha)
        rows[:, 7:10] = (b.poses[:, :3] - a.poses[:, :3]) / span
        rows[:, 10:13] = rotation_vector_between(a.poses[:, 3:], b.poses[:, 3:]) / span
        return b.ids, rows, a.time + alpha * span

    def frame(self, number: int) -> Shown | None:
        """Frame ``number`` if it is still held."""
        return next((f for f in self.frames if f.frame == number), None)
