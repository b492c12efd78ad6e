"""The session plugin: one log file per session of a task-based simulation (paper section 6).

A scene with a ``Session`` block, run by ``colosseum run`` (or by an engine whose
``config.options["sessions"]`` names a folder), writes one JSON-lines file per run:
``<Name>-<date>-<time>.jsonl`` in the folder ``--sessions DIR`` names, else the block's
``Folder``, else ``sessions/`` in the working directory — never inside the content
folder (a folder there is told and replaced by ``<content>-sessions`` beside it) and
never over an existing file. Every line is one record with the simulated time ``t`` (s)
and the ``frame``:

- ``session``: the header (format version, wall-clock start, scene, seed, the recording
  replayed or written, the chair);
- ``pose``: the chair's position (m), heading ``yaw`` (degrees) and speed (m/s), at
  ``PoseRate`` Hz;
- ``collision``: the chair (a part: chassis, wheel, caster) began touching something that
  is not ``Ground`` (a wall, the furniture, a cup), with the impulse (N·s) and the speed;
- ``grasp`` / ``release``: a hand took or let go of an object;
- ``task``: what a script emitted as ``emit("task", {task = ..., event = ..., ...})``;
- ``anomaly``: a visual anomaly switched or its severity set (engine.anomalies'
  ``AnomalySwitched``: ``name``, ``anomaly_kind``, ``on``, ``onset``, its parameters,
  ``source``); the anomalies plugin sends its own marker for it;
- ``mode``: the wheelchair's navigation mode (at the start and when it changes);
- ``end``: the session ended: a script's ``emit("session_end", {reason = ...})`` (which
  stops the run when ``EndRun``), or the run stopping (``reason`` "stopped").

Every record but poses also goes out as a marker to the scene's ``Output`` streams
(OSC, LSL), so a recording of physiological signals lines up with the session (grasps
and releases, and anomaly switches, are sent by the hands and anomalies plugins
themselves, with or without a session: once). A
session recorded with ``--record`` replays (``--replay``) to the same log; ``colosseum
score RECORDING`` does that and prints what :func:`summarize` reads from it.
"""

from __future__ import annotations

import json
import logging
import math
import time
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from components import Hand, Joint, Name, SessionSettings, Transform
from engine.events import (
    AnomalySwitched,
    ContactBegan,
    CustomEvent,
    HandGrasped,
    HandReleased,
)
from engine.rotation import quat_to_euler
from engine.system import Phase, PluginName, System
from systems.wheelchair import WheelchairModeChanged

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.session")

FORMAT, VERSION = "colosseum-session", 1
#: Seconds between flushes of the log to disk (and at the end).
FLUSH_EVERY = 1.0


def scene_settings(engine: Engine) -> SessionSettings | None:
    """The scene's ``Session`` block (None: the scene has none)."""
    from engine.scene import SceneIds

    ids = engine.try_resource(SceneIds)
    return None if ids is None else ids.spec.settings.get("Session")


def log_folder(asked: str | Path | None, scene_folder: str, content: Path | None,
               cwd: Path | None = None) -> Path:
    """Where the logs go: ``asked`` (--sessions), else the scene's folder, else sessions/ in
    the working directory; one inside the content folder is told and moved beside it. A
    scene's folder must lie in the working directory: content is shared and served, so it
    may not choose where on this machine files are written (an absolute path or one
    climbing out is told, and sessions/ used)."""
    cwd = Path.cwd() if cwd is None else cwd
    chosen = Path(asked) if asked else Path(scene_folder) if scene_folder else Path("sessions")
    folder = (cwd / chosen).resolve()
    here = cwd.resolve()
    if not asked and scene_folder and folder != here and here not in folder.parents:
        log.warning("Session Folder %r leads out of the working directory; a scene may not "
                    "choose where on this machine its logs are written, so they go to "
                    "sessions/ here (colosseum run --sessions DIR chooses any folder)",
                    scene_folder)
        folder = here / "sessions"
    if content is not None:
        content = content.resolve()
        if folder == content or content in folder.parents:
            beside = content.parent / f"{content.name}-sessions"
            log.warning("session logs never go inside the content folder (%s asked); they go "
                        "to %s", folder, beside)
            folder = beside
    return folder


def log_name(scene_name: str, content: Path | None) -> str:
    """The log file's name before its date: the scene's ``Name`` (a name, never a path that
    would put the file elsewhere: its last part is used, and told), else the content
    folder's."""
    name = scene_name or (content.name if content is not None else "session")
    if Path(name).name != name or name.strip(".") == "":
        log.warning("Session Name %r is a path; the log file is named by its last part", name)
        name = Path(name).name.strip(".") or "session"
    return name


def open_log(folder: Path, name: str, started: float) -> tuple[Path, IO[str]]:
    """A new file ``name-date-time.jsonl`` in ``folder`` (``-2``, ``-3``... if taken)."""
    folder.mkdir(parents=True, exist_ok=True)
    stamp = time.strftime("%Y%m%d-%H%M%S", time.localtime(started))
    for n in range(1, 1000):
        path = folder / f"{name}-{stamp}{'' if n == 1 else f'-{n}'}.jsonl"
        try:
            return path, path.open("x", encoding="utf-8")
        except FileExistsError:
            continue
    raise OSError(f"{folder}: no free name for {name}-{stamp}.jsonl")


class SessionLog(System):
    """Writes the session's records (POST_PHYSICS: poses after the frame's step)."""

    phase = Phase.POST_PHYSICS
    reads = (Name, Transform, Joint, Hand)
    writes = ()

    def __init__(self) -> None:
        self.path: Path | None = None
        self.records = 0
        self._file: IO[str] | None = None
        self._settings = SessionSettings()
        self._engine: Engine | None = None
        self._chair: int | None = None
        self._parts: set[int] = set()
        self._ground: set[int] = set()
        self._next_pose = 0.0
        self._flushed = 0.0
        self._resolved = False
        self._ended = False

    # -- starting --------------------------------------------------------------------
    def setup(self, engine: Engine) -> None:
        settings = scene_settings(engine)
        opts = engine.config.options
        if settings is None or not (opts.get("session_log") or opts.get("sessions")):
            return
        self._settings, self._engine = settings, engine
        content = engine.config.content_dir
        folder = log_folder(opts.get("sessions"), settings.folder, content)
        name = log_name(settings.name, content)
        started = time.time()
        try:
            self.path, self._file = open_log(folder, name, started)
        except OSError as exc:
            log.error("session log: %s; this session is not logged", exc)
            return
        log.info("session log: %s", self.path)
        events = engine.events
        events.subscribe(CustomEvent, self._on_custom)
        events.subscribe(HandGrasped, lambda e: self._hand("grasp", e.hand, e.object))
        events.subscribe(HandReleased, lambda e: self._hand("release", e.hand, e.object))
        events.subscribe(WheelchairModeChanged, self._on_mode)
        events.subscribe(ContactBegan, self._on_contact)
        events.subscribe(AnomalySwitched, self._on_anomaly)
        self._write({"kind": "session", "format": FORMAT, "version": VERSION,
                     "started": time.strftime("%Y-%m-%dT%H:%M:%S%z",
                                              time.localtime(started)),
                     "scene": _scene_path(engine), "seed": engine.config.seed,
                     "replay": _text(opts.get("replay")), "record": _text(opts.get("record")),
                     "chair": settings.chair})

    def _resolve(self, engine: Engine) -> None:
        """The chair's entity and parts (what is jointed to it), the ground's entities."""
        world = engine.world
        names = {n.id: e for e, n in world.get_component(Name)}
        settings = self._settings
        missing = [g for g in settings.ground if g not in names]
        if missing:
            log.warning("session log: no ground object %s; touching it would count as a "
                        "collision", ", ".join(map(repr, missing)))
        self._ground = {names[g] for g in settings.ground if g in names}
        self._chair = names.get(settings.chair) if settings.chair else None
        if self._chair is None:
            if settings.chair:
                log.warning("session log: no chair %r; its pose is not logged", settings.chair)
            return
        hands = {e for e, _ in world.get_component(Hand)}
        links: dict[int, set[int]] = {}
        for _, joint in world.get_component(Joint):
            a, b = joint.body_a, joint.body_b
            if b is None or a in hands or b in hands:
                continue
            links.setdefault(a, set()).add(b)
            links.setdefault(b, set()).add(a)
        parts, todo = {self._chair}, [self._chair]
        while todo:
            for other in links.get(todo.pop(), ()):
                if other not in parts:
                    parts.add(other)
                    todo.append(other)
        self._parts = parts

    # -- each frame --------------------------------------------------------------------
    def run(self, engine: Engine, dt: float) -> None:
        if self._file is None or self._ended:
            return
        if not self._resolved:  # the first frame: every scene object exists by now
            self._resolved = True
            self._resolve(engine)
        now = engine.time + dt  # after this frame's step
        if self._chair is not None and now + 1e-9 >= self._next_pose:
            self._next_pose = now + 1.0 / max(self._settings.pose_rate, 1e-6)
            t = engine.world.try_component(self._chair, Transform)
            if t is not None:
                yaw = quat_to_euler(t.orientation)[2]
                self._write({"kind": "pose", "x": _round(t.position[0]),
                             "y": _round(t.position[1]), "z": _round(t.position[2]),
                             "yaw": round(yaw, 2),
                             "speed": _round(math.hypot(*t.linear_velocity[:2]))}, now)
        if time.monotonic() - self._flushed >= FLUSH_EVERY:
            self._flushed = time.monotonic()
            self._file.flush()

    # -- what happens ------------------------------------------------------------------
    def _on_custom(self, event: CustomEvent) -> None:
        data = event.data if isinstance(event.data, dict) else {"value": event.data}
        if event.name == "task":
            self._record({"kind": "task", **data})
        elif event.name == "session_end":
            self._end(str(data.get("reason", "done")), data)

    def _on_anomaly(self, event: AnomalySwitched) -> None:
        if self._file is None or self._ended:
            return
        self._write({"kind": "anomaly", "name": event.anomaly, "anomaly_kind": event.kind,
                     "on": event.enabled, "onset": event.onset, **dict(event.severity),
                     "source": event.source})

    def _hand(self, kind: str, hand: int, obj: int) -> None:
        # the hands plugin sends its own marker for it (with or without a session)
        self._record({"kind": kind, "hand": self._name(hand), "object": self._name(obj)},
                     marker=False)

    def _on_mode(self, event: WheelchairModeChanged) -> None:
        self._record({"kind": "mode", "chair": self._name(event.chair), "mode": event.mode})

    def _on_contact(self, event: ContactBegan) -> None:
        parts = self._parts
        if not parts:
            return
        a, b = event.a, event.b
        if (a in parts) == (b in parts):  # within the chair, or not the chair at all
            return
        part, other = (a, b) if a in parts else (b, a)
        if other in self._ground or other < 0:  # the static world without a name: ground
            return
        speed = 0.0
        engine = self._engine
        t = None if engine is None or self._chair is None else \
            engine.world.try_component(self._chair, Transform)
        if t is not None:
            speed = math.hypot(*t.linear_velocity[:2])
        self._record({"kind": "collision", "part": self._name(part),
                      "object": self._name(other), "impulse": _round(event.impulse),
                      "speed": _round(speed)})

    def _end(self, reason: str, data: dict[str, Any]) -> None:
        if self._ended or self._file is None:
            return
        self._record({**{k: v for k, v in data.items() if k != "reason"}, "kind": "end",
                      "reason": reason})
        self._ended = True
        self._file.flush()
        log.info("session ended (%s); logged to %s", reason, self.path)
        if self._settings.end_run and self._engine is not None:
            self._engine.request_quit()

    def _record(self, record: dict[str, Any], marker: bool = True) -> None:
        """A record in the log, and (``marker``) as a marker on the Output streams."""
        if self._file is None or self._ended:
            return
        self._write(record)
        engine = self._engine
        if marker and engine is not None:
            text = " ".join(str(v) for k, v in record.items() if k != "kind")
            engine.events.emit(CustomEvent("marker", f"{record['kind']} {text}".strip()))

    def _write(self, record: dict[str, Any], t: float | None = None) -> None:
        assert self._file is not None
        engine = self._engine
        stamp = {"t": _round(engine.time if t is None else t), "frame": engine.frame} \
            if engine is not None else {}
        self._file.write(json.dumps({**stamp, **record}, default=str) + "\n")
        self.records += 1

    def _name(self, entity: int) -> str:
        engine = self._engine
        name = None if engine is None else engine.world.try_component(entity, Name)
        return name.id if name is not None else f"entity {entity}"

    def shutdown(self, engine: Engine) -> None:
        if self._file is None:
            return
        if not self._ended:
            self._end("stopped", {})
        self._file.close()
        self._file = None


def _round(x: float) -> float:
    return round(float(x), 4)


def _text(value: Any) -> str | None:
    return None if value is None else str(value)


def _scene_path(engine: Engine) -> str | None:
    from engine.scene import SceneIds

    ids = engine.try_resource(SceneIds)
    db = None if ids is None else ids.spec.db
    return None if db is None else str(db.path)


def summarize(path: Path) -> dict[str, Any]:
    """What a session log says: each task's events and when it was done, grasps,
    collisions, the distance the chair went, the anomalies switched, how it ended."""
    tasks: dict[str, dict[str, Any]] = {}
    counts = {"grasp": 0, "release": 0, "collision": 0, "anomaly": 0}
    distance, last, end, header = 0.0, None, None, None
    for line in Path(path).read_text(encoding="utf-8").splitlines():
        record = json.loads(line)
        kind = record.get("kind")
        if kind == "session":
            header = record
        elif kind == "pose":
            here = (record["x"], record["y"])
            if last is not None:
                distance += math.dist(last, here)
            last = here
        elif kind == "task":
            task = tasks.setdefault(record.get("task", "?"), {"events": 0, "done": None})
            task["events"] += 1
            if record.get("event") == "done":
                task["done"] = record["t"]
        elif kind == "end":
            end = record
        if kind in counts:
            counts[kind] += 1
    return {"scene": None if header is None else header.get("scene"), "tasks": tasks,
            **counts, "distance": round(distance, 3),
            "end": None if end is None else {"reason": end.get("reason"), "t": end.get("t")}}


class SessionPlugin:
    """Session logs (``requestPlugin("session")``)."""

    name = PluginName.SESSION

    def build(self, engine: Engine) -> None:
        system = SessionLog()
        engine.insert_resource(system)
        engine.add_system(system)
