"""Input recording and replay (``--record FILE`` / ``--replay FILE``).

The recorder writes every input event (keys, devices, custom events) with the
frame it was delivered in, one JSON object per line. Replaying the file in
serial mode with the same seed re-emits the events at the same frames, which
reproduces the run exactly: a session with a tracker and a glove can be
studied again without the hardware.
"""

from __future__ import annotations

import json
import logging
from dataclasses import asdict
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from engine.events import CustomEvent, InputEvent, KeyEvent
from engine.system import Phase, System

log = logging.getLogger("colosseum")

if TYPE_CHECKING:
    from engine.app import Engine

RECORDED: dict[str, type] = {"key": KeyEvent, "input": InputEvent, "custom": CustomEvent}


class ReplayError(Exception):
    pass


class InputRecorder(System):
    """Appends each delivered input event to a JSON-lines file."""

    phase = Phase.INPUT

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._out: IO[str] | None = None
        self._engine: Engine | None = None
        self.recorded = 0

    def setup(self, engine: Engine) -> None:
        self._engine = engine
        self._out = self.path.open("w", encoding="utf-8")
        for tag, kind in RECORDED.items():
            engine.events.subscribe(kind, lambda ev, tag=tag: self._write(tag, ev))

    def _write(self, tag: str, event: Any) -> None:
        if self._out is None or self._engine is None:
            return
        record = {"frame": self._engine.frame, "type": tag, **asdict(event)}
        self._out.write(json.dumps(record) + "\n")
        self.recorded += 1

    def run(self, engine: Engine, dt: float) -> None:
        return None

    def shutdown(self, engine: Engine) -> None:
        """Close the file and say what it holds (an empty recording is not a silent one)."""
        if self._out is None:
            return
        self._out.close()
        self._out = None
        if self.recorded:
            log.info("recorded %d input event(s) over %d frames to %s", self.recorded,
                     engine.frame, self.path)
        else:
            log.warning("--record: no input event arrived in %d frames (no key pressed, no "
                        "device sent anything); %s is empty", engine.frame, self.path)


class InputReplayer(System):
    """Emits the recorded events of each frame at the start of that frame."""

    phase = Phase.INPUT

    def __init__(self, path: Path) -> None:
        self.by_frame: dict[int, list[Any]] = {}
        for number, line in enumerate(Path(path).read_text(encoding="utf-8").splitlines(), 1):
            if not line.strip():
                continue
            try:
                record = json.loads(line)
                kind = RECORDED[record.pop("type")]
                frame = int(record.pop("frame"))
                event = kind(**record)
            except (ValueError, KeyError, TypeError) as exc:
                raise ReplayError(f"{path}:{number}: not a recorded input event ({exc})") from exc
            self.by_frame.setdefault(frame, []).append(event)

    def run(self, engine: Engine, dt: float) -> None:
        for event in self.by_frame.pop(engine.frame, ()):
            engine.events.emit(event)
