"""The real-time controller, driven by an injected clock so pacing is exact."""

from __future__ import annotations

import numpy as np
import pytest

from engine.realtime import CostLog, Pacing, RealTimeController
from systems import create_engine


class FakeClock:
    def __init__(self) -> None:
        self.now = 100.0
        self.sleeps: list[float] = []

    def __call__(self) -> float:
        return self.now

    def sleep(self, seconds: float) -> None:
        self.sleeps.append(seconds)
        self.now += seconds

    def work(self, seconds: float) -> None:
        self.now += seconds


def controller(clock: FakeClock, **kw) -> RealTimeController:
    return RealTimeController(Pacing(dt=0.01, **kw), clock=clock, sleep=clock.sleep)


def test_sleeps_the_rest_of_the_step_when_ahead():
    clock = FakeClock()
    ctl = controller(clock)
    for _ in range(100):
        tick = ctl.begin()
        clock.work(0.004)
        ctl.end(tick, 0.003)
    assert clock.sleeps == pytest.approx([0.006] * 100)
    assert ctl.sim_time == pytest.approx(1.0)
    assert ctl.real_time_factor == pytest.approx(1.0)


def test_runs_in_slow_motion_when_behind_and_does_not_catch_up():
    clock = FakeClock()
    ctl = controller(clock)
    for _ in range(50):
        tick = ctl.begin()
        clock.work(0.02)  # twice as long as the step simulates
        ctl.end(tick, 0.02)
    assert clock.sleeps == []
    assert ctl.real_time_factor == pytest.approx(0.5)
    # once fast again, it sleeps normally instead of racing to repay the debt
    tick = ctl.begin()
    clock.work(0.001)
    ctl.end(tick, 0.001)
    assert clock.sleeps == pytest.approx([0.009])


def test_takes_more_substeps_instead_of_sleeping_when_configured():
    clock = FakeClock()
    ctl = controller(clock, early="substep", max_substeps=8)
    tick = ctl.begin()
    assert tick.substeps == 1
    clock.work(0.002)  # 2 ms of physics for one substep, no other work
    ctl.end(tick, 0.002)
    tick = ctl.begin()
    assert tick.substeps == 5  # five 2 ms substeps fit in a 10 ms step
    assert tick.substep_dt == pytest.approx(0.002)
    clock.work(0.001 * tick.substeps)
    ctl.end(tick, 0.001 * tick.substeps)
    assert ctl.begin().substeps == 8  # bounded by max_substeps


def test_grows_the_step_within_its_bound_when_late():
    clock = FakeClock()
    ctl = controller(clock, late="grow", max_dt=0.025)
    tick = ctl.begin()
    clock.work(0.015)
    ctl.end(tick, 0.015)
    assert ctl.begin().dt == pytest.approx(0.015)  # keeps real time with a coarser step
    tick = ctl.begin()
    clock.work(0.05)
    ctl.end(tick, 0.05)
    assert ctl.begin().dt == pytest.approx(0.025)  # never past the bound
    for _ in range(3):
        tick = ctl.begin()
        clock.work(0.001)
        ctl.end(tick, 0.001)
    assert ctl.begin().dt == pytest.approx(0.01)  # back to the nominal step when fast again


def test_unpaced_never_sleeps_and_still_measures():
    clock = FakeClock()
    ctl = controller(clock, paced=False)
    for _ in range(10):
        tick = ctl.begin()
        clock.work(0.001)
        ctl.record_step(0.0008)
        ctl.end(tick, 0.0008)
    assert clock.sleeps == []
    assert ctl.real_time_factor == pytest.approx(10.0)
    assert ctl.step_costs.mean() == pytest.approx(0.0008)
    assert ctl.tick_costs.percentile(99) == pytest.approx(0.001)


def test_rejects_unknown_policies():
    with pytest.raises(ValueError, match="early policy"):
        Pacing(early="nap")
    with pytest.raises(ValueError, match="late policy"):
        Pacing(late="panic")


def test_engine_paces_frames_and_reports_physics_time_over_wall_time():
    from components import Physical, Transform
    from engine import EngineConfig

    clock = FakeClock()
    with create_engine(EngineConfig(backend="ballistic", dt=0.01), clock=clock,
                sleep=clock.sleep) as eng:
        eng.spawn(Transform(), Physical())
        eng.run(frames=50)
        assert len(clock.sleeps) == 50 and all(s == pytest.approx(0.01) for s in clock.sleeps)
        assert eng.physics.time == pytest.approx(0.5)
        assert eng.real_time_factor == pytest.approx(1.0)  # paced: one simulated s per s


def test_cost_log_holds_a_long_run_in_fixed_memory_with_its_percentiles() -> None:
    """A week of frames must not grow the statistics: past the exact first values the
    costs go into a fixed histogram, whose percentiles stay within a bin (2.3 %) of the
    exact ones and whose mean stays exact."""
    rng = np.random.default_rng(3)
    costs = rng.lognormal(np.log(0.004), 0.6, 300_000)  # seconds, a frame-time spread
    log = CostLog()
    for value in costs[:CostLog.EXACT * 2].tolist():
        log.add(value)
    held = log._data.nbytes + log._bins.nbytes
    for value in costs[CostLog.EXACT * 2:].tolist():
        log.add(value)
    assert log._data.nbytes + log._bins.nbytes == held  # nothing grew with 290,000 more
    assert log.count == len(costs)
    assert log.mean() == pytest.approx(costs.mean(), rel=1e-12)
    for q in (1, 50, 90, 99, 99.9):
        assert log.percentile(q) == pytest.approx(np.percentile(costs, q), rel=0.023)
