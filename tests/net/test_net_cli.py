"""What serve, join and keygen tell an author when something is wrong: one line, the
reason and what to do, an exit code, never a traceback."""

from __future__ import annotations

import shutil
import socket
import subprocess
import sys
from pathlib import Path

import pytest

from tests.net.net_helpers import (
    MULTIUSER,
    ROOT,
    free_port,
    join_args,
    local_server,
    processes,
    serve_args,
)


def colosseum(*args: object, timeout: float = 30) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "engine.cli", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True, timeout=timeout)


def told(result: subprocess.CompletedProcess[str], code: int, *words: str) -> None:
    assert result.returncode == code, result.stderr
    assert "Traceback" not in result.stderr, result.stderr
    for word in words:
        assert word in result.stderr, result.stderr


def test_no_server_there() -> None:
    port = free_port()
    result = colosseum(*join_args(port, "alice", "--frames", 5))
    told(result, 1, f"no answer from tcp://127.0.0.1:{port}", "colosseum serve")


def test_bad_addresses_are_usage_errors() -> None:
    told(colosseum("join", "udp://x:1", "--frames", 1), 2, "tcp://HOST:PORT")
    told(colosseum("serve", MULTIUSER, "--bind", "127.0.0.1:5555"), 2, "tcp://HOST:PORT")
    told(colosseum("join", "tcp://127.0.0.1:5555", "--swap-barrier"), 2, "--display")


def test_port_in_use() -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        told(colosseum(*serve_args(port, "--frames", 5)), 1, "is in use", "--bind")


@pytest.mark.slow
def test_other_content_is_refused(tmp_path: Path) -> None:
    copy = tmp_path / "multiuser"
    shutil.copytree(MULTIUSER, copy)
    (copy / "main.scene").write_text((copy / "main.scene").read_text().replace(
        "crate_mass 50", "crate_mass 60"))
    port = free_port()
    with local_server(port) as server, processes(tmp_path) as procs:
        node = procs.start("node", *join_args(port, "alice", "--frames", 5, path=copy))
        server.step_until(lambda e: node.poll() is not None, 20, "the node giving up")
        assert node.returncode == 1
        assert "content folder differs" in procs.log(node)
        assert "Traceback" not in procs.log(node)
        same = procs.start("same", *join_args(port, "bob", "--frames", 5, path=MULTIUSER))
        server.step_until(lambda e: same.poll() is not None, 20, "the right node finishing")
        assert same.returncode == 0, procs.log(same)


@pytest.mark.slow
def test_curve_refuses_a_node_without_the_key(tmp_path: Path) -> None:
    keys, strangers = tmp_path / "keys", tmp_path / "strangers"
    told(colosseum("keygen", keys, "--user", "alice"), 0)
    told(colosseum("keygen", strangers, "--user", "mallory"), 0)
    shutil.copy(keys / "server.key", strangers / "server.key")  # knows the server, not a user
    port = free_port()
    with local_server(port, "--key", keys) as server, processes(tmp_path) as procs:
        plain = procs.start("plain", *join_args(port, "alice", "--frames", 5))
        server.step_until(lambda e: plain.poll() is not None, 20, "the plain node giving up")
        assert plain.returncode == 1, procs.log(plain)
        assert "another security mechanism" in procs.log(plain), procs.log(plain)
        stranger = procs.start("mallory", *join_args(port, "mallory", "--frames", 5, "--key",
                                                     strangers))
        server.step_until(lambda e: stranger.poll() is not None, 20, "mallory giving up")
        assert stranger.returncode == 1 and "refused this node's key" in procs.log(stranger), \
            procs.log(stranger)
        assert not server.server.peers
        alice = procs.start("alice", *join_args(port, "alice", "--frames", 30, "--key", keys))
        server.step_until(lambda e: alice.poll() is not None, 20, "alice finishing")
        assert alice.returncode == 0, procs.log(alice)
        assert server.server.counts["hello"] == 0  # hellos are not counted as requests
