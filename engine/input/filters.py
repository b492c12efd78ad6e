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

import numpy as np

from engine.rotation import quat_multiply, rotation_vector_between, slerp

#: Cutoff (Hz) of the filter on the speed the one-euro cutoff is computed from.
DERIVATIVE_CUTOFF = 1.0
#: Shortest time between two samples (s); samples closer than this (one packet) count so.
MIN_DT = 1e-4


def smoothing(cutoff: float, dt: float) -> float:
    """Weight of a new sample in an exponential low-pass of ``cutoff`` Hz after ``dt`` s."""
    tau = 1.0 / (2.0 * math.pi * cutoff)
    return 1.0 / (1.0 + tau / dt)


class OneEuro:
    """One-euro filter of a vector signal (positions, or any number of channels)."""

    __slots__ = ("min_cutoff", "beta", "value", "speed", "time")

    def __init__(self, min_cutoff: float = 1.0, beta: float = 10.0) -> None:
        self.min_cutoff = min_cutoff
        self.beta = beta
        self.value: np.ndarray | None = None
        self.speed: np.ndarray | None = None  # filtered derivative (units per second)
        self.time = 0.0

    def __call__(self, x: np.ndarray, t: float) -> np.ndarray:
        if self.value is None:
            self.value, self.speed, self.time = x.copy(), np.zeros_like(x), t
            return self.value
        assert self.speed is not None
        dt = max(t - self.time, MIN_DT)
        self.time = max(t, self.time)
        derivative = (x - self.value) / dt
        self.speed = self.speed + smoothing(DERIVATIVE_CUTOFF, dt) * (derivative - self.speed)
        cutoff = self.min_cutoff + self.beta * float(np.linalg.norm(self.speed))
        self.value = self.value + smoothing(cutoff, dt) * (x - self.value)
        return self.value


class OneEuroRotation:
    """One-euro filter of an orientation: slerp toward each sample, cutoff from angular speed."""

    __slots__ = ("min_cutoff", "beta", "value", "angular_speed", "time")

    def __init__(self, min_cutoff: float = 1.0, beta: float = 10.0) -> None:
        self.min_cutoff = min_cutoff
        self.beta = beta
        self.value: np.ndarray | None = None
        self.angular_speed = 0.0  # rad/s, filtered
        self.time = 0.0

    def __call__(self, q: np.ndarray, t: float) -> np.ndarray:
        if self.value is None:
            self.value, self.time = q.copy(), t
            return self.value
        dt = max(t - self.time, MIN_DT)
        self.time = max(t, self.time)
        rate = float(np.linalg.norm(rotation_vector_between(self.value, q))) / dt
        self.angular_speed += smoothing(DERIVATIVE_CUTOFF, dt) * (rate - self.angular_speed)
        cutoff = self.min_cutoff + self.beta * self.angular_speed
        self.value = slerp(self.value, q, smoothing(cutoff, dt))
        return self.value


class Velocity:
    """Linear and angular velocity from consecutive poses and their timestamps."""

    __slots__ = ("position", "orientation", "time", "linear", "angular")

    def __init__(self) -> None:
        self.position: np.ndarray | None = None
        self.orientation: np.ndarray | None = None
        self.time = 0.0
        self.linear = np.zeros(3)
        self.angular = np.zeros(3)

    def update(self, p: np.ndarray, q: np.ndarray, t: float) -> None:
        if self.position is not None and self.orientation is not None and t > self.time:
            dt = t - self.time
            self.linear = (p - self.position) / dt
            self.angular = rotation_vector_between(self.orientation, q) / dt
        if self.position is None or t > self.time:
            self.position, self.orientation, self.time = p, q, t


def predict(p: np.ndarray, q: np.ndarray, linear: np.ndarray, angular: np.ndarray,
            lead: float) -> tuple[np.ndarray, np.ndarray]:
    """The pose ``lead`` seconds ahead at constant linear (m/s) and angular (rad/s) velocity."""
    turn = angular * lead
    angle = float(np.linalg.norm(turn))
    if angle < 1e-12:
        return p + linear * lead, q
    axis = turn / angle
    half = 0.5 * angle
    step = np.array([math.cos(half), *(axis * math.sin(half))])
    return p + linear * lead, quat_multiply(step, q)
