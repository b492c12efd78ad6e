"""Benchmark: the boxes scene in 2D through PymunkBackend against pymunk driven directly.

The scene is issue 4's "boxes" laid out in the side view: a ground plane and N boxes
(1 m, 1 kg, friction 0.5) in columns 10 high, 1.2 m apart in X and 1.1 m apart
vertically, the lowest centred at z = 0.55 m; Δt = 1/60 s, 20 solver iterations,
sleeping off (``--sleeping`` turns it on in both). Both worlds are built with the
same pymunk settings and stepped in the same run, alternating every ten steps, so
they see the same machine and the same simulated phase. The backend takes a step longer
than ``MAX_SUBSTEP`` as :func:`substeps` equal parts (1/60 s: two), and so does the raw
space here, which makes it the fair reference: the same chipmunk work, without the
engine's passes. With the warm start off the two follow bit-identical trajectories; on,
as benched (the engine's default), its preloads and holds part them within the first
steps (the table's "same" says which). Ours is timed with the ECS sync: every body's state
written by ``read_state_into`` straight into the rows of a pose table of N + 1
Transforms (:class:`app.bench.readback.EcsReadback`), and then again with
``contacts()`` too (which the engine collects every step). Times are medians over the
blocks and a ratio is the median of the blocks' own ratios (this is a shared machine;
means are in the returned dicts). Then the readback alone, old path beside new
(:func:`app.bench.readback.time_readback`). With ``--sleeping`` the raw space sleeps
by chipmunk's own rule after ``SLEEP_TIME`` and ours by the engine's sleep rule, so
the two no longer follow the same trajectories.

``--rule`` runs the engine's sleep rule in ours alone (chipmunk's sleeping off in the
raw space), with a sleep time no body reaches (``RULE_SLEEP_TIME``): at rest in this
scene the whole pile would otherwise be asleep within seconds of settling (the resting
hold) and ours would only be skipping steps, so the ratio is what the rule's pass costs
each step on top of the warm start (its islands, found only on steps where some body is
ready to sleep, are not in it).

Run: ``python -m app.bench.physics2d [--n 100 500 2000] [--steps S] [--sleeping|--rule]
[--cpu-time]``.
"""

from __future__ import annotations

import argparse
import gc
import math
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pymunk

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from app.bench import print_row  # noqa: E402
from app.bench.readback import EcsReadback, pose_table, time_readback  # noqa: E402
from components import MaterialProps, Physical, Shape  # noqa: E402
from engine.physics.backend import WorldSettings  # noqa: E402
from engine.physics.pymunk2d import PymunkBackend  # noqa: E402
from engine.physics.pymunk2d.backend import (  # noqa: E402
    COLLISION_SLOP,
    MAX_SUBSTEP,
    substeps,
)
from engine.physics.pymunk2d.shapes import PLANE_DEPTH, PLANE_HALF_LENGTH  # noqa: E402
from engine.physics.sleep import SLEEP_TIME  # noqa: E402

DT = 1.0 / 60.0
ITERATIONS = 20
ERP = 0.2
FRICTION = 0.5
GROUND_KEY = 10**6
#: Steps timed together; raw and ours alternate block by block.
BLOCK = 10
#: ``--rule``'s sleep time (s): longer than any run, so no body falls asleep.
RULE_SLEEP_TIME = 1e9


def box_positions(n: int) -> np.ndarray:
    """Centres (x, z) of the boxes: columns of 10, 1.2 m apart, 1.1 m up, from z = 0.55."""
    i = np.arange(n)
    return np.stack([(i // 10) * 1.2, 0.55 + (i % 10) * 1.1], axis=1)


def build_raw(n: int, sleeping: bool = False) -> pymunk.Space:
    """The scene in a bare pymunk space, configured as PymunkBackend configures its own."""
    space = pymunk.Space()
    space.gravity = (0.0, -9.81)
    space.iterations = ITERATIONS
    space.collision_slop = COLLISION_SLOP
    space.collision_bias = (1.0 - ERP) ** 60
    space.sleep_time_threshold = SLEEP_TIME if sleeping else math.inf
    ground = pymunk.Body(body_type=pymunk.Body.STATIC)
    half, depth = PLANE_HALF_LENGTH, PLANE_DEPTH
    floor = pymunk.Poly(ground, [(half, 0.0), (-half, 0.0), (-half, -depth), (half, -depth)])
    floor.friction = math.sqrt(FRICTION)  # pymunk multiplies: the pair's μ is 0.5
    space.add(ground, floor)
    for x, z in box_positions(n):
        body = pymunk.Body(1.0, pymunk.moment_for_box(1.0, (1.0, 1.0)))
        body.position = (float(x), float(z))
        shape = pymunk.Poly.create_box(body, (1.0, 1.0))
        shape.friction = math.sqrt(FRICTION)
        space.add(body, shape)
    return space


def build_ours(n: int, sleeping: bool = False, rule: bool = False) -> PymunkBackend:
    """The scene through PymunkBackend; ``rule``: the sleep rule on, with a sleep time no
    body reaches (unless ``sleeping``)."""
    backend = PymunkBackend()
    backend.configure(WorldSettings(iterations=ITERATIONS, erp=ERP, auto_sleep=sleeping or rule,
                                    sleep_time=RULE_SLEEP_TIME if rule and not sleeping
                                    else SLEEP_TIME))
    material = MaterialProps(friction=FRICTION)
    backend.add_body(GROUND_KEY, Physical(kind="static", mass=None, material=material,
                                          shapes=[Shape("plane", (0.0, 0.0, 1.0, 0.0))]),
                     np.zeros(3), np.array([1.0, 0.0, 0.0, 0.0]))
    cube = Physical(mass=1.0, shapes=[Shape("box", (1.0, 1.0, 1.0))], material=material)
    quat = np.array([1.0, 0.0, 0.0, 0.0])
    for key, (x, z) in enumerate(box_positions(n)):
        backend.add_body(key, cube, np.array([x, 0.0, z]), quat)
    return backend


def bench_one(n: int, steps: int, sleeping: bool = False, rule: bool = False,
              cpu: bool = False) -> dict:
    """Alternate raw and backend blocks of steps; ms per step (medians, and means).
    ``rule``: ours runs the sleep rule (as by default, but with a sleep time no body
    reaches) while the raw space does not sleep: the rule's cost each step. ``cpu``: time
    by the thread's CPU time instead of the wall clock (on a machine shared by more
    processes than it has cores the wall clock counts the time others ran; the CPU time
    does not)."""
    raw, ours = build_raw(n, sleeping), build_ours(n, sleeping, rule)
    # the ECS pose table (entity = body key, as in the engine); no body comes or goes here
    readback = EcsReadback(ours, pose_table(ours.keys()))
    clock = time.thread_time_ns if cpu else time.perf_counter_ns
    blocks = max(1, steps // BLOCK)
    # per block of BLOCK steps, in ns: raw, our step, our sync, our contacts
    times = np.zeros((blocks, 4), np.int64)

    def ours_block(i: int) -> None:
        for _ in range(BLOCK):
            t1 = clock()
            ours.step(DT)
            t2 = clock()
            readback()
            t3 = clock()
            ours.contacts()
            times[i, 1:] += t2 - t1, t3 - t2, clock() - t3

    _interleaved(blocks, raw, ours_block, times, clock)
    raw_xz = np.array([b.position for b in raw.bodies if b.body_type == pymunk.Body.DYNAMIC])
    state = ours.read_state()
    order = np.argsort(state.keys)[:n]  # keys 0..n-1 in build order, then the ground
    same = bool(np.array_equal(raw_xz, state.position[order][:, ::2]))
    contacts = len(ours.contacts())
    ours.close()
    return {"n": n, "steps": blocks * BLOCK, "sleeping": sleeping, "rule": rule or sleeping,
            "clock": "thread CPU time" if cpu else "wall", **_summary(times),
            "contacts": contacts, "same_trajectory": same}


def _summary(times: np.ndarray) -> dict[str, float]:
    """ms per step from blocks of (raw, our step, our sync, our contacts) ns: medians,
    means, and ratios as the median of each block's own ratio (raw and ours ran back to
    back: robust to the other work a shared machine does in between)."""
    med = np.median(times, axis=0) * 1e-6 / BLOCK
    mean = times.mean(axis=0) * 1e-6 / BLOCK
    raw = times[:, 0].astype(np.float64)
    return {
        "raw_ms": float(med[0]),
        "step_ms": float(med[1]),
        "sync_ms": float(med[2]),
        "contacts_ms": float(med[3]),
        "ours_ms": float(med[1] + med[2]),
        "ratio": float(np.median((times[:, 1] + times[:, 2]) / raw)),
        "ratio_with_contacts": float(np.median(times[:, 1:].sum(axis=1) / raw)),
        "ratio_of_means": float((mean[1] + mean[2]) / mean[0]),
        "raw_mean_ms": float(mean[0]),
        "ours_mean_ms": float(mean[1] + mean[2]),
    }


def _interleaved(blocks: int, raw: pymunk.Space, ours_block: Any, times: np.ndarray,
                 clock: Any) -> None:
    """Blocks of raw steps and of ours, back to back, garbage collection off; who goes
    first alternates, so neither always finds a cold cache. ``clock``: ours' too."""
    parts = substeps(DT)
    part = DT / parts
    gc.disable()
    try:
        for i in range(blocks):
            if i % 2:
                ours_block(i)
            t0 = clock()
            for _ in range(BLOCK):
                for _ in range(parts):
                    raw.step(part)
            times[i, 0] = clock() - t0
            if not i % 2:
                ours_block(i)
    finally:
        gc.enable()


def run_bench(ns: tuple[int, ...] = (100, 500, 2000), steps: int | None = None,
              sleeping: bool = False, rule: bool = False, cpu: bool = False) -> list[dict]:
    """Run the benchmark for each N and print the table; returns one dict per N."""
    rows = []
    what = ("on in both" if sleeping else "rule on in ours, off in raw" if rule else "off")
    print(f"boxes in 2D, dt 1/60 s, {ITERATIONS} iterations, warm start on in ours, "
          f"sleeping {what}; median ms per step ({'thread CPU time' if cpu else 'wall'})")
    print(f"each step is taken as {substeps(DT)} equal substep(s) (MAX_SUBSTEP {MAX_SUBSTEP} s), "
          "by ours and by the raw space alike")
    print(f"{'N':>6} {'raw':>8} {'ours':>8} {'=step':>8} {'+sync':>7} {'ratio':>7} "
          f"{'contacts':>9} {'ratio+c':>8} {'same':>5}")
    for n in ns:
        r = bench_one(n, steps if steps is not None else max(150, 150_000 // max(n, 1)),
                      sleeping, rule, cpu)
        rows.append(r)
        print(f"{r['n']:>6} {r['raw_ms']:>8.3f} {r['ours_ms']:>8.3f} {r['step_ms']:>8.3f} "
              f"{r['sync_ms']:>7.3f} {r['ratio']:>6.3f}x {r['contacts_ms']:>9.3f} "
              f"{r['ratio_with_contacts']:>7.3f}x {'yes' if r['same_trajectory'] else 'NO':>5}",
              flush=True)
    print("readback of every body into the ECS pose table, µs per call (median)")
    for n in ns:
        backend = build_ours(n, sleeping)
        for _ in range(60):
            backend.step(DT)
        row = time_readback(backend)
        backend.close()
        print_row(row)
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[100, 500, 2000])
    parser.add_argument("--steps", type=int, default=None, help="steps per N (default: auto)")
    parser.add_argument("--sleeping", action="store_true", help="auto-sleep on in both")
    parser.add_argument("--rule", action="store_true",
                        help="the sleep rule on in ours (raw: chipmunk sleeping off)")
    parser.add_argument("--cpu-time", action="store_true",
                        help="time by the thread's CPU time (a machine shared by many)")
    args = parser.parse_args(argv)
    run_bench(tuple(args.n), args.steps, args.sleeping, args.rule, args.cpu_time)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
