"""Continuous bindings from inputs to actuators (paper section 3.5)."""

from __future__ import annotations

from dataclasses import dataclass


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
