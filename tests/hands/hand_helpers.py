"""A virtual-hand rig for tests: a scene, trackers moved along functions of time, gloves."""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from components import HandState, Transform, Visual
from engine import EngineConfig, Phase, system
from engine.scene import instantiate, spec_from_text
from services.input import InputHub
from services.input.events import Button, TrackerPose
from systems import create_engine

Path3 = Callable[[float], np.ndarray]
IDENTITY = (1.0, 0.0, 0.0, 0.0)
G = 9.81


@dataclass
class Rig:
    """An engine running ``scene`` whose trackers follow ``paths`` (time -> position) and
    whose gloves are down while ``gloves`` (time -> bool) say so, turned as ``turns`` say.
    Tracker poses carry the path's velocity (a central difference), as a tracking system
    reports one; the input layer derives their angular velocity from the turns."""

    scene: str
    folder: Path
    backend: str = "ode"
    mode: str = "serial"
    dt: float = 1.0 / 120.0
    paths: dict[str, Path3] = field(default_factory=dict)
    #: tracker -> time -> its orientation (w, x, y, z; default the identity)
    turns: dict[str, Callable[[float], tuple[float, ...]]] = field(default_factory=dict)
    gloves: dict[str, Callable[[float], bool]] = field(default_factory=dict)
    options: dict[str, object] = field(default_factory=dict)

    def __post_init__(self) -> None:
        cfg = EngineConfig(backend=self.backend, mode=self.mode, fast=True, dt=self.dt,
                           content_dir=self.folder, options=dict(self.options))
        self.engine = create_engine(cfg)
        self.ids = instantiate(self.engine, spec_from_text(self.scene, self.folder))
        self.engine.start()
        hub = self.engine.resource(InputHub)
        hub.clock = lambda: self.engine.time  # the devices' clock: simulated time
        self.hub = hub
        self.pressed: dict[str, bool] = {}

        @system(Phase.INPUT, before=("InputSystem",))
        def devices(e, dt):
            t = e.time
            for name, path in self.paths.items():
                h = 1e-4
                v = (path(t + h) - path(t - h)) / (2 * h)
                turn = self.turns.get(name)
                hub.inject(TrackerPose(name, tuple(path(t)), IDENTITY if turn is None else
                                       tuple(turn(t)), tuple(v), t))
            for glove, down in self.gloves.items():
                now = bool(down(t))
                if now != self.pressed.get(glove, False):
                    self.pressed[glove] = now
                    hub.inject(Button(glove, "pinch", now, t))

        self.engine.add_system(devices)

    def run(self, seconds: float) -> None:
        self.engine.run(seconds=seconds)

    def position(self, name: str) -> np.ndarray:
        return self.engine.world.component_for_entity(self.ids[name], Transform).position.copy()

    def orientation(self, name: str) -> np.ndarray:
        return self.engine.world.component_for_entity(self.ids[name],
                                                      Transform).orientation.copy()

    def spin(self, name: str) -> np.ndarray:
        return self.engine.world.component_for_entity(self.ids[name],
                                                      Transform).angular_velocity.copy()

    def state(self, name: str) -> HandState:
        return self.engine.world.component_for_entity(self.ids[name], HandState)

    def visual(self, name: str) -> Visual:
        return self.engine.world.component_for_entity(self.ids[name], Visual)

    def every_frame(self, fn: Callable, phase: Phase = Phase.POST_PHYSICS,
                    after: tuple[str, ...] = ()) -> None:
        self.engine.add_system(system(phase, reads=(Transform, HandState, Visual),
                                      after=after)(fn))

    def close(self) -> None:
        self.engine.close()

    def __enter__(self) -> Rig:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


def ramp(start: tuple[float, ...], end: tuple[float, ...], t0: float, t1: float) -> Path3:
    """Still at ``start`` until t0, then at constant speed to ``end`` at t1, then still.
    (Smooth enough for the drive: a step in velocity, not in position.)"""
    a, b = np.asarray(start, float), np.asarray(end, float)

    def path(t: float) -> np.ndarray:
        s = min(max((t - t0) / (t1 - t0), 0.0), 1.0)
        return a + (b - a) * s

    return path


def waypoints(*points: tuple[float, tuple[float, ...]]) -> Path3:
    """Piecewise linear through (time, position) points, still before and after."""
    times = np.array([p[0] for p in points])
    spots = np.array([p[1] for p in points], float)

    def path(t: float) -> np.ndarray:
        return np.array([np.interp(t, times, spots[:, k]) for k in range(3)])

    return path


def between(t0: float, t1: float = float("inf")) -> Callable[[float], bool]:
    return lambda t: t0 <= t < t1


def about_y(angle: Callable[[float], float]) -> Callable[[float], tuple[float, ...]]:
    """Orientations turning by ``angle(t)`` radians about +Y (the one turn pymunk's plane
    has too)."""
    return lambda t: (math.cos(angle(t) / 2), 0.0, math.sin(angle(t) / 2), 0.0)
