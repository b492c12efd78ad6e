"""bench physics2d: its bare pymunk space takes the backend's substeps, and --rule runs the
sleep rule without putting the pile to sleep."""

from __future__ import annotations

import time

import numpy as np
import pymunk

from app.bench import physics2d as bench
from engine.physics.backend import WorldSettings


def test_the_raw_space_steps_as_the_backend_does() -> None:
    """With the warm start off the bench's raw space and the backend follow the same
    trajectory to the bit at 1/60 s, which the backend takes as two substeps."""
    n = 30
    raw, ours = bench.build_raw(n), bench.build_ours(n)
    ours.configure(WorldSettings(iterations=bench.ITERATIONS, erp=bench.ERP,
                                 auto_sleep=False, warm_start=0.0))
    times = np.zeros((6, 4), np.int64)

    def ours_block(i: int) -> None:
        for _ in range(bench.BLOCK):
            ours.step(bench.DT)

    bench._interleaved(len(times), raw, ours_block, times, time.perf_counter_ns)
    raw_xz = np.array([b.position for b in raw.bodies if b.body_type == pymunk.Body.DYNAMIC])
    state = ours.read_state()
    order = np.argsort(state.keys)[:n]
    assert np.array_equal(raw_xz, state.position[order][:, ::2])
    assert (times[:, 0] > 0).all()


def test_rule_runs_the_sleep_rule_without_sleeping() -> None:
    """--rule's backend runs the sleep rule with a sleep time no body reaches: after 4 s
    none sleeps, where with the rule's own sleep time the settled pile is asleep."""
    rule, sleeping = bench.build_ours(40, rule=True), bench.build_ours(40, sleeping=True)
    for _ in range(240):
        rule.step(bench.DT)
        sleeping.step(bench.DT)
    assert not any(rule.is_sleeping(k) for k in range(40))
    assert all(sleeping.is_sleeping(k) for k in range(40))
