"""Outputs: named engine values sent every frame over OSC or LSL, and task markers.

Where force feedback starts (the paper's future work): a wheel's torque, a hand's
contact force or any value a system sets goes out each frame to whatever listens —
a motor controller, a logger, LabRecorder. ``Output { Kind "osc" Port 9001 Value
"wheel:left" }`` sends::

    /colosseum/out/wheel/left   value...        (one message per value, every frame)
    /colosseum/marker           "text"          (task events: grasps, anomaly switches)

With ``Kind "lsl"`` each value is a float32 stream named ``<Name>-<value>`` (type
``Colosseum``), and markers go to the string stream ``<Name>-markers`` (type
``Markers``), timestamped on LSL's clock.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from typing import Any, Protocol

from services.input.device import DeviceError
from services.input.lsl import load_pylsl

log = logging.getLogger("colosseum.input")

OUT_PREFIX = "/colosseum/out/"
MARKER_ADDRESS = "/colosseum/marker"


class Publisher(Protocol):
    """Where an Output block's values go."""

    def send(self, values: dict[str, Sequence[float]]) -> None: ...

    def marker(self, text: str, timestamp: float | None = None) -> None: ...

    def close(self) -> None: ...


def value_address(name: str) -> str:
    """``"wheel:left"`` -> ``"/colosseum/out/wheel/left"``."""
    return OUT_PREFIX + name.replace(":", "/")


class OscOutput:
    """Values and markers as OSC messages to one UDP address."""

    def __init__(self, address: str, port: int) -> None:
        from pythonosc.udp_client import SimpleUDPClient  # loaded for an OSC output only

        self.target = f"{address}:{port}"
        self._client = SimpleUDPClient(address, port)
        self._failed = False

    def send(self, values: dict[str, Sequence[float]]) -> None:
        for name, value in values.items():
            self._send(value_address(name), [float(v) for v in value])

    def marker(self, text: str, timestamp: float | None = None) -> None:
        self._send(MARKER_ADDRESS, text)

    def _send(self, address: str, payload: Any) -> None:
        try:
            self._client.send_message(address, payload)
        except OSError as exc:  # an unreachable address: say so once, keep running
            if not self._failed:
                self._failed = True
                log.error("output to %s failed: %s (further failures are not reported)",
                          self.target, exc)

    def close(self) -> None:
        self._client.close()


#: The process's LSL outlets by stream name, type, channels and format: engines built one
#: after another in one process (an experiment's trials, --watch restarts) publish on the
#: same streams, so a recorder (LabRecorder) keeps one stream instead of losing it.
_OUTLETS: dict[tuple[str, str, int, int], Any] = {}


def _outlet(lsl: Any, name: str, kind: str, channels: int, fmt: int) -> Any:
    key = (name, kind, channels, fmt)
    outlet = _OUTLETS.get(key)
    if outlet is None:
        info = lsl.StreamInfo(name, kind, channels, lsl.IRREGULAR_RATE, fmt, name)
        outlet = _OUTLETS[key] = lsl.StreamOutlet(info)
    return outlet


class LslOutput:
    """One float32 outlet per value (made at its first frame) and a marker outlet (both
    kept for the process: :data:`_OUTLETS`)."""

    def __init__(self, name: str, scope: str = "site") -> None:
        self.name = name
        self._lsl = load_pylsl(scope)
        self._outlets: dict[str, Any] = {}
        lsl = self._lsl
        self._markers = _outlet(lsl, f"{name}-markers", "Markers", 1, lsl.cf_string)

    def send(self, values: dict[str, Sequence[float]]) -> None:
        lsl = self._lsl
        for key, value in values.items():
            outlet = self._outlets.get(key)
            if outlet is None:
                outlet = self._outlets[key] = _outlet(lsl, f"{self.name}-{key}", "Colosseum",
                                                      len(value), lsl.cf_float32)
            if len(value) != outlet.channel_count:
                log.error("output %s: %d values, its stream has %d channels; not sent", key,
                          len(value), outlet.channel_count)
                continue
            outlet.push_sample([float(v) for v in value])

    def marker(self, text: str, timestamp: float | None = None) -> None:
        """A marker stamped ``timestamp`` (LSL clock, s), else now."""
        if timestamp is None:
            self._markers.push_sample([text])
        else:
            self._markers.push_sample([text], timestamp)

    def close(self) -> None:
        self._outlets.clear()
        self._markers = None


def make_publisher(kind: str, address: str, port: int, name: str,
                   scope: str = "site") -> Publisher:
    """The publisher of an Output block; DeviceError when its transport cannot start."""
    if kind == "osc":
        try:
            return OscOutput(address, port)
        except OSError as exc:
            raise DeviceError(f"output to {address}:{port} (osc): {exc}") from exc
    if kind == "lsl":
        try:
            return LslOutput(name, scope)
        except DeviceError as exc:
            raise DeviceError(f"output {name!r} (lsl): {exc}") from exc
    raise DeviceError(f"unknown output kind {kind!r} (osc or lsl)")
