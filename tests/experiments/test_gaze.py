"""Where the head looked, for the report's gaze map: the floor point its line of sight
meets, or a point a few metres ahead when it looks level or up."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from app.experiments.report import GAZE_REACH, gaze_points, plots
from engine.experiments.tracking import COLUMNS


def _head(x: float, y: float, z: float, pitch: float, yaw: float = 0.0) -> list[float]:
    """A tracking row of a head at (x, y, z) turned ``yaw`` about z, then pitched (rad,
    negative: down) about its right axis."""
    qyaw = np.array([math.cos(yaw / 2), 0.0, 0.0, math.sin(yaw / 2)])
    qpitch = np.array([math.cos(pitch / 2), math.sin(pitch / 2), 0.0, 0.0])
    w1, x1, y1, z1 = qyaw
    w2, x2, y2, z2 = qpitch
    q = [w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
         w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2]
    return [0.0, 0.0, x, y, z, *q]


def test_a_look_down_meets_the_floor_and_a_level_one_counts_a_few_metres_ahead():
    rows = np.array([
        _head(0.0, 0.0, 1.6, -math.pi / 4),  # 45° down: the floor 1.6 m ahead
        _head(1.0, 2.0, 1.2, -math.pi / 3, yaw=math.pi / 2),  # turned left: toward -x
        _head(0.0, 0.0, 1.6, 0.0),  # level: GAZE_REACH ahead
        _head(0.0, 0.0, 1.6, 0.3),  # up: GAZE_REACH ahead along its line of sight
    ])
    points = gaze_points(rows)
    assert points[0] == pytest.approx((0.0, 1.6), abs=1e-9)
    assert points[1] == pytest.approx((1.0 - 1.2 / math.tan(math.pi / 3), 2.0), abs=1e-9)
    assert points[2] == pytest.approx((0.0, GAZE_REACH), abs=1e-9)
    assert points[3] == pytest.approx((0.0, GAZE_REACH * math.cos(0.3)), abs=1e-9)


def test_the_report_draws_the_gaze_map_where_the_head_was_tracked(tmp_path: Path):
    session = tmp_path / "p1"
    (session / "tracking").mkdir(parents=True)
    lines = [",".join(COLUMNS)]
    for i in range(50):
        row = _head(0.0, 0.0, 1.6, -0.2 - 0.01 * i, yaw=0.02 * i)
        lines.append(f"{0.1 * i:.6f},{i},head," + ",".join(f"{v:.6f}" for v in row[2:]))
    (session / "tracking" / "trial-001.csv").write_text("\n".join(lines) + "\n")
    trial = {"_session": str(session), "trial": "1", "practice": "0", "start_s": "0",
             "end_s": "5", "blur": "0"}
    made = plots(tmp_path, ["blur"], [trial])
    assert tmp_path / "gaze.png" in made and (tmp_path / "gaze.png").stat().st_size > 1000


def test_the_floor_plan_is_the_static_boxes_between_floor_and_head_height():
    """content/stroke's apartment: its outer walls frame the plan (0..10 by 0..8 m), and a
    wall's footprint is its length by its thickness."""
    from app.experiments.report import floor_plan

    plan = floor_plan(Path(__file__).resolve().parents[2] / "content" / "stroke")
    corners = np.concatenate(plan)
    assert corners[:, 0].min() == pytest.approx(-0.05, abs=0.01)
    assert corners[:, 0].max() == pytest.approx(10.05, abs=0.01)
    assert corners[:, 1].max() == pytest.approx(8.05, abs=0.01)
    spans = {tuple(np.round(c.max(axis=0) - c.min(axis=0), 3)) for c in plan}
    assert (10.1, 0.1) in spans  # "wall 0.0": 10.1 m long, 0.1 m thick
