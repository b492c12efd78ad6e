"""``--record FILE`` and ``--replay FILE`` as systems that switch the input hub over.

They only configure the :class:`InputHub` (which the input plugin owns) before the first
frame: the recorder taps the raw input of every frame, the replayer replaces the live
devices with the file. Replaying a recording made with another scene works, with a
warning: the events may not fit it.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import TYPE_CHECKING

from engine.system import Phase, PluginName, System
from services.input.hub import InputHub
from services.input.record import ReplayError, read_recording, scene_fingerprint

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.input")


def input_hub(engine: Engine) -> InputHub:
    """The engine's input hub, loading the input plugin if it is not there yet."""
    hub = engine.try_resource(InputHub)
    if hub is None:
        try:
            engine.request_plugin(PluginName.INPUT)
        except KeyError as exc:
            raise ReplayError("recording and replaying input needs the input plugin, which "
                              "this engine does not have") from exc
        hub = engine.resource(InputHub)
    return hub


def scene_identity(engine: Engine) -> dict[str, str]:
    """The scene's path and fingerprint, as a recording's header names them."""
    from engine.scene import SceneIds

    ids = engine.try_resource(SceneIds)
    db = None if ids is None else ids.spec.db
    if db is None:
        return {"scene": "", "scene_sha256": ""}
    return {"scene": str(db.path), "scene_sha256": scene_fingerprint(db.sources)}


class InputRecorder(System):
    """Records every frame's raw input to a file (``--record``)."""

    phase = Phase.INPUT
    #: Set up once the input system has made the hub (a content system ordered before the
    #: input system must not bring the recorder's setup ahead of it).
    after = ("InputSystem",)

    def __init__(self, path: Path) -> None:
        self.path = Path(path)

    def setup(self, engine: Engine) -> None:
        input_hub(engine).record(self.path, {**scene_identity(engine),
                                             "seed": engine.config.seed,
                                             **engine.config.options.get("run_flags", {})})

    def run(self, engine: Engine, dt: float) -> None:
        """Nothing per frame: the hub writes each frame as it collects it."""


class InputReplayer(System):
    """Delivers a recording instead of the live devices (``--replay``)."""

    phase = Phase.INPUT
    after = ("InputSystem",)  # see InputRecorder

    def __init__(self, path: Path) -> None:
        self.recording = read_recording(Path(path))

    def setup(self, engine: Engine) -> None:
        header = self.recording.header
        here = scene_identity(engine)
        if header.get("scene_sha256") and header["scene_sha256"] != here["scene_sha256"]:
            log.warning("%s was recorded with scene %s; this run's scene (%s) differs, so its "
                        "input may not fit", self.recording.path, header.get("scene") or "?",
                        here["scene"] or "none")
        if header.get("seed") is not None and header["seed"] != engine.config.seed:
            log.warning("%s was recorded with --seed %s, this run has --seed %s: the run will "
                        "not repeat the recorded one", self.recording.path, header["seed"],
                        engine.config.seed)
        input_hub(engine).replay(self.recording)

    def run(self, engine: Engine, dt: float) -> None:
        """Nothing per frame: the hub delivers the recorded frames."""
