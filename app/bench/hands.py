"""``colosseum bench hands``: how closely and how cheaply virtual hands follow trackers.

Rows, each at 120 Hz physics (serial, unpaced), on ODE and on pymunk (``--backend``: one):

* ``tracking``: a hand whose tracker swings along X on a sinusoid peaking at 1 m/s
  (0.2 m amplitude, 5 rad/s); the tracking error RMS (mm, the distance in space) between
  the hand and the tracker's pose for the same instant, and the lag (ms) that best lines
  the hand's path up with the tracker's (cross-correlation, to a tenth of a
  millisecond). Goals: ≤ 5 mm and ≤ 15 ms.
* ``held cup``: a hand holding a 0.3 kg cup still in the air for 2 s: the cup's jitter,
  the RMS of its distance from its mean position (mm). Goal: ≤ 0.5 mm; a cup that was
  not lifted off the table (so not held) fails it.
* ``cost``: ms per physics step of a table with cups and 10 tracked hands moving among
  them, beside the same scene and tracker traffic without the hands, in the same run; the
  difference per hand per step (µs). A first run warms up (imports, caches) and is
  discarded; then runs with and without hands alternate :data:`REPEATS` times and the
  medians are reported, so one disturbed run (a loaded machine) does not decide it.
  Goal: ≤ 20 µs.

Beside them, on ODE, the fingered hand's rows (``Hand { Fingers 1 }``): fingertip
tracking, penetration, held jitter, a 3 Hz shake, a hand-over, a 3 m/s swipe at a thin
plate, its cost per hand per step beside the palm's, and two hands in a 90 Hz frame
(:mod:`app.bench.fingers`). On pymunk, the 2D fingered hand's rows: fingertip tracking
in the plane and its cost per hand per step beside the 2D palm's.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

import numpy as np

RATE = 120.0
BACKENDS = ("ode", "pymunk")
AMPLITUDE, OMEGA = 0.2, 5.0  # peak speed A ω = 1 m/s
TRACK_SECONDS = 6.0
HANDS = 10
#: Runs with and without hands, alternated, whose medians the cost row reports.
REPEATS = 3


def _rig(scene: str, folder: Path, backend: str, paths: dict[str, Any], seconds: float,
         on_frame: Any = None) -> float:
    """Run ``scene`` with trackers on ``paths`` (t -> position); CPU seconds per step
    (the fingered hand's runner, :func:`app.bench.fingers.run`, fed tracker poses)."""
    from app.bench.fingers import run

    feeds = {name: _pose_feed(name, path) for name, path in paths.items()}
    return run(scene, folder, feeds, seconds, on_frame, rate=RATE, settle=0.5, backend=backend)


def _pose_feed(name: str, path: Any) -> Any:
    """A tracker's pose at t on ``path``, its velocity by central difference."""
    from services.input.events import TrackerPose

    def feed(t: float) -> TrackerPose:
        v = (path(t + 1e-4) - path(t - 1e-4)) / 2e-4
        return TrackerPose(name, tuple(path(t)), (1.0, 0.0, 0.0, 0.0), tuple(v), t)

    return feed


def _hand(name: str, x: float, y: float, z: float) -> str:
    return f'Object {{ ID "{name}" Position [{x} {y} {z}] Hand {{ Tracker "{name}" }} }}\n'


def tracking(folder: Path, backend: str, seconds: float) -> dict[str, Any]:
    from components import Transform

    def swing(t: float) -> np.ndarray:
        return np.array([AMPLITUDE * np.sin(OMEGA * t), 0.0, 1.0])

    hand: list[np.ndarray] = []
    times: list[float] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        times.append(e.time + 1.0 / RATE)  # where the step just taken left it
        hand.append(e.world.component_for_entity(ids["hand_r"], Transform).position.copy())

    _rig(_hand("hand_r", 0, 0, 1), folder, backend, {"hand_r": swing}, seconds, note)
    t, spots = np.array(times[60:]), np.array(hand[60:])
    x = spots[:, 0]
    off = spots - np.array([swing(ti) for ti in t])
    error_mm = float(np.sqrt(np.mean(np.sum(off**2, axis=1)))) * 1e3
    shifts = np.arange(-0.05, 0.05, 1e-4)
    misfit = [np.mean((x - AMPLITUDE * np.sin(OMEGA * (t - s))) ** 2) for s in shifts]
    lag_ms = float(shifts[int(np.argmin(misfit))]) * 1e3
    return {"case": "tracking, 1 m/s peak", "backend": backend, "error_rms_mm": error_mm,
            "lag_ms": lag_ms, "goal": "<= 5 mm, <= 15 ms",
            "ok": "yes" if error_mm <= 5 and abs(lag_ms) <= 15 else "NO"}


def held_cup(folder: Path, backend: str, seconds: float) -> dict[str, Any]:
    from components import Transform
    from services.input import InputHub
    from services.input.events import Button

    scene = ('Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
             '  PhysicalAttributes { Geometry { Primitive "box" Size [1 1 0.05] } } }\n'
             'Object { ID "cup" Position [0 0 0.8] PhysicalAttributes { Mass 0.3\n'
             '  Geometry { Primitive "cylinder" Size [0.08 0.1] } } }\n'
             'Object { ID "hand_r" Position [0 0 0.9] Hand { Tracker "hand_r" Glove "g" } }\n')
    cup: list[np.ndarray] = []

    def pinch(e: Any, ids: dict[str, int]) -> None:
        if abs(e.time - 0.3) < 0.5 / RATE:
            e.resource(InputHub).inject(Button("g", "pinch", True, e.time))
        if e.time > 1.5:
            cup.append(e.world.component_for_entity(ids["cup"], Transform).position.copy())

    def lift(t: float) -> np.ndarray:
        return np.array([0.0, 0.0, np.interp(t, [0.0, 0.3, 0.4, 1.0], [0.9, 0.857, 0.857,
                                                                        1.1])])

    _rig(scene, folder, backend, {"hand_r": lift}, seconds, pinch)
    spots = np.array(cup)
    jitter_mm = float(np.sqrt(np.mean(np.sum((spots - spots.mean(axis=0)) ** 2, axis=1))))
    jitter_mm *= 1e3
    held = bool(spots[:, 2].min() > 0.8 + 0.2)  # lifted with the hand (it rested at 0.8)
    return {"case": "held cup at rest", "backend": backend, "jitter_rms_mm": jitter_mm,
            "goal": "<= 0.5 mm, held",
            "ok": "yes" if jitter_mm <= 0.5 and held else "NO" if held else "NO (not held)"}


def cost(folder: Path, backend: str, seconds: float) -> dict[str, Any]:
    table = ('Object { ID "floor" PhysicalAttributes { Geometry { Primitive "plane" } } }\n'
             'Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
             '  PhysicalAttributes { Geometry { Primitive "box" Size [3 2 0.05] } } }\n')
    cups = "".join(f'Object {{ ID "cup{i}" Position [{-1.2 + 0.27 * i} 0 0.8] PhysicalAttributes '
                   f'{{ Mass 0.3 Geometry {{ Primitive "cylinder" Size [0.08 0.1] }} }} }}\n'
                   for i in range(HANDS))
    names = [f"h{i}" for i in range(HANDS)]
    hands = "".join(_hand(n, -1.2 + 0.27 * i, -0.3, 1.0) for i, n in enumerate(names))

    def wave(i: int) -> Any:
        return lambda t: np.array([-1.2 + 0.27 * i + 0.1 * np.sin(3 * t + i), -0.3,
                                   1.0 + 0.05 * np.sin(2 * t)])

    traffic = {n: wave(i) for i, n in enumerate(names)}
    _rig(table + cups + hands, folder, backend, traffic, seconds)  # warm-up, discarded
    runs: list[tuple[float, float]] = []
    for _ in range(REPEATS):
        # the same tracker traffic without the hands: the input layer's cost is not theirs
        runs.append((_rig(table + cups + hands, folder, backend, traffic, seconds),
                     _rig(table + cups, folder, backend, traffic, seconds)))
    with_hands = float(np.median([w for w, _ in runs]))
    without = float(np.median([wo for _, wo in runs]))
    per_hand = float(np.median([w - wo for w, wo in runs])) / HANDS * 1e6
    return {"case": f"cost, {HANDS} hands", "backend": backend, "ms_per_step": with_hands * 1e3,
            "without_hands_ms": without * 1e3, "us_per_hand_step": per_hand,
            "goal": "<= 20 us", "ok": "yes" if per_hand <= 20 else "NO"}


def run_bench(quick: bool = False, backend: str | None = None) -> list[dict[str, Any]]:
    if backend is not None and backend not in BACKENDS:
        raise SystemExit(f"colosseum bench hands: no backend {backend!r} with hands (one "
                         f"of {', '.join(BACKENDS)})")
    seconds = 1.0 if quick else TRACK_SECONDS
    rows: list[dict[str, Any]] = []
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-hands-") as tmp:
        folder = Path(tmp)
        for name in BACKENDS if backend is None else (backend,):
            rows += [tracking(folder, name, seconds), held_cup(folder, name, 2.0),
                     cost(folder, name, 0.5 if quick else 3.0)]
            if name == "ode":
                from app.bench.fingers import run_rows

                rows += run_rows(folder, quick)
            elif name == "pymunk":
                from app.bench.fingers import run_rows_2d

                rows += run_rows_2d(folder, quick)
    return rows
