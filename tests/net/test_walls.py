"""Cluster walls: off-axis projection from screen corners (checked against geometry), and
display nodes that draw the same server frames behind a swap barrier."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from engine.render.math3d import off_axis, perspective, project
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


@pytest.mark.slow
def test_display_nodes_draw_the_same_frames(tmp_path: Path) -> None:
    port = free_port()
    with local_server(port) as server, processes(tmp_path) as procs:
        walls = {name: procs.start(name, *join_args(
            port, f"wall-{name}", "--display", name, "--swap-barrier", "--frames", 150,
            "--stats", tmp_path / f"{name}.json", *extra))
            for name, extra in (("front", ("--screenshot", tmp_path / "front.png")),
                                ("left", ()))}
        server.step_until(lambda e: all(w.poll() is not None for w in walls.values()), 40,
                          "both walls finishing")
        for wall in walls.values():
            assert wall.returncode == 0, procs.log(wall)
    front, left = (stats(tmp_path / f"{n}.json")["net"] for n in ("front", "left"))
    # over the time both ran, each drew exactly the frames the other drew
    start = max(front["shown_frames"][0], left["shown_frames"][0])
    end = min(front["shown_frames"][-1], left["shown_frames"][-1])
    both = [[f for f in n["shown_frames"] if start <= f <= end] for n in (front, left)]
    assert len(both[0]) > 30
    assert sorted(set(both[0])) == sorted(set(both[1]))
    image = np.asarray(Image.open(tmp_path / "front.png").convert("RGB"), float)
    assert image.std() > 5  # the front wall drew the scene (ground, crate, paddles)
