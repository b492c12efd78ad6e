"""Serial devices through a pseudo-terminal pair: a wheel encoder printing counts."""

from __future__ import annotations

import math
import os
import threading
import time
from pathlib import Path

import pytest
from input_helpers import input_engine, run_until

from services.input import DeviceError, InputHub, InputState, serial_line
from services.input.device import BadMessage
from services.input.serial_line import LineFormat, SerialDevice


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


@pytest.mark.parametrize("chunk", [1, 700, 1025, 6000])
def test_a_line_too_long_is_one_bad_line_however_the_reads_split_it(chunk: int) -> None:
    device = SerialDevice("encoders", "/dev/unused")
    data = b"x" * 5000 + b"\nleft 7\n"
    for start in range(0, len(data), chunk):
        device.take(data[start:start + chunk], 1.0)
    assert device.bad.total == 1
    assert [e.count for e in device.poll(1.0)] == [7]


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


def test_a_template_with_a_spare_field_reads_its_one_event():
    """Found by the fuzzer: a tracker's seven fields and a lone {value} (no {axis}) made
    a KeyError on every line; the template makes a tracker, the spare field is ignored."""
    fmt = LineFormat("T {name} {x}{y}{z} {qw} {qx} {qy} {qz}{value}")
    assert fmt.kind == "tracker"
    with pytest.raises(BadMessage):
        fmt.event("T t 578 2 8 8 0.", "dev", 1.0)


def test_an_unplugged_port_is_reported_and_reopened_when_it_comes_back(tmp_path: Path,
                                                                        caplog, monkeypatch):
    """A USB adapter's port goes away and comes back (udev gives it the same link): the
    device said so and stopped reading for the rest of the run."""
    monkeypatch.setattr(serial_line, "REOPEN_EVERY", 0.1)
    link = tmp_path / "ttyWheels"
    master, slave = os.openpty()
    link.symlink_to(os.ttyname(slave))
    device = SerialDevice("wheels", str(link))
    device.open()
    try:
        os.write(master, b"left 5\n")
        events = wait_for_events(device)
        assert [e.count for e in events] == [5]
        os.close(master)  # unplugged
        os.close(slave)
        deadline = time.monotonic() + 5.0
        while "port lost" not in caplog.text and time.monotonic() < deadline:
            time.sleep(0.01)
        assert "'wheels' (serial, " in caplog.text and "reopening it every" in caplog.text
        master, slave = os.openpty()  # plugged in again
        link.unlink()
        link.symlink_to(os.ttyname(slave))
        events = []
        deadline = time.monotonic() + 5.0
        while not events and time.monotonic() < deadline:  # an encoder keeps sending
            os.write(master, b"left 7\n")  # (what came before the reopen is flushed)
            events = wait_for_events(device, 0.1)
        assert events and {e.count for e in events} == {7}
        assert device.status().state == "open" and device.status().detail == ""
    finally:
        device.close()
        os.close(master)
        os.close(slave)


def wait_for_events(device: SerialDevice, patience: float = 5.0) -> list:
    deadline = time.monotonic() + patience
    while time.monotonic() < deadline:
        events = device.poll(time.monotonic())
        if events:
            return events
        time.sleep(0.01)
    return []
