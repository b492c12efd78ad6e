"""A server and two nodes, each its own process on loopback: what the nodes show is the
server's simulation, and what their devices say moves things on the server."""

from __future__ import annotations

import math
import time
from pathlib import Path

import pytest
from pythonosc.udp_client import SimpleUDPClient

from services.net.codec import POSITION_STEP
from tests.net.net_helpers import (
    ROOT,
    free_port,
    join_args,
    object_block,
    processes,
    saved_time,
    serve_args,
    stats,
)

DT = 1 / 60
G = 9.81
FALLER = (0.0, 5.0, 500.0)  # content/multiuser: free fall from here, 1 m/s along x


def faller_at(t: float) -> tuple[list[float], float]:
    """Where the faller is at server time ``t`` as a node shows it: between the discrete
    states n and n + 1 (ODE's semi-implicit Euler: v first, then x), and its vertical
    velocity between them."""
    n = math.floor(t / DT + 1e-6)
    alpha = t / DT - n

    def z(k: int) -> float:
        return FALLER[2] - G * DT * DT * k * (k + 1) / 2

    return ([FALLER[0] + t, FALLER[1], z(n) + alpha * (z(n + 1) - z(n))],
            (z(n + 1) - z(n)) / DT)


def send_tracker(client: SimpleUDPClient, x: float, z: float) -> None:
    client.send_message("/colosseum/tracker/hand_r", [x, 0.0, z, 1.0, 0.0, 0.0, 0.0])


@pytest.mark.slow
def test_two_nodes_follow_the_server_and_lift_the_crate_together(tmp_path: Path) -> None:
    port = free_port()
    osc = {user: free_port() for user in ("alice", "bob")}
    with processes(tmp_path) as procs:
        server = procs.start("server", *serve_args(port, "--seconds", 14, "--stats",
                                                   tmp_path / "server.json"))
        procs.wait_log(server, "serving")
        nodes = {user: procs.start(user, *join_args(
            port, user, "--frames", frames, "--input", f"osc:{osc[user]}", "--stats",
            tmp_path / f"{user}.json", "--save-state", tmp_path / f"{user}.scene"))
            for user, frames in (("alice", 300), ("bob", 360))}
        for node in nodes.values():
            procs.wait_log(node, "joined tcp")
        clients = {user: SimpleUDPClient("127.0.0.1", p) for user, p in osc.items()}
        start = time.monotonic()
        while (elapsed := time.monotonic() - start) < 3.0:  # both raise by 0.3 m in 1.5 s
            lift = 0.3 * min(elapsed / 1.5, 1.0)
            send_tracker(clients["alice"], -0.6, 0.25 + lift)
            send_tracker(clients["bob"], 0.6, 0.25 + lift)
            time.sleep(1 / 60)
        for node in nodes.values():
            assert procs.wait(node, 30) == 0, procs.log(node)
        assert procs.wait(server, 30) == 0, procs.log(server)

    for user in nodes:
        saved = (tmp_path / f"{user}.scene").read_text()
        t = saved_time(saved)
        where, vz = faller_at(t)
        faller = object_block(saved, "faller")
        assert faller["Position"] == pytest.approx(where, abs=1e-3), (user, t)
        # a velocity is two positions' difference over a frame: their rounding over dt
        assert faller["Velocity"][2] == pytest.approx(vz, abs=2 * POSITION_STEP / DT), (user, t)
        node = stats(tmp_path / f"{user}.json")["net"]
        assert node["malformed"] == 0 and node["gaps"] == 0, node
        # a busy server's sender replaces a frame it has not sent yet by the next (their
        # events joined): a few frame numbers may be skipped, never most
        assert node["dropped"] <= node["frames_received"] // 10, node
        assert node["latency_ms_p50"] < 50.0, node
    bob = (tmp_path / "bob.scene").read_text()
    # alice's tracker moved alice's paddle on the server, and bob's node shows it there
    assert object_block(bob, "paddle_alice")["Position"] == pytest.approx([-0.6, 0, 0.55],
                                                                           abs=0.01)
    crate = object_block(bob, "crate")  # lifted by both, level
    assert crate["Position"][2] == pytest.approx(0.75 + 0.3, abs=0.02)
    assert abs(crate["Quaternion"][0]) == pytest.approx(1.0, abs=1e-3)
    served = stats(tmp_path / "server.json")["net"]
    assert served["inputs"] > 50 and served["malformed"] == 0, served


@pytest.mark.slow
def test_a_node_plays_the_servers_sounds(tmp_path: Path) -> None:
    """The demo's ball knocks on the ground on the server; the node, with no physics of
    its own, plays those knocks into its own mix."""
    import soundfile

    port = free_port()
    demo = ROOT / "content" / "demo"
    with processes(tmp_path) as procs:
        server = procs.start("server", *serve_args(port, "--seconds", 8, content=demo))
        procs.wait_log(server, "serving")
        node = procs.start("node", *join_args(port, "ear", "--frames", 300, "--sound",
                                              f"wave:{tmp_path / 'mix.wav'}", "--stats",
                                              tmp_path / "ear.json"))
        assert procs.wait(node, 40) == 0, procs.log(node)
    heard = stats(tmp_path / "ear.json")["sound"]
    assert heard["contact_sounds"] > 0 and heard["played"] > 0, heard
    mix, _ = soundfile.read(tmp_path / "mix.wav")
    assert float(abs(mix).max()) > 0.01
