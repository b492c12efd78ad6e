"""Faults: a node killed mid-grasp, a late joiner, garbage on the wire, a server restart,
a stalled node. The server is stepped in this process (its state inspected); nodes are
real processes."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest
import zmq
from pythonosc.udp_client import SimpleUDPClient

from engine.events import CustomEvent
from engine.input import InputState
from engine.net import protocol
from engine.scene import SceneIds
from systems.scripting import ScriptingSystem
from tests.net.net_helpers import (
    free_port,
    join_args,
    local_server,
    object_block,
    processes,
    serve_args,
    stats,
)

pytestmark = pytest.mark.slow


def test_a_killed_node_lets_go_of_what_it_held(tmp_path: Path) -> None:
    """... and what stands for its user (``User "alice"``) leaves the world after
    --leave-after seconds; the other user's stays."""
    port, osc = free_port(), free_port()
    left: list[str] = []
    with local_server(port, "--timeout", 1.0, "--leave-after", 0.5) as server, \
            processes(tmp_path) as procs:
        server.engine.events.subscribe(
            CustomEvent, lambda e: left.append(e.data) if e.name == "userLeft" else None)
        node = procs.start("alice", *join_args(port, "alice", "--seconds", 30, "--input",
                                               f"osc:{osc}"))
        state = server.engine.resource(InputState)
        server.step_until(lambda e: server.server.peers, 20, "alice joining")
        glove = SimpleUDPClient("127.0.0.1", osc)

        def grasping(_: object) -> bool:  # the glove's pinch held, the hand tracked
            glove.send_message("/colosseum/button/glove_r/index", [1])
            glove.send_message("/colosseum/tracker/hand_r", [0.0, 0.0, 1.0, 1, 0, 0, 0])
            tracker = state.tracker("alice/hand_r")
            return state.buttons.get(("alice/glove_r", "index")) and tracker is not None \
                and tracker.tracked

        server.step_until(grasping, 10, "alice's pinch and hand arriving on the server")
        procs.signal(node, signal.SIGKILL)  # no bye: the server finds out by the silence
        server.step_until(lambda e: not state.buttons.get(("alice/glove_r", "index")), 5,
                          "alice's pinch being released")
        assert "alice/hand_r" in state.lost and not state.tracker("alice/hand_r").tracked
        assert left == ["alice"] and not server.server.peers
        left_at = server.engine.time
        ids = server.engine.resource(SceneIds).entities
        server.step_until(lambda e: not e.world.entity_exists(ids["paddle_alice"]), 5,
                          "alice's paddle leaving")
        assert server.engine.time - left_at == pytest.approx(0.5, abs=0.05)
        assert server.engine.world.entity_exists(ids["paddle_bob"])


def test_a_late_joiner_gets_the_full_state_then_follows(tmp_path: Path) -> None:
    port = free_port()
    with local_server(port) as server, processes(tmp_path) as procs:
        api = server.engine.resource(ScriptingSystem).api
        server.run_for(0.3)
        api.spawn('Object { ID "early" Position [3 0 1] Size [0.5] Dynamic 0 '
                  'VisualAttributes { Geometry { Primitive "sphere" } } }')
        server.run_for(0.2)
        node = procs.start("late", *join_args(port, "late", "--frames", 120, "--save-state",
                                              tmp_path / "late.scene"))
        server.step_until(lambda e: server.server.peers, 20, "the late node joining")
        server.run_for(0.3)
        made = api.spawn('Object { ID "after" Position [-3 0 2] Size [0.5] Dynamic 0 '
                         'VisualAttributes { Geometry { Primitive "box" } } }')
        server.run_for(0.3)
        api.delete(made[1])
        api.spawn('Object { ID "kept" Position [0 3 2] Size [0.5] Dynamic 0 }')
        server.step_until(lambda e: node.poll() is not None, 20, "the node finishing")
        assert node.returncode == 0, procs.log(node)
    saved = (tmp_path / "late.scene").read_text()
    assert object_block(saved, "early")["Position"] == pytest.approx([3, 0, 1], abs=1e-3)
    assert object_block(saved, "kept")["Position"] == pytest.approx([0, 3, 2], abs=1e-3)
    assert 'ID "after"' not in saved  # spawned after the node joined, deleted again


def test_malformed_and_oversized_messages_are_counted_not_fatal(tmp_path: Path) -> None:
    port = free_port()
    garbage = [b"\xff\xfe not json", b"[1, 2, 3]", b'{"type": "launch"}', b'{"type": "hello"}',
               b'{"type": "input", "events": [{"type": "tracker"}]}',
               b'{"x": "' + b"a" * (protocol.MAX_MESSAGE + 10) + b'"}']
    with local_server(port) as server, processes(tmp_path) as procs:
        ctx = zmq.Context()
        raw = ctx.socket(zmq.DEALER)
        raw.linger = 0
        raw.connect(f"tcp://127.0.0.1:{port + 1}")
        try:
            for message in garbage:
                raw.send(message)
            raw.send_multipart([b"two", b"frames"])
            counts = server.server.counts
            server.step_until(lambda e: counts["malformed"] + counts["oversized"] >= 5, 5,
                              "the garbage arriving")
            # a node joined now sends a broken event among good ones
            raw.send(protocol.encode({"type": "hello", "v": protocol.VERSION, "user": "eve",
                                      "content": server.server.content}))
            server.step_until(lambda e: server.server.peers, 5, "eve joining")
            raw.send(protocol.encode({"type": "input", "events": [
                {"type": "tracker", "device": "hand_r", "position": [0, 0, "x"],
                 "orientation": [1, 0, 0, 0]},
                {"type": "button", "device": "glove", "name": "index", "pressed": True}]}))
            state = server.engine.resource(InputState)
            server.step_until(lambda e: state.buttons.get(("eve/glove", "index")), 5,
                              "eve's good event arriving")
        finally:
            raw.close(0)
            ctx.term()
        assert counts["oversized"] == 1 and counts["malformed"] == 6, dict(counts)
        node = procs.start("bob", *join_args(port, "bob", "--frames", 30))
        server.step_until(lambda e: node.poll() is not None, 20, "a good node running after")
        assert node.returncode == 0, procs.log(node)


def test_a_node_rejoins_a_restarted_server(tmp_path: Path) -> None:
    port = free_port()
    with processes(tmp_path) as procs:
        first = procs.start("first", *serve_args(port, "--seconds", 4))
        procs.wait_log(first, "serving")
        node = procs.start("node", *join_args(port, "alice", "--seconds", 9, "--stats",
                                              tmp_path / "node.json", "--timeout", 1))
        procs.wait_log(node, "joined tcp")
        assert procs.wait(first, 20) == 0
        time.sleep(1.5)  # the node notices the silence and waits
        second = procs.start("second", *serve_args(port, "--seconds", 8))
        procs.wait_log(second, "alice joined", 20)
        assert procs.wait(node, 30) == 0, procs.log(node)
        second.kill()
    node_stats = stats(tmp_path / "node.json")["net"]
    assert node_stats["resyncs"] >= 1, node_stats
    assert "server stopped" in procs.log(node) or "nothing from" in procs.log(node)


def test_a_stalled_node_does_not_slow_the_server(tmp_path: Path) -> None:
    port = free_port()
    with local_server(port, "--timeout", 5.0) as server, processes(tmp_path) as procs:
        node = procs.start("slow", *join_args(port, "slow", "--seconds", 6, "--stats",
                                              tmp_path / "slow.json"))
        server.step_until(lambda e: server.server.peers, 20, "the node joining")
        server.run_for(0.5)
        procs.signal(node, signal.SIGSTOP)
        start_frame, t0 = server.engine.frame, time.monotonic()
        server.run_for(2.0)
        frames = server.engine.frame - start_frame
        procs.signal(node, signal.SIGCONT)
        assert frames >= 0.8 * 60 * (time.monotonic() - t0), frames
        server.step_until(lambda e: node.poll() is not None, 30, "the node finishing")
        assert node.returncode == 0, procs.log(node)
    node_stats = json.loads((tmp_path / "slow.json").read_text())["net"]
    assert node_stats["frames_received"] > 0
