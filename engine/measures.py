"""Final values a run reports: what a sweep tabulates and ``--stats`` writes under
``measures``.

A scene names them with ``Measure`` blocks (an object's position, velocity or speed at the
end of the run), a Lua script with ``measure(name, value)`` (the last value given wins).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare

#: What a Measure block can read of its object: position and velocity components, speed.
QUANTITIES = ("x", "y", "z", "vx", "vy", "vz", "speed")


@dataclass(frozen=True, slots=True)
class MeasureSpec:
    """``Measure { ID Object Value }``: the named quantity of an object at the end."""

    id: str
    object: str
    value: str


@dataclass(slots=True)
class Measures:
    """The values scripts reported (``measure(name, value)``), by name."""

    values: dict[str, float] = field(default_factory=dict)

    def set(self, name: str, value: float) -> None:
        if not isinstance(name, str) or not name:
            raise ValueError(f"a measure needs a name, got {name!r}")
        number = math.nan if isinstance(value, bool) else float(value)  # not 1 for true
        if not math.isfinite(number):
            raise ValueError(f"measure {name!r}: {value!r} is not a finite number")
        self.values[name] = number


def quantity(value: str, position: tuple[float, ...], velocity: tuple[float, ...]) -> float:
    """One of :data:`QUANTITIES` from a position and a velocity."""
    if value == "speed":
        return math.sqrt(sum(v * v for v in velocity))
    if value.startswith("v"):
        return float(velocity["xyz".index(value[1])])
    return float(position["xyz".index(value)])


def build_measure(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Measure`` block: a value the run reports at its end (the scene's measures)."""
    ctx.scene("measures").append(MeasureSpec(v["ID"], v["Object"], v["Value"]))
    return []


MEASURE_BLOCK = declare(BlockDeclaration(
    "Measure", inside=("Scene",), build=build_measure, entity=False,
    doc="a value the run reports at its end (--stats measures, colosseum sweep's table)",
    keys=(
        Key("ID", "string", "", "name other declarations use to refer to this measure",
            required=True),
        Key("Object", "ref", None, "the object measured", ref="Object", required=True),
        Key("Value", "enum", "z", "x, y, z (m), vx, vy, vz (m/s) or speed (m/s) at the end "
            "of the run", allowed=QUANTITIES),
    )))
