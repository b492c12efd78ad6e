"""Input-stream targets of the fuzzer (``python -m tools.fuzz --kind osc``): OSC packets
into the OSC device's parser, serial bytes into the serial device's line parser (with
its line template), and recording files read and replayed through the input hub.

Packets and lines are made well formed (every address and field of the protocol, every
OSC argument type, bundles) and then mutated; recordings are written by the recorder
itself and then mutated in their numbers, JSON values and bytes. A packet or line must
end as an event or a counted bad message; a recording as a replay or a ReplayError
naming the file and line.
"""

from __future__ import annotations

import json
import random
from dataclasses import dataclass, field
from pathlib import Path

from pythonosc.osc_bundle_builder import IMMEDIATELY, OscBundleBuilder
from pythonosc.osc_message_builder import OscMessageBuilder

from engine.scene.inputs import InputSpec, TrackerSpec, WheelSpec
from services.input import InputHub, read_recording
from services.input.events import (
    Axis,
    Button,
    DeviceLost,
    KeyEvent,
    Pointer,
    TrackerPose,
    WheelCount,
)
from services.input.osc import PREFIX, OscDevice
from services.input.record import FrameInput, RecordWriter, ReplayError
from services.input.serial_line import LineFormat, SerialDevice
from tools.fuzz_assets import HOSTILE_NUMBERS, mutate_json, mutate_numbers
from tools.fuzz_core import Outcome, Target, mutate_bytes
from tools.fuzz_scene import mutate

_ODD_FLOATS = [float("nan"), float("inf"), -float("inf"), 3e38, -0.0, 0.0, 1.0, 1e-45]


@dataclass(slots=True)
class Packets:
    """Datagrams, each given to the parser in turn."""

    data: bytes
    sizes: list[int] = field(default_factory=list, metadata={"keep": True})


def _osc_message(rng: random.Random) -> bytes:
    kind = rng.choice(["tracker/hand_r", "wheel/left", "button/glove/index", "axis/pad/x",
                       "tracker/", "button/x", "wheel", "nothing/here", ""])
    address = rng.choice([PREFIX, PREFIX, "/", "/other/", ""]) + kind
    builder = OscMessageBuilder(address=address or "/")
    right = 7 if kind.startswith("tracker") else 1
    count = right if rng.random() < 0.7 else rng.choice([0, 1, 7, 10, 3, 11])
    for _ in range(count):
        value = rng.uniform(-1, 1) if rng.random() < 0.7 else rng.choice(
            [rng.randrange(-5, 2**31), rng.choice(_ODD_FLOATS), "x", "", True, False, None,
             b"\x00\x01", rng.randrange(2**40)])
        try:
            builder.add_arg(value)
        except ValueError:  # a value python-osc cannot send
            builder.add_arg(0)
    return builder.build().dgram


def make_packets(rng: random.Random) -> Packets:
    """A few OSC messages and bundles (nested too), some mutated."""
    datagrams = []
    for _ in range(rng.randrange(1, 6)):
        if rng.random() < 0.3:
            bundle = OscBundleBuilder(IMMEDIATELY)
            for _ in range(rng.randrange(0, 4)):
                bundle.add_content(OscMessageBuilder.build(_builder_of(rng)))
            data = bundle.build().dgram
        else:
            data = _osc_message(rng)
        if rng.random() < 0.5:
            data = mutate_bytes(rng, data, rng.randrange(1, 5))
        datagrams.append(data)
    return Packets(b"".join(datagrams), [len(d) for d in datagrams])


def _builder_of(rng: random.Random) -> OscMessageBuilder:
    """A builder holding one message (a bundle takes builders' messages)."""
    from pythonosc.osc_message import OscMessage

    message = OscMessage(_osc_message(rng))
    builder = OscMessageBuilder(address=message.address)
    for value in message.params:
        builder.add_arg(value)
    return builder


def _split(inp: Packets) -> list[bytes]:
    """The datagrams, cut at the sizes they were made with (a shrunk input's last one
    takes what is left)."""
    out, at = [], 0
    for size in inp.sizes:
        out.append(inp.data[at:at + size])
        at += size
    if at < len(inp.data) or not out:
        out.append(inp.data[at:])
    return out


def exercise_osc(inp: Packets, folder: Path) -> Outcome:
    """Each datagram through the OSC device's parser, as its receive thread does."""
    device = OscDevice("osc", port=0)
    for data in _split(inp):
        device.take(data, 1.0)
    events = device.poll(10.0)
    return "ok" if events and not device.bad.total else "message"


def _packet_files(inp: Packets, stem: str) -> dict[str, bytes | str]:
    return {f"{stem}.osc": inp.data, f"{stem}.sizes.json": json.dumps(inp.sizes)}


# -- serial lines ------------------------------------------------------------------------

TEMPLATES = ["{name} {count}", "{count}", "glove {button} {pressed}", "{axis} {value}",
             "{x} {y} {z} {qw} {qx} {qy} {qz}", "T {name} {x},{y},{z} {qw} {qx} {qy} {qz}",
             "{name}:{count};"]
_LINE_FRAGMENTS = ["{", "}", "{name}", "{count}", "{value}", "{x}", " ", "\t", "\r", "\n", "\x00",
                   "\xff", "-", "+", "1", "nan", "inf", "1e999", "99999999999999999999999",
                   "(", "[", "\\", "*", "?", "{bogus}", "{0}", "{{", "é"]


@dataclass(slots=True)
class SerialInput:
    """A line template (the scene's ``Line``) and the bytes a port sends, in chunks."""

    template: str
    data: bytes
    chunk: int = field(default=64, metadata={"keep": True})


def _line(rng: random.Random, template: str) -> str:
    line = template
    for name, value in (("name", "left"), ("count", str(rng.randrange(-5000, 5000))),
                        ("button", "index"), ("pressed", rng.choice("01")), ("axis", "x")):
        line = line.replace("{" + name + "}", value)
    for name in ("value", "x", "y", "z", "qw", "qx", "qy", "qz"):
        line = line.replace("{" + name + "}", repr(rng.uniform(-1, 1)) if rng.random() < 0.9
                            else rng.choice(HOSTILE_NUMBERS))
    return line


def make_serial(rng: random.Random) -> SerialInput:
    """Lines of a template, some mutated, some overlong or not text; now and then the
    template itself mutated."""
    template = rng.choice(TEMPLATES)
    lines = [_line(rng, template) for _ in range(rng.randrange(1, 12))]
    text = "\n".join(mutate(rng, line, rng.randrange(1, 4), _LINE_FRAGMENTS)
                     if rng.random() < 0.3 else line for line in lines)
    data = text.encode("utf-8", "replace")
    if rng.random() < 0.2:
        data = mutate_bytes(rng, data, rng.randrange(1, 5))
    if rng.random() < 0.05:
        data += b"x" * rng.choice([1023, 1024, 1025, 5000]) + b"\n1 2\n"
    if rng.random() < 0.15:
        template = mutate(rng, template, rng.randrange(1, 4), _LINE_FRAGMENTS)
    return SerialInput(template, data, rng.choice([1, 7, 64, 4096]))


def exercise_serial(inp: SerialInput, folder: Path) -> Outcome:
    """The template compiled as a scene's Device does (ValueError is the scene's message),
    then the bytes through the serial device's line parser in chunks, as reads give them."""
    try:
        LineFormat(inp.template)
    except ValueError:
        return "message"
    device = SerialDevice("serial", "/dev/null", line=inp.template)
    chunk = max(inp.chunk, 1)
    for at in range(0, len(inp.data), chunk):
        device.take(inp.data[at:at + chunk], 1.0)
    events = device.poll(10.0)
    return "ok" if events and not device.bad.total else "message"


def _serial_files(inp: SerialInput, stem: str) -> dict[str, bytes | str]:
    return {f"{stem}.template.txt": inp.template, f"{stem}.serial": inp.data}


# -- recordings --------------------------------------------------------------------------


@dataclass(slots=True)
class RecordingInput:
    """A recording file's bytes."""

    data: bytes


def _event(rng: random.Random, t: float) -> object:
    odd = rng.random() < 0.05
    number = (lambda: rng.choice(_ODD_FLOATS)) if odd else (lambda: rng.uniform(-1, 1))
    kind = rng.randrange(7)
    if kind == 0:
        return TrackerPose("hand_r", (number(), number(), number()), (1.0, 0.0, 0.0, 0.0),
                           rng.choice([None, (number(), 0.0, 0.0)]), t)
    if kind == 1:
        return WheelCount("left", rng.randrange(-10**6, 10**6), t)
    if kind == 2:
        return Button("glove", "index", rng.random() < 0.5, t)
    if kind == 3:
        return Axis("pad", "x", number(), t)
    if kind == 4:
        return KeyEvent("Up", rng.random() < 0.5, "keyboard", t)
    if kind == 5:
        return Pointer("mouse", number(), number(), 0.0, t)
    return DeviceLost("hand_r", t)


def make_recording(rng: random.Random, folder: Path | None = None) -> RecordingInput:
    """A recording the recorder writes, then mutated in numbers, values or bytes."""
    import tempfile

    with tempfile.TemporaryDirectory(prefix="fuzz-rec.") as tmp:
        path = Path(tmp) / "run.input"
        writer = RecordWriter(path, {"scene": "main.scene", "seed": 0, "devices": []})
        t = 100.0
        for frame in range(rng.randrange(0, 12)):
            t += 1 / 60
            writer.write(frame, FrameInput(t, [_event(rng, t) for _ in range(rng.randrange(3))]))
        writer.close()
        data = path.read_bytes()
    how = rng.randrange(10)
    if how < 3:
        lines = data.split(b"\n")
        i = rng.randrange(len(lines))
        try:
            record = mutate_json(rng, json.loads(lines[i]), rng.randrange(1, 3))
            lines[i] = json.dumps(record).encode()
        except ValueError:
            pass
        data = b"\n".join(lines)
    elif how < 6:
        data = mutate_numbers(rng, data, rng.randrange(1, 4))
    elif how < 9:
        data = mutate_bytes(rng, data, rng.randrange(1, 5))
    return RecordingInput(data)


_REPLAYED = InputSpec(trackers=(TrackerSpec("hand_r", filter="one_euro", predict=0.02),),
                      wheels=(WheelSpec("left"),))


def exercise_recording(inp: RecordingInput, folder: Path) -> Outcome:
    """The file read as ``--replay`` reads it, then its frames delivered by the input hub
    (filters, wheel rates) as a run does."""
    path = folder / "run.input"
    path.write_bytes(inp.data)
    try:
        recording = read_recording(path)
    except ReplayError:
        return "message"
    hub = InputHub(_REPLAYED, [])
    hub.replay(recording)
    try:
        for frame in sorted(recording.frames)[:100]:
            hub.step(frame)
    finally:
        hub.close()
    return "ok"


def _recording_files(inp: RecordingInput, stem: str) -> dict[str, bytes | str]:
    return {f"{stem}.input": inp.data}


OSC = Target("osc", make_packets, exercise_osc, _packet_files)
SERIAL = Target("serial", make_serial, exercise_serial, _serial_files)
RECORDING = Target("recording", make_recording, exercise_recording, _recording_files)
