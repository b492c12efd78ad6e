"""The experiment plugin: runs an experiment's trials in the engine
(``colosseum experiment run``; engine.experiments has the design and the files).

The driver (app.experiments.cli) hands the :class:`TrialRunner` one trial at a time
(:meth:`TrialRunner.begin`); in the trial's first frame (POST_PHYSICS, after the scripts
have started) the runner sets its condition — each factor's anomaly switched and set, the
levels readable by ``experiment:condition(name)`` from the start — stamps the start on
the simulated, wall and LSL clocks, sends a ``trial_start`` marker to the Output streams
stamped with that LSL time, emits the custom event ``trialStart`` (Python systems and
Lua's ``on``) and calls every script's ``onTrialStart(trial)``. The trial ends with
``trial:finish(outcome)`` (Lua, or :meth:`TrialRunner.finish` from Python), with the first
``trial:respond(name, value)`` where the design's ``EndOn`` is ``response``, or at the
design's ``Timeout`` (outcome ``timeout``); then ``onTrialEnd(trial)``, ``trialEnd`` and a
``trial_end`` marker, and :attr:`TrialRunner.result` holds what the row records. Tracked
objects' poses go to the trial's tracking log at the design's rate.

The runner is the engine's :class:`engine.services.ExperimentControl`, which Lua's
``experiment`` table and Python systems use.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from components import Camera, Name, Transform
from engine.events import CustomEvent
from engine.experiments.design import OFF_LEVELS, Design, TrialPlan
from engine.experiments.tracking import TrackLog, WheelLog
from engine.measures import Measures
from engine.services import ExperimentControl
from engine.system import Phase, PluginName, System
from services.input.state import InputState

if TYPE_CHECKING:
    from engine.app import Engine

log = logging.getLogger("colosseum.experiment")


def lsl_clock() -> float | None:
    """LSL's clock now (s), or None where pylsl cannot be loaded."""
    try:
        import pylsl
    except Exception:  # noqa: BLE001 - no liblsl: rows get no LSL time
        return None
    return float(pylsl.local_clock())


@dataclass(slots=True)
class TrialResult:
    """What a finished trial's row records."""

    plan: TrialPlan
    start: float
    end: float
    wall: float
    lsl_start: float | None
    lsl_end: float | None
    outcome: str
    responses: dict[str, Any] = field(default_factory=dict)
    measures: dict[str, float] = field(default_factory=dict)


def level_value(level: str) -> Any:
    """A level as a parameter's value: a number where it reads as one."""
    try:
        return float(level)
    except ValueError:
        return level


class TrialRunner(System):
    """Runs the trial :meth:`begin` gave it (see the module doc)."""

    phase = Phase.POST_PHYSICS
    reads = (Name, Transform, Camera)
    writes = ()
    before = ("OutputSystem",)  # its markers go out in the frame they are made

    def __init__(self, design: Design, participant: int) -> None:
        self.design, self.participant = design, participant
        self.plan: TrialPlan | None = None
        self.result: TrialResult | None = None
        self.track_path: Path | None = None
        self._engine: Engine | None = None
        self._started = False
        self._ending: str | None = None
        self._responses: dict[str, Any] = {}
        self._start = self._wall = 0.0
        self._lsl_start: float | None = None
        self._track: TrackLog | None = None
        self._wheels: WheelLog | None = None
        self._track_rows: np.ndarray | None = None
        self._track_version = -1
        self._track_entities: list[int] = []
        self._camera: tuple[int, Camera] | None = None

    # -- the driver's side ---------------------------------------------------------------
    def begin(self, plan: TrialPlan, track_path: Path | None = None) -> None:
        """Run ``plan`` from the next frame on."""
        self.plan, self.result, self.track_path = plan, None, track_path
        self._started, self._ending, self._responses = False, None, {}

    @property
    def ended(self) -> bool:
        return self.result is not None

    # -- ExperimentControl -----------------------------------------------------------------
    def condition(self, factor: str) -> str | None:
        if self.plan is None:
            return None
        if factor not in self.plan.condition:
            known = [f.id for f in self.design.factors] + [s.id for s in self.design.staircases]
            if factor in known:
                return None  # a staircase's trial has no level of the factors
            raise KeyError(f"no factor {factor!r} (factors: {', '.join(known) or 'none'})")
        return self.plan.condition[factor]

    def trial_data(self) -> dict[str, Any] | None:
        plan = self.plan
        if plan is None or not self._started:  # between trials: none (its condition is set
            return None                         # when it starts)
        data: dict[str, Any] = {
            "index": plan.index, "block": plan.block, "blockTrial": plan.block_trial,
            "practice": plan.practice, "condition": dict(plan.condition),
            "participant": self.participant, "experiment": self.design.id,
            "staircase": plan.staircase, "responses": dict(self._responses)}
        if plan.staircase is not None:
            data["intensity"] = float(plan.condition[plan.staircase])
        if self.result is not None:
            data.update(outcome=self.result.outcome,
                        duration=self.result.end - self.result.start)
        return data

    def respond(self, name: str, value: Any) -> None:
        if not name:
            raise ValueError("respond: a response needs a name")
        if self.plan is None or not self._started or self.result is not None:
            raise ValueError(f"respond({name!r}): no trial is running")
        self._responses[name] = value
        self._marker(f"response {self.plan.index} {name}={value}", lsl_clock())
        if self.design.end_on == "response" and self._ending is None:
            self._ending = "response"

    def finish(self, outcome: str = "done") -> None:
        if self.plan is None or not self._started or self.result is not None:
            raise ValueError("finish: no trial is running")
        if self._ending is None:
            self._ending = str(outcome)

    # -- each frame -------------------------------------------------------------------------
    def setup(self, engine: Engine) -> None:
        self._engine = engine

    def run(self, engine: Engine, dt: float) -> None:
        if self.plan is None or self.result is not None:
            return
        if not self._started:
            self._begin_trial(engine)
        now = engine.time + dt  # after this frame's step
        if self._track is not None and self._track.due(now):
            self._sample(engine, now)
        if self._ending is None and now - self._start >= self.design.timeout - 1e-9:
            self._ending = "timeout"
        if self._ending is not None:
            self._end_trial(engine, now)

    def _begin_trial(self, engine: Engine) -> None:
        plan = self.plan
        assert plan is not None
        self._started = True
        self._apply(engine, plan)
        measures = engine.try_resource(Measures)
        if measures is not None:
            measures.values.clear()
        self._start, self._wall = engine.time, time.time()
        self._lsl_start = lsl_clock()
        levels = " ".join(f"{k}={v}" for k, v in plan.condition.items())
        self._marker(f"trial_start {plan.index} block={plan.block} {levels}".strip(),
                     self._lsl_start)
        if self.track_path is not None and (self.design.track or self.design.track_camera):
            self._open_track(engine)
        data = self.trial_data()
        engine.events.emit(CustomEvent("trialStart", data))
        self._call_scripts(engine, "onTrialStart")

    def _apply(self, engine: Engine, plan: TrialPlan) -> None:
        """Switch and set the anomalies the condition names."""
        from engine.anomalies import Anomalies

        anomalies = engine.try_resource(Anomalies)
        targets = [(f.id, f.anomaly, f.param) for f in self.design.factors] + \
                  [(s.id, s.anomaly, s.param) for s in self.design.staircases]
        for key, anomaly, param in targets:
            if anomaly is None or key not in plan.condition:
                continue
            if anomalies is None:
                log.warning("experiment: factor %r switches anomaly %r, but the anomalies "
                            "plugin is not loaded", key, anomaly)
                continue
            level = plan.condition[key]
            on = level.lower() not in OFF_LEVELS
            values = {param: level_value(level)} if param is not None and on else None
            for problem in anomalies.set(anomaly, "experiment", enabled=on, values=values):
                log.warning("experiment: trial %d, %s=%s: %s", plan.index, key, level, problem)

    def _end_trial(self, engine: Engine, now: float) -> None:
        plan = self.plan
        assert plan is not None and self._ending is not None
        from systems.measures import final_values

        lsl_end = lsl_clock()
        self.result = TrialResult(plan, self._start, now, self._wall, self._lsl_start,
                                  lsl_end, self._ending, dict(self._responses),
                                  final_values(engine))
        self._stop_logs(keep=True)
        self._marker(f"trial_end {plan.index} {self._ending}", lsl_end)
        engine.events.emit(CustomEvent("trialEnd", self.trial_data()))
        self._call_scripts(engine, "onTrialEnd")

    def abandon(self) -> None:
        """The run stopped mid-trial: no row, no tracking CSV."""
        self._stop_logs(keep=False)

    def _stop_logs(self, keep: bool) -> None:
        """Close the trial's tracking and wheel logs (``keep``: written out, else
        abandoned)."""
        for trial_log in (self._track, self._wheels):
            if trial_log is not None:
                trial_log.close() if keep else trial_log.abandon()
        self._track = self._wheels = None

    # -- helpers -----------------------------------------------------------------------------
    def _marker(self, text: str, stamp: float | None) -> None:
        engine = self._engine
        if engine is None:
            return
        from systems.input import Outputs

        outputs = engine.try_resource(Outputs)
        if outputs is not None:
            outputs.marker(text, stamp)

    def _call_scripts(self, engine: Engine, callback: str) -> None:
        from systems.scripting import ScriptingSystem

        scripting = engine.try_resource(ScriptingSystem)
        runtime = None if scripting is None else scripting.runtime
        api = None if scripting is None else scripting.api
        if runtime is None or api is None:
            return
        data = self.trial_data()
        assert data is not None
        runtime.broadcast(callback, api.trial_table(data))

    def _open_track(self, engine: Engine) -> None:
        assert self.track_path is not None
        names = {n.id: e for e, n in engine.world.get_component(Name)}
        entities, labels = [], []
        for object_id in self.design.track:
            if object_id in names:
                entities.append(names[object_id])
                labels.append(object_id)
            else:
                log.warning("experiment: no object %r to track", object_id)
        self._camera = None
        if self.design.track_camera:
            self._camera = next(((e, c) for e, c in engine.world.get_component(Camera)
                                 if c.active), None)
            if self._camera is None:
                log.warning("experiment: TrackCamera, but the scene has no active camera")
            else:
                labels.append("head")
        self._track_entities = entities
        self._track_version = -1
        if labels:
            self._track = TrackLog(self.track_path, labels, self.design.track_rate)

    def _sample(self, engine: Engine, now: float) -> None:
        assert self._track is not None
        poses = engine.world.poses
        if self._track_version != poses.version:
            self._track_version = poses.version
            rows = poses.rows(self._track_entities)
            self._track_rows = rows
            if (rows < 0).any():
                log.warning("experiment: a tracked object is gone; its rows repeat its last "
                            "pose")
        rows = self._track_rows
        assert rows is not None
        sample = poses.table[rows, :7]
        if self._camera is not None:
            sample = np.vstack([sample, self._head(engine)])
        self._track.sample(now, engine.frame, sample)
        inputs = engine.try_resource(InputState)
        if inputs is not None and inputs.wheels:  # the wheelchair's counters, beside
            if self._wheels is None:
                assert self.track_path is not None
                self._wheels = WheelLog(self.track_path.with_name(
                    self.track_path.stem + ".wheels.csv"))
            self._wheels.sample(now, engine.frame, inputs.wheels)

    def _head(self, engine: Engine) -> np.ndarray:
        """The active camera's pose as drawn: at its offset from the object it follows."""
        from services.render.camera import camera_view_of

        assert self._camera is not None
        entity, camera = self._camera
        view = camera_view_of(camera, entity, engine.world.poses)
        return np.concatenate([view.position, view.orientation])[None, :]

    def shutdown(self, engine: Engine) -> None:
        self.abandon()


class ExperimentPlugin:
    """Adds a :class:`TrialRunner` as the engine's ExperimentControl."""

    name = PluginName.EXPERIMENT

    def __init__(self, runner: TrialRunner) -> None:
        self.runner = runner

    def build(self, engine: Engine) -> None:
        engine.insert_resource(self.runner)
        engine.insert_resource(self.runner, as_type=ExperimentControl)
        engine.add_system(self.runner)
