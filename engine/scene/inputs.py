"""The scene's ``Input`` and ``Output`` blocks as plain specs (read by :mod:`services.input`).

``Input { Device {...} Tracker {...} Wheel {...} Button {...} }`` names the devices to
open and how each tracker, wheel counter and button is calibrated; ``Output {...}``
names engine values sent out every frame. The schema checks types; this module checks
what needs more than one key (a tracker naming a device that is not declared, two
devices with one ID, a serial line with an unknown field, an axis map that is not a
permutation) and reports it at the author's line, before anything opens.

>>> axes_map("x -z y")
((0, 1.0), (2, -1.0), (1, 1.0))
>>> line_fields("{name} {count}")
('name', 'count')
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

import engine.scene.schema as sc
from engine.rotation import IDENTITY, euler_to_quat
from engine.scene.db import Block, Value
from engine.scene.diagnostics import Loc, Reporter, suggest

#: The trackers and gloves the desktop device emulates (the mouse drives one hand at a
#: time, its left button is that hand's glove ``pinch``), known to every scene.
DESKTOP_TRACKERS = ("hand_l", "hand_r")
DESKTOP_GLOVES = ("glove_l", "glove_r")

#: Fields a serial ``Line`` may hold, and what each one reads.
LINE_FIELDS = ("name", "count", "button", "pressed", "axis", "value",
               "x", "y", "z", "qw", "qx", "qy", "qz")
#: The field sets a line must complete to be one event (besides an optional {name}).
LINE_EVENTS = {"wheel": ("count",), "button": ("button", "pressed"), "axis": ("axis", "value"),
               "tracker": ("x", "y", "z", "qw", "qx", "qy", "qz")}
_FIELD = re.compile(r"\{(\w*)\}")

Axes = tuple[tuple[int, float], tuple[int, float], tuple[int, float]]
IDENTITY_AXES: Axes = ((0, 1.0), (1, 1.0), (2, 1.0))


def axes_map(text: str) -> Axes:
    """``"x -z y"`` -> for engine X, Y, Z: (device axis index, sign). ValueError if bad."""
    words = text.lower().split()
    if len(words) != 3:
        raise ValueError(f"Axes needs three words (one per engine axis X Y Z), got {text!r}")
    out = []
    for w in words:
        sign = -1.0 if w.startswith("-") else 1.0
        letter = w.lstrip("+-")
        if letter not in ("x", "y", "z"):
            raise ValueError(f"Axes word {w!r} is not x, y or z (optionally signed)")
        out.append(("xyz".index(letter), sign))
    if len({i for i, _ in out}) != 3:
        raise ValueError(f"Axes {text!r} names a device axis twice")
    return (out[0], out[1], out[2])


def line_fields(template: str) -> tuple[str, ...]:
    """The ``{field}`` names of a serial line template; ValueError names what is wrong."""
    names = tuple(_FIELD.findall(template))
    unknown = [n for n in names if n not in LINE_FIELDS]
    if unknown:
        raise ValueError(f"unknown field {{{unknown[0]}}} in Line{suggest(unknown[0], LINE_FIELDS)}"
                         f"; fields: {' '.join('{' + f + '}' for f in LINE_FIELDS)}")
    if len(set(names)) != len(names):
        raise ValueError("a field appears twice in Line")
    kinds = [k for k, need in LINE_EVENTS.items() if set(need) <= set(names)]
    if len(kinds) != 1:
        raise ValueError("Line must hold the fields of exactly one event: {count} (a wheel), "
                         "{button} {pressed}, {axis} {value}, or {x} {y} {z} {qw} {qx} {qy} {qz}")
    return names


@dataclass(frozen=True, slots=True)
class DeviceSpec:
    """One device to open (a ``Device`` block or ``--input KIND:ARG``)."""

    id: str
    kind: str
    port: int = 9000
    address: str = "127.0.0.1"
    path: str = ""
    baud: int = 115200
    line: str = "{name} {count}"
    streams: tuple[str, ...] = ()
    scope: str = "site"
    timeout: float | None = None
    turns_per_second: float = 0.5


@dataclass(frozen=True, slots=True)
class TrackerSpec:
    """How one tracker's raw poses become scene poses."""

    id: str
    device: str = ""
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0)
    rotation: tuple[float, float, float, float] = IDENTITY
    scale: float = 1.0
    axes: Axes = IDENTITY_AXES
    filter: str = "none"
    min_cutoff: float = 1.0
    beta: float = 10.0
    predict: float = 0.0  # seconds
    #: The ID of the object (or camera) the tracker's pose moves.
    object: str | None = None


@dataclass(frozen=True, slots=True)
class WheelSpec:
    id: str
    counts_per_turn: int = 1024
    wrap: int = 0
    max_turns_per_second: float = 20.0
    invert: bool = False
    window: float = 0.1


@dataclass(frozen=True, slots=True)
class ButtonSpec:
    id: str
    device: str
    name: str
    invert: bool = False


@dataclass(frozen=True, slots=True)
class OutputSpec:
    kind: str = "osc"
    address: str = "127.0.0.1"
    port: int = 9001
    name: str = "colosseum"
    values: tuple[str, ...] = ()
    markers: bool = True
    scope: str = "site"


@dataclass(frozen=True, slots=True)
class InputSpec:
    """Everything the scene says about input and output; empty when it says nothing."""

    devices: tuple[DeviceSpec, ...] = ()
    trackers: tuple[TrackerSpec, ...] = ()
    wheels: tuple[WheelSpec, ...] = ()
    buttons: tuple[ButtonSpec, ...] = ()
    outputs: tuple[OutputSpec, ...] = ()
    lost_after: float = 0.5


_DEFAULTS = {name: {k: f.default for k, f in sc.SCHEMAS[name].items()}
             for name in ("Input", "InputDevice", "InputTracker", "InputWheel", "InputButton",
                          "Output")}


class _Keys:
    """A block's plain values (the last one written wins), schema defaults filled in."""

    def __init__(self, block: Block, schema: str) -> None:
        self.values = dict(_DEFAULTS[schema])
        self.written: dict[str, Value] = {}
        self.repeated: dict[str, list[Value]] = {}
        self.loc = block.loc
        for e in block:
            self.written[e.key] = e.value
            self.repeated.setdefault(e.key, []).append(e.value)
            self.values[e.key] = e.value.py()

    def __call__(self, key: str) -> Any:
        return self.values[key]

    def loc_of(self, key: str) -> Loc:
        v = self.written.get(key)
        return self.loc if v is None else v.loc


def read_inputs(inputs: list[Block], outputs: list[Block], report: Reporter) -> InputSpec:
    """The specs of every ``Input`` and ``Output`` block; problems go to ``report``."""
    devices: dict[str, DeviceSpec] = {}
    trackers: list[TrackerSpec] = []
    tracker_device: list[tuple[str, Loc]] = []
    wheels: list[WheelSpec] = []
    buttons: list[ButtonSpec] = []
    lost_after = 0.5
    seen: dict[tuple[str, str], Loc] = {}

    def unique(kind: str, name: str, loc: Loc) -> None:
        first = seen.get((kind, name))
        if first is None:
            seen[(kind, name)] = loc
        else:
            report.error(loc, f"duplicate {kind} '{name}' (first declared at {first.path}:"
                              f"{first.line}:{first.col})")

    for block in inputs:
        top = _Keys(block, "Input")
        lost_after = _positive(top, "LostAfter", report)
        for b in block.blocks("Device"):
            d = _device(_Keys(b, "InputDevice"), report)
            unique("input device", d.id, b.loc)
            devices[d.id] = d
        for b in block.blocks("Tracker"):
            k = _Keys(b, "InputTracker")
            trackers.append(_tracker(k, report))
            unique("tracker", trackers[-1].id, b.loc)
            if trackers[-1].device:
                tracker_device.append((trackers[-1].device, k.loc_of("Device")))
        for b in block.blocks("Wheel"):
            k = _Keys(b, "InputWheel")
            wheels.append(WheelSpec(str(k("ID")), max(int(k("CountsPerTurn")), 1),
                                    int(k("Wrap")), _positive(k, "MaxTurnsPerSecond", report),
                                    bool(k("Invert")), _positive(k, "Window", report)))
            unique("wheel", wheels[-1].id, b.loc)
            if int(k("CountsPerTurn")) < 1:
                report.error(k.loc_of("CountsPerTurn"), "CountsPerTurn must be at least 1")
            if int(k("Wrap")) < 0:
                report.error(k.loc_of("Wrap"), "Wrap must not be negative")
        for b in block.blocks("Button"):
            k = _Keys(b, "InputButton")
            buttons.append(ButtonSpec(str(k("ID")), str(k("Device")), str(k("Name")),
                                      bool(k("Invert"))))
            unique("button", buttons[-1].id, b.loc)
    for name, loc in tracker_device:
        if name not in devices:
            report.error(loc, f"unknown input device '{name}'{suggest(name, devices)}"
                              f" (declared: {', '.join(devices) or 'none'})")
    outs = []
    for block in outputs:
        k = _Keys(block, "Output")
        values = tuple(str(v.py()) for v in k.repeated.get("Value", ()))
        outs.append(OutputSpec(str(k("Kind")), str(k("Address")), _port(k, report),
                               str(k("Name")), values, bool(k("Markers")), str(k("Scope"))))
    return InputSpec(tuple(devices.values()), tuple(trackers), tuple(wheels), tuple(buttons),
                     tuple(outs), lost_after)


def _device(k: _Keys, report: Reporter) -> DeviceSpec:
    kind = str(k("Kind"))
    if kind == "serial" and not k("Path"):
        report.error(k.loc, "a serial Device needs a Path (the port, e.g. /dev/ttyUSB0)")
    if kind == "serial":
        try:
            line_fields(str(k("Line")))
        except ValueError as exc:
            report.error(k.loc_of("Line"), str(exc))
    timeout = None if k("Timeout") is None else _positive(k, "Timeout", report)
    return DeviceSpec(str(k("ID") or kind), kind, _port(k, report), str(k("Address")),
                      str(k("Path")), int(k("Baud")), str(k("Line")),
                      tuple(str(s) for s in k("Streams")), str(k("Scope")), timeout,
                      _positive(k, "TurnsPerSecond", report))


def _tracker(k: _Keys, report: Reporter) -> TrackerSpec:
    try:
        axes = axes_map(str(k("Axes")))
    except ValueError as exc:
        report.error(k.loc_of("Axes"), str(exc))
        axes = IDENTITY_AXES
    if float(k("Predict")) < 0:
        report.error(k.loc_of("Predict"), "Predict must not be negative (ms ahead)")
    if float(k("Scale")) == 0:
        report.error(k.loc_of("Scale"), "Scale must not be 0")
    if k("Object") is not None and k("Camera") is not None:
        report.error(k.loc_of("Camera"), "a Tracker moves one Object or one Camera, not both")
    moved = k("Object") if k("Object") is not None else k("Camera")
    return TrackerSpec(
        str(k("ID")), str(k("Device")), _vec3(k("Offset")),
        euler_to_quat(k("Rotation")),
        float(k("Scale")), axes, str(k("Filter")),
        _positive(k, "MinCutoff", report), float(k("Beta")),
        max(float(k("Predict")), 0.0) / 1000.0,
        None if moved is None else str(moved))


def _vec3(v: Any) -> tuple[float, float, float]:
    x, y, z = (float(c) for c in v)
    return (x, y, z)


def _positive(k: _Keys, key: str, report: Reporter) -> float:
    value = float(k(key))
    if not value > 0:
        report.error(k.loc_of(key), f"{key} must be positive, got {value:g}")
        return float(_DEFAULTS_FOR.get(key, 1.0))
    return value


def _port(k: _Keys, report: Reporter) -> int:
    port = int(k("Port"))
    if not 0 <= port <= 65535:
        report.error(k.loc_of("Port"), f"Port must be 0..65535, got {port}")
        return 0
    return port


_DEFAULTS_FOR = {key: f.default for name in _DEFAULTS for key, f in sc.SCHEMAS[name].items()
                 if isinstance(f.default, float)}
