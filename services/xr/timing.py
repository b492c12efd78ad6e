"""Frame-timing arithmetic of a headset display, kept apart from the runtime.

The runtime paces the frame loop (``xrWaitFrame`` blocks until the engine should start
the next frame) and says when that frame will be shown (``predictedDisplayTime``) and
how far apart frames are (``predictedDisplayPeriod``). Physics keeps its own fixed step:
in serial mode :class:`StepPlanner` turns each display period into a whole number of
fixed steps and carries the remainder to the next frame, so simulated time follows the
headset's clock exactly over many frames whatever the two rates are. :class:`FrameCounts`
keeps the figures ``--stats`` reports.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from engine.realtime import CostLog

NS = 1_000_000_000


def seconds(xr_time_ns: int) -> float:
    """An ``XrTime`` or ``XrDuration`` (nanoseconds) in seconds."""
    return xr_time_ns / NS


@dataclass(slots=True)
class StepPlanner:
    """How many fixed steps of ``dt`` each display frame takes (serial mode).

    >>> plan = StepPlanner(0.01)
    >>> [plan.steps(1 / 90) for _ in range(9)]  # 90 Hz frames over 100 Hz physics
    [1, 1, 1, 1, 1, 1, 1, 1, 2]
    >>> plan.simulated, round(plan.carry, 12)
    (0.1, 0.0)
    """

    dt: float
    #: At most this many steps a frame: past it the world runs slow rather than
    #: spending ever longer frames catching up (what is left over is dropped).
    max_steps: int = 8
    carry: float = 0.0
    simulated: float = 0.0
    dropped: float = 0.0
    _taken: int = field(default=0, repr=False)

    def __post_init__(self) -> None:
        if not self.dt > 0.0:
            raise ValueError(f"the physics step must be > 0, got {self.dt!r}")

    def steps(self, period: float) -> int:
        """The steps to take for a display frame ``period`` seconds long."""
        if period < 0.0:
            period = 0.0
        self.carry += period
        n = int((self.carry + 1e-9 * self.dt) // self.dt)
        self.carry -= n * self.dt
        if n > self.max_steps:
            self.dropped += (n - self.max_steps) * self.dt
            n = self.max_steps
        if abs(self.carry) < 1e-12:
            self.carry = 0.0
        self._taken += n
        self.simulated = self._taken * self.dt
        return n


@dataclass(slots=True)
class FrameCounts:
    """What the display did, for ``--stats`` (``xr.*``)."""

    submitted: int = 0
    skipped: int = 0  # frames the runtime said not to draw (shouldRender false)
    late: int = 0  # submitted after their predicted display time
    hud: int = 0  # frames submitted with the HUD's head-locked layer
    render: CostLog = field(default_factory=CostLog)  # seconds per stereo frame drawn
    wait: CostLog = field(default_factory=CostLog)  # seconds blocked in xrWaitFrame

    def ended(self, drawn: bool, end_time_ns: int | None, display_time_ns: int) -> None:
        """A frame ended: drawn or skipped; late when it ended after it was due
        (``end_time_ns`` None: the runtime cannot say what time it is)."""
        if drawn:
            self.submitted += 1
        else:
            self.skipped += 1
        if drawn and end_time_ns is not None and end_time_ns > display_time_ns:
            self.late += 1
