"""Which devices to open: the scene's ``Input { Device }`` blocks and ``--input`` options.

``--input KIND[:ARG]`` adds a device, or replaces the scene's device of the same ID
(a device's ID defaults to its kind)::

    --input osc:9000            OSC on UDP port 9000 (127.0.0.1); osc:0.0.0.0:9000 for the LAN
    --input serial:/dev/ttyUSB0 a serial line (115200 baud); serial:/dev/ttyUSB0@9600
    --input lsl:hand_r,type:Wheel  LSL streams by name or type
    --input desktop             mouse and keys emulate the hands and wheels
    --input openxr              a headset and its controllers

>>> spec = parse_input_option("osc:9001")
>>> spec.id, spec.port, spec.address
('osc', 9001, '127.0.0.1')
>>> parse_input_option("serial:/dev/ttyUSB0@9600").baud
9600
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable

from engine.scene.inputs import INPUT_KINDS, DeviceSpec
from services.input.desktop import DesktopDevice, WindowDevice
from services.input.device import MONOTONIC, Clock, DeviceError, InputDevice

USAGE = ("--input osc:PORT, osc:ADDRESS:PORT, serial:PATH[@BAUD], lsl:STREAM[,STREAM...], "
         "desktop or openxr")


def parse_input_option(text: str) -> DeviceSpec:
    """A ``--input`` value as a DeviceSpec; ValueError says what is expected."""
    kind, _, arg = text.partition(":")
    if kind not in INPUT_KINDS:
        raise ValueError(f"unknown input kind {kind!r} in {text!r}; use {USAGE}")
    try:
        if kind == "osc":
            address, _, port = arg.rpartition(":")
            return DeviceSpec("osc", "osc", port=_port(port), address=address or "127.0.0.1")
        if kind == "serial":
            path, _, baud = arg.partition("@")
            if not path:
                raise ValueError("serial needs the port's path")
            return DeviceSpec("serial", "serial", path=path, baud=int(baud) if baud else 115200)
        if kind == "lsl":
            streams = tuple(s for s in arg.split(",") if s)
            if not streams:
                raise ValueError("lsl needs stream names (or type:TYPE)")
            return DeviceSpec("lsl", "lsl", streams=streams)
    except ValueError as exc:
        raise ValueError(f"bad --input {text!r}: {exc}; use {USAGE}") from exc
    if arg:
        raise ValueError(f"bad --input {text!r}: {kind} takes no argument; use {USAGE}")
    return DeviceSpec(kind, kind)


def input_option(text: str) -> DeviceSpec:
    """:func:`parse_input_option` for argparse (its message reaches the user as it is)."""
    try:
        return parse_input_option(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from exc


def _port(text: str) -> int:
    port = int(text)
    if not 0 <= port <= 65535:
        raise ValueError(f"port {port} is not 0..65535")
    return port


def merge_devices(scene: Iterable[DeviceSpec], overrides: Iterable[DeviceSpec]
                  ) -> list[DeviceSpec]:
    """The scene's devices with the command line's replacing those of the same ID."""
    merged = {d.id: d for d in scene}
    merged.update({d.id: d for d in overrides})
    return list(merged.values())


def make_device(spec: DeviceSpec, window: WindowDevice, clock: Clock = MONOTONIC
                ) -> InputDevice:
    """The device a spec describes (its transport is claimed later, by ``open``)."""
    if spec.kind == "osc":
        from services.input.osc import OscDevice  # python-osc: loaded for an OSC device only

        return OscDevice(spec.id, spec.port, spec.address, clock)
    if spec.kind == "serial":
        from services.input.serial_line import SerialDevice

        return SerialDevice(spec.id, spec.path, spec.baud, spec.line, clock)
    if spec.kind == "lsl":
        from services.input.lsl import LslDevice

        return LslDevice(spec.id, spec.streams, spec.scope, clock)
    if spec.kind == "openxr":
        from services.input.openxr import OpenXRDevice

        return OpenXRDevice(spec.id, clock)
    if spec.kind == "desktop":
        return DesktopDevice(spec.id, window, spec.turns_per_second)
    raise DeviceError(f"unknown input device kind {spec.kind!r}")
