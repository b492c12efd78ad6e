"""Wheel counters to angular velocity: counts over device time, never over frames."""

from __future__ import annotations

import math

import pytest

from services.input import WheelRate


@pytest.mark.parametrize("interval", [0.001, 0.004, 1 / 90, 0.02])
@pytest.mark.parametrize("turns_per_second", [-3.0, 0.25, 1.0, 7.5])
def test_a_steady_wheel_reads_its_angular_velocity_at_any_sample_rate(interval,
                                                                      turns_per_second):
    cpt = 1024
    wheel = WheelRate(counts_per_turn=cpt, window=0.1)
    t = 0.0
    for i in range(200):
        t = i * interval
        wheel.add(round(turns_per_second * cpt * t), t)
    # counts are whole numbers: the rate is exact to one count over the window
    one_count = 1.0 / cpt / (wheel._samples[-1][0] - wheel._samples[0][0])
    assert wheel.turns_per_second(t) == pytest.approx(turns_per_second, abs=one_count)
    assert wheel.angular_velocity(t) == pytest.approx(2 * math.pi * turns_per_second,
                                                      abs=2 * math.pi * one_count)


def test_the_rate_does_not_depend_on_how_counts_are_grouped_into_frames():
    """The same counts read at 30 or at 120 frames per second give the same rate."""
    cpt, rate = 500, 2.0
    samples = [(i * 0.002, round(rate * cpt * i * 0.002)) for i in range(300)]
    results = []
    for fps in (30, 120):
        wheel = WheelRate(counts_per_turn=cpt)
        frame_end = 1.0 / fps
        for t, count in samples:
            while t > frame_end:
                frame_end += 1.0 / fps
            wheel.add(count, t)
        results.append(wheel.turns_per_second(samples[-1][0]))
    assert results[0] == results[1] == pytest.approx(rate, rel=1e-3)


def test_a_wrapping_counter_is_unwrapped_the_short_way():
    wheel = WheelRate(counts_per_turn=1000, wrap=65536, window=0.05)
    count, t = 65000, 0.0
    for _ in range(60):  # forward through the wrap at 10 turns/s
        t += 0.001
        count = (count + 10) % 65536
        assert wheel.add(count, t) is None
    assert wheel.turns_per_second(t) == pytest.approx(10.0)
    assert wheel.total == 590
    for _ in range(80):  # and back again through it
        t += 0.001
        count = (count - 10) % 65536
        wheel.add(count, t)
    assert wheel.turns_per_second(t) == pytest.approx(-10.0)
    assert wheel.total == 590 - 800


def test_a_counter_reset_is_reported_and_not_taken_for_motion():
    wheel = WheelRate(counts_per_turn=1024, max_turns_per_second=20.0, window=0.05)
    for i in range(50):
        wheel.add(50_000 + i * 5, i * 0.001)
    problem = wheel.add(0, 0.050)  # the device restarted
    assert problem is not None and "reset" in problem
    assert wheel.resets == 1
    total = wheel.total
    for i in range(1, 50):
        assert wheel.add(i * 5, 0.050 + i * 0.001) is None
    assert wheel.total == total + 49 * 5
    assert wheel.turns_per_second(0.099) == pytest.approx(5 / 0.001 / 1024)


def test_inverted_wheels_count_backwards_and_a_quiet_wheel_stands():
    wheel = WheelRate(counts_per_turn=100, invert=True, window=0.1)
    for i in range(20):
        wheel.add(i * 10, i * 0.01)
    assert wheel.turns_per_second(0.19) == pytest.approx(-10.0)
    assert wheel.turns == pytest.approx(-1.9)
    assert wheel.turns_per_second(0.19 + 0.05) != 0.0  # a short gap: still rolling
    assert wheel.turns_per_second(0.19 + 0.5) == 0.0  # nothing for half a second: standing
