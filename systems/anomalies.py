"""The anomalies plugin: a run's visual anomalies (engine.anomalies), switched from the scene,
Lua, any input binding and Python, ramped frame by frame, and told when switched.

It owns the :class:`engine.anomalies.Anomalies` resource, declares the scene's anomaly
blocks in it, and each frame (POST_PHYSICS, after input and scripts) switches those whose
``Input`` binding was pressed and moves every onset ramp by the frame's time step; the
render system draws what it finds there. Every switch and change of severity is an
:class:`engine.events.AnomalySwitched` event (a session log subscribes to it) and a marker
on the Output streams (``anomaly ID on KIND Key=value ...``, OSC or LSL, timestamped
there).

Python systems switch anomalies through the resource::

    engine.resource(Anomalies).set("hemianopia", "python", enabled=True,
                                   values={"Side": "right", "Sparing": 5})
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from typing import TYPE_CHECKING

from engine.anomalies import Anomalies, AnomalySpec
from engine.events import AnomalySwitched, CustomEvent
from engine.system import Phase, PluginName, System
from services.input import Binding, InputState, parse_binding

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.anomalies")


@dataclass(slots=True)
class _Switch:
    """An anomaly's Input binding and where its value stood last frame."""

    anomaly: str
    binding: Binding
    last: float = 0.0


def marker_text(event: AnomalySwitched) -> str:
    """The marker an Output stream gets for a switch: ``anomaly ID on|off KIND Key=value ...
    onset=S source=...`` (one line; vectors as comma-separated numbers)."""
    def show(value: object) -> str:
        if isinstance(value, tuple):
            return ",".join(f"{v:g}" for v in value)
        return f"{value:g}" if isinstance(value, float) else str(value)

    severity = " ".join(f"{key}={show(value)}" for key, value in event.severity)
    return (f"anomaly {event.anomaly} {'on' if event.enabled else 'off'} {event.kind} "
            f"{severity} onset={event.onset:g} source={event.source}")


class AnomalySystem(System):
    """Switches anomalies from their inputs and ramps them (see the module doc)."""

    phase = Phase.POST_PHYSICS
    reads = ()
    writes = ()

    def __init__(self, switches: bool = True) -> None:
        self.anomalies = Anomalies()
        #: False on a join node: its keys go to the server, which switches and tells it
        self.switches = switches
        self._switches: list[_Switch] = []

    def setup(self, engine: Engine) -> None:
        def tell(event: AnomalySwitched) -> None:
            engine.events.emit(event)
            engine.events.emit(CustomEvent("marker", marker_text(event)))

        self.anomalies.emit = tell
        engine.insert_resource(self.anomalies)
        for spec in _scene_anomalies(engine):
            self.anomalies.declare(spec.id, spec.values, spec.kind, False, spec.onset, spec.eye)
            if spec.enabled:  # on from the first frame, told as the scene's switch
                self.anomalies.get(spec.id).level = 1.0
                self.anomalies.switch(spec.id, True, "scene")
            if spec.input is not None and self.switches:
                self._bind(spec)

    def _bind(self, spec: AnomalySpec) -> None:
        try:
            binding = parse_binding(spec.input or "")
            if binding.kind in ("tracker", "wheel"):
                raise ValueError(f"a {binding.kind} cannot switch an anomaly; use key:NAME, "
                                 "button:DEVICE/NAME or axis:DEVICE/NAME")
        except ValueError as exc:
            log.error("%s: anomaly %r: Input %s; it is switched from Lua and Python only",
                      spec.origin, spec.id, exc)
            return
        self._switches.append(_Switch(spec.id, binding))

    def run(self, engine: Engine, dt: float) -> None:
        inputs = engine.try_resource(InputState)
        if inputs is not None:
            for switch in self._switches:
                self._read(switch, inputs)
        self.anomalies.step(dt)

    def _read(self, switch: _Switch, inputs: InputState) -> None:
        """A press toggles; of two keys (key:A/B) the first switches on, the second off."""
        value = inputs.read(switch.binding)
        if not isinstance(value, float):
            return
        last, switch.last = switch.last, value
        source = f"input:{switch.binding.text}"
        if value > 0.5 >= last:
            two_keys = switch.binding.kind == "key" and len(switch.binding.parts) == 2
            enabled = True if two_keys else not self.anomalies.get(switch.anomaly).enabled
            self.anomalies.switch(switch.anomaly, enabled, source)
        elif value < -0.5 <= last:
            self.anomalies.switch(switch.anomaly, False, source)


def _scene_anomalies(engine: Engine) -> list[AnomalySpec]:
    from engine.scene import SceneIds

    ids = engine.try_resource(SceneIds)
    return [] if ids is None else ids.spec.anomalies


class AnomaliesPlugin:
    """Visual anomalies of a stroke (``requestPlugin("anomalies")``); loads the input plugin
    its switches read."""

    name = PluginName.ANOMALIES

    def __init__(self, switches: bool = True) -> None:
        self.switches = switches

    def build(self, engine: Engine) -> None:
        from systems.input import InputPlugin

        engine.add_plugin(InputPlugin())
        engine.add_system(AnomalySystem(self.switches))
