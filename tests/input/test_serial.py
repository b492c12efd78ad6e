"""Serial devices through a pseudo-terminal pair: a wheel encoder printing counts."""

from __future__ import annotations

import math
import os
import threading
import time
from pathlib import Path

import pytest
from input_helpers import input_engine, run_until

from engine.input import DeviceError, InputHub, InputState
from engine.input.serial_line import LineFormat, SerialDevice


@pytest.fixture
def pty_pair():
    """(writer fd, port path): what is written to the fd arrives on the port."""
    master, slave = os.openpty()
    yield master, os.ttyname(slave)
    os.close(master)
    os.close(slave)


def serial_scene(path: str, extra: str = "") -> str:
    return f"""
Input {{
  Device {{ ID "encoders" Kind "serial" Path "{path}" Baud 115200 }}
  Wheel {{ ID "left" CountsPerTurn 1024 Window 0.2 }}
  {extra}
}}
"""


def test_a_serial_wheel_reads_the_angular_velocity_it_turns_at(tmp_path: Path, pty_pair):
    writer, path = pty_pair
    turns_per_second = 2.0
    with input_engine(serial_scene(path), tmp_path) as engine:
        engine.step()
        sent: list[float] = []

        def turn() -> None:
            start = time.monotonic()
            while (now := time.monotonic()) - start < 0.6:
                os.write(writer, f"left {round(turns_per_second * 1024 * (now - start))}\n"
                         .encode())
                sent.append(now)
                time.sleep(0.004)

        thread = threading.Thread(target=turn)
        thread.start()
        while thread.is_alive():
            engine.step()
            time.sleep(0.005)
        thread.join()
        engine.step()
        wheel = engine.resource(InputState).wheel("left")
        t0, t1 = wheel.rate._samples[0][0], wheel.rate._samples[-1][0]
        assert t1 - t0 >= 0.2  # measured over the window, on receive timestamps
        expected = 2 * math.pi * turns_per_second
        measured = wheel.rate.angular_velocity(t1)
        assert measured == pytest.approx(expected, rel=0.1)
        assert len(sent) > 50


def test_bad_serial_lines_are_counted_and_skipped(tmp_path: Path, pty_pair):
    writer, path = pty_pair
    with input_engine(serial_scene(path), tmp_path) as engine:
        engine.step()
        os.write(writer, b"left abc\nno count here\n\xff\xfe\n" + b"x" * 5000 + b"\nleft 1.5\n")
        os.write(writer, b"left 512\n")
        state = engine.resource(InputState)
        run_until(engine, lambda: state.wheel("left") is not None)
        device = next(d for d in engine.resource(InputHub).devices
                      if isinstance(d, SerialDevice))
        assert state.wheel("left").count == 512
        assert device.status().bad == 5


def test_a_port_in_use_names_the_port_and_the_device(pty_pair):
    _, path = pty_pair
    first = SerialDevice("wheels", path)
    first.open()
    try:
        with pytest.raises(DeviceError, match=rf"'gloves' \(serial, {path}\).*already in use"):
            SerialDevice("gloves", path).open()
    finally:
        first.close()
    with pytest.raises(DeviceError, match=r"'x' \(serial, /dev/nonexistent\): cannot open"):
        SerialDevice("x", "/dev/nonexistent").open()


def test_line_templates_read_every_event_kind():
    t = 1.0
    assert LineFormat("{button} {pressed}").event("thumb 0", "glove_l", t).device == "glove_l"
    axis = LineFormat("A {axis}={value}").event("A  grip=0.25", "pad", t)
    assert (axis.device, axis.name, axis.value) == ("pad", "grip", 0.25)
    pose = LineFormat("{name} {x} {y} {z} {qw} {qx} {qy} {qz}").event(
        "wrist 1 2 3 0 0 0 1", "tracker", t)
    assert pose.device == "wrist" and pose.position == (1.0, 2.0, 3.0)
    for bad in ("{count} {count}", "{count} {button} {pressed}", "{speed}", "{name}"):
        with pytest.raises(ValueError):
            LineFormat(bad)
