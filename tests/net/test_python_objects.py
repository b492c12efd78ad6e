"""Objects a content folder's Python system makes (engine.spawn, no scene text) reach the
nodes: a server process runs the system; a node process joins and saves what it shows."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from services.net.codec import POSITION_STEP
from tests.net.net_helpers import (
    free_port,
    join_args,
    object_block,
    processes,
    saved_time,
    serve_args,
)

DT = 1 / 60
SCENE = """World { Gravity [0 0 -9.81] TimeStep 1/60 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Camera { ID "eye" Position [0 -6 2] LookAt [0 0 1] }
"""
MAKER = """
import numpy as np

from components import Name, Physical, Shape, Transform, Visual
from engine import Phase, system

made = {}


@system(Phase.SCRIPT, reads=(Transform,), writes=(Name, Transform, Visual, Physical))
def make(engine, dt):
    t = engine.time
    if "early" not in made:  # before any node joins: they find it in the full state
        made["early"] = engine.spawn(Name("early"), Transform((0, 3, 1)), Visual(
            [Shape("box", (0.5, 0.4, 0.3))], color=(1.0, 0.0, 0.0, 1.0)), Physical(
            kind="static", shapes=[Shape("box", (0.5, 0.4, 0.3))]))
    if t > 2.0 and "late" not in made:  # while the node watches
        made["late"] = engine.spawn(Name("late"), Transform((t, 0, 2)),
                                    Visual([Shape("sphere", (0.25,))]))
        made["plain"] = engine.spawn(Transform((1, 1, 1)), Visual([Shape("cylinder", (0.1, 0.5))]))
        made["gone"] = engine.spawn(Name("gone"), Transform((5, 5, 5)), Visual())
        engine.spawn(Name("meshy"), Transform(), Visual([Shape(
            "mesh", (1.0,), vertices=np.eye(3), faces=np.array([[0, 1, 2]]))]))
    if t > 3.0 and "gone" in made:
        engine.despawn(made.pop("gone"))
    if "late" in made:  # moving at 1 m/s along x: x is the time
        engine.world.component_for_entity(made["late"], Transform).position[0] = t


def build(engine):
    engine.add_system(make)
"""


@pytest.mark.slow
def test_objects_made_in_python_reach_the_nodes(tmp_path: Path) -> None:
    folder = tmp_path / "content"
    (folder / "systems").mkdir(parents=True)
    (folder / "main.scene").write_text(SCENE)
    (folder / "systems" / "maker.py").write_text(MAKER)
    port = free_port()
    with processes(tmp_path) as procs:
        server = procs.start("server", *serve_args(port, "--seconds", 7, content=folder))
        procs.wait_log(server, "serving")
        time.sleep(1.0)
        node = procs.start("node", *join_args(port, "ann", "--frames", 240, "--save-state",
                                              tmp_path / "node.scene", path=folder))
        assert procs.wait(node, 30) == 0, procs.log(node)
        assert procs.wait(server, 30) == 0, procs.log(server)
        server_log, node_log = procs.log(server), procs.log(node)
    saved = (tmp_path / "node.scene").read_text()
    early = saved[saved.index('ID "early"'):]
    assert object_block(saved, "early")["Position"] == [0.0, 3.0, 1.0]
    assert "Color [1.0 0.0 0.0 1.0]" in early[:early.index("\n}")]
    # made while the node watched, and moved by the system: where the server put it
    t = saved_time(saved)
    assert object_block(saved, "late")["Position"][0] == pytest.approx(t, abs=DT + POSITION_STEP)
    assert 'ID "unnamed~' in saved and 'Primitive "cylinder"' in saved
    assert 'ID "gone"' not in saved  # removed on the server at 3 s, so on the node
    # a mesh made of arrays has no scene text: told once on the server, naming it
    assert 'ID "meshy"' not in saved
    assert server_log.count("object 'meshy', made in Python, is not shown on the nodes") == 1
    assert "Traceback" not in server_log + node_log
