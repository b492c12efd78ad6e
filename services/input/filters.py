"""Tracker smoothing and prediction, on device timestamps (never on frame counts).

The one-euro filter (Casiez, Roussel and Vogel, CHI 2012) is a low-pass filter whose
cutoff rises with speed: at rest it cuts jitter hard (``min_cutoff`` Hz), in fast motion
it follows closely (``beta`` scales the cutoff with the filtered speed). Positions are
filtered as vectors (one cutoff from the speed, so a straight motion stays straight);
orientations by slerp with the cutoff from the angular speed.

Constant-velocity prediction moves a pose ``lead`` seconds ahead along its velocity
and angular velocity, to hide the latency between a sensor and the frame shown.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from engine.rotation import quat_from_rotation_vector, quat_product, rotation_vector

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

#: Cutoff (Hz) of the filter on the speed the one-euro cutoff is computed from.
DERIVATIVE_CUTOFF = 1.0
#: Shortest time between two samples (s); samples closer than this (one packet) count so.
MIN_DT = 1e-4


def smoothing(cutoff: float, dt: float) -> float:
    """Weight of a new sample in an exponential low-pass of ``cutoff`` Hz after ``dt`` s."""
    tau = 1.0 / (2.0 * math.pi * cutoff)
    return 1.0 / (1.0 + tau / dt)


class OneEuro:
    """One-euro filter of a vector signal (a position: a tuple of floats)."""

    __slots__ = ("min_cutoff", "beta", "value", "speed", "time")

    def __init__(self, min_cutoff: float = 1.0, beta: float = 10.0) -> None:
        self.min_cutoff = min_cutoff
        self.beta = beta
        self.value: tuple[float, ...] | None = None
        self.speed: tuple[float, ...] = ()  # filtered derivative (units per second)
        self.time = 0.0

    def __call__(self, x: Sequence[float], t: float) -> tuple[float, ...]:
        if self.value is None:
            self.value, self.speed, self.time = tuple(x), (0.0,) * len(x), t
            return self.value
        dt = max(t - self.time, MIN_DT)
        self.time = max(t, self.time)
        a = smoothing(DERIVATIVE_CUTOFF, dt)
        self.speed = tuple(s + a * ((xi - v) / dt - s)
                           for s, xi, v in zip(self.speed, x, self.value, strict=True))
        cutoff = self.min_cutoff + self.beta * math.sqrt(sum(s * s for s in self.speed))
        b = smoothing(cutoff, dt)
        self.value = tuple(v + b * (xi - v) for v, xi in zip(self.value, x, strict=True))
        return self.value


class OneEuroRotation:
    """One-euro filter of an orientation: slerp toward each sample, cutoff from angular speed."""

    __slots__ = ("min_cutoff", "beta", "value", "angular_speed", "time")

    def __init__(self, min_cutoff: float = 1.0, beta: float = 10.0) -> None:
        self.min_cutoff = min_cutoff
        self.beta = beta
        self.value: Quat | None = None
        self.angular_speed = 0.0  # rad/s, filtered
        self.time = 0.0

    def __call__(self, q: Quat, t: float) -> Quat:
        if self.value is None:
            self.value, self.time = q, t
            return q
        dt = max(t - self.time, MIN_DT)
        self.time = max(t, self.time)
        turn = rotation_vector(self.value, q)
        rate = math.sqrt(turn[0] ** 2 + turn[1] ** 2 + turn[2] ** 2) / dt
        self.angular_speed += smoothing(DERIVATIVE_CUTOFF, dt) * (rate - self.angular_speed)
        b = smoothing(self.min_cutoff + self.beta * self.angular_speed, dt)
        # slerp by b: the same way round, b of the angle
        self.value = quat_product(quat_from_rotation_vector(
            (turn[0] * b, turn[1] * b, turn[2] * b)), self.value)
        return self.value


class Velocity:
    """Linear and angular velocity from consecutive poses and their timestamps."""

    __slots__ = ("position", "orientation", "time", "linear", "angular")

    def __init__(self) -> None:
        self.position: Vec3 | None = None
        self.orientation: Quat = (1.0, 0.0, 0.0, 0.0)
        self.time = 0.0
        self.linear: Vec3 = (0.0, 0.0, 0.0)
        self.angular: Vec3 = (0.0, 0.0, 0.0)

    def update(self, p: Vec3, q: Quat, t: float) -> None:
        if self.position is not None and t > self.time:
            dt = t - self.time
            x, y, z = self.position
            self.linear = ((p[0] - x) / dt, (p[1] - y) / dt, (p[2] - z) / dt)
            wx, wy, wz = rotation_vector(self.orientation, q)
            self.angular = (wx / dt, wy / dt, wz / dt)
        if self.position is None or t > self.time:
            self.position, self.orientation, self.time = p, q, t


def predict(p: Vec3, q: Quat, linear: Vec3, angular: Vec3, lead: float) -> tuple[Vec3, Quat]:
    """The pose ``lead`` seconds ahead at constant linear (m/s) and angular (rad/s) velocity."""
    turn = quat_from_rotation_vector((angular[0] * lead, angular[1] * lead, angular[2] * lead))
    return ((p[0] + linear[0] * lead, p[1] + linear[1] * lead, p[2] + linear[2] * lead),
            quat_product(turn, q))
