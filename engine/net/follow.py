"""What a node shows: the server's frames, interpolated, or one frame exactly.

:class:`Follower` keeps the last few frames a node decoded (every replicated body's
pose in each, as :class:`~engine.net.codec.PoseDecoder` holds them) with the server
time they stand for. A node drawing on its own clock shows :meth:`Follower.at` a time
a little behind the newest frame (``delay``, so there is a frame on each side to
interpolate between: positions linearly, orientations by slerp); a display of a wall
shows one frame exactly (:meth:`Follower.frame`), the one every display draws.

>>> import numpy as np
>>> f = Follower(delay=0.0)
>>> ids = np.array([1], np.uint32)
>>> f.push(1, 0.0, ids, np.array([[0.0, 0, 0, 1, 0, 0, 0]]), wall=10.0)
>>> f.push(2, 0.1, ids, np.array([[1.0, 0, 0, 1, 0, 0, 0]]), wall=10.1)
>>> float(f.at(0.05)[1][0, 0])
0.5
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from engine.rotation import slerp


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
        """(ids, poses, time shown) at server ``time``: between the two frames around it,
        or the nearest frame when ``time`` is outside those held (or the bodies changed
        between them)."""
        frames = self.frames
        newest = frames[-1]
        if time >= newest.time or len(frames) == 1:
            return newest.ids, newest.poses, newest.time
        after = next((i for i, f in enumerate(frames) if f.time > time), len(frames) - 1)
        if after == 0:
            first = frames[0]
            return first.ids, first.poses, first.time
        a, b = frames[after - 1], frames[after]
        if len(a.ids) != len(b.ids) or (a.ids != b.ids).any():
            return b.ids, b.poses, b.time
        alpha = (time - a.time) / (b.time - a.time) if b.time > a.time else 1.0
        poses = np.empty_like(b.poses)
        poses[:, :3] = a.poses[:, :3] + (b.poses[:, :3] - a.poses[:, :3]) * alpha
        poses[:, 3:] = slerp(a.poses[:, 3:], b.poses[:, 3:], alpha)
        return b.ids, poses, time

    def frame(self, number: int) -> Shown | None:
        """Frame ``number`` if it is still held."""
        return next((f for f in self.frames if f.frame == number), None)
