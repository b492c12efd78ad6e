"""Input test helpers: engines with the input plugin and a scene, polling until a
condition holds (real transports deliver on their own threads, a little later), and a
loopback OSC receiver for what Output blocks send."""

from __future__ import annotations

import socket
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path

from pythonosc.osc_packet import OscPacket

from engine import Engine, EngineConfig
from engine.scene import instantiate, spec_from_text
from systems.input import InputPlugin

#: Seconds a test waits for packets on loopback before it calls them lost.
PATIENCE = 5.0


@contextmanager
def input_engine(scene: str, folder: Path, extra_plugins: tuple = (), **config: object
                 ) -> Iterator[Engine]:
    """An engine with the input plugin and ``scene`` loaded (nothing started yet)."""
    cfg = EngineConfig(**{"backend": "ballistic", "fast": True, **config})  # type: ignore[arg-type]
    with Engine(cfg, plugins=[InputPlugin(), *extra_plugins]) as engine:
        instantiate(engine, spec_from_text(scene, folder))
        yield engine


def run_until(engine: Engine, done: Callable[[], bool], patience: float = PATIENCE) -> int:
    """Run frames until ``done()``; returns how many it took. Fails after ``patience`` s."""
    deadline = time.monotonic() + patience
    frames = 0
    while not done():
        if time.monotonic() > deadline:
            raise AssertionError(f"condition not met after {frames} frames ({patience} s)")
        engine.step()
        frames += 1
        time.sleep(0.001)
    return frames


@contextmanager
def osc_receiver() -> Iterator[socket.socket]:
    """A UDP socket on 127.0.0.1 (its port: ``getsockname()[1]``) for an Output block."""
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", 0))
    sock.settimeout(0.05)
    try:
        yield sock
    finally:
        sock.close()


def received(sock: socket.socket) -> list[tuple[str, list]]:
    """The OSC messages waiting on ``sock``: (address, arguments), in arrival order."""
    out = []
    while True:
        try:
            data = sock.recv(65536)
        except TimeoutError:
            return out
        out += [(m.message.address, list(m.message.params)) for m in OscPacket(data).messages]

