"""``colosseum bench hands``: every fingered-hand figure at two steps and on both backends,
with the palm-only hand's beside it (issue 29), one table per kind of row.

Each row is one (case, step, backend): the scene's step ``step s`` (0.005 and 0.01 s:
200 and 100 Hz frames) and the step physics took (``physics step s``: hands step at
1/120 s or finer, so 0.01 s is two substeps of 0.005), on ODE (the fingered hand,
:mod:`app.bench.fingers`) and on pymunk (the 2D hand in the X–Z plane,
:mod:`app.bench.fingers2d`). Where the palm-only hand has the same figure (tracking error
and lag at the same speed, a held object's jitter: :mod:`app.bench.hands`) it is measured
at the same step on the same backend and printed beside the fingered one; ``ok`` holds
both to the goal. Then the cost rows (:func:`app.bench.hands.cost`, the palm-only hand's
at 120 Hz; :func:`app.bench.fingers.cost`, fingered beside palm-only, at both steps; two
fingered hands in a 90 Hz frame).
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Collection
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from app.bench import fingers, fingers2d
from app.bench.hands import (
    cost,
    held_cup,
    palm_hand_over,
    palm_push,
    palm_shake,
    palm_swipe,
    tracking,
)

STEPS = (0.005, 0.01)
BACKENDS = ("ode", "pymunk")
TRACKING = ("tracking: RMS distance (mm) from the tracked pose, the fingered hand's tips or "
            "palm beside the palm-only hand on the same sinusoid along X")
PENETRATION = ("penetration: how deep (mm) the fingered hand's bones go into what they press,"
               " every contact of the run; palm-only: its palm's deepest into a cup it is "
               "pressed onto and grasps by the button, and into the box it pushes flat")
HELD = ("held still: the object's jitter (mm, RMS from its mean) while the tracked hand "
        "holds still in the air; palm-only: a cup held by its grasp button")
SHAKE = ("shake: a 0.3 kg cup pinched (palm-only: held by its button) and shaken up and "
         "down at 3 Hz, +-10 cm, for 2 s: the share of frames it was held, how far (mm) it "
         "got from the tracked grip")
HAND_OVER = ("hand-over: an object held up by the right hand, taken by the left, let go by "
             "the right: how far it moved (mm); fingered: a pinched ball, palm-only: a cup "
             "held by the button, the left hand under it")
SWIPE = ("swipe: the open hand swept at 3 m/s at a fixed 5 mm plate: the farthest any of "
         "its bodies' centres got (mm from the plate's middle; its near face at -2.5)")


@dataclass(frozen=True, slots=True)
class Job:
    """One group of rows measured together at one step on one backend."""

    group: str  # what ``only`` picks
    cases: tuple[str, ...]  # the rows it gives, in order
    backend: str
    step: float
    measure: Callable[[Path, str, float, bool], list[dict[str, Any]]]


def _verdict(meets: dict[str, bool]) -> str:
    """``yes`` when every named figure meets its goal, else which do not."""
    missed = [name for name, ok in meets.items() if not ok]
    return "yes" if not missed else f"NO ({', '.join(missed)})"


def _tracking(folder: Path, backend: str, rate: float, quick: bool) -> list[dict[str, Any]]:
    seconds, palm_seconds = (1.5, 1.0) if quick else (4.0, 6.0)
    rows = []
    for speed, case, goal in ((0.5, "fingertips, 0.5 m/s", 3.0), (1.0, "palm, 1 m/s", 5.0)):
        measure = fingers.fingertips if backend == "ode" else fingers2d.fingertips_2d
        fingered = measure(folder, seconds, rate, speed)
        palm = tracking(folder, backend, palm_seconds, rate, speed)
        ours = fingered["error_rms_mm"] if speed <= 0.5 else fingered["palm_rms_mm"]
        tips = fingered["tips_rms_mm"]
        rows.append({"kind": TRACKING, "case": case, "fingered mm": ours,
                     "tips mm": tips if isinstance(tips, str) else
                     " ".join(f"{x:.2f}" for x in tips),
                     "palm-only mm": palm["error_rms_mm"], "palm-only lag ms": palm["lag_ms"],
                     "goal": f"<= {goal:g} mm ({'tips' if speed <= 0.5 else 'palm'}), "
                     "<= 15 ms", "ok": _verdict({
                         "fingered": ours <= goal, "palm-only": palm["error_rms_mm"] <= goal
                         and abs(palm["lag_ms"]) <= 15})})
    return rows


def _penetration(case: str, deep: list[float], palm: list[float]) -> dict[str, Any]:
    """The depths' distribution (mm), the palm-only hand's deepest beside it."""
    d = np.array(deep or [0.0]) * 1e3
    palm_deepest = max(palm) * 1e3 if palm else float("nan")
    return {"kind": PENETRATION, "case": case, "contacts": len(deep),
            "median mm": float(np.median(d)), "p95 mm": float(np.percentile(d, 95)),
            "deepest mm": float(d.max()), "palm-only deepest mm": palm_deepest,
            "goal": "deepest <= 2 mm",
            "ok": _verdict({"fingered": bool(deep) and d.max() <= 2.0,
                            "palm-only": bool(palm) and palm_deepest <= 2.0})}


def _held_ball(folder: Path, backend: str, rate: float, quick: bool) -> list[dict[str, Any]]:
    """The pinched ball: penetration while it is grasped and lifted, jitter held still;
    the palm-only hand's held cup beside it (pressed on, grasped by the button, lifted)."""
    if backend == "ode":
        got = fingers.pinched_ball(folder, rate)
    else:
        got = fingers2d.held_ball_2d(folder, rate)
    palm = held_cup(folder, backend, 2.0, rate)
    palm_held = palm["ok"] != "NO (not held)"
    jitter = got["jitter_rms_mm"]
    return [_penetration("pinched ball, lifted", got["depths"], palm["depths"]),
            {"kind": HELD, "case": "pinched ball held still", "fingered mm": jitter,
             "palm-only mm": palm["jitter_rms_mm"], "goal": "<= 0.5 mm, held",
             "ok": _verdict({"fingered": got["held"] and jitter <= 0.5,
                             "palm-only": palm_held and palm["jitter_rms_mm"] <= 0.5})}]


def _pushed_box(folder: Path, backend: str, rate: float, quick: bool) -> list[dict[str, Any]]:
    """A pointing index pushing a box; the palm-only hand's flat palm pushing it beside."""
    if backend == "ode":
        deep = fingers.pushed_box_depths(folder, rate)
    else:
        deep = fingers2d.pushed_box_2d(folder, rate)["depths"]
    return [_penetration("index pushing a box", deep, palm_push(folder, backend, rate)["depths"])]


def _shake(folder: Path, backend: str, rate: float, quick: bool) -> list[dict[str, Any]]:
    row = (fingers.shake if backend == "ode" else fingers2d.shake_2d)(folder, rate)
    palm = palm_shake(folder, backend, rate)
    return [{"kind": SHAKE, "case": "cup shaken 3 Hz +-10 cm",
             "held share": row["held_share"], "farthest mm": row["farthest_mm"],
             "palm-only held share": palm["held_share"],
             "palm-only farthest mm": palm["farthest_mm"],
             "goal": "held throughout, within 50 mm",
             "ok": _verdict({"fingered": row["ok"] in ("yes", True),
                             "palm-only": palm["ok"]})}]


def _hand_over(folder: Path, backend: str, rate: float, quick: bool) -> list[dict[str, Any]]:
    row = (fingers.hand_over if backend == "ode" else fingers2d.hand_over_2d)(folder, rate)
    palm = palm_hand_over(folder, backend, rate)
    return [{"kind": HAND_OVER, "case": "right to left", "moved mm": row["moved_mm"],
             "palm-only moved mm": palm["moved_mm"], "goal": "<= 5 mm, still held",
             "ok": _verdict({"fingered": row["moved_mm"] <= 5.0 and row["held"],
                             "palm-only": palm["moved_mm"] <= 5.0 and palm["held"]})}]


def _swipe(folder: Path, backend: str, rate: float, quick: bool) -> list[dict[str, Any]]:
    row = (fingers.swipe if backend == "ode" else fingers2d.swipe_2d)(folder, rate)
    palm = palm_swipe(folder, backend, rate)
    far, palm_far = row["farthest_centre_mm"], palm["farthest_centre_mm"]
    return [{"kind": SWIPE, "case": "open hand, 3 m/s, 5 mm plate", "farthest mm": far,
             "palm-only farthest mm": palm_far,
             "goal": "no centre past the near face (< -2.5 mm)",
             "ok": _verdict({"fingered": far < -2.5, "palm-only": palm_far < -2.5})}]


GROUPS: dict[str, tuple[tuple[str, ...], Callable[..., list[dict[str, Any]]]]] = {
    "tracking": (("fingertips, 0.5 m/s", "palm, 1 m/s"), _tracking),
    "held ball": (("pinched ball, lifted", "pinched ball held still"), _held_ball),
    "pushed box": (("index pushing a box",), _pushed_box),
    "shake": (("cup shaken 3 Hz +-10 cm",), _shake),
    "hand-over": (("right to left",), _hand_over),
    "swipe": (("open hand, 3 m/s, 5 mm plate",), _swipe),
}


def plan(quick: bool = False, backends: Collection[str] = BACKENDS,
         only: Collection[str] | None = None) -> list[Job]:
    """Every group at every step on every backend (``quick``: at 0.01 s only)."""
    steps = STEPS[1:] if quick else STEPS
    return [Job(group, cases, backend, step, measure)
            for backend in BACKENDS if backend in backends
            for group, (cases, measure) in GROUPS.items() if only is None or group in only
            for step in steps]


def run_rows(folder: Path, quick: bool = False, backends: Collection[str] = BACKENDS,
             only: Collection[str] | None = None) -> list[dict[str, Any]]:
    """The planned rows, each keyed by case, backend and step, grouped by kind."""
    rows: list[dict[str, Any]] = []
    for job in plan(quick, backends, only):
        measured = job.measure(folder, job.backend, 1.0 / job.step, quick)
        physics = float(fingers.run.physics_step)  # type: ignore[attr-defined]
        for row in measured:
            kind, case = row.pop("kind"), row.pop("case")
            rows.append({"kind": kind, "case": case, "backend": job.backend,
                         "step s": job.step, "physics step s": physics, **row})
    order = list(dict.fromkeys(r["kind"] for r in rows))
    return sorted(rows, key=lambda r: order.index(r["kind"]))  # stable: one table a kind


def run_bench(quick: bool = False, backend: str | None = None) -> list[dict[str, Any]]:
    """Every planned row (``quick``: shorter runs at 0.01 s), then the cost rows."""
    if backend is not None and backend not in BACKENDS:
        raise SystemExit(f"colosseum bench hands: no backend {backend!r} with hands (one "
                         f"of {', '.join(BACKENDS)})")
    names = BACKENDS if backend is None else (backend,)
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-hands-") as tmp:
        folder = Path(tmp)
        rows = run_rows(folder, quick, names)
        for name in names:
            rows.append(cost(folder, name, 0.5 if quick else 3.0))
            for step in STEPS[1:] if quick else STEPS:  # the fingered hand's at both steps
                rows += fingers.cost(folder, 0.5 if quick else 2.0, backend=name,
                                     rate=1.0 / step)
            if name == "ode":
                rows.append(fingers.frame_budget(folder, 1.0 if quick else 3.0))
    return rows
