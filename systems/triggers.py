"""Triggers: sensor volumes that tell which bodies enter and leave them, colliding with none.

A trigger (``PhysicalAttributes { Trigger 1 ... }``, a glTF ``trigger``) is a body in
collision category 0, so the backends never make a contact for it. After each step
this system tests every body whose category meets the trigger's ``Mask`` against the
trigger's shapes: a body counts as inside while its bounding sphere (centred on its
position, reaching its farthest shape) overlaps one of them. Spheres, boxes, capsules,
cylinders and planes are tested exactly against that sphere; a mesh or hull trigger by
its bounding box.

Each crossing is told once, as a :class:`TriggerEvent` for Python systems and as the
custom event ``"trigger"`` for Lua::

    on("trigger", function(e) print(e.trigger, e.other, e.entered) end)
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from components import Name, Physical, Shape, Transform, Trigger
from engine.events import CustomEvent
from engine.rotation import quat_to_matrix
from engine.system import Phase, PluginName, System

if TYPE_CHECKING:
    from engine.app import Engine


@dataclass(frozen=True, slots=True)
class TriggerEvent:
    """Body ``other`` entered (or left) trigger ``trigger`` (entity ids)."""

    trigger: int
    other: int
    entered: bool


def bounding_radius(shapes: list[Shape]) -> float:
    """How far from a body's origin its shapes reach (planes excluded: they are static)."""
    reach = 0.0
    for s in shapes:
        offset = float(np.linalg.norm(s.offset))
        if s.kind == "sphere":
            r = s.size[0]
        elif s.kind == "box":
            r = float(np.linalg.norm(s.size)) / 2
        elif s.kind in ("capsule", "cylinder"):
            half = s.size[1] / 2
            r = s.size[0] + half if s.kind == "capsule" else float(np.hypot(s.size[0], half))
        elif s.vertices is not None and len(s.vertices):
            r = float(np.linalg.norm(s.vertices, axis=1).max())
        else:
            continue
        reach = max(reach, offset + r)
    return reach


def overlaps(shape: Shape, points: np.ndarray, radii: np.ndarray) -> np.ndarray:
    """Which spheres (``points`` in the shape's frame, ``radii``) overlap ``shape``."""
    p = points
    if shape.kind == "sphere":
        return np.linalg.norm(p, axis=1) <= shape.size[0] + radii
    if shape.kind in ("box", "mesh", "hull"):
        if shape.kind == "box":
            centre, half = np.zeros(3), np.asarray(shape.size) / 2
        else:  # a mesh trigger by its bounding box
            lo, hi = shape.vertices.min(axis=0), shape.vertices.max(axis=0)
            centre, half = (lo + hi) / 2, (hi - lo) / 2
        gap = np.maximum(np.abs(p - centre) - half, 0.0)
        return np.linalg.norm(gap, axis=1) <= radii
    radius, half = shape.size[0], shape.size[1] / 2
    if shape.kind == "capsule":
        axial = p[:, 2] - np.clip(p[:, 2], -half, half)
        return np.hypot(np.hypot(p[:, 0], p[:, 1]), axial) <= radius + radii
    radial = np.maximum(np.hypot(p[:, 0], p[:, 1]) - radius, 0.0)
    axial = np.maximum(np.abs(p[:, 2]) - half, 0.0)
    return np.hypot(radial, axial) <= radii


class TriggerSystem(System):
    """After the step: who is inside each trigger now; crossings told as events."""

    phase = Phase.POST_PHYSICS
    reads = (Name, Physical, Transform, Trigger)
    writes = (Trigger,)

    def __init__(self) -> None:
        self._radii: dict[int, tuple[int, float]] = {}  # entity -> (id(shapes), radius)

    def run(self, engine: Engine, dt: float) -> None:
        world = engine.world
        triggers = world.get_components(Trigger, Transform, Physical)
        if not triggers:
            return
        bodies = [(e, t, p) for e, (t, p) in world.get_components(Transform, Physical)
                  if p.category and p.kind != "static"]
        keys = np.array([e for e, _, _ in bodies], np.int64)
        centres = np.array([t.position for _, t, _ in bodies]).reshape(-1, 3)
        radii = np.array([self._radius(e, p) for e, _, p in bodies])
        categories = np.array([p.category for _, _, p in bodies], np.int64)
        for entity, (trigger, t, physical) in triggers:
            near = (categories & trigger.mask) != 0
            inside = self._inside(physical.shapes, t, centres[near], radii[near])
            now = set(keys[near][inside].tolist())
            for other in sorted(now - trigger.inside):
                self._tell(engine, entity, other, True)
            for other in sorted(trigger.inside - now):
                self._tell(engine, entity, other, False)
            trigger.inside = now

    def _radius(self, entity: int, physical: Physical) -> float:
        key = id(physical.shapes)
        found = self._radii.get(entity)
        if found is None or found[0] != key:
            found = self._radii[entity] = (key, bounding_radius(physical.shapes))
        return found[1]

    @staticmethod
    def _inside(shapes: list[Shape], t: Transform, centres: np.ndarray,
                radii: np.ndarray) -> np.ndarray:
        hit = np.zeros(len(centres), bool)
        if not len(centres):
            return hit
        rotation = quat_to_matrix(np.asarray(t.orientation))
        local = (centres - t.position) @ rotation  # into the trigger's frame
        for s in shapes:
            if s.kind == "plane":  # world frame: normal and offset
                normal, d = np.asarray(s.size[:3]), s.size[3]
                hit |= centres @ normal - d <= radii
                continue
            shape_rotation = quat_to_matrix(np.asarray(s.rotation))
            hit |= overlaps(s, (local - np.asarray(s.offset)) @ shape_rotation, radii)
        return hit

    @staticmethod
    def _tell(engine: Engine, trigger: int, other: int, entered: bool) -> None:
        engine.events.emit(TriggerEvent(trigger, other, entered))
        names = [engine.world.try_component(e, Name) for e in (trigger, other)]
        engine.events.emit(CustomEvent("trigger", {
            "trigger": names[0].id if names[0] else trigger,
            "other": names[1].id if names[1] else other, "entered": entered}))


class TriggersPlugin:
    """Tells scripts and systems which bodies enter and leave triggers."""

    name = PluginName.TRIGGERS

    def build(self, engine: Engine) -> None:
        engine.add_system(TriggerSystem())
