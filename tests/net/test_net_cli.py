"""What serve, join and keygen tell an author when something is wrong: one line, the
reason and what to do, an exit code, never a traceback."""

from __future__ import annotations

import logging
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
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)], cwd=ROOT,
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
    keys, strangers, stolen = tmp_path / "keys", tmp_path / "strangers", tmp_path / "stolen"
    told(colosseum("keygen", keys, "--user", "alice", "--user", "bob"), 0)
    told(colosseum("keygen", strangers, "--user", "mallory"), 0)
    shutil.copy(keys / "server.key", strangers / "server.key")  # knows the server, not a user
    (stolen / "users").mkdir(parents=True)  # bob holding alice's key, to drive her hands
    shutil.copy(keys / "server.key", stolen / "server.key")
    shutil.copy(keys / "users" / "alice.key_secret", stolen / "users" / "bob.key_secret")
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
        posing = procs.start("posing", *join_args(port, "bob", "--frames", 5, "--key", stolen))
        server.step_until(lambda e: posing.poll() is not None, 20, "bob-as-alice giving up")
        assert posing.returncode == 1 and "its key is 'alice''s, not 'bob''s" in procs.log(
            posing), procs.log(posing)
        assert not server.server.peers
        alice = procs.start("alice", *join_args(port, "alice", "--frames", 30, "--key", keys))
        server.step_until(lambda e: alice.poll() is not None, 20, "alice finishing")
        assert alice.returncode == 0, procs.log(alice)
        assert server.server.counts["hello"] == 0  # hellos are not counted as requests


def test_serve_takes_params_and_headless(tmp_path: Path) -> None:
    """serve takes run's --param (a scene variable) and --headless (it always is)."""
    port = free_port()
    out = tmp_path / "served.scene"
    told(colosseum(*serve_args(port, "--headless", "--frames", 3, "--param", "crate_mass=60",
                               "--save-state", out)), 0)
    assert "crate_mass 60" in out.read_text()
    told(colosseum(*serve_args(port, "--frames", 3, "--param", "crate_mas=60")), 1,
         "did you mean 'crate_mass'")


def test_serve_binds_loopback_unless_told_and_warns_off_it_without_a_key(
        tmp_path: Path, caplog: pytest.LogCaptureFixture,
        capsys: pytest.CaptureFixture[str]) -> None:
    """The default --bind is loopback; another address without --key is warned about
    before anything is bound. (The address off loopback here is one no interface has, so
    the bind fails: no socket leaves 127.0.0.1.)"""
    from app.cli import build_parser
    from app.cli_net import serving_engine
    from services.net.protocol import is_loopback

    parser = build_parser()
    assert is_loopback(parser.parse_args(["serve", str(MULTIUSER)]).bind)
    caplog.set_level(logging.WARNING, "colosseum.net")
    port = free_port()
    made = serving_engine(parser.parse_args([str(a) for a in serve_args(port)]))
    assert not isinstance(made, int)
    made[0].close()
    made[1].close()
    assert "without --key" not in caplog.text  # loopback: nothing to warn about
    off = f"tcp://192.0.2.1:{port}"  # TEST-NET-1 (RFC 5737): on no interface here
    assert serving_engine(parser.parse_args(["serve", str(MULTIUSER), "--bind", off])) == 1
    assert f"serving on {off} without --key" in caplog.text
    assert f"cannot bind {off}" in capsys.readouterr().err
    caplog.clear()
    keys = tmp_path / "keys"
    told(colosseum("keygen", keys, "--user", "alice"), 0)
    assert serving_engine(parser.parse_args(["serve", str(MULTIUSER), "--bind", off,
                                             "--key", str(keys)])) == 1
    assert "without --key" not in caplog.text


def test_a_node_joins_content_whose_systems_declare_blocks(tmp_path: Path) -> None:
    """The server's state names the content's own block (content/pool's Buoyancy): the node
    checks it knowing that block, joined with the same argument serve was given."""
    port = free_port()
    scene = ROOT / "content" / "pool" / "main.scene"
    with processes(tmp_path) as procs:
        server = procs.start("server", "serve", scene, "--bind", f"tcp://127.0.0.1:{port}",
                             "--seconds", "20")
        node = procs.start("node", *join_args(port, "alice", "--frames", 20, path=scene))
        assert node.wait(timeout=60) == 0, procs.log(node)
        assert "unknown key" not in procs.log(node)
        server.kill()
