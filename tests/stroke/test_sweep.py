"""Sweeping in content/stroke: crumbs counted in the dust pan finish the task wherever the
pan stands, the broom pushes crumbs by contact, and the 200 crumbs sleep once they rest,
so the solver does no work for them."""

from __future__ import annotations

import shutil
import statistics
import time
from pathlib import Path

import numpy as np
import pytest
from chair_helpers import CONTENT
from test_stroke_content import records, session_engine

from components import Name, Transform
from engine import Phase, system
from engine.physics import commands as cmd
from engine.rotation import quat_to_matrix

pytest.importorskip("engine.physics.ode3d")

CRUMBS = 200
UPRIGHT = (1.0, 0.0, 0.0, 0.0)


def names(engine) -> dict[str, int]:
    return {n.id: e for e, n in engine.world.get_component(Name)}


def crumb_positions(engine, ids: dict[str, int]) -> np.ndarray:
    return np.array([engine.world.component_for_entity(ids[f"crumb {i}"], Transform).position
                     for i in range(CRUMBS)])


def test_crumbs_in_the_dust_pan_finish_the_sweep_wherever_the_pan_stands(tmp_path):
    """The pan moved into the kitchen and turned 45 degrees: 185 crumbs dropped onto its
    floor (counted in the pan's own frame, tasks.lua M.PAN: unturned, the grid's corners
    would stick out of it), 15 left on the floor 6 cm past its side wall. The sweep is
    done with 185 swept; the breakfast is not, so the session goes on."""
    inside, outside = 185, CRUMBS - 185
    pan_at = np.array([6.9, 6.2, 0.024])
    turn = (np.cos(np.pi / 8), 0.0, 0.0, np.sin(np.pi / 8))  # 45 degrees about Z
    axes = quat_to_matrix(np.array(turn))
    with session_engine(CONTENT, tmp_path) as engine:
        ids = names(engine)

        def put(crumb: int, local: tuple[float, float, float]) -> None:
            engine.physics.set_pose(ids[f"crumb {crumb}"], pan_at + axes @ local, turn)

        @system(Phase.SCRIPT)
        def into_the_pan(e, dt):
            if e.frame == 5:
                e.physics.set_pose(ids["dust pan"], pan_at, turn)
            if e.frame != 10:
                return
            for i in range(inside):  # a 15 x 13 grid on the pan's floor (0.25 x 0.22 m)
                row, column = divmod(i, 15)
                put(i, (-0.105 + 0.015 * column, -0.09 + 0.015 * row, -0.008))
            for k in range(outside):  # the floor is 0.024 m below the pan's origin
                put(inside + k, (0.185, -0.09 + 0.013 * k, -0.018))

        engine.add_system(into_the_pan)
        engine.run(seconds=1.5)
        pan = engine.world.component_for_entity(ids["dust pan"], Transform).position
        assert np.linalg.norm(pan[:2] - pan_at[:2]) < 0.01  # it stayed put
    log = records(tmp_path)
    sweep = [r for r in log if r["kind"] == "task" and r["task"] == "sweep"]
    done = [r for r in sweep if r["event"] == "done"]
    assert len(done) == 1 and done[0]["swept"] == inside
    assert max(r["swept"] for r in sweep if r["event"] == "progress") == inside
    assert not [r for r in log if r["kind"] == "task" and r["task"] == "breakfast"
                and r["event"] == "done"]
    assert log[-1]["kind"] == "end" and log[-1]["reason"] == "stopped"  # not "done"


def test_the_broom_pushes_the_crumbs_it_sweeps_through(tmp_path):
    """The broom, upright with its bristles 3 mm off the floor, is carried across the
    crumbs at 0.4 m/s along +Y: put at its path's start once, then a kinematic target
    each frame, so it moves by velocity and collides. The crumbs it meets wake and go
    along ahead of its head, and end piled against the bristles' face; crumbs well beside
    its path stay where they lay, asleep."""
    x, y0, y1, speed = 6.7, 5.62, 6.5, 0.4
    start = 2.0  # s: the crumbs are all asleep by then
    with session_engine(CONTENT, tmp_path) as engine:
        ids = names(engine)
        broom = ids["broom"]

        def at(t: float) -> np.ndarray:
            y = min(y0 + speed * max(t - start, 0.0), y1)
            return np.array([x, y, 0.685 + 0.003])  # the bristles' bottom 0.685 m down

        @system(Phase.PRE_PHYSICS)
        def stroke(e, dt):
            if e.time < start - 0.5:
                return
            if not hasattr(stroke, "placed"):
                e.physics.push(cmd.SetGravityEnabled(broom, False))
                e.physics.set_pose(broom, at(0.0), UPRIGHT)
                stroke.placed = True
            e.physics.push(cmd.SetKinematicTarget(broom, at(e.time + dt), UPRIGHT, dt))

        engine.add_system(stroke)
        engine.run(seconds=start)
        backend = engine.physics.backend
        before = crumb_positions(engine, ids)
        assert all(backend.is_sleeping(ids[f"crumb {i}"]) for i in range(CRUMBS))
        engine.run(seconds=(y1 - y0) / speed + 0.5)
        after = crumb_positions(engine, ids)
        reached = engine.world.component_for_entity(broom, Transform).position
        beside = [backend.is_sleeping(ids[f"crumb {i}"]) for i in range(CRUMBS)
                  if abs(before[i, 0] - x) > 0.35]
    assert np.linalg.norm(reached - at(1e9)) < 0.01  # it followed its path to the end
    ahead = (np.abs(before[:, 0] - x) < 0.12) & (before[:, 1] < y1 - 0.15)
    assert ahead.sum() >= 15
    moved = after[ahead] - before[ahead]
    face = y1 + 0.025 + 0.006  # the bristles' face at the end, and a crumb's half size
    assert np.all(after[ahead, 1] > face - 0.002), after[ahead]  # none under or through
    assert np.all(after[ahead, 1] < face + 0.06), after[ahead]  # a pile a few crumbs deep
    assert np.abs(moved[:, 0]).max() < 0.03 and np.abs(moved[:, 2]).max() < 0.003
    far = np.abs(before[:, 0] - x) > 0.35
    assert far.sum() >= 50 and np.abs(after[far] - before[far]).max() < 0.002
    assert all(beside)


def crumbless(folder: Path) -> Path:
    """content/stroke without its crumbs."""
    shutil.copytree(CONTENT, folder, ignore=shutil.ignore_patterns("demo.input"))
    (folder / "crumbs.scene").write_text("// no crumbs\n")
    return folder


def test_the_crumbs_fall_asleep_and_then_cost_the_solver_nothing(tmp_path):
    """Settled, all 200 crumbs are asleep: the solver then has exactly the awake bodies
    and contacts of the apartment without crumbs, and a step costs a small part of what
    it costs with the crumbs kept awake (CPU time of the stepping thread, rounds
    alternating so that load from elsewhere falls on both alike)."""
    with session_engine(CONTENT, tmp_path / "a") as engine, session_engine(
            crumbless(tmp_path / "bare"), tmp_path / "b") as bare:
        ids = names(engine)
        crumbs = [ids[f"crumb {i}"] for i in range(CRUMBS)]
        engine.run(seconds=2.0)
        bare.run(seconds=2.0)
        world, empty = engine.physics.backend, bare.physics.backend
        assert all(world.is_sleeping(c) for c in crumbs)
        assert world.body_count() - empty.body_count() == CRUMBS
        dt = engine.config.dt

        def awake(backend) -> int:
            return backend.body_count() - backend.sleeping_count()

        for _ in range(5):  # stepped alike, the same work is left for the solver
            world.step(dt)
            empty.step(dt)
            assert awake(world) == awake(empty)
            assert len(world.contacts()) == len(empty.contacts())
        assert not np.isin(world.contacts()["a"], crumbs).any()

        def cost(step) -> float:
            began = time.thread_time()
            for _ in range(20):
                step()
            return time.thread_time() - began

        def woken() -> None:
            for c in crumbs:
                world.set_sleeping(c, False)
            world.step(dt)

        asleep, kept_awake = [], []
        for _ in range(5):
            asleep.append(cost(lambda: world.step(dt)))
            kept_awake.append(cost(woken))
            for _ in range(120):  # asleep again before the next round
                world.step(dt)
            assert all(world.is_sleeping(c) for c in crumbs)
    assert statistics.median(asleep) < 0.25 * statistics.median(kept_awake)
