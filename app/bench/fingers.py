"""``colosseum bench hands``, the fingered hand's rows (``Hand { Fingers 1 }``, ODE; the 2D
hand's on pymunk: :mod:`app.bench.fingers2d`; the tables: :mod:`app.bench.hands`).

Each row is measured beside the palm-only hand's rows of :mod:`app.bench.hands`, with
tracked 26-joint hands from :func:`services.input.hand_pose.pose_hand` and
:mod:`app.bench.hand_grips` (a pinch closing round an object), at the frame rate each is
given (``rate``; the bench runs every row at 200 and at 100 Hz, steps of 0.005 and 0.01 s;
120 Hz by default), serial, unpaced:

* ``fingertips``: the hand swinging along X at 0.5 m/s peak with its fingers curling and
  opening; RMS of each physical fingertip's distance from its tracked tip at the same
  instant (mm). Goal ≤ 3 mm. ``fingered palm``: the same at 1 m/s,
  the palm's (goal ≤ 5 mm).
* ``penetration``: how deep fingertips and phalanges go into what they press while a
  ball is pinched, lifted and held, and into a box a finger pushes along the table:
  the contact depths' median, 95th percentile and deepest (mm). Goal: deepest ≤ 2 mm.
* ``held still``: the pinched ball's jitter (RMS distance from its mean, mm) while the
  tracked hand holds still in the air. Goal ≤ 0.5 mm, held.
* ``shake``: a 0.3 kg cup pinched and shaken up and down at 3 Hz, ±10 cm for 2 s: still
  held throughout, and within 5 cm of the tracked grip's centre. Goal: survives.
* ``hand-over``: a ball held by the right hand, taken by the left, let go by the right:
  how far the ball moved from before the left took it to after the right let go (mm).
  Goal ≤ 5 mm.
* ``swipe``: the tracked hand sweeping at 3 m/s through a fixed 5 mm plate (less than
  the deviation distance past it): how far past the plate's near face any bone got (mm).
  Goal: not through (less than the plate's 5 mm).
* ``cost``: ms per physics step of 4 fingered hands moving, beside 4 palm-only hands and
  no hands, runs alternated :data:`REPEATS` times, medians; µs per hand per step.
  Goal ≤ 150 µs per fingered hand. ``two hands at 90 Hz``: CPU ms per 90 Hz frame of two
  fingered hands moving, beside the 11.1 ms frame budget.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np

from app.bench.hand_grips import pinch

RATE = 120.0
REPEATS = 3
FINGERED_COST = ("cost: fingered hands waving and curling, CPU per physics step and "
                 "hand, beside the same scene and traffic without hands; the palm-only "
                 "hands' in the same runs (the issue's goal is ODE's)")
FRAME_BUDGET = "frame budget: two fingered hands moving, CPU per 90 Hz frame"
#: How much narrower than the object the tracked pinch closes (m).
SQUEEZE = 0.01
TOP = 0.75
TABLE = ('Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
         '  PhysicalAttributes { Geometry { Primitive "box" Size [1.2 1 0.05] } } }\n')
Feed = Callable[[float], Any]
#: The rows' objects: a 0.3 kg cup on the table, a 0.5 kg box a hand pushes along it, a
#: fixed 5 mm plate a hand is swept at (at x = 0).
CUP = ('Object { ID "cup" Position [0 0 0.8] PhysicalAttributes { Mass 0.3\n'
       '  Geometry { Primitive "cylinder" Size [0.08 0.1] } } }\n')
PUSHED_BOX = ('Object { ID "box" Position [0.1 0 0.8] PhysicalAttributes { Mass 0.5\n'
              '  Geometry { Primitive "box" Size [0.1 0.1 0.1] } } }\n')
PLATE = ('Object { ID "plate" Position [0 0 1] Dynamic 0\n'
         '  PhysicalAttributes { Geometry { Primitive "box" Size [0.005 0.4 0.4] } } }\n')


def shaken(t: float) -> float:
    """The shake rows' motion up and down (m): 3 Hz, ±10 cm, from 1.7 s on."""
    return 0.1 * float(np.sin(2 * np.pi * 3.0 * (t - 1.7))) if t > 1.7 else 0.0


def hand(name: str, tracker: str, at: tuple[float, float, float] = (0.0, 0.0, 1.0)) -> str:
    return (f'Object {{ ID "{name}" Position [{at[0]} {at[1]} {at[2]}] '
            f'Hand {{ Tracker "{tracker}" Fingers 1 }} }}\n')


def ball(name: str, width: float, at: tuple[float, ...], mass: float = 0.3) -> str:
    return (f'Object {{ ID "{name}" Position [{at[0]} {at[1]} {at[2]}] PhysicalAttributes '
            f'{{ Mass {mass} Geometry {{ Primitive "sphere" Size [{width}] }} }} }}\n')


def run(scene: str, folder: Path, feeds: dict[str, Feed], seconds: float,
        on_frame: Callable[[Any, dict[str, int]], None] | None = None, rate: float = RATE,
        settle: float = 0.5, backend: str = "ode") -> float:
    """Run ``scene`` with tracked hands (name -> t -> HandJoints, or TrackerPose for a
    palm-only hand) on ``backend``; CPU seconds per physics step after ``settle`` seconds."""
    from engine import EngineConfig, Phase, system
    from engine.scene import instantiate, spec_from_text
    from services.input import InputHub
    from systems import create_engine

    config = EngineConfig(backend=backend, fast=True, dt=1.0 / rate, content_dir=folder,
                          debug=False)
    with create_engine(config) as engine:
        ids = instantiate(engine, spec_from_text(scene, folder))
        engine.start()
        hub = engine.resource(InputHub)
        hub.clock = lambda: engine.time

        @system(Phase.INPUT, before=("InputSystem",))
        def trackers(e: Any, dt: float) -> None:
            for feed in feeds.values():
                hub.inject(feed(e.time))

        engine.add_system(trackers)
        if on_frame is not None:
            engine.add_system(system(Phase.POST_PHYSICS)(lambda e, dt: on_frame(e, ids)))
        engine.run(seconds=settle)
        steps0, frames0, t0 = engine.physics.steps, engine.frame, time.thread_time()
        engine.run(seconds=seconds)
        spent = time.thread_time() - t0
        run.per_frame = spent / max(engine.frame - frames0, 1)  # type: ignore[attr-defined]
        # the step physics took (hands step at 1/120 s or finer: 0.01 s is two substeps)
        substeps = max(engine.physics.controller.substeps, 1)
        run.physics_step = config.dt / substeps  # type: ignore[attr-defined]
        return spent / max(engine.physics.steps - steps0, 1)


def physical_tips(engine: Any, palm: int) -> np.ndarray:
    """The fingered hand's physical fingertips (5, 3)."""
    from systems import hand_fingers
    from systems.hands import Hands

    rig = engine.resource(Hands).rigs[palm]
    return hand_fingers.tips_now(engine, rig.fingers)


def bones_of(engine: Any, palm: int) -> list[int]:
    from systems.hands import Hands

    fingers = engine.resource(Hands).rigs[palm].fingers
    return [] if fingers is None else list(fingers.bones)


def fingertips(folder: Path, seconds: float, rate: float = RATE, speed: float = 0.5
               ) -> dict[str, Any]:
    from components import Transform
    from services.input.events import HAND_JOINTS
    from services.input.hand_pose import pose_hand

    omega = 5.0
    amp = speed / omega
    tips = [HAND_JOINTS.index(f"{f}_tip") for f in ("thumb", "index", "middle", "ring",
                                                    "little")]

    def sample(t: float) -> Any:
        curl = 0.3 + 0.2 * np.sin(2.0 * t)
        return pose_hand("right", (amp * np.sin(omega * t), 0.0, 1.0), (1.0, 0.0, 0.0, 0.0),
                         dict.fromkeys(("thumb", "index", "middle", "ring", "little"), curl),
                         timestamp=t)

    tip_err: list[np.ndarray] = []
    palm_err: list[float] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        if bones_of(e, ids["hand_r"]):
            tracked = sample(e.time + 1.0 / rate)  # where the step just taken should be
            p = np.asarray(tracked.positions)
            tip_err.append(np.linalg.norm(physical_tips(e, ids["hand_r"]) - p[tips], axis=1))
            palm = e.world.component_for_entity(ids["hand_r"], Transform).position
            palm_err.append(float(np.linalg.norm(palm - p[0])))

    run(hand("hand_r", "right"), folder, {"right": sample}, seconds, note, rate)
    err = np.array(tip_err) * 1e3
    rms = np.sqrt(np.mean(err**2, axis=0))
    palm_mm = float(np.sqrt(np.mean(np.square(palm_err)))) * 1e3
    goal = 3.0 if speed <= 0.5 else 5.0
    worst = float(rms.max()) if speed <= 0.5 else palm_mm
    return {"case": f"fingered, {speed:g} m/s, {rate:g} Hz", "backend": "ode",
            "error_rms_mm": worst, "tips_rms_mm": " ".join(f"{x:.2f}" for x in rms),
            "palm_rms_mm": palm_mm, "goal": f"<= {goal:g} mm "
            f"({'tips' if speed <= 0.5 else 'palm'})",
            "ok": "yes" if worst <= goal else "NO"}


def grasping(device: str, centre: np.ndarray, width: float, across: tuple[float, ...],
             motion: Callable[[float], np.ndarray], *, left: bool = False,
             close: tuple[float, float] = (0.3, 0.7), open_at: float = 1e9) -> Feed:
    """A tracked hand that pinches an object of ``width`` at ``centre``: open round it,
    closed 2 cm narrower than it between ``close``, moved by ``motion(t)`` (an offset),
    opened again from ``open_at``."""
    def feed(t: float) -> Any:
        grip = float(np.interp(t, [close[0], close[1], open_at, open_at + 0.3],
                               [width + 0.04, width - SQUEEZE, width - SQUEEZE, width + 0.05]))
        return pinch(device, centre + motion(t), across, width, grip, left=left,
                     timestamp=t)
    return feed


def lift(height: float = 0.15, start: float = 0.9, end: float = 1.5
         ) -> Callable[[float], np.ndarray]:
    return lambda t: np.array([0.0, 0.0, float(np.interp(t, [start, end], [0.0, height]))])


def depths(engine: Any, bones: set[int], obj: int) -> list[float]:
    """This frame's contact depths between the bones and ``obj`` (m)."""
    from engine.events import Contacts

    out: list[float] = []
    for c in engine.events.frame(Contacts):
        a, b = c.batch["a"], c.batch["b"]
        mine = (np.isin(a, list(bones)) & (b == obj)) | (np.isin(b, list(bones)) & (a == obj))
        out += c.batch["depth"][mine].tolist()
    return out


def held_ball(folder: Path, rate: float = RATE) -> list[dict[str, Any]]:
    """Pinch a ball, lift it, hold still: penetration while grasping, jitter while still."""
    got = pinched_ball(folder, rate)
    jitter, ok = got["jitter_rms_mm"], got["held"]
    return [penetration_row("pinched ball, lifted", got["depths"]),
            {"case": "fingered, held ball still", "backend": "ode", "jitter_rms_mm": jitter,
             "goal": "<= 0.5 mm, held", "ok": "yes" if jitter <= 0.5 and ok else
             "NO" if ok else "NO (not held)"}]


def pinched_ball(folder: Path, rate: float = RATE) -> dict[str, Any]:
    """:func:`held_ball`'s run: the bones' contact depths in the ball (m), its jitter held
    still (mm) and whether it was held, lifted, throughout."""
    width = 0.06
    centre = np.array([0.0, 0.0, TOP + width / 2])
    feed = grasping("right", centre, width, (0.0, 1.0, 0.0), lift())
    return held_ball_run(TABLE + ball("ball", width, centre) + hand("hand_r", "right"),
                         folder, feed, centre, rate)


def held_ball_run(scene: str, folder: Path, feed: Feed, centre: np.ndarray, rate: float,
                  backend: str = "ode") -> dict[str, Any]:
    """Run ``scene`` (a right hand ``hand_r`` and a ``ball`` at ``centre``) with the right
    hand fed ``feed`` for 3 s: the bones' contact depths in the ball (m), the ball's jitter
    after 2 s (mm) and whether it was held, lifted, all that time (both backends' rows)."""
    from components import HandState, Transform

    deep: list[float] = []
    spots: list[np.ndarray] = []
    held: list[bool] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        deep.extend(depths(e, set(bones_of(e, ids["hand_r"])), ids["ball"]))
        if e.time > 2.0:
            spots.append(e.world.component_for_entity(ids["ball"], Transform).position.copy())
            held.append(ids["ball"] in e.world.component_for_entity(ids["hand_r"],
                                                                    HandState).held)

    run(scene, folder, {"right": feed}, 3.0, note, rate, settle=0.0, backend=backend)
    s = np.array(spots)
    jitter = float(np.sqrt(np.mean(np.sum((s - s.mean(axis=0)) ** 2, axis=1)))) * 1e3
    return {"depths": deep, "jitter_rms_mm": jitter,
            "held": bool(all(held) and s[:, 2].min() > centre[2] + 0.1)}


def penetration_row(case: str, deep: list[float]) -> dict[str, Any]:
    d = np.array(deep or [0.0]) * 1e3
    return {"case": f"fingered penetration, {case}", "backend": "ode",
            "contacts": len(deep), "median_mm": float(np.median(d)),
            "p95_mm": float(np.percentile(d, 95)), "deepest_mm": float(d.max()),
            "goal": "deepest <= 2 mm", "ok": "yes" if deep and d.max() <= 2.0 else "NO"}


def pushed_box(folder: Path, rate: float = RATE) -> dict[str, Any]:
    """A pointing index finger pushes a 0.5 kg box along the table."""
    return penetration_row("index pushing a box", pushed_box_depths(folder, rate))


def pushed_box_depths(folder: Path, rate: float = RATE) -> list[float]:
    """:func:`pushed_box`'s run: the bones' contact depths in the box (m)."""
    from services.input.hand_pose import GESTURES, pose_hand

    # the hand's fingers along +x, its pointing index 4 cm above the table; it moves +x
    q = (1.0, 0.0, 0.0, 0.0)

    def feed(t: float) -> Any:
        x = float(np.interp(t, [0.0, 0.4, 2.0], [-0.22, -0.22, 0.05]))
        return pose_hand("right", (x, 0.0, TOP + 0.04), q, GESTURES["point"], timestamp=t)

    deep: list[float] = []
    run(TABLE + PUSHED_BOX + hand("hand_r", "right", (-0.15, 0.0, 0.8)), folder, {"right": feed},
        2.0, lambda e, ids: deep.extend(depths(e, set(bones_of(e, ids["hand_r"])),
                                               ids["box"])), rate, settle=0.0)
    return deep


def shake(folder: Path, rate: float = RATE) -> dict[str, Any]:
    """A 0.3 kg cup pinched, lifted, shaken at 3 Hz ±10 cm for 2 s."""
    got = shaken_cup(folder, rate, lambda centre, width, motion: grasping(
        "right", centre, width, (0.0, 1.0, 0.0), motion))
    return {"case": "fingered, cup shaken 3 Hz +-10 cm", "backend": "ode",
            "held_share": got["held_share"], "farthest_mm": got["farthest_mm"],
            "goal": "held throughout", "ok": "yes" if got["ok"] else "NO"}


def shaken_cup(folder: Path, rate: float,
               pinching: Callable[[np.ndarray, float, Callable[[float], np.ndarray]], Feed],
               backend: str = "ode") -> dict[str, Any]:
    """A 0.3 kg cup on the table, pinched by the right hand ``pinching(centre, width,
    motion)`` feeds, lifted and shaken up and down at 3 Hz ±10 cm for 2 s (both backends'
    rows): the share of frames it was held, how far (mm) it got from the tracked grip's
    centre, and whether it was held throughout within 5 cm."""
    from components import HandState, Transform

    width = 0.08
    centre = np.array([0.0, 0.0, TOP + 0.05])

    def motion(t: float) -> np.ndarray:
        up = lift(0.2)(t)
        up[2] += shaken(t)
        return up

    worst: list[float] = []
    held: list[bool] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        if e.time > 1.7:
            tracked = centre + motion(e.time)
            cup_at = e.world.component_for_entity(ids["cup"], Transform).position
            worst.append(float(np.linalg.norm(cup_at - tracked)))
            held.append(ids["cup"] in e.world.component_for_entity(ids["hand_r"],
                                                                   HandState).held)

    run(TABLE + CUP + hand("hand_r", "right"), folder,
        {"right": pinching(centre, width, motion)}, 3.7, note, rate, settle=0.0,
        backend=backend)
    return {"held_share": float(np.mean(held)) if held else 0.0,
            "farthest_mm": max(worst) * 1e3 if worst else float("nan"),
            "ok": bool(held) and all(held) and max(worst) < 0.05}


def hand_over(folder: Path, rate: float = RATE) -> dict[str, Any]:
    """The right hand holds a ball up; the left takes it; the right lets go."""
    from components import Transform

    width = 0.06
    centre = np.array([0.0, 0.0, TOP + width / 2])
    seen: dict[str, np.ndarray] = {}
    right = grasping("right", centre, width, (0.0, 1.0, 0.0), lift(), open_at=2.6)

    def left(t: float) -> Any:
        """Open, 0.25 m aside until the ball is up, then over it (at 0.5 m/s) and closed:
        a hand kept on the ball from the start would push it before the right holds it."""
        aside = np.array([0.0, float(np.interp(t, [1.2, 1.7], [0.25, 0.0])), 0.0])
        at = seen.get("ball", centre + np.array([0.0, 0.0, 0.15])) + aside
        grip = float(np.interp(t, [1.8, 2.2], [width + 0.04, width - 0.02]))
        return pinch("left", at, (1.0, 0.0, 0.0), width, grip, left=True, timestamp=t)

    def note(e: Any, ids: dict[str, int]) -> None:
        spot = e.world.component_for_entity(ids["ball"], Transform).position.copy()
        if e.time < 1.75:
            seen["ball"] = spot  # where the left hand reaches for it
        seen["last"] = spot

    scene = TABLE + ball("ball", width, centre) + hand("hand_r", "right") + \
        hand("hand_l", "left", (0.0, 0.3, 1.0))
    run(scene, folder, {"right": right, "left": left}, 3.6, note, rate, settle=0.0)
    moved = float(np.linalg.norm(seen["last"] - seen["ball"])) * 1e3
    lifted = bool(seen["last"][2] > centre[2] + 0.1)
    return {"case": "fingered, hand-over right to left", "backend": "ode",
            "moved_mm": moved, "held": lifted, "goal": "<= 5 mm, still held",
            "ok": "yes" if moved <= 5.0 and lifted else "NO"}


def swipe(folder: Path, rate: float = RATE) -> dict[str, Any]:
    """The open hand swept at 3 m/s through a fixed 5 mm plate at x = 0."""
    from components import Transform
    from services.input.hand_pose import GESTURES, pose_hand

    q = (np.cos(np.pi / 4), 0.0, 0.0, np.sin(np.pi / 4))  # fingers along +y, edge-on

    def feed(t: float) -> Any:
        x = float(np.interp(t, [0.0, 0.3, 0.4], [-0.12, -0.12, 0.18]))  # 3 m/s
        return pose_hand("right", (x, -0.05, 1.0), q, GESTURES["open"], timestamp=t)

    farthest = [-1.0]

    def note(e: Any, ids: dict[str, int]) -> None:
        for body in [ids["hand_r"], *bones_of(e, ids["hand_r"])]:
            x = float(e.world.component_for_entity(body, Transform).position[0])
            farthest[0] = max(farthest[0], x)

    run(PLATE + hand("hand_r", "right", (-0.12, 0.0, 1.0)), folder, {"right": feed}, 0.6,
        note, rate, settle=0.0)
    return {"case": "fingered, 3 m/s swipe at a 5 mm plate", "backend": "ode",
            "farthest_centre_mm": farthest[0] * 1e3, "goal": "no bone's centre past "
            "the plate (< -2.5 mm)", "ok": "yes" if farthest[0] < -0.0025 else "NO"}


def _waving(name: str, i: int) -> Feed:
    """A hand waving and curling; its samples kept (the cost rows time the hands, not
    the making of their samples: the warm-up run makes them)."""
    from services.input.hand_pose import pose_hand

    @cache
    def feed(t: float) -> Any:
        c = 0.4 + 0.3 * np.sin(2.0 * t + i)
        at = (-0.6 + 0.4 * i + 0.1 * np.sin(3.0 * t + i), -0.3, 1.1 + 0.05 * np.sin(2 * t))
        return pose_hand(name, at, (1.0, 0.0, 0.0, 0.0),
                         dict.fromkeys(("thumb", "index", "middle", "ring", "little"), c),
                         timestamp=t)
    return feed


def _as_tracker(feed: Feed, name: str) -> Feed:
    from services.input.events import TrackerPose

    @cache
    def pose(t: float) -> Any:
        h = feed(t)
        return TrackerPose(name, h.positions[0], h.orientations[0], (0.0, 0.0, 0.0), t)
    return pose


def cost(folder: Path, seconds: float, count: int = 4, backend: str = "ode",
         rate: float = RATE) -> list[dict[str, Any]]:
    """Fingered hands, palm-only hands and none, the same tracked traffic, alternated, in
    frames at ``rate`` Hz (CPU per physics step: hands step at 1/120 s or finer)."""
    names = [f"h{i}" for i in range(count)]
    feeds: dict[str, Feed] = {n: _waving(n, i) for i, n in enumerate(names)}
    feeds.update({f"{n}_palm": _as_tracker(feeds[n], f"{n}_palm") for n in names})
    at = [(-0.6 + 0.4 * i, -0.3, 1.1) for i in range(count)]
    fingered = TABLE + "".join(hand(f"hand{i}", n, at[i]) for i, n in enumerate(names))
    palms = TABLE + "".join(f'Object {{ ID "hand{i}" Position [{at[i][0]} {at[i][1]} '
                            f'{at[i][2]}] Hand {{ Tracker "{n}_palm" }} }}\n'
                            for i, n in enumerate(names))
    on = {"backend": backend, "rate": rate}

    def frame(scene: str) -> tuple[float, float]:
        """CPU s per frame and the physics steps a frame took (hands substep a long one)."""
        per_step = run(scene, folder, feeds, seconds, **on)
        per_frame = run.per_frame  # type: ignore[attr-defined]
        return per_frame, per_frame / per_step

    frame(fingered)  # warm-up, discarded
    runs = [(frame(fingered), frame(palms), frame(TABLE)) for _ in range(REPEATS)]
    (f, steps), (p, _), (n, _) = ((np.array([r[k][0] for r in runs]),
                                   np.array([r[k][1] for r in runs])) for k in range(3))
    # the frames' difference per hand and per physics step of the hands' scene (at 100 Hz
    # two of 0.005 s, where the scene without hands takes one of 0.01 s)
    per_f, per_p = (f - n) / steps / count * 1e6, (p - n) / steps / count * 1e6
    spread = f"{per_f.min():.0f}-{per_f.max():.0f}"
    return [{"kind": FINGERED_COST, "case": f"cost, {count} fingered hands",
             "backend": backend, "step s": round(1.0 / rate, 6),
             "physics step s": round(1.0 / rate / float(np.median(steps)), 6),
             "ms/step": float(np.median(f / steps)) * 1e3,
             "without hands ms/step": float(np.median(n / steps)) * 1e3,
             "us per hand-step": float(np.median(per_f)), "spread us": spread,
             "palm-only us per hand-step": float(np.median(per_p)),
             "goal": "<= 150 us (ODE)" if backend == "ode" else "(ODE's goal)",
             "ok": ("yes" if np.median(per_f) <= 150 else "NO") if backend == "ode" else "-"}]


def frame_budget(folder: Path, seconds: float) -> dict[str, Any]:
    """Two fingered hands moving, frames at 90 Hz: CPU ms per frame against 11.1 ms."""
    feeds = {"right": _waving("right", 0), "left": _waving("left", 1)}
    scene = TABLE + hand("hand_r", "right", (-0.6, -0.3, 1.1)) + \
        hand("hand_l", "left", (-0.2, -0.3, 1.1))
    run(scene, folder, feeds, seconds, rate=90.0)
    ms = run.per_frame * 1e3  # type: ignore[attr-defined]
    return {"kind": FRAME_BUDGET, "case": "two fingered hands, 90 Hz frames", "backend": "ode",
            "ms/frame": ms, "budget ms": 1e3 / 90.0, "goal": "inside the frame budget",
            "ok": "yes" if ms < 1e3 / 90.0 else "NO"}
