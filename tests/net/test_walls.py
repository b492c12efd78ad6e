"""Cluster walls: off-axis projection from screen corners (checked against geometry),
display nodes that draw the same server frames behind a swap barrier, and a wall's eye
moved by a head tracker on another node."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from pythonosc.udp_client import SimpleUDPClient

from engine.scene import SceneIds
from services.net.server import NetServer, Peer
from services.render.math3d import off_axis, perspective, project
from tests.net.net_helpers import free_port, join_args, local_server, processes, stats

FRONT = (np.array([-2.0, 2, 0]), np.array([2.0, 2, 0]), np.array([-2.0, 2, 3]))
LEFT = (np.array([-2.0, -2, 0]), np.array([-2.0, 2, 0]), np.array([-2.0, -2, 3]))


@pytest.mark.parametrize("eye", [(0, -1, 1.6), (1.5, 1.2, 0.3), (-1.9, -1.9, 2.9)])
def test_screen_corners_land_on_the_viewport_corners(eye: tuple[float, ...]) -> None:
    for ll, lr, ul in (FRONT, LEFT):
        view, proj = off_axis(np.array(eye, float), ll, lr, ul, 0.01, 100)
        ur = lr + ul - ll
        for corner, pixel in ((ll, (0, 100)), (lr, (200, 100)), (ul, (0, 0)),
                              (ur, (200, 0))):
            x, y, depth = project(corner, view, proj, 200, 100)
            assert (x, y) == pytest.approx(pixel, abs=1e-9)
            assert -1 < depth < 1


def test_walls_meet_where_the_screens_do() -> None:
    """A point on the corner edge the two walls share is drawn on the right edge of the
    left wall and the left edge of the front wall, at the same height: the walls join."""
    eye = np.array([0.4, -0.7, 1.7])
    point = np.array([-2.0, 2.0, 1.1])
    on_left = project(point, *off_axis(eye, *LEFT, 0.1, 100), 400, 300)
    on_front = project(point, *off_axis(eye, *FRONT, 0.1, 100), 400, 300)
    assert on_left[0] == pytest.approx(400, abs=1e-9) and on_front[0] == pytest.approx(0,
                                                                                      abs=1e-9)
    assert on_left[1] == pytest.approx(on_front[1], abs=1e-9)


def test_a_centred_eye_is_an_ordinary_perspective() -> None:
    eye = np.array([0.0, -1.0, 1.5])  # 3 m from the front wall, level with its middle
    view, proj = off_axis(eye, *FRONT, 0.1, 100)
    fov = math.degrees(2 * math.atan(1.5 / 3.0))
    assert proj == pytest.approx(perspective(fov, 4 / 3, 0.1, 100))


def test_an_eye_behind_the_screen_is_refused() -> None:
    with pytest.raises(ValueError, match="behind the screen"):
        off_axis(np.array([0.0, 3.0, 1.0]), *FRONT, 0.1, 100)


def test_the_barrier_waits_for_every_display_then_lets_the_ready_ones_go() -> None:
    now = [0.0]
    server = NetServer("tcp://127.0.0.1:1", "", clock=lambda: now[0], barrier_wait=0.1)
    for user, display in (("front", "front"), ("left", "left"), ("alice", None)):
        server.peers[user.encode()] = Peer(user.encode(), user, display, heard=0.0)
    front, left, _ = server.peers.values()
    front.ready = (1, 10, 1)  # the oldest and newest frame it holds, its round
    assert server.barrier() is None  # left is not ready, and the wait has not run out
    now[0] = 0.05
    left.ready = (5, 12, 1)
    assert server.barrier() == 10  # the newest frame both hold
    front.ready = (2, 13, 2)
    now[0] = 0.1
    assert server.barrier() is None
    now[0] = 0.21
    assert server.barrier() == 13  # left came too late: front goes alone, and it is counted
    front.ready, left.ready = (3, 14, 3), (20, 21, 2)  # left joined again, after front's 14
    assert server.barrier() == 20  # the oldest left holds: front is about to receive it
    assert server._releases == [{"frame": 10, "rounds": {"front": 1, "left": 1}},
                                {"frame": 13, "rounds": {"front": 2}},
                                {"frame": 20, "rounds": {"front": 3, "left": 2}}]
    assert server.stats()["barrier_timeouts"] == 1
    assert front.ready is None and left.ready is None


@pytest.mark.slow
def test_display_nodes_draw_the_same_frames(tmp_path: Path) -> None:
    port = free_port()
    # a barrier that outwaits any stall of a loaded machine: every frame is drawn by both.
    # The left wall draws every other frame (it saves them), waiting at the barrier
    # between drawing and swapping; on the frames it does not draw, and on the front
    # wall's (which draws only its screenshot), at the frame's end.
    drawn = tmp_path / "left-frames"
    with local_server(port, "--barrier-wait", 10) as server, processes(tmp_path) as procs:
        walls = {name: procs.start(name, *join_args(
            port, f"wall-{name}", "--display", name, "--swap-barrier", "--frames", 150,
            "--stats", tmp_path / f"{name}.json", *extra))
            for name, extra in (("front", ("--screenshot", tmp_path / "front.png")),
                                ("left", ("--record-frames", drawn, "--record-every", 2,
                                          "--size", "64x48")))}
        server.step_until(lambda e: all(w.poll() is not None for w in walls.values()), 40,
                          "both walls finishing")
        for wall in walls.values():
            assert wall.returncode == 0, procs.log(wall)
        assert server.server.stats()["barrier_timeouts"] == 0
    assert stats(tmp_path / "left.json")["render"]["frames_drawn"] >= 60
    front, left = (stats(tmp_path / f"{n}.json")["net"] for n in ("front", "left"))
    # over the time both ran, each drew exactly the frames the other drew
    start = max(front["shown_frames"][0], left["shown_frames"][0])
    end = min(front["shown_frames"][-1], left["shown_frames"][-1])
    both = [[f for f in n["shown_frames"] if start <= f <= end] for n in (front, left)]
    assert len(both[0]) > 30
    assert sorted(set(both[0])) == sorted(set(both[1]))
    image = np.asarray(Image.open(tmp_path / "front.png").convert("RGB"), float)
    assert image.std() > 5  # the front wall drew the scene (ground, crate, paddles)


CAVE = """World { Gravity [0 0 0] TimeStep 1/60 }
Input { Tracker { ID "viewer/head" Object "head" } }
Display { ID "front" LowerLeft [-2 2 0] LowerRight [2 2 0] UpperLeft [-2 2 3] Head "head" }
Object { ID "head" Position [0 -1 1.5] VisualAttributes { Visible 0 } }
Object { ID "marker" Position [0 5 1.5] Size [0.4] Dynamic 0
  VisualAttributes { Geometry { Primitive "sphere" } Color [1 0 0] } }
"""
MARKER = np.array([0.0, 5.0, 1.5])
WALL = (np.array([-2.0, 2, 0]), np.array([2.0, 2, 0]), np.array([-2.0, 2, 3]))


def marker_pixel(frame: Path) -> np.ndarray:
    """Where the marker is drawn in a frame (the centroid of the pixels that are not the
    background's colour, the corner's)."""
    image = np.asarray(Image.open(frame).convert("RGB"), float)
    drawn = np.abs(image - image[0, 0]).sum(axis=2) > 60
    assert drawn.sum() > 20, f"no marker drawn in {frame}"
    rows, columns = np.nonzero(drawn)
    return np.array([columns.mean(), rows.mean()])


def seen_from(eye: tuple[float, float, float]) -> np.ndarray:
    x, y, _ = project(MARKER, *off_axis(np.array(eye), *WALL, 0.1, 100), 160, 120)
    return np.array([x, y])


@pytest.mark.slow
def test_a_head_tracker_on_one_node_moves_the_eye_of_a_wall_on_another(tmp_path: Path
                                                                       ) -> None:
    """The viewer's node sends its head tracker; on the server it moves the object the
    Display names as its Head; the wall, another node, draws off-axis from it."""
    content = tmp_path / "cave"
    content.mkdir()
    (content / "main.scene").write_text(CAVE)
    drawn = tmp_path / "front-frames"
    port, osc = free_port(), free_port()
    with local_server(port, content=content) as server, processes(tmp_path) as procs:
        procs.start("front", *join_args(port, "wall", "--display", "front", "--frames", 3000,
                                        "--record-frames", drawn, "--record-every", 10,
                                        "--size", "160x120"))
        procs.start("viewer", *join_args(port, "viewer", "--frames", 3000, "--input",
                                         f"osc:{osc}"))
        server.step_until(lambda e: len(server.server.peers) == 2, 30, "both nodes joining")

        def written() -> list[Path]:  # every frame file but the newest (maybe half written)
            return sorted(drawn.glob("*.png"))[:-1] if drawn.is_dir() else []

        server.step_until(lambda e: written(), 20, "the wall drawing a frame")
        before = marker_pixel(written()[-1])
        head = server.engine.resource(SceneIds).entities["head"]
        poses = server.engine.world.poses
        tracker = SimpleUDPClient("127.0.0.1", osc)

        def moved(_: object) -> bool:
            tracker.send_message("/colosseum/tracker/head", [1.5, -1.0, 1.5, 1, 0, 0, 0])
            return bool(np.allclose(poses.position[poses.row_of[head]], (1.5, -1.0, 1.5)))

        server.step_until(moved, 15, "the viewer's head tracker moving the head")
        last = len(written())
        server.step_until(lambda e: len(written()) >= last + 2, 15, "the wall drawing on")
        after = marker_pixel(written()[-1])
    assert before == pytest.approx(seen_from((0.0, -1.0, 1.5)), abs=2)  # the scene's head
    assert after == pytest.approx(seen_from((1.5, -1.0, 1.5)), abs=2)  # the tracked head
    assert after[0] - before[0] > 20
