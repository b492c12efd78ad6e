"""The scene's ``Input`` and ``Output`` blocks, declared on the block registry, and the
plain specs they make (read by :mod:`services.input`).

``Input { Device {...} Tracker {...} Wheel {...} Button {...} }`` names the devices to
open and how each tracker, wheel counter and button is calibrated; ``Output {...}``
names engine values sent out every frame. The schema checks types; each block's build
checks what needs more than one key (a serial line with an unknown field, an axis map
that is not a permutation, two devices with one ID) and the finish step what needs
every block (a tracker naming a device no ``Input`` declares; the trackers and gloves a
hand names), each told at the author's line, before anything opens. Several ``Input``
blocks make one :class:`InputSpec`.

>>> axes_map("x -z y")
((0, 1.0), (2, -1.0), (1, 1.0))
>>> line_fields("{name} {count}")
('name', 'count')
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from components.blocks import BlockDeclaration, BuildContext, Key, declare
from engine.rotation import IDENTITY, euler_to_quat
from engine.scene.diagnostics import suggest

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
#: The choices of the blocks' enums.
INPUT_KINDS = ("osc", "lsl", "serial", "openxr", "desktop")
OUTPUT_KINDS = ("osc", "lsl")
LSL_SCOPES = ("machine", "link", "site", "organization", "global")
TRACKER_FILTERS = ("none", "oneeuro")

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


@dataclass(frozen=True, slots=True)
class _LostAfter:
    """An ``Input`` block's own ``LostAfter`` (the last block's holds)."""

    seconds: float


@dataclass(frozen=True, slots=True)
class _DeviceNamed:
    """A tracker's ``Device``, checked once every ``Input`` block is read (told at its
    line through the tracker's context)."""

    name: str
    at: BuildContext


def build_input(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """An ``Input`` block's own key; its Device, Tracker, Wheel and Button blocks build
    their parts after it (the finish step puts every block's together)."""
    return [_LostAfter(_positive(v, ctx, "LostAfter"))]


def build_device(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """One device to open; a serial one needs a Path and a Line it can read."""
    kind = str(v["Kind"])
    if kind == "serial" and not v["Path"]:
        ctx.error(None, "a serial Device needs a Path (the port, e.g. /dev/ttyUSB0)")
    if kind == "serial":
        try:
            line_fields(str(v["Line"]))
        except ValueError as exc:
            ctx.error("Line", str(exc))
    timeout = None if v["Timeout"] is None else _positive(v, ctx, "Timeout")
    device = DeviceSpec(str(v["ID"] or kind), kind, _port(v, ctx), str(v["Address"]),
                        str(v["Path"]), int(v["Baud"]), str(v["Line"]),
                        tuple(str(s) for s in v["Streams"]), str(v["Scope"]), timeout,
                        _positive(v, ctx, "TurnsPerSecond"))
    _unique(ctx, "input device", device.id)
    return [device]


def build_tracker(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """One tracker's calibration; the device it names is checked by the finish step."""
    try:
        axes = axes_map(str(v["Axes"]))
    except ValueError as exc:
        ctx.error("Axes", str(exc))
        axes = IDENTITY_AXES
    if float(v["Predict"]) < 0:
        ctx.error("Predict", "Predict must not be negative (ms ahead)")
    if float(v["Scale"]) == 0:
        ctx.error("Scale", "Scale must not be 0")
    if v["Object"] is not None and v["Camera"] is not None:
        ctx.error("Camera", "a Tracker moves one Object or one Camera, not both")
    moved = v["Object"] if v["Object"] is not None else v["Camera"]
    tracker = TrackerSpec(
        str(v["ID"]), str(v["Device"]), _vec3(v["Offset"]), euler_to_quat(v["Rotation"]),
        float(v["Scale"]), axes, str(v["Filter"]), _positive(v, ctx, "MinCutoff"),
        float(v["Beta"]), max(float(v["Predict"]), 0.0) / 1000.0,
        None if moved is None else str(moved))
    _unique(ctx, "tracker", tracker.id)
    return [tracker, _DeviceNamed(tracker.device, ctx)] if tracker.device else [tracker]


def build_wheel(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """One wheel counter's calibration."""
    wheel = WheelSpec(str(v["ID"]), max(int(v["CountsPerTurn"]), 1), int(v["Wrap"]),
                      _positive(v, ctx, "MaxTurnsPerSecond"), bool(v["Invert"]),
                      _positive(v, ctx, "Window"))
    _unique(ctx, "wheel", wheel.id)
    if int(v["CountsPerTurn"]) < 1:
        ctx.error("CountsPerTurn", "CountsPerTurn must be at least 1")
    if int(v["Wrap"]) < 0:
        ctx.error("Wrap", "Wrap must not be negative")
    return [wheel]


def build_button(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """A button given a name of its own."""
    button = ButtonSpec(str(v["ID"]), str(v["Device"]), str(v["Name"]), bool(v["Invert"]))
    _unique(ctx, "button", button.id)
    return [button]


def build_output(v: Mapping[str, Any], ctx: BuildContext) -> list[Any]:
    """One ``Output``: its values, in the order written."""
    return [OutputSpec(str(v["Kind"]), str(v["Address"]), _port(v, ctx), str(v["Name"]),
                       tuple(str(x) for x in v["Value"]), bool(v["Markers"]),
                       str(v["Scope"]))]


def finish_input(parts: list[Any], ctx: BuildContext) -> None:
    """Every ``Input`` block's parts as the scene's one InputSpec (a device declared
    twice keeps its first place, the later one's values); then the devices trackers
    name, and the trackers and gloves other blocks name (a hand's)."""
    devices: dict[str, DeviceSpec] = {}
    for part in parts:
        if isinstance(part, DeviceSpec):
            devices[part.id] = part
    for part in parts:
        if isinstance(part, _DeviceNamed) and part.name not in devices:
            part.at.error("Device", f"unknown input device '{part.name}'"
                          f"{suggest(part.name, devices)}"
                          f" (declared: {', '.join(devices) or 'none'})")
    lost = [p.seconds for p in parts if isinstance(p, _LostAfter)]
    spec: InputSpec = ctx.scene("input")
    spec = replace(spec, devices=tuple(devices.values()), trackers=_all(parts, TrackerSpec),
                   wheels=_all(parts, WheelSpec), buttons=_all(parts, ButtonSpec),
                   lost_after=lost[-1] if lost else spec.lost_after)
    ctx.settle("input", spec)
    _check_input_names(spec, ctx.gathered("input names"))


def finish_output(parts: list[Any], ctx: BuildContext) -> None:
    """Every ``Output`` block's spec, in file order, into the scene's InputSpec."""
    ctx.settle("input", replace(ctx.scene("input"), outputs=_all(parts, OutputSpec)))


def _check_input_names(inputs: InputSpec, named: list[Any]) -> None:
    """Trackers and gloves blocks name (a hand's: who, kind, name, its context and key)
    must be ones the scene declares (or the desktop device's); with none declared, names
    from a device that sends them (OSC, LSL) are expected, and a name nothing declares is
    told as a warning."""
    declared = {"tracker": {t.id for t in inputs.trackers},
                "glove": {b.device for b in inputs.buttons}}
    desktop = {"tracker": DESKTOP_TRACKERS, "glove": DESKTOP_GLOVES}
    for who, what, name, at, key in named:
        known_here = {*declared[what], *desktop[what]}
        if name in known_here:
            continue
        known = ", ".join(sorted(known_here))
        hint = suggest(name, sorted(known_here))
        if declared[what]:
            at.error(key, f"{who}: no {what} {name!r} in this scene's Input "
                     f"(known: {known}){hint}")
        else:
            at.warning(key, f"{who}: {what} {name!r} is declared nowhere; it must come "
                       f"from a device that sends it (known here: {known}){hint}")


def _all(parts: list[Any], kind: type) -> tuple[Any, ...]:
    return tuple(p for p in parts if isinstance(p, kind))


def _unique(ctx: BuildContext, kind: str, name: str) -> None:
    """Claim ``name`` among the scene's ``kind``s; a second one is told at its block."""
    first = ctx.claim(kind, name)
    if first is not None:
        ctx.error(None, f"duplicate {kind} '{name}' (first declared at {first})")


def _vec3(v: Any) -> tuple[float, float, float]:
    x, y, z = (float(c) for c in v)
    return (x, y, z)


def _positive(v: Mapping[str, Any], ctx: BuildContext, key: str) -> float:
    value = float(v[key])
    if not value > 0:
        ctx.error(key, f"{key} must be positive, got {value:g}")
        return float(_FLOAT_DEFAULTS.get(key, 1.0))
    return value


def _port(v: Mapping[str, Any], ctx: BuildContext) -> int:
    port = int(v["Port"])
    if not 0 <= port <= 65535:
        ctx.error("Port", f"Port must be 0..65535, got {port}")
        return 0
    return port


INPUT_BLOCK = declare(BlockDeclaration(
    "Input", inside=("Scene",), build=build_input, entity=False, named=False,
    finish=finish_input, doc="input devices and how their trackers, wheels and buttons are "
    "calibrated (services.input)", keys=(
        Key("LostAfter", "float", 0.5, "s of silence after which a tracker, glove or wheel "
            "is reported lost (DeviceLost) until it sends again"),
    )))
DEVICE_BLOCK = declare(BlockDeclaration(
    "InputDevice", key="Device", inside=("Input",), build=build_device, repeat=True,
    doc="a device to open", keys=(
        Key("ID", "string", "", "name trackers refer to (default: the Kind)"),
        Key("Kind", "enum", None, "transport", required=True, allowed=INPUT_KINDS),
        Key("Port", "int", 9000, "osc: UDP port to listen on"),
        Key("Address", "string", "127.0.0.1", "osc: address to listen on (0.0.0.0: every "
            "network interface)"),
        Key("Path", "string", "", "serial: the port, e.g. /dev/ttyUSB0"),
        Key("Baud", "int", 115200, "serial: bits per second"),
        Key("Line", "string", "{name} {count}", "serial: one line's fields: {name} {count} "
            "{button} {pressed} {axis} {value} {x} {y} {z} {qw} {qx} {qy} {qz}"),
        Key("Streams", "stringvector", (), "lsl: streams to open, by name or \"type:TYPE\""),
        Key("Scope", "enum", "site", "lsl: how far stream discovery reaches",
            allowed=LSL_SCOPES),
        Key("Timeout", "float", None, "s; overrides Input LostAfter for this device's "
            "sources"),
        Key("TurnsPerSecond", "float", 0.5, "desktop: wheel turns per second while W/S/A/D "
            "are held"),
    )))
TRACKER_BLOCK = declare(BlockDeclaration(
    "InputTracker", key="Tracker", inside=("Input",), build=build_tracker, repeat=True,
    doc="calibration and filtering of one 6-DOF tracker", keys=(
        Key("ID", "string", None, "the tracker's name as its device sends it", required=True),
        Key("Device", "string", "", "only poses from this device (its ID); default: any"),
        Key("Offset", "vec3", (0.0, 0.0, 0.0), "added after rotation and scale", unit="m"),
        Key("Rotation", "vec3", (0.0, 0.0, 0.0), "Euler degrees turning the device frame "
            "into the scene frame"),
        Key("Scale", "float", 1.0, "device units to metres"),
        Key("Axes", "string", "x y z", "which device axis becomes engine X, Y and Z, e.g. "
            "\"x -z y\" for a Y-up device"),
        Key("Filter", "enum", "none", "jitter filter", allowed=TRACKER_FILTERS),
        Key("MinCutoff", "float", 1.0, "one-euro: Hz, jitter cut at rest (lower: smoother)"),
        Key("Beta", "float", 10.0, "one-euro: s/m, how fast the cutoff rises with speed "
            "(higher: less lag in fast moves)"),
        Key("Predict", "float", 0.0, "ms of constant-velocity prediction"),
        Key("Object", "ref", None, "an object without physics (a cursor, a marker) whose pose "
            "follows the tracker", ref="Object"),
        Key("Camera", "ref", None, "a camera (give it an ID) whose pose follows the tracker: "
            "a headset", ref="Camera"),
    )))
WHEEL_BLOCK = declare(BlockDeclaration(
    "InputWheel", key="Wheel", inside=("Input",), build=build_wheel, repeat=True,
    doc="a wheel counter: counts to angular velocity", keys=(
        Key("ID", "string", None, "the counter's name as its device sends it", required=True),
        Key("CountsPerTurn", "int", 1024, "encoder counts per wheel revolution"),
        Key("Wrap", "int", 0, "the counter wraps to 0 at this value (0: it never wraps)"),
        Key("MaxTurnsPerSecond", "float", 20.0, "faster jumps are a counter reset, not "
            "motion"),
        Key("Invert", "bool", 0, "1: counts run backwards"),
        Key("Window", "float", 0.1, "s of counts the angular velocity is measured over"),
    )))
BUTTON_BLOCK = declare(BlockDeclaration(
    "InputButton", key="Button", inside=("Input",), build=build_button, repeat=True,
    doc="a button given a name of its own", keys=(
        Key("ID", "string", None, "the name scripts and controllers use", required=True),
        Key("Device", "string", None, "the glove or device sending it", required=True),
        Key("Name", "string", None, "the button's name on that device", required=True),
        Key("Invert", "bool", 0, "1: a normally-closed switch (pressed when it reads 0)"),
    )))
OUTPUT_BLOCK = declare(BlockDeclaration(
    "Output", inside=("Scene",), build=build_output, entity=False, named=False,
    finish=finish_output, doc="engine values published every frame over OSC or LSL", keys=(
        Key("Kind", "enum", "osc", "transport", allowed=OUTPUT_KINDS),
        Key("Address", "string", "127.0.0.1", "osc: where to send"),
        Key("Port", "int", 9001, "osc: UDP port to send to"),
        Key("Name", "string", "colosseum", "lsl: stream name prefix"),
        Key("Scope", "enum", "site", "lsl: how far stream discovery reaches",
            allowed=LSL_SCOPES),
        Key("Value", "string", None, "a value sent every frame: position:OBJECT, "
            "velocity:OBJECT, angular_velocity:OBJECT, controller:ID, wheel:NAME, "
            "tracker:NAME, or a name Python systems set", repeat=True),
        Key("Markers", "bool", 1, "1: send task markers (Lua emit(\"marker\", text))"),
    )))
#: A number key's default, where a wrong value is told and the default taken instead.
_FLOAT_DEFAULTS = {k.name: k.default for block in (INPUT_BLOCK, DEVICE_BLOCK, TRACKER_BLOCK,
                                                   WHEEL_BLOCK, BUTTON_BLOCK, OUTPUT_BLOCK)
                   for k in block.keys if isinstance(k.default, float)}
