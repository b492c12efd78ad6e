"""The body an entity has in the dynamics backend, and its surface material."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from components.shape import Shape


class BodyKind(StrEnum):
    """How a body moves: by the solver, not at all, or along a path it is given."""

    DYNAMIC = "dynamic"
    STATIC = "static"
    KINEMATIC = "kinematic"


@dataclass(slots=True)
class MaterialProps:
    """Surface response of a body: Coulomb friction, restitution, softness."""

    name: str = "default"
    friction: float = 0.5
    bounce: float = 0.0
    bounce_velocity: float = 0.1
    softness: float = 0.0
    density: float = 1000.0
    contact_sound: str | None = None


def build_material(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Material`` block: surface properties objects name by ID (built before them)."""
    ctx.check_mass("Density")
    name = str(v["ID"])
    ctx.scene("materials")[name] = MaterialProps(
        name=name, friction=float(v["Friction"]), bounce=float(v["Bounce"]),
        bounce_velocity=float(v["BounceVelocity"]), softness=float(v["Softness"]),
        density=float(v["Density"]),
        contact_sound=ctx.sound_file("ContactSound", "the material stays silent"))
    if ctx.given("Density"):  # its objects' masses come from it
        ctx.scene("dense_materials").add(name)
    return []


_MATERIAL = MaterialProps()
MATERIAL_BLOCK = declare(BlockDeclaration(
    "Material", inside=("Scene",), build=build_material, entity=False, first=True,
    doc="surface properties", keys=(
        Key("ID", "string", None, "name or number objects use to refer to it", required=True,
            example='"wood"'),
        Key("Friction", "float", _MATERIAL.friction, "Coulomb coefficient"),
        Key("Bounce", "float", _MATERIAL.bounce, "restitution 0..1"),
        Key("BounceVelocity", "float", _MATERIAL.bounce_velocity,
            "m/s below which nothing bounces"),
        Key("Softness", "float", _MATERIAL.softness, "contact softness (0 = hard)"),
        Key("Density", "float", _MATERIAL.density, "kg/m^3"),
        Key("ContactSound", "asset", None, "played on impacts", example='"sounds/knock.wav"'),
    )))


@dataclass(slots=True)
class Physical:
    """The body an entity has in the dynamics backend.

    ``kind`` is a :class:`BodyKind`. ``mass`` wins over the material density when
    both are given. ``category``/``mask`` filter collisions as bit sets: two bodies
    collide when each one's category meets the other's mask.

    ``center_of_mass`` (m, body frame) and ``inertia`` (principal moments about the
    centre of mass, kg·m², along the axes ``inertia_rotation`` turns the body frame's
    onto) are a modelling tool's numbers for a body whose mass is not spread like its
    shapes (a weighted door, a hollow can); None: from the shapes (with a given centre
    alone, the shapes' inertia about their own centroid, moved there).
    """

    kind: str = BodyKind.DYNAMIC
    mass: float | None = 1.0
    shapes: list[Shape] = field(default_factory=lambda: [Shape()])
    material: MaterialProps = field(default_factory=MaterialProps)
    linear_damping: float = 0.0
    angular_damping: float = 0.0
    can_sleep: bool = True
    category: int = 1
    mask: int = 0xFFFFFFFF
    gravity: bool = True
    #: Gravity on this body times this (KHR's gravityFactor): 0.5 half, -0.5 it rises at
    #: half g; ``gravity`` False switches it off whatever the factor.
    gravity_factor: float = 1.0
    center_of_mass: tuple[float, float, float] | None = None
    inertia: tuple[float, float, float] | None = None
    inertia_rotation: tuple[float, float, float, float] = (1.0, 0.0, 0.0, 0.0)
