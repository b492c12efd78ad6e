"""Two users' virtual hands, each driven from its own node process, lift the 50 kg crate
together on the server (one hand's 300 N cannot: 490 N); killing one node lets its hand
go, and the crate comes down onto its far edge (the other hand's 300 N hold its own side
up by about 9 degrees: 300 N x 0.42 m against 490 N x 0.26 m about that edge)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from pythonosc.udp_client import SimpleUDPClient

from components import HandState, Transform
from engine.scene import SceneIds
from tests.net.net_helpers import free_port, join_args, local_server, object_block, processes

SCENE = """World { TimeStep 1/120 }
Object { ID "floor" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "crate" Position [0 0 0.25]
  PhysicalAttributes { Mass 50 Geometry { Primitive "box" Size [0.6 0.4 0.5] } } }
Object { ID "alice hand" Position [0.2 0 0.6]
  Hand { Tracker "alice/hand_r" Glove "alice/glove_r" } }
Object { ID "bob hand" Position [-0.2 0 0.6]
  Hand { Tracker "bob/hand_r" Glove "bob/glove_r" } }
"""
X = {"alice": 0.2, "bob": -0.2}


def height(t: float) -> float:
    """Down onto the crate's top, grasp at 0.6 s, up by 0.2 m over a second, hold."""
    return float(np.interp(t, [0.0, 0.5, 0.8, 1.8], [0.6, 0.505, 0.505, 0.705]))


@pytest.mark.slow
def test_two_users_lift_the_crate_and_a_killed_node_lets_go(tmp_path: Path) -> None:
    content = tmp_path / "lift"
    content.mkdir()
    (content / "main.scene").write_text(SCENE)
    port = free_port()
    osc = {user: free_port() for user in X}
    with local_server(port, content=content) as server, processes(tmp_path) as procs:
        nodes = {user: procs.start(user, *join_args(
            port, user, "--seconds", 30, "--input", f"osc:{osc[user]}", path=content))
            for user in X}
        server.step_until(lambda e: len(server.server.peers) == 2, 30, "both users joining")
        engine = server.engine
        ids = engine.resource(SceneIds)
        crate = engine.world.component_for_entity(ids.entities["crate"], Transform)
        clients = {user: SimpleUDPClient("127.0.0.1", p) for user, p in osc.items()}
        start = time.monotonic()
        hands = {user: engine.world.component_for_entity(ids.entities[f"{user} hand"],
                                                         HandState) for user in X}
        pinched: set[str] = set()

        def devices(users: tuple[str, ...]) -> float:
            """Each user's tracker and glove, as their devices would send them now: the
            pinch from 0.6 s on, once the server has the hand touching the crate (a loaded
            machine's server can lag the wall clock by more than the 0.1 s the descent
            leaves; a pinch before the touch grasps nothing)."""
            t = time.monotonic() - start
            for user in users:
                if t >= 0.6 and hands[user].touching:
                    pinched.add(user)
                clients[user].send_message("/colosseum/tracker/hand_r",
                                           [X[user], 0.0, height(t), 1.0, 0.0, 0.0, 0.0])
                clients[user].send_message("/colosseum/button/glove_r/pinch",
                                           [int(user in pinched)])
            return t

        server.step_until(lambda e: devices(("alice", "bob")) > 3.5, 10, "the lift")
        lifted = crate.position[2]
        assert lifted > 0.25 + 0.15, lifted  # up with both hands (a little behind them)
        procs.signal(nodes["alice"], 9)  # alice's node dies holding the crate
        server.step_until(lambda e: devices(("bob",)) > 3.5 + 3.0 and crate.position[2] < 0.32,
                          8, "the crate coming down once alice's hand let go")
        bob_saves = tmp_path / "bob.scene"
        watcher = procs.start("watcher", *join_args(port, "carol", "--frames", 20,
                                                    "--save-state", bob_saves, path=content))
        server.step_until(lambda e: devices(("bob",)) and watcher.poll() is not None, 20,
                          "a late joiner saving what it sees")
        assert watcher.returncode == 0, procs.log(watcher)
    # the third node sees the crate down on its edge, bob's side held up
    assert 0.25 - 0.01 < object_block(bob_saves.read_text(), "crate")["Position"][2] < 0.32
