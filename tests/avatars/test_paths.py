"""Walking a path: straight on at the ground speed of what the avatar plays (measured from
a clip's root motion, or its Clip block's GroundSpeed, in metres at the avatar's scale),
and round a corner no faster than its TurnRate."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from avatar_helpers import GROUND, MODELS, avatar_engine, content, entity, position

from components import Transform
from systems.avatars import ARRIVE

DT = 1 / 64


@pytest.mark.parametrize("avatar,speed", [
    ('Model "models/walker.glb" Animation "Walk"', 1.4),  # root motion: 1.4 m per 1 s loop
    ('Model "models/walker.glb" Animation "Walk" Clip { Name "Walk" Speed 1.5 }', 2.1),
    ('Model "models/walker.glb" Blend ["Walk" "Run"] Weights [0.5 0.5]', 0.5 * (1.4 + 3.5)),
    ('Model "models/hound.glb" Scale 0.02 Animation "Walk" '
     'Clip { Name "Walk" GroundSpeed 1.2 }', 1.2)])
def test_an_avatar_walks_a_straight_path_at_the_ground_speed_of_its_clips(
        tmp_path: Path, avatar: str, speed: float):
    folder = content(tmp_path, "\n".join([
        GROUND, f'Avatar {{ ID "w" {avatar} Path [0 0 0  0 30 0] PathLoop 0 }}']),
        models=(MODELS / "walker.glb", MODELS / "hound.glb"))
    with avatar_engine(folder, dt=DT) as engine:
        engine.run(frames=128)  # 2 s
        at = position(engine, "w")
    assert at[1] == pytest.approx(2.0 * speed, rel=0.02)
    assert abs(at[0]) < 1e-9  # facing +Y from the start: no turn


def test_an_avatar_turns_at_most_its_turn_rate_and_walks_through_each_point(tmp_path: Path):
    folder = content(tmp_path, "\n".join([
        GROUND, 'Avatar { ID "w" Model "models/walker.glb" Animation "Walk" TurnRate 90 '
                'Path [0 0 0  0 2 0  2 2 0] PathLoop 0 }']))
    with avatar_engine(folder, dt=DT) as engine:
        headings, points = [], []
        w = entity(engine, "w")
        for _ in range(320):  # 5 s
            engine.step()
            q = engine.world.component_for_entity(w, Transform).orientation
            headings.append(2 * math.atan2(q[3], q[0]))  # about Z
            points.append(position(engine, "w")[:2])
    turns = np.abs(np.diff(np.unwrap(headings)))
    assert turns.max() <= math.radians(90) * DT + 1e-9
    points = np.array(points)
    assert np.linalg.norm(points - (0, 2), axis=1).min() < 0.2  # the corner is reached
    # it turns once ARRIVE from the corner, on a curve of radius 1.4 m/s / (pi/2 per s)
    assert points[:, 1].max() == pytest.approx(2 - ARRIVE + 1.4 / (math.pi / 2), abs=0.02)
    assert np.linalg.norm(points[-1] - (2, 2)) < 0.2  # the last point: it stops there
    np.testing.assert_array_equal(points[-1], points[-40])
