"""Buoyancy: a content folder's own system with its own scene block.

``Object { ... Buoyancy { Density 1000 Level 0.5 Drag 4 } }`` makes an object float in a
pool whose surface is at height ``Level``: each frame it is pushed up by the weight of
the liquid it displaces (Archimedes), and the part under water is slowed by a linear
drag. The block is declared here, beside its component, with engine.scene.blocks: the
scene checks it (``colosseum check content/pool``), documents it (``colosseum keys
Buoyancy --content content/pool``) and a saved state writes it back.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from components import Physical, Transform
from engine import Phase, System
from engine.physics.commands import ApplyForce
from engine.scene.blocks import key, scene_block

G = 9.81


@scene_block("Buoyancy", doc="floats in a pool of liquid (content/pool/systems/buoyancy.py)")
@dataclass
class Buoyancy:
    density: float = key(1000.0, "kg/m³, the liquid's density", low=0.0, high=20000.0)
    level: float = key(0.0, "m, the height (z) of the liquid's surface")
    drag: float = key(4.0, "N·s/m per kg, how much the liquid slows what is in it", low=0.0)


def submerged(kind: str, size: tuple[float, ...], z: float, level: float) -> float:
    """The volume (m³) of a shape centred at height ``z`` below the surface ``level``: a
    sphere's cap, or an upright box's or cylinder's slice."""
    if kind == "sphere":
        r = size[0]
        h = min(max(level - (z - r), 0.0), 2 * r)
        return math.pi * h * h * (3 * r - h) / 3
    if kind == "box":
        sx, sy, sz = size
        return sx * sy * min(max(level - (z - sz / 2), 0.0), sz)
    if kind == "cylinder":
        r, height = size[0], size[1]
        return math.pi * r * r * min(max(level - (z - height / 2), 0.0), height)
    return 0.0


def volume(kind: str, size: tuple[float, ...]) -> float:
    return submerged(kind, size, 0.0, math.inf)


class BuoyancySystem(System):
    """Pushes every object with a Buoyancy block up by the liquid it displaces."""

    phase = Phase.PRE_PHYSICS
    reads = (Buoyancy, Transform, Physical)
    writes = ()

    def run(self, engine, dt: float) -> None:
        for entity, (pool, t, body) in engine.world.get_components(Buoyancy, Transform,
                                                                   Physical):
            shape = body.shapes[0]
            under = submerged(shape.kind, tuple(shape.size), float(t.position[2]), pool.level)
            if under <= 0.0:
                continue
            share = under / volume(shape.kind, tuple(shape.size))
            mass = body.mass or 1.0
            lift = pool.density * under * G
            drag = [-pool.drag * mass * share * float(v) for v in t.linear_velocity]
            engine.physics.push(ApplyForce(entity, (drag[0], drag[1], lift + drag[2])))


def build(engine) -> None:
    engine.add_system(BuoyancySystem())
