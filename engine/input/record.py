"""Input recordings: every typed event with its device timestamp and delivery frame.

The format (documented for other tools in docs/input-format.md) is JSON lines. The
first line is the header::

    {"format": "colosseum-input", "version": 1, "scene": "content/demo/main.scene",
     "scene_sha256": "...", "seed": 0, "devices": [{"id": "osc", "kind": "osc", ...}]}

then, for each frame, an optional clock line and that frame's events in the order
they were delivered::

    {"frame": 12, "clock": 5321.0402}
    {"frame": 12, "type": "tracker", "device": "hand_r", "position": [0.1, 0.2, 1.0],
     "orientation": [1.0, 0.0, 0.0, 0.0], "velocity": null, "timestamp": 5321.0371}

Events are the raw ones the devices produced (before calibration and filtering, which
the scene applies again on replay), plus the DeviceLost/DeviceFound the watchdog
decided. Floats are written with ``repr`` precision, so a replay in serial mode with the
same seed delivers bit-identical values at the same frames.
"""

from __future__ import annotations

import hashlib
import json
import logging
from collections import Counter
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import IO, Any

from engine.input.device import make_pose, numbers
from engine.input.events import (
    HAND_JOINTS,
    TAGS,
    AnyInput,
    Axis,
    Button,
    HandJoints,
    KeyEvent,
    Pointer,
    TrackerPose,
    WheelCount,
)

log = logging.getLogger("colosseum.input")

FORMAT = "colosseum-input"
VERSION = 1
_CLASSES = {tag: cls for cls, tag in TAGS.items()}


class ReplayError(Exception):
    """A recording that cannot be replayed; the message names the file and line."""


@dataclass(slots=True)
class FrameInput:
    """What the input layer delivers in one frame: its clock and the raw events."""

    clock: float
    events: list[AnyInput] = field(default_factory=list)


@dataclass(slots=True)
class Recording:
    header: dict[str, Any]
    frames: dict[int, FrameInput]
    path: Path

    @property
    def event_count(self) -> int:
        return sum(len(f.events) for f in self.frames.values())


def scene_fingerprint(sources: dict[str, str]) -> str:
    """A hash of the scene's text (every file it includes), to notice another scene;
    comments and trailing blanks are left out, so a note added to a scene leaves its
    recordings fitting it."""
    digest = hashlib.sha256()
    for path in sorted(sources):
        digest.update(_without_comments(sources[path]).encode("utf-8"))
    return digest.hexdigest()


def _without_comments(text: str) -> str:
    """Scene text without its ``//`` comments (outside quoted strings) and blank lines.

    >>> _without_comments('a 1  // one\\nFile "x//y" // two\\n\\n// three\\n')
    'a 1\\nFile "x//y"'
    """
    lines = []
    for line in text.splitlines():
        quoted, cut = False, len(line)
        for i, ch in enumerate(line):
            if ch == '"':
                quoted = not quoted
            elif not quoted and line.startswith("//", i):
                cut = i
                break
        kept = line[:cut].rstrip()
        if kept:
            lines.append(kept)
    return "\n".join(lines)


def event_record(frame: int, event: AnyInput) -> dict[str, Any]:
    record: dict[str, Any] = {"frame": frame, "type": TAGS[type(event)]}
    for f in fields(event):  # type: ignore[arg-type]
        value = getattr(event, f.name)
        record[f.name] = list(value) if isinstance(value, tuple) else value
    return record


def event_from_record(record: dict[str, Any]) -> AnyInput:
    """The event of one line (``frame`` already taken out), checked as a device's message
    is: ValueError (or BadMessage) says what is wrong, so a hand-written file is safe."""
    cls = _CLASSES.get(record.pop("type", None))
    if cls is None:
        raise ValueError(f"unknown or missing type (known: {', '.join(_CLASSES)})")
    timestamp = numbers([record.pop("timestamp", 0.0)], 1, "timestamp")[0]
    device = record.pop("device", "keyboard" if cls is KeyEvent else None)
    if not isinstance(device, str) or not device:
        raise ValueError("device must be a non-empty string")
    event: AnyInput
    if cls is TrackerPose:
        velocity = record.pop("velocity", None)
        pose = [*_list(record.pop("position"), 3), *_list(record.pop("orientation"), 4)]
        event = make_pose(device, numbers(pose, 7, "position and orientation"), timestamp,
                          None if velocity is None else numbers(_list(velocity, 3), 3,
                                                                "velocity"))
    elif cls in (Button, Axis):
        name = _text(record.pop("name"), "name")
        if cls is Button:
            event = Button(device, name, _flag(record.pop("pressed")), timestamp)
        else:
            event = Axis(device, name, numbers([record.pop("value")], 1, "value")[0], timestamp)
    elif cls is WheelCount:
        count = record.pop("count")
        if isinstance(count, bool) or not isinstance(count, int):
            raise ValueError(f"count {count!r} is not a whole number")
        event = WheelCount(device, count, timestamp)
    elif cls is KeyEvent:
        event = KeyEvent(_text(record.pop("key"), "key"), _flag(record.pop("pressed")), device,
                         timestamp)
    elif cls is HandJoints:
        event = _hand(device, record, timestamp)
    elif cls is Pointer:
        x, y, scroll = numbers([record.pop("x"), record.pop("y"), record.pop("scroll", 0.0)], 3,
                               "pointer")
        event = Pointer(device, x, y, scroll, timestamp)
    else:
        event = cls(device, timestamp)
    if record:
        raise ValueError(f"unexpected field(s): {', '.join(record)}")
    return event


def _hand(device: str, record: dict[str, Any], timestamp: float) -> HandJoints:
    """A recorded hand: 26 positions, orientations (w, x, y, z), radii and validity
    flags, each list checked as a device's message is."""
    n = len(HAND_JOINTS)
    positions = [numbers(_list(p, 3), 3, "joint position") for p in
                 _list(record.pop("positions"), n)]
    turns = [numbers(_list(q, 4), 4, "joint orientation") for q in
             _list(record.pop("orientations"), n)]
    radii = numbers(_list(record.pop("radii"), n), n, "joint radii")
    valid = _list(record.pop("valid"), n)
    if not all(isinstance(v, bool) for v in valid):
        raise ValueError(f"valid must be {n} flags (true or false), got {valid!r}")
    return HandJoints(device, tuple((p[0], p[1], p[2]) for p in positions),
                      tuple((q[0], q[1], q[2], q[3]) for q in turns),
                      tuple(radii), tuple(valid), timestamp)


def _list(value: object, length: int) -> list[Any]:
    if not isinstance(value, list) or len(value) != length:
        raise ValueError(f"expected a list of {length} numbers, got {value!r}")
    return value


def _text(value: object, what: str) -> str:
    if not isinstance(value, str) or not value:
        raise ValueError(f"{what} must be a non-empty string")
    return value


def _flag(value: object) -> bool:
    if not isinstance(value, bool):
        raise ValueError(f"pressed must be true or false, got {value!r}")
    return value


class RecordWriter:
    """Writes a recording as the run goes; the header goes out at once."""

    def __init__(self, path: Path, header: dict[str, Any]) -> None:
        self.path = Path(path)
        self._out: IO[str] | None = self.path.open("w", encoding="utf-8")
        self._out.write(json.dumps({"format": FORMAT, "version": VERSION, **header}) + "\n")
        self.frames = 0
        self.counts: Counter[str] = Counter()

    def write(self, frame: int, batch: FrameInput) -> None:
        out = self._out
        if out is None:
            return
        out.write(json.dumps({"frame": frame, "clock": batch.clock}) + "\n")
        for event in batch.events:
            out.write(json.dumps(event_record(frame, event)) + "\n")
            self.counts[TAGS[type(event)]] += 1
        self.frames += 1

    def close(self) -> str:
        """Close the file; returns (and logs) what it holds."""
        if self._out is not None:
            self._out.close()
            self._out = None
        if self.counts:
            what = ", ".join(f"{n} {tag}" for tag, n in sorted(self.counts.items()))
            summary = f"recorded {what} event(s) over {self.frames} frame(s) to {self.path}"
        else:
            summary = (f"recorded {self.frames} frame(s) to {self.path}; no device produced "
                       "an event (the file holds the header and the frame clocks)")
        log.info("%s", summary)
        return summary


#: Header keys holding the run's flags that change what it simulates (``--param``,
#: ``--dt``, ``--substeps``, ``--backend``): a replay runs with them again.
RUN_KEYS = ("params", "dt", "substeps", "backend")


def read_header(path: Path) -> dict[str, Any]:
    """A recording's header line alone (what a run needs before its scene is built);
    ReplayError says what is wrong with it."""
    path = Path(path)
    try:
        with path.open(encoding="utf-8") as lines:
            first = next((line for line in lines if line.strip()), "")
    except (OSError, UnicodeDecodeError) as exc:
        raise ReplayError(f"{path}: cannot read the recording: {exc}") from exc
    if not first:
        raise ReplayError(f"{path}: empty; a recording starts with its header line")
    try:
        header = json.loads(first)
        if not isinstance(header, dict):
            raise ValueError("a line must be a JSON object")
        _check_header(header)
    except ValueError as exc:
        raise ReplayError(f"{path}:1: not a recorded input line ({exc})") from exc
    return header


def read_recording(path: Path) -> Recording:
    """Parse a recording; ReplayError names the line of the first problem."""
    path = Path(path)
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except (OSError, UnicodeDecodeError) as exc:
        raise ReplayError(f"{path}: cannot read the recording: {exc}") from exc
    header: dict[str, Any] | None = None
    clocks: dict[int, float] = {}
    events: dict[int, list[AnyInput]] = {}
    for number, line in enumerate(lines, 1):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
            if not isinstance(record, dict):
                raise ValueError("a line must be a JSON object")
            if header is None:
                _check_header(record)
                header = record
                continue
            frame = int(record.pop("frame"))
            if frame < 0:
                raise ValueError("frame must not be negative")
            if "clock" in record:
                clocks[frame] = float(record["clock"])
            else:
                events.setdefault(frame, []).append(event_from_record(record))
        except (ValueError, KeyError, TypeError, OverflowError) as exc:  # inf: OverflowError
            raise ReplayError(f"{path}:{number}: not a recorded input line ({exc})") from exc
    if header is None:
        raise ReplayError(f"{path}: empty; a recording starts with its header line")
    frames: dict[int, FrameInput] = {}
    clock = 0.0
    for frame in sorted(clocks.keys() | events.keys()):
        batch = events.get(frame, [])
        # a frame without a clock line runs on its newest event's timestamp
        clock = clocks.get(frame, max([clock, *(e.timestamp for e in batch)]))
        frames[frame] = FrameInput(clock, batch)
    return Recording(header, frames, path)


def _check_header(record: dict[str, Any]) -> None:
    if record.get("format") != FORMAT:
        raise ValueError(f'the first line must be the header {{"format": "{FORMAT}", '
                         f'"version": {VERSION}, ...}}')
    if record.get("version") != VERSION:
        raise ValueError(f"format version {record.get('version')!r} is not {VERSION}")
