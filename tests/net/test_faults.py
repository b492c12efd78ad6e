"""Faults: a node killed mid-grasp, a late joiner, garbage on the wire, a server restart,
a stalled node. The server is stepped in this process (its state inspected); nodes are
real processes."""

from __future__ import annotations

import json
import logging
import signal
import time
from pathlib import Path

import pytest
import zmq
from pythonosc.udp_client import SimpleUDPClient

from engine.events import CustomEvent
from engine.scene import SceneIds
from services.input import InputState
from services.net import protocol
from systems.scripting import ScriptingSystem
from tests.net.net_helpers import (
    free_port,
    hello,
    join_args,
    local_server,
    object_block,
    processes,
    raw_control,
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
        with raw_control(port) as raw:
            for message in garbage:
                raw.send(message)
            raw.send_multipart([b"two", b"frames"])
            counts = server.server.counts
            server.step_until(lambda e: counts["malformed"] + counts["oversized"] >= 5, 5,
                              "the garbage arriving")
            # a node joined now sends a broken event among good ones
            raw.send(hello("eve", server.server.content))
            server.step_until(lambda e: server.server.peers, 5, "eve joining")
            raw.send(protocol.encode({"type": "input", "events": [
                {"type": "tracker", "device": "hand_r", "position": [0, 0, "x"],
                 "orientation": [1, 0, 0, 0]},
                {"type": "button", "device": "glove", "name": "index", "pressed": True}]}))
            state = server.engine.resource(InputState)
            server.step_until(lambda e: state.buttons.get(("eve/glove", "index")), 5,
                              "eve's good event arriving")
        assert counts["oversized"] == 1 and counts["malformed"] == 6, dict(counts)
        node = procs.start("bob", *join_args(port, "bob", "--frames", 30))
        server.step_until(lambda e: node.poll() is not None, 20, "a good node running after")
        assert node.returncode == 0, procs.log(node)


def test_a_node_rejoins_a_restarted_server(tmp_path: Path) -> None:
    """The server is killed (no goodbye) with a node attached, and another started in its
    place: the node waits, rejoins once (not once per message it queued meanwhile, each of
    which the new server answered 'say hello') and shows the new server's world."""
    port = free_port()
    with processes(tmp_path) as procs:
        first = procs.start("first", *serve_args(port, "--seconds", 30))
        procs.wait_log(first, "serving")
        node = procs.start("node", *join_args(port, "alice", "--seconds", 9, "--stats",
                                              tmp_path / "node.json", "--timeout", 1,
                                              "--save-state", tmp_path / "node.scene"))
        procs.wait_log(first, "alice joined")
        time.sleep(0.5)
        procs.signal(first, signal.SIGKILL)
        procs.wait(first)
        time.sleep(1.5)  # the node notices the silence and waits, sending its heartbeats
        second = procs.start("second", *serve_args(port, "--seconds", 12, "--param",
                                                   "crate_mass=60"))
        procs.wait_log(second, "alice joined", 20)
        assert procs.wait(node, 30) == 0, procs.log(node)
        second.kill()
    node_stats = stats(tmp_path / "node.json")["net"]
    assert node_stats["resyncs"] == 1, (node_stats, procs.log(node))
    assert "nothing from" in procs.log(node)
    assert "crate_mass 60" in (tmp_path / "node.scene").read_text()  # the second's world


def test_a_stalled_node_does_not_slow_the_server(tmp_path: Path) -> None:
    """... and counts the frames it lost. While it stalls each frame carries 256 kB (a
    script's custom event), so the queues on the way (ZeroMQ's, the kernel's) fill up
    and the server's socket drops the node's frames."""
    port = free_port()
    with local_server(port, "--timeout", 5.0) as server, processes(tmp_path) as procs:
        node = procs.start("slow", *join_args(port, "slow", "--seconds", 6, "--stats",
                                              tmp_path / "slow.json"))
        server.step_until(lambda e: server.server.peers, 20, "the node joining")
        server.run_for(0.5)
        procs.signal(node, signal.SIGSTOP)
        start_frame, t0 = server.engine.frame, time.monotonic()
        while time.monotonic() - t0 < 2.0:
            server.engine.events.emit(CustomEvent("ballast", "x" * 262144))
            server.engine.step()
        frames = server.engine.frame - start_frame
        procs.signal(node, signal.SIGCONT)
        assert frames >= 0.8 * 60 * (time.monotonic() - t0), frames
        server.step_until(lambda e: node.poll() is not None, 30, "the node finishing")
        assert node.returncode == 0, procs.log(node)
    node_stats = json.loads((tmp_path / "slow.json").read_text())["net"]
    assert node_stats["frames_received"] > 0
    # more frames went out while it stalled than the queues hold: it missed some, and said
    assert node_stats["dropped"] > 0 and node_stats["frames_received"] < \
        server.server.frames_sent, node_stats


def test_a_node_building_its_scene_is_not_let_go() -> None:
    """A node is silent from its hello until its first frame (a large scene built, a
    renderer started): the stroke simulator took over 2 s under load, and the server let
    it go and made it rejoin. Until its first message JOIN_GRACE holds, then --timeout."""
    from services.net.server import JOIN_GRACE, NetServer

    now = [0.0]
    port = free_port()
    server = NetServer(f"tcp://127.0.0.1:{port}", "content", timeout=2.0, clock=lambda: now[0])
    server.bind()
    try:
        with raw_control(port) as node:
            node.send(hello("slow", "content"))
            end = time.monotonic() + 5
            while not server.peers and time.monotonic() < end:
                server.poll()
                time.sleep(0.01)
            assert server.peers
            now[0] = JOIN_GRACE - 1.0  # still building
            server.poll()
            assert server.peers and not server.left
            node.send(protocol.encode({"type": "beat"}))
            while not server.counts["beat"] and time.monotonic() < end:
                server.poll()
                time.sleep(0.01)
            now[0] += 2.5  # running now: the timeout holds
            server.poll()
            assert not server.peers and [p.user for p in server.left] == ["slow"]
    finally:
        server.close()


def test_custom_events_beyond_a_frames_limit_are_counted_and_told(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A frame tells the nodes MAX_CUSTOM custom events; a script that emits more in one
    frame is told so, and the rest are counted (--stats net), not dropped unsaid."""
    from systems.net import MAX_CUSTOM

    port = free_port()
    caplog.set_level(logging.WARNING, "colosseum.net")
    with local_server(port) as server, raw_control(port) as control:
        state = control.context.socket(zmq.SUB)
        state.linger = 0
        state.setsockopt(zmq.SUBSCRIBE, b"")
        state.connect(f"tcp://127.0.0.1:{port}")
        try:
            control.send(hello("eve", server.server.content))
            server.step_until(lambda e: state.poll(0), 10, "frames reaching eve")
            for i in range(MAX_CUSTOM + 6):
                server.engine.events.emit(CustomEvent("tick", i))
            server.engine.step()
            told: list[list[object]] = []

            def custom(_: object) -> bool:
                while state.poll(0):
                    kind, header, *_ = state.recv_multipart()
                    if kind == protocol.STATE:
                        told.extend(json.loads(header).get("events", {}).get("custom", []))
                return any(name == "tick" for name, _ in told)

            server.step_until(custom, 5, "the frame of the ticks reaching eve")
        finally:
            state.close(0)
        assert [data for name, data in told if name == "tick"] == list(range(MAX_CUSTOM))
        assert server.engine.stat_sources["net"]()["custom_dropped"] == 6
    assert f"the first {MAX_CUSTOM}, not the other 6 ('tick')" in caplog.text
