"""``colosseum bench physics``: the "boxes" scene on our ODE backend beside plain C.

Scene (issue 4): a ground plane and N boxes of 1 m and 1 kg in columns 10 high,
1.2 m apart horizontally and 1.1 m vertically, the lowest centred at 0.55 m;
Δt 1/60 s, the default world (``WorldSettings()``: QuickStep iterations, ERP, CFM, the
warm start of resting islands, contact softness, exact joint islands), at most 4
contacts per pair, μ 0.5.

The reference is ``app/bench/bench_ode.c``, compiled here with ``cc -O2`` against the
same libode (pkg-config) and the engine's own step (``engine/physics/ode3d/stepper.h``,
which both include, run with the same settings) into a temporary folder and run in the
same session, both plain ("C") and summing the contact impulses after the step as our
backend does to report them ("C+fb"). With sleeping on, both sides run the engine's
sleep rule (:mod:`engine.physics.sleep`) the same way: its per-body pass and island
decision (``engine/physics/sleep.h``) after each step, on the islands the step found
(stepper.h's ``cs_sleep``; ODE's own auto-disable off), so they put the same boxes to
sleep on the same steps ("asleep" counts them at the end) and the "on" rows compare the
same work. The rule's numpy-side cost (:class:`SleepRule.update`, which the pymunk
backend runs) is timed on its own below.

For each N and with sleeping off and on it reports ms per step of: plain C; our
raw ``OdeBackend.step``; our step plus the ECS sync (every body's state written in C
into a snapshot table and copied into the pose table as the physics system
does, :class:`app.bench.readback.EcsReadback`). Times are the
stepping thread's CPU time (C: CLOCK_THREAD_CPUTIME_ID, Python: time.thread_time),
so other work on a shared machine does not count; each variant runs ``repeats``
times, alternating, and the fastest run counts.

Then the readback alone, side by side on the settled scene (µs per call, median):
``read_state`` (fresh arrays) copied into the pose table by ``PoseCopy`` (the path
the dynamics system takes today) against ``read_state_into`` the table's rows. And
the sleep rule's own cost per step (:class:`engine.physics.sleep.SleepRule`, every
body awake and slow, so every test runs), beside the plain-C step it rides on.

Run: ``python -m app.bench.physics [--n 100 500 2000] [--steps S] [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import os
import shlex
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from app.bench import print_row
from app.bench.readback import EcsReadback, pose_table, time_readback
from engine.physics.backend import WorldSettings
from engine.physics.sleep import (
    SLEEP_ANGULAR,
    SLEEP_LINEAR,
    SLEEP_TIME,
    SMOOTHING,
    STEADY_SHARE,
    SleepRule,
)

DT = 1.0 / 60.0
SOURCE = Path(__file__).with_name("bench_ode.c")
#: The engine's step over libode, which the reference includes (stepper.h).
STEPPER = Path(__file__).resolve().parents[2] / "engine" / "physics" / "ode3d"


def box_positions(n: int) -> np.ndarray:
    """Centres of the boxes, in the order bench_ode.c creates them (column by column)."""
    i = np.arange(n)
    col, level = i // 10, i % 10
    side = math.ceil(math.sqrt((n + 9) // 10)) if n else 1
    return np.column_stack([1.2 * (col % side), 1.2 * (col // side), 0.55 + 1.1 * level])


def compile_reference(folder: Path) -> Path:
    """Build bench_ode.c with the system compiler against pkg-config's libode."""
    flags = subprocess.run(["pkg-config", "--cflags", "--libs", "ode"], check=True,
                           capture_output=True, text=True).stdout
    exe = folder / "bench_ode"
    cc = os.environ.get("CC", "cc")
    cmd = [cc, "-O2", f"-I{STEPPER}", "-o", str(exe), str(SOURCE), *shlex.split(flags), "-lm"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode:
        raise RuntimeError(f"cannot compile {SOURCE}: {' '.join(cmd)}\n{done.stderr}")
    return exe


def run_reference(exe: Path, n: int, steps: int, sleep: bool,
                  feedback: bool = False) -> tuple[float, float, int]:
    """(ms per step, mean box height at the end, bodies asleep at the end) of the plain C
    program, with the default world's settings."""
    w = WorldSettings()
    out = subprocess.run([str(exe), str(n), str(steps), str(int(sleep)), str(int(feedback)),
                          repr(SLEEP_TIME), repr(SLEEP_LINEAR), repr(SLEEP_ANGULAR),
                          repr(STEADY_SHARE), repr(SMOOTHING),
                          str(w.iterations), repr(w.erp), repr(w.cfm), repr(w.warm_start),
                          repr(w.contact_softness), str(w.exact_rows)],
                         check=True, capture_output=True, text=True).stdout
    fields = dict(item.split("=") for item in out.split())
    return float(fields["ms_per_step"]), float(fields["mean_z"]), int(fields["asleep"])


def build_ours(n: int, sleep: bool) -> Any:
    """The same scene through OdeBackend, with the settings bench_ode.c is given."""
    from components import MaterialProps, Physical, Shape
    from engine.physics.ode3d import OdeBackend

    backend = OdeBackend(WorldSettings(max_contacts=4, auto_sleep=sleep))
    material = MaterialProps(friction=0.5)
    backend.add_static_plane((0.0, 0.0, 1.0), 0.0, material)
    body = Physical(mass=1.0, shapes=[Shape("box", (1.0, 1.0, 1.0))], material=material)
    identity = np.array([1.0, 0.0, 0.0, 0.0])
    for key, pos in enumerate(box_positions(n)):
        backend.add_body(key, body, pos, identity)
    return backend


def time_ours(n: int, steps: int, sleep: bool, sync: bool) -> tuple[float, float, int]:
    """(ms per step, mean box height at the end, bodies asleep at the end); ``sync`` adds
    the ECS readback."""
    backend = build_ours(n, sleep)
    readback = EcsReadback(backend, pose_table(backend.keys()))
    step = backend.step
    t0 = time.thread_time()
    if sync:
        for _ in range(steps):
            step(DT)
            readback()
    else:
        for _ in range(steps):
            step(DT)
    ms = (time.thread_time() - t0) / steps * 1e3
    mean_z = float(backend.read_state().position[:, 2].mean()) if n else 0.0
    asleep = backend.sleeping_count()
    backend.close()
    return ms, mean_z, asleep


def time_sleep_rule(n: int, calls: int = 2000, islands: bool = False) -> float:
    """µs per :meth:`SleepRule.update` for ``n`` awake bodies, slow and jittering: every
    test of the rule runs each step, and nothing falls asleep.

    Without ``islands`` no body is ever quiet for SleepTime (it is made unreachable),
    the common step. With them the bodies stand in columns of ten, touching, each
    column's top body restless: the rest are ready every step, so the islands are looked
    for every step, and every one is held awake by its top.
    """
    rule = SleepRule()
    rule.configure(1e-9 if islands else 1e9, SLEEP_LINEAR, SLEEP_ANGULAR)
    rule.layout(np.arange(n), np.ones(n, bool), np.ones(n, bool))
    rule.awake[:] = True
    rng = np.random.default_rng(1)
    jitter = rng.normal(0.0, 2e-5 if islands else 0.01, (8, 6, n))
    if islands:
        jitter[::2, 0, 9::10] += 0.02  # a top that keeps changing speed: never steady
    rows = np.arange(n)
    touching = np.column_stack([rows, rows + 1])[(rows % 10 != 9) & (rows + 1 < n)]
    for i in range(3):  # warm: by the third step bodies are ready, and scipy imported
        rule.velocity[:] = jitter[i]
        rule.update(DT, None, lambda: touching)
    t0 = time.perf_counter()
    for i in range(calls):
        rule.velocity[:] = jitter[i % 8]
        rule.update(DT, None, lambda: touching)
    return (time.perf_counter() - t0) / calls * 1e6


#: The two tables' titles: what a row measures, its units and its reference.
STEP_KIND = ("one step, wall ms/step (the fastest of the repeats); reference: the same world "
             "in plain C (libode; C+fb: also reading every pose back)")
READBACK_KIND = ("readback of every body into the ECS pose table, us/call (median), and the "
                 "sleep rule's cost per step beside the plain-C step")


def run_bench(ns: tuple[int, ...] = (100, 500, 2000), steps: int | None = None,
              backend: str = "ode", quick: bool = False, repeats: int = 3) -> list[dict]:
    """Measure every N with sleeping off and on; returns one row per (N, sleeping)."""
    if backend == "pymunk":
        from app.bench.physics2d import run_bench as run_2d

        return run_2d((100, 500) if quick else ns, 300 if quick else steps)
    if backend != "ode":
        raise ValueError(f"bench physics: no benchmark for backend {backend!r} "
                         "(choose ode or pymunk)")
    if quick:
        ns = tuple(n for n in ns if n <= 500) or ns[:1]
        repeats = 1
    steps = steps or (60 if quick else 240)
    rows = []
    with tempfile.TemporaryDirectory(prefix="colosseum-bench-") as tmp:
        exe = compile_reference(Path(tmp))
        for n in ns:
            for sleep in (False, True):
                c_ms = fb_ms = raw_ms = sync_ms = math.inf
                c_z = ours_z = 0.0
                c_asleep = ours_asleep = 0
                for _ in range(repeats):
                    ms, c_z, c_asleep = run_reference(exe, n, steps, sleep)
                    c_ms = min(c_ms, ms)
                    fb_ms = min(fb_ms, run_reference(exe, n, steps, sleep, feedback=True)[0])
                    ms, ours_z, ours_asleep = time_ours(n, steps, sleep, sync=False)
                    raw_ms = min(raw_ms, ms)
                    sync_ms = min(sync_ms, time_ours(n, steps, sleep, sync=True)[0])
                row: dict[str, Any] = {
                       "kind": STEP_KIND, "N": n, "sleeping": "on" if sleep else "off",
                       "C ms": c_ms,
                       "C+fb ms": fb_ms, "ours ms": raw_ms, "ours+sync ms": sync_ms,
                       "ratio": raw_ms / c_ms, "ratio+sync": sync_ms / c_ms,
                       "ratio+sync vs C+fb": sync_ms / fb_ms,
                       "realtime 60Hz": "yes" if sync_ms < 1e3 * DT else "no",
                       "mean z C": c_z, "mean z ours": ours_z, "asleep C": c_asleep,
                       "asleep ours": ours_asleep}
                print_row(row)
                rows.append(row)
    print(f"\n{READBACK_KIND}")
    for n in ns:
        backend = build_ours(n, False)
        for _ in range(steps):
            backend.step(DT)
        row = {"kind": READBACK_KIND, **time_readback(backend, 500 if quick else 4000)}
        backend.close()
        c_ms = next(r["C ms"] for r in rows if r.get("N") == n and r.get("sleeping") == "off")
        rule_us = time_sleep_rule(n, 200 if quick else 2000)
        islands_us = time_sleep_rule(n, 100 if quick else 500, islands=True)
        row.update({"sleep rule us": rule_us, "rule/C step": rule_us * 1e-3 / c_ms,
                    "+islands us": islands_us, "+islands/C step": islands_us * 1e-3 / c_ms})
        print_row(row)
        rows.append(row)
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, nargs="+", default=[100, 500, 2000])
    parser.add_argument("--steps", type=int, default=None)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args(argv)
    from app.bench import print_table

    rows = run_bench(tuple(args.n), args.steps, quick=args.quick, repeats=args.repeats)
    print_table(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
