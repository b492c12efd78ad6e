"""Continuous bindings from inputs to actuators (paper section 3.5)."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare


@dataclass(slots=True)
class Controller:
    """A continuous binding from an input to an actuator, with gain and limits.

    ``input`` names a key pair ``"key:Up/Down"``, an axis ``"axis:0"``, a tracked
    device ``"tracker:hand_r"`` or a wheel counter ``"wheel:left"``; ``target``
    names the actuator: ``"motor:<joint id>"``, ``"force:<object id>"`` or
    ``"kinematic:<object id>"``.
    """

    input: str = ""
    target: str = ""
    gain: float = 1.0
    low: float = float("-inf")
    high: float = float("inf")
    value: float = 0.0


def build_controller(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A ``Controller`` block, on an object or an entity of its own (no bound: none)."""
    low, high = v["Low"], v["High"]
    return [Controller(input=v["Input"], target=v["Target"], gain=float(v["Gain"]),
                       low=float("-inf") if low is None else float(low),
                       high=float("inf") if high is None else float(high))]


CONTROLLER_BLOCK = declare(BlockDeclaration(
    "Controller", inside=("Scene", "Object"), build=build_controller,
    doc={"Scene": "an input bound to a motor, force or kinematic target",
         "Object": "input bound to this object"}, keys=(
        Key("ID", "string", "", "name other declarations use to refer to this controller",
            example='"throttle"'),
        Key("Input", "string", None, '"key:A", "key:Up/Down", "axis:DEVICE/NAME", '
            '"button:DEVICE/NAME", "button:ID", "tracker:NAME" or "wheel:NAME" (rad/s)',
            required=True, example='"key:Up/Down"'),
        Key("Target", "string", None, '"motor:JOINT", "force:OBJECT" or "kinematic:OBJECT"',
            required=True, example='"motor:pivot"'),
        Key("Gain", "float", 1.0, "target value per unit of input"),
        Key("Low", "float", None, "lower bound of the target value", example="-90"),
        Key("High", "float", None, "upper bound of the target value", example="90"),
    )))
