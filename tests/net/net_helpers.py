"""Servers and nodes in real processes on loopback, each bounded in time and always ended."""

from __future__ import annotations

import contextlib
import json
import os
import re
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]
MULTIUSER = ROOT / "content" / "multiuser"
#: The longest any one process of these tests may live.
PROCESS_LIMIT = 60.0


@contextlib.contextmanager
def raw_control(port: int) -> Iterator[Any]:
    """A node's control socket without a NetClient (a DEALER on the server's PORT + 1), for
    tests that send what a real node never would; closed, and its context ended, after."""
    import zmq

    ctx = zmq.Context()
    sock = ctx.socket(zmq.DEALER)
    sock.linger = 0
    sock.connect(f"tcp://127.0.0.1:{port + 1}")
    try:
        yield sock
    finally:
        sock.close(0)
        ctx.term()


def hello(user: str, content: str) -> bytes:
    """The hello a node opens with, as ``user`` holding ``content`` (its fingerprint)."""
    from services.net import protocol

    return protocol.encode({"type": "hello", "v": protocol.VERSION, "user": user,
                            "content": content})


def free_port() -> int:
    """A port P with P and P + 1 free on 127.0.0.1 (a server takes both)."""
    for _ in range(100):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        if port < 65535:
            with socket.socket() as s, contextlib.suppress(OSError):
                s.bind(("127.0.0.1", port + 1))
                return port
    raise RuntimeError("no two free ports next to each other")


class Processes:
    """Started colosseum processes; every one is ended on exit, whatever happened."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.procs: list[tuple[subprocess.Popen, Path]] = []

    def start(self, name: str, *args: Any) -> subprocess.Popen:
        log = self.folder / f"{name}.log"
        out = log.open("w")
        proc = subprocess.Popen(["timeout", "-s", "KILL", str(int(PROCESS_LIMIT)),
                                 sys.executable, "-m", "app.cli", *map(str, args)],
                                cwd=ROOT, stdout=out, stderr=subprocess.STDOUT,
                                env={**os.environ, "PYTHONUNBUFFERED": "1"},
                                start_new_session=True)
        out.close()
        self.procs.append((proc, log))
        return proc

    def log(self, proc: subprocess.Popen) -> str:
        path = next(p for q, p in self.procs if q is proc)
        return path.read_text(errors="replace")

    def wait(self, proc: subprocess.Popen, timeout: float = 30.0) -> int:
        try:
            return proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.signal(proc, signal.SIGKILL)
            raise AssertionError(f"process did not end in {timeout} s:\n{self.log(proc)}"
                                 ) from None

    def wait_log(self, proc: subprocess.Popen, pattern: str, timeout: float = 20.0) -> str:
        """Wait until the process logged a line matching ``pattern``; returns the log."""
        return wait_for(lambda: re.search(pattern, self.log(proc)) and self.log(proc),
                        timeout, f"{pattern!r} in the log of {proc.args}",
                        lambda: self.log(proc))

    def signal(self, proc: subprocess.Popen, number: int) -> None:
        """Signal the process and the one it runs (``timeout`` wraps each)."""
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, number)

    def close(self) -> None:
        for proc, _ in self.procs:
            self.signal(proc, signal.SIGKILL)
            with contextlib.suppress(subprocess.TimeoutExpired):
                proc.wait(10)


@contextlib.contextmanager
def processes(folder: Path) -> Iterator[Processes]:
    procs = Processes(folder)
    try:
        yield procs
    finally:
        procs.close()


def wait_for(predicate: Callable[[], Any], timeout: float, what: str,
             detail: Callable[[], str] = lambda: "") -> Any:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        value = predicate()
        if value:
            return value
        time.sleep(0.05)
    raise AssertionError(f"waited {timeout} s for {what}\n{detail()}")


def serve_args(port: int, *extra: Any, content: Path = MULTIUSER) -> list[Any]:
    return ["serve", content, "--bind", f"tcp://127.0.0.1:{port}", *extra]


def join_args(port: int, user: str, *extra: Any, path: Path | None = None) -> list[Any]:
    return ["join", f"tcp://127.0.0.1:{port}", *([] if path is None else [path]),
            "--user", user, "--headless", *extra]


def stats(path: Path) -> dict[str, Any]:
    return json.loads(path.read_text())


def object_block(scene_text: str, object_id: str) -> dict[str, list[float]]:
    """Position, Quaternion and Velocity of one object in a saved state."""
    start = scene_text.index(f'ID "{object_id}"')
    block = scene_text[start:scene_text.index("\n}", start)]
    out = {}
    for key in ("Position", "Quaternion", "Velocity"):
        match = re.search(rf"^\s*{key} \[([^\]]*)\]", block, re.M)
        if match:
            out[key] = [float(x) for x in match.group(1).split()]
    return out


def saved_time(scene_text: str) -> float:
    match = re.search(r"^\s*Time ([0-9.e+-]+)", scene_text, re.M)
    assert match, "the saved state has no World Time"
    return float(match.group(1))


class LocalServer:
    """``colosseum serve`` in this process, stepped by the test (its state inspectable)."""

    def __init__(self, port: int, *flags: Any, content: Path = MULTIUSER) -> None:
        from app.cli import build_parser
        from app.cli_net import serving_engine

        args = build_parser().parse_args([str(a) for a in serve_args(port, *flags,
                                                                     content=content)])
        made = serving_engine(args)
        assert not isinstance(made, int), f"the server did not start (exit code {made})"
        self.engine, self.server, scene = made
        scene.instantiate(self.engine)
        self.engine.start()

    def step_until(self, predicate: Callable[[Any], Any], timeout: float, what: str) -> Any:
        """Step frames (in real time) until ``predicate(engine)`` holds."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            self.engine.step()
            value = predicate(self.engine)
            if value:
                return value
        raise AssertionError(f"the server stepped {timeout} s and {what} did not happen")

    def run_for(self, seconds: float) -> None:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            self.engine.step()

    def close(self) -> None:
        self.engine.close()
        self.server.close()


@contextlib.contextmanager
def local_server(port: int, *flags: Any, content: Path = MULTIUSER) -> Iterator[LocalServer]:
    server = LocalServer(port, *flags, content=content)
    try:
        yield server
    finally:
        server.close()
