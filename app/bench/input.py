"""``colosseum bench input``: OSC input latency and cost, beside a bare python-osc server.

Three trackers at 240 Hz and two gloves (a button message each at 240 Hz) are sent
over UDP on 127.0.0.1 by a sender thread — 1,200 messages a second, each stream
stamped with its send times, from a separate process (as a tracking bridge would be). Rows:

* ``osc -> InputState`` — the engine at 90 frames per second (paced, serial mode): send
  to the moment the event is delivered on the bus, with InputState updated, so every
  later system of that frame sees it. Its floor is the wait for the next frame's INPUT
  phase (0 to 11.1 ms at 90 Hz, so its p99 is about a frame whatever the engine does):
  no target of its own, its CPU per event is compared with the reference's;
* ``osc -> bound Transform`` — send to the frame in which the tracker-bound object's
  Transform holds that sample (read in POST_PHYSICS);
* ``osc -> physics step`` — send to the start of the physics step that moves a kinematic
  body to that sample (a Controller ``tracker:hand_l`` → ``kinematic:paddle``, acting in
  PRE_PHYSICS of the same frame; the body's pose after the step is checked to hold it);
* ``python-osc server (reference)`` — python-osc's own BlockingOSCUDPServer with a
  dispatcher, in the same run on the same stream: send to handler, no frames. Its CPU
  per event is the floor of receiving and parsing in Python.

* ``hands through the hub`` — tracked hands (26 joints, one-euro filtered per joint and
  calibrated, as ``Tracker { ID "hand_r" Filter "oneeuro" Offset ... }`` does) injected
  one per frame and applied by the hub, no transport: hands per second on the main
  thread, beside the reference of the same 26 joints sent as 26 TrackerPose events
  through the same hub (one-euro each, no prediction). Interleaved runs; the spread is
  the range of the per-run ratios.

CPU µs per event counts the receiving thread(s) (their own CPU clocks) plus, for the
engine, the main thread's time in the INPUT-phase system; ``cpu ratio`` = engine /
reference. ``lost`` = sent - delivered (target 0).
"""

from __future__ import annotations

import multiprocessing
import tempfile
import threading
import time
from collections import deque
from pathlib import Path
from typing import Any

import numpy as np

RATE = 240.0
TRACKERS = ("head", "hand_l", "hand_r")
GLOVES = ("glove_l", "glove_r")
FRAME_HZ = 90.0


def _send(port: int, seconds: float, pipe: Any) -> None:
    """The sender process: every stream at RATE Hz; returns each stream's send times."""
    from pythonosc.udp_client import SimpleUDPClient

    client = SimpleUDPClient("127.0.0.1", port)
    sent: dict[str, list[float]] = {name: [] for name in (*TRACKERS, *GLOVES)}
    pipe.send("ready")
    start = time.perf_counter()  # CLOCK_MONOTONIC: the same clock in every process
    tick = 0
    while time.perf_counter() - start < seconds:
        for i, name in enumerate(TRACKERS):
            sent[name].append(time.perf_counter())
            client.send_message(f"/colosseum/tracker/{name}",
                                [float(tick), float(i), 1.0, 1.0, 0.0, 0.0, 0.0])
        for name in GLOVES:
            sent[name].append(time.perf_counter())
            client.send_message(f"/colosseum/button/{name}/index", tick % 2)
        tick += 1
        time.sleep(max(0.0, start + tick / RATE - time.perf_counter()))
    pipe.send(sent)


class Sender:
    """A separate process sending the streams (a device or bridge is another program)."""

    def __init__(self, port: int, seconds: float) -> None:
        context = multiprocessing.get_context("spawn")
        self._pipe, child = context.Pipe()
        self._process = context.Process(target=_send, args=(port, seconds, child),
                                        name="bench-sender")
        self.sent: dict[str, list[float]] = {}

    def start(self) -> None:
        self._process.start()
        if self._pipe.recv() != "ready":
            raise RuntimeError("the sender process did not start")

    @property
    def done(self) -> bool:
        if not self.sent and self._pipe.poll():
            self.sent = self._pipe.recv()
        return bool(self.sent)

    def join(self) -> None:
        while not self.done:
            time.sleep(0.01)
        self._process.join()

    @property
    def total(self) -> int:
        return sum(len(v) for v in self.sent.values())


def thread_cpu(thread: threading.Thread) -> float:
    """CPU seconds ``thread`` has used (its own clock, read from another thread)."""
    assert thread.ident is not None
    return time.clock_gettime(time.pthread_getcpuclockid(thread.ident))


def _latencies(sent: dict[str, list[float]], got: dict[str, list[float]]) -> np.ndarray:
    out = []
    for name, times in got.items():
        n = min(len(times), len(sent[name]))
        out.append(np.asarray(times[:n]) - np.asarray(sent[name][:n]))
    return np.concatenate(out) if out else np.zeros(0)


def _row(path: str, sent: int, latencies: np.ndarray, delivered: int,
         cpu_us: float | None) -> dict[str, Any]:
    ms = latencies * 1e3
    row: dict[str, Any] = {"path": path, "sent": sent, "delivered": delivered,
                           "lost": sent - delivered,
                           "p50 ms": float(np.percentile(ms, 50)) if len(ms) else float("nan"),
                           "p99 ms": float(np.percentile(ms, 99)) if len(ms) else float("nan"),
                           "max ms": float(ms.max()) if len(ms) else float("nan")}
    if cpu_us is not None:
        row["cpu us/event"] = cpu_us
    return row


#: The engine run's scene: an OSC device, a tracked marker, a paddle a controller drives.
_SCENE = ('Input { Device { Kind "osc" Port 0 } Tracker { ID "hand_r" Object "marker" } }\n'
          'Object { ID "marker" VisualAttributes { Geometry { Primitive "sphere" } } }\n'
          'Object { ID "paddle" Kinematic 1 PhysicalAttributes { Gravity 0 '
          'Geometry { Primitive "box" Size [0.1 0.1 0.1] } } }\n'
          'Controller { Input "tracker:hand_l" Target "kinematic:paddle" }\n')


def _engine_run(seconds: float, folder: Path) -> list[dict[str, Any]]:
    from components import Transform
    from engine import Engine, EngineConfig, Phase, system
    from engine.scene import instantiate, spec_from_text
    from services.input import Button, InputHub, InputState, TrackerPose
    from services.input.osc import OscDevice
    from systems.controllers import ControllersPlugin
    from systems.dynamics import DynamicsPlugin
    from systems.input import InputPlugin, InputSystem

    got: dict[str, list[float]] = {name: [] for name in (*TRACKERS, *GLOVES)}
    stamped: dict[str, list[float]] = {name: [] for name in (*TRACKERS, *GLOVES)}
    seen_in_transform: list[tuple[float, float]] = []  # (tick in the Transform, time seen)
    stepped: list[tuple[float, float]] = []  # (tick the step takes the paddle to, time)
    reached: list[bool] = []  # the paddle's pose after each such step holds that tick

    def on_event(event: TrackerPose | Button) -> None:
        got[event.device].append(time.perf_counter())
        stamped[event.device].append(event.timestamp)  # when the device thread had it

    cfg = EngineConfig(backend="ballistic", dt=1.0 / FRAME_HZ, fast=False, debug=False)
    with Engine(cfg, plugins=[InputPlugin(), DynamicsPlugin(), ControllersPlugin()]) as engine:
        ids = instantiate(engine, spec_from_text(_SCENE, folder))
        marker, paddle = ids["marker"], ids["paddle"]

        @system(Phase.FIXED, before=("DynamicsSystem",))
        def step_starts(eng: Any, dt: float) -> None:
            tracker = eng.resource(InputState).tracker("hand_l")
            if tracker is not None:
                stepped.append((float(tracker.position[0]), time.perf_counter()))

        @system(Phase.POST_PHYSICS, reads=(Transform,))
        def watch(eng: Any, dt: float) -> None:
            x = float(eng.world.component_for_entity(marker, Transform).position[0])
            seen_in_transform.append((x, time.perf_counter()))
            if stepped:
                paddle_x = eng.world.component_for_entity(paddle, Transform).position[0]
                reached.append(abs(paddle_x - stepped[-1][0]) < 1e-6)

        engine.add_system(step_starts)
        engine.add_system(watch)
        engine.start()
        hub = engine.resource(InputHub)
        hub.start()
        main_cpu = _timed(next(s for s in engine.systems[Phase.INPUT]
                               if isinstance(s, InputSystem)))
        engine.events.subscribe(TrackerPose, on_event)
        engine.events.subscribe(Button, on_event)
        device = next(d for d in hub.devices if isinstance(d, OscDevice))
        io_thread = device.threads[0]
        io_before = thread_cpu(io_thread)
        sender = Sender(device.port, seconds)
        sender.start()
        engine.run(until=lambda eng: sender.done)
        sender.join()
        engine.run(frames=5)  # whatever is still on its way
        io_cpu = thread_cpu(io_thread) - io_before
    return _engine_rows(sender, got, stamped, seen_in_transform, stepped, reached,
                        io_cpu + main_cpu[0])


def _timed(system: Any) -> list[float]:
    """Wrap ``system.run`` to add the main thread's CPU seconds in it to the one-element
    list returned."""
    spent = [0.0]
    original_run = system.run

    def timed_run(eng: Any, dt: float) -> None:
        t0 = time.thread_time()
        original_run(eng, dt)
        spent[0] += time.thread_time() - t0

    system.run = timed_run
    return spent


def _engine_rows(sender: Any, got: dict[str, list[float]], stamped: dict[str, list[float]],
                 seen_in_transform: list[tuple[float, float]],
                 stepped: list[tuple[float, float]], reached: list[bool],
                 cpu_s: float) -> list[dict[str, Any]]:
    """The engine run's rows: latency from the sender to the device thread, the state
    table, the bound Transform and the physics step."""
    delivered = sum(len(v) for v in got.values())
    cpu_us = cpu_s / max(delivered, 1) * 1e6
    ticks = sender.sent["hand_r"]
    first_seen: dict[int, float] = {}
    for tick, when in seen_in_transform:
        first_seen.setdefault(int(tick), when)
    transform_lat = np.array([first_seen[k] - ticks[k] for k in first_seen
                              if 0 <= k < len(ticks) and k > 0])
    hand_l = sender.sent["hand_l"]
    first_step: dict[int, float] = {}
    for tick, when in stepped:
        first_step.setdefault(int(tick), when)
    step_lat = np.array([first_step[k] - hand_l[k] for k in first_step
                         if 0 < k < len(hand_l)])
    if reached and sum(reached) < 0.99 * len(reached):
        raise RuntimeError(f"the paddle reached its commanded target after only "
                           f"{sum(reached)} of {len(reached)} steps")
    return [_row("osc -> device thread", sender.total, _latencies(sender.sent, stamped),
                 delivered, None),
            _row("osc -> InputState (90 Hz frames)", sender.total,
                 _latencies(sender.sent, got), delivered, cpu_us),
            _row("osc -> bound Transform (per frame)", len(transform_lat), transform_lat,
                 len(transform_lat), None),
            _row("osc -> physics step (kinematic target)", len(step_lat), step_lat,
                 len(step_lat), None)]


def _reference_run(seconds: float) -> dict[str, Any]:
    from pythonosc.dispatcher import Dispatcher
    from pythonosc.osc_server import BlockingOSCUDPServer

    got: dict[str, deque[float]] = {name: deque() for name in (*TRACKERS, *GLOVES)}

    def handler(address: str, *args: Any) -> None:
        got[address.split("/")[3]].append(time.perf_counter())

    dispatcher = Dispatcher()
    dispatcher.map("/colosseum/*", handler)
    server = BlockingOSCUDPServer(("127.0.0.1", 0), dispatcher)
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05})
    thread.start()
    cpu_before = thread_cpu(thread)
    sender = Sender(server.server_address[1], seconds)
    sender.start()
    sender.join()
    time.sleep(0.1)
    cpu = thread_cpu(thread) - cpu_before
    server.shutdown()
    thread.join()
    server.server_close()
    delivered = sum(len(v) for v in got.values())
    return _row("python-osc server (reference)", sender.total,
                _latencies(sender.sent, {k: list(v) for k, v in got.items()}), delivered,
                cpu / max(delivered, 1) * 1e6)


def _hub_rate(hands: bool, events: list[Any], frames: int) -> float:
    """Frames per second the hub applies, each holding one hand (or its 26 poses)."""
    from engine.scene.inputs import InputSpec, TrackerSpec
    from services.input import InputHub

    clock = [100.0]
    names = ["hand_r"] if hands else [e.device for e in events[0]]
    spec = InputSpec(trackers=tuple(TrackerSpec(n, filter="oneeuro", offset=(0.0, 0.0, 0.5))
                                    for n in names), lost_after=1e9)
    hub = InputHub(spec, [], clock=lambda: clock[0])
    start = time.perf_counter()
    for frame in range(frames):
        clock[0] = 100.0 + frame / FRAME_HZ
        for event in events[frame % len(events)]:
            hub.inject(event)
        hub.step(frame)
    return frames / (time.perf_counter() - start)


def _hand_rows(quick: bool) -> list[dict[str, Any]]:
    """Hands per second through the hub, beside their joints as 26 trackers."""
    from services.input import TrackerPose
    from services.input.hand_pose import GESTURES, pose_hand

    frames, runs = (300, 3) if quick else (1500, 5)
    rng = np.random.default_rng(1)
    hands = [pose_hand("hand_r", tuple(rng.normal(0, 0.01, 3)), (1.0, 0.0, 0.0, 0.0),
                       GESTURES["pinch"]) for _ in range(32)]
    as_hands = [[h] for h in hands]
    as_poses = [[TrackerPose(f"joint{i}", p, q) for i, (p, q) in
                 enumerate(zip(h.positions, h.orientations, strict=True))] for h in hands]
    ours, ref = [], []
    for _ in range(runs):  # interleaved: both see the same load
        ours.append(_hub_rate(True, as_hands, frames))
        ref.append(_hub_rate(False, as_poses, frames))
    ratios = np.asarray(ref) / np.asarray(ours)  # time per hand / time per 26 poses
    return [{"path": "hands through the hub (26 joints, one-euro)",
             "hands/s": float(np.median(ours)), "us/hand": 1e6 / float(np.median(ours)),
             "26 poses us": 1e6 / float(np.median(ref)),
             "ratio": float(np.median(ratios)),
             "ratio spread": f"{ratios.min():.2f}-{ratios.max():.2f}"}]


def run_bench(quick: bool = False) -> list[dict[str, Any]]:
    seconds = 2.0 if quick else 10.0
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-input-") as tmp:
        rows = _engine_run(seconds, Path(tmp))
    reference = _reference_run(seconds)
    frame_ms = 1e3 / FRAME_HZ
    ours = rows[1]
    ours["cpu ratio"] = ours["cpu us/event"] / reference["cpu us/event"]
    physics = rows[3]  # the goal: packet to the physics step that uses it, one frame,
    physics["target p99 ms"] = round(frame_ms, 1)  # and no event lost on the way
    physics["ok"] = "yes" if physics["p99 ms"] <= frame_ms and all(
        row["lost"] == 0 for row in rows) else "NO"
    return [*rows, reference, *_hand_rows(quick)]
