"""Light sources."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from components.transform import Transform


@dataclass(slots=True)
class Light:
    """A light source: directional, point or spot."""

    kind: str = "directional"
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    intensity: float = 1.0
    direction: tuple[float, float, float] = (0.3, 0.5, -1.0)
    cutoff: float = 30.0
    shadows: bool = True


#: The kinds of light a scene may declare.
LIGHT_TYPES = ("directional", "point", "spot")


def build_light(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Light`` block: an entity with its place and the light."""
    return [Transform(v["Position"]),
            Light(kind=v["Type"], color=_floats(v["Color"]), intensity=float(v["Intensity"]),
                  direction=_floats(v["Direction"]), cutoff=float(v["Cutoff"]),
                  shadows=bool(v["Shadows"]))]


def _floats(value: Any) -> Any:
    return tuple(float(x) for x in value)


LIGHT_BLOCK = declare(BlockDeclaration(
    "Light", inside=("Scene",), build=build_light, doc="a light source", keys=(
        Key("ID", "string", "", "name other declarations use to refer to this light",
            example='"sun"'),
        Key("Type", "enum", "directional", "directional, point or spot", allowed=LIGHT_TYPES),
        Key("Position", "vec3", (0.0, 0.0, 10.0), "world frame (point and spot lights)",
            unit="m"),
        Key("Direction", "vec3", (0.3, 0.5, -1.0), "world frame (directional and spot "
            "lights)"),
        Key("Color", "vec3", (1.0, 1.0, 1.0), "RGB, 0..1"),
        Key("Intensity", "float", 1.0, "colour multiplier"),
        Key("Cutoff", "float", 30.0, "spot cone half-angle, degrees"),
        Key("Shadows", "bool", 1, "1: casts shadows (one light does)"),
    )))
