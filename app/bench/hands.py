"""``colosseum bench hands``, the palm-only hand's rows: how closely and how cheaply it
follows its tracker (the bench and its tables: :mod:`app.bench.hand_rows`).

Rows, at the frame rate given (120 Hz by default; the bench runs tracking and the held cup
at 200 and 100 Hz beside the fingered hand's rows, the cost at 120 Hz), serial, unpaced,
on ODE and on pymunk (``--backend``: one):

* ``tracking``: a hand whose tracker swings along X on a sinusoid peaking at 1 m/s
  (0.2 m amplitude, 5 rad/s; or another ``speed``); the tracking error RMS (mm, the
  distance in space) between the hand and the tracker's pose for the same instant, and
  the lag (ms) that best lines the hand's path up with the tracker's (cross-correlation,
  to a tenth of a millisecond). Goals: ≤ 5 mm and ≤ 15 ms.
* ``held cup``: a hand holding a 0.3 kg cup still in the air for 2 s: the cup's jitter,
  the RMS of its distance from its mean position (mm). Goal: ≤ 0.5 mm; a cup that was
  not lifted off the table (so not held) fails it.
* ``cost``: ms per physics step of a table with cups and 10 tracked hands moving among
  them, beside the same scene and tracker traffic without the hands, in the same run; the
  difference per hand per step (µs). A first run warms up (imports, caches) and is
  discarded; then runs with and without hands alternate :data:`REPEATS` times and the
  medians are reported, so one disturbed run (a loaded machine) does not decide it.
  Goal: ≤ 20 µs.
"""

from __future__ import annotations

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
PALM_COST = (f"cost: {HANDS} palm-only hands moving over cups, CPU per physics step, beside "
             "the same scene and tracker traffic without the hands")


def _rig(scene: str, folder: Path, backend: str, paths: dict[str, Any], seconds: float,
         on_frame: Any = None, rate: float = RATE) -> float:
    """Run ``scene`` with trackers on ``paths`` (t -> position); CPU seconds per step
    (the fingered hand's runner, :func:`app.bench.fingers.run`, fed tracker poses)."""
    from app.bench.fingers import run

    feeds = {name: _pose_feed(name, path) for name, path in paths.items()}
    return run(scene, folder, feeds, seconds, on_frame, rate=rate, settle=0.5, backend=backend)


def _pose_feed(name: str, path: Any) -> Any:
    """A tracker's pose at t on ``path``, its velocity by central difference."""
    from services.input.events import TrackerPose

    def feed(t: float) -> TrackerPose:
        v = (path(t + 1e-4) - path(t - 1e-4)) / 2e-4
        return TrackerPose(name, tuple(path(t)), (1.0, 0.0, 0.0, 0.0), tuple(v), t)

    return feed


def _hand(name: str, x: float, y: float, z: float) -> str:
    return f'Object {{ ID "{name}" Position [{x} {y} {z}] Hand {{ Tracker "{name}" }} }}\n'


def tracking(folder: Path, backend: str, seconds: float, rate: float = RATE,
             speed: float = AMPLITUDE * OMEGA) -> dict[str, Any]:
    """The palm-only hand on a sinusoid along X peaking at ``speed``: its error and lag."""
    from components import Transform

    amplitude = speed / OMEGA

    def swing(t: float) -> np.ndarray:
        return np.array([amplitude * np.sin(OMEGA * t), 0.0, 1.0])

    hand: list[np.ndarray] = []
    times: list[float] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        times.append(e.time + 1.0 / rate)  # where the step just taken left it
        hand.append(e.world.component_for_entity(ids["hand_r"], Transform).position.copy())

    _rig(_hand("hand_r", 0, 0, 1), folder, backend, {"hand_r": swing}, seconds, note, rate)
    skip = round(0.5 * rate)  # its first half second
    t, spots = np.array(times[skip:]), np.array(hand[skip:])
    x = spots[:, 0]
    off = spots - np.array([swing(ti) for ti in t])
    error_mm = float(np.sqrt(np.mean(np.sum(off**2, axis=1)))) * 1e3
    shifts = np.arange(-0.05, 0.05, 1e-4)
    misfit = [np.mean((x - amplitude * np.sin(OMEGA * (t - s))) ** 2) for s in shifts]
    lag_ms = float(shifts[int(np.argmin(misfit))]) * 1e3
    return {"case": f"tracking, {speed:g} m/s peak", "backend": backend,
            "error_rms_mm": error_mm, "lag_ms": lag_ms, "goal": "<= 5 mm, <= 15 ms",
            "ok": "yes" if error_mm <= 5 and abs(lag_ms) <= 15 else "NO"}


CUP_SCENE = ('Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
             '  PhysicalAttributes { Geometry { Primitive "box" Size [1 1 0.05] } } }\n'
             'Object { ID "cup" Position [0 0 0.8] PhysicalAttributes { Mass 0.3\n'
             '  Geometry { Primitive "cylinder" Size [0.08 0.1] } } }\n'
             'Object { ID "hand_r" Position [0 0 0.9] Hand { Tracker "hand_r" Glove "g" } }\n')


def held_cup(folder: Path, backend: str, seconds: float, rate: float = RATE
             ) -> dict[str, Any]:
    from components import Transform
    from services.input import InputHub
    from services.input.events import Button

    cup: list[np.ndarray] = []
    deep: list[float] = []

    def pinch(e: Any, ids: dict[str, int]) -> None:
        from app.bench.fingers import depths

        deep.extend(depths(e, {ids["hand_r"]}, ids["cup"]))
        if abs(e.time - 0.3) < 0.5 / rate:
            e.resource(InputHub).inject(Button("g", "pinch", True, e.time))
        if e.time > 1.5:
            cup.append(e.world.component_for_entity(ids["cup"], Transform).position.copy())

    def lift(t: float) -> np.ndarray:
        return np.array([0.0, 0.0, np.interp(t, [0.0, 0.3, 0.4, 1.0], [0.9, 0.857, 0.857,
                                                                        1.1])])

    _rig(CUP_SCENE, folder, backend, {"hand_r": lift}, seconds, pinch, rate)
    spots = np.array(cup)
    jitter_mm = float(np.sqrt(np.mean(np.sum((spots - spots.mean(axis=0)) ** 2, axis=1))))
    jitter_mm *= 1e3
    held = bool(spots[:, 2].min() > 0.8 + 0.2)  # lifted with the hand (it rested at 0.8)
    return {"case": "held cup at rest", "backend": backend, "jitter_rms_mm": jitter_mm,
            "depths": deep, "goal": "<= 0.5 mm, held",
            "ok": "yes" if jitter_mm <= 0.5 and held else "NO" if held else "NO (not held)"}


def _press(e: Any, glove: str, at: float, down: bool, rate: float) -> None:
    """The glove's pinch button pressed (or let go) in the frame nearest ``at``."""
    from services.input import InputHub
    from services.input.events import Button

    if abs(e.time - at) < 0.5 / rate:
        e.resource(InputHub).inject(Button(glove, "pinch", down, e.time))


def _lifted(t: float) -> np.ndarray:
    """:func:`held_cup`'s hand: down onto the cup, grasped at 0.3 s, lifted 25 cm by 1 s."""
    return np.array([0.0, 0.0, np.interp(t, [0.0, 0.3, 0.4, 1.0], [0.9, 0.857, 0.857, 1.1])])


def palm_push(folder: Path, backend: str, rate: float) -> dict[str, Any]:
    """The palm-only hand, flat, pushes a 0.5 kg box along the table (as the fingered
    hand's pointing index does): the palm's contact depths in the box (m)."""
    from app.bench.fingers import PUSHED_BOX, TABLE, TOP, depths


    def path(t: float) -> np.ndarray:
        return np.array([float(np.interp(t, [0.0, 0.9, 2.5], [-0.2, -0.2, 0.05])), 0.0,
                         TOP + 0.03])

    deep: list[float] = []
    _rig(TABLE + PUSHED_BOX + _hand("hand_r", -0.2, 0.0, TOP + 0.03), folder, backend,
         {"hand_r": path}, 2.0, lambda e, ids: deep.extend(depths(e, {ids["hand_r"]},
                                                                   ids["box"])), rate)
    return {"depths": deep}


def palm_shake(folder: Path, backend: str, rate: float) -> dict[str, Any]:
    """:func:`held_cup`'s cup, held by the grasp button, shaken up and down at 3 Hz ±10 cm
    for 2 s: held throughout, and how far it got from where the hand holds it (mm)."""
    from app.bench.fingers import shaken
    from components import HandState, Transform

    def path(t: float) -> np.ndarray:
        at = _lifted(t)
        at[2] += shaken(t)
        return at

    off: list[np.ndarray] = []
    held: list[bool] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        _press(e, "g", 0.3, True, rate)
        if e.time > 1.7:
            cup = e.world.component_for_entity(ids["cup"], Transform).position
            off.append(cup - path(e.time))
            held.append(ids["cup"] in e.world.component_for_entity(ids["hand_r"],
                                                                   HandState).held)

    _rig(CUP_SCENE, folder, backend, {"hand_r": path}, 3.2, note, rate)
    far = float(np.linalg.norm(np.array(off) - off[0], axis=1).max()) if off else float("nan")
    return {"held_share": float(np.mean(held)) if held else 0.0, "farthest_mm": far * 1e3,
            "ok": bool(held) and all(held) and far < 0.05}


def palm_hand_over(folder: Path, backend: str, rate: float) -> dict[str, Any]:
    """:func:`held_cup`'s cup held up by the right hand's button; the left hand comes in
    under it from the side, up against its bottom, grasps it (2.1 s); the right lets go
    (2.6 s).
    How far the cup moved (mm) from before the left came to after the right let go."""
    from components import HandState, Transform

    seen: dict[str, np.ndarray] = {}

    def left(t: float) -> np.ndarray:
        under = seen.get("cup", np.array([0.0, 0.0, 1.04])) - [0.0, 0.0, 0.05 + 0.015 - 0.003]
        return np.array([float(np.interp(t, [1.0, 1.5], [0.3, 0.0])), 0.0,
                         float(np.interp(t, [1.5, 1.9], [under[2] - 0.03, under[2]]))])

    def note(e: Any, ids: dict[str, int]) -> None:
        _press(e, "g", 0.3, True, rate)
        _press(e, "gl", 2.1, True, rate)
        _press(e, "g", 2.6, False, rate)
        spot = e.world.component_for_entity(ids["cup"], Transform).position.copy()
        if e.time < 1.5:
            seen["cup"] = spot  # where the left hand comes up to
        seen["last"] = spot
        seen["held"] = np.array([ids["cup"] in e.world.component_for_entity(
            ids["hand_l"], HandState).held])

    scene = CUP_SCENE + _hand("hand_l", 0.3, 0.0, 0.95).replace('" }', '" Glove "gl" }')
    _rig(scene, folder, backend, {"hand_r": _lifted, "hand_l": left}, 3.1, note, rate)
    return {"moved_mm": float(np.linalg.norm(seen["last"] - seen["cup"])) * 1e3,
            "held": bool(seen["held"][0])}


def palm_swipe(folder: Path, backend: str, rate: float) -> dict[str, Any]:
    """The palm-only hand swept at 3 m/s along X at a fixed 5 mm plate at x = 0: the
    farthest its centre got (mm; the plate's near face at -2.5, the palm's own face
    45 mm ahead of its centre)."""
    from app.bench.fingers import PLATE
    from components import Transform

    farthest = [-1.0]

    def path(t: float) -> np.ndarray:
        return np.array([float(np.interp(t, [0.0, 0.8, 0.9], [-0.12, -0.12, 0.18])), 0.0, 1.0])

    def note(e: Any, ids: dict[str, int]) -> None:
        x = float(e.world.component_for_entity(ids["hand_r"], Transform).position[0])
        farthest[0] = max(farthest[0], x)

    _rig(PLATE + _hand("hand_r", -0.12, 0.0, 1.0), folder, backend, {"hand_r": path}, 0.6,
         note, rate)
    return {"farthest_centre_mm": farthest[0] * 1e3}


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
    return {"kind": PALM_COST, "case": f"cost, {HANDS} hands", "backend": backend,
            "ms/step": with_hands * 1e3, "without hands ms/step": without * 1e3,
            "us per hand-step": per_hand, "goal": "<= 20 us",
            "ok": "yes" if per_hand <= 20 else "NO"}
