"""The engine's run-time choices (``EngineConfig``), apart from the engine itself: the
command line reads its defaults without loading the runtime (esper, the physics driver)
that :mod:`engine.app` brings."""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from engine.physics.backend import BackendName, WorldSettings
from engine.realtime import TIME_STEP, Pacing


@dataclass(slots=True)
class EngineConfig:
    """Run-time choices; the CLI fills these from its flags."""

    content_dir: Path | None = None
    mode: str = "serial"  # "serial" | "threaded"
    backend: str = BackendName.ODE
    dt: float = TIME_STEP
    substeps: int = 1
    seed: int = 0
    fast: bool = False
    early: str = "sleep"
    late: str = "slowmo"
    max_dt: float = 1.0 / 20.0
    max_substeps: int = 8
    headless: bool = True
    render: bool = False
    sound: str = "null"
    world: WorldSettings = field(default_factory=WorldSettings)
    #: Folders besides the content folder that its scene and scripts may name files in
    #: (``--allow-path``; see :mod:`engine.confine`).
    allow_paths: tuple[Path, ...] = ()
    options: dict[str, Any] = field(default_factory=dict)
    #: Check that every system touches only the component types it declares (slower; the
    #: test suite turns it on with COLOSSEUM_DEBUG=1, ``colosseum run --debug`` too).
    debug: bool = field(default_factory=lambda: os.environ.get("COLOSSEUM_DEBUG") == "1")

    def pacing(self) -> Pacing:
        return Pacing(dt=self.dt, paced=not self.fast, early=self.early, late=self.late,
                      max_dt=max(self.max_dt, self.dt), substeps=self.substeps,
                      max_substeps=max(self.max_substeps, self.substeps))

