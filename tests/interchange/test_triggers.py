"""Triggers: which bodies are inside a trigger's shapes, and entering and leaving told once
each, to Python systems and to Lua."""

from __future__ import annotations

import math

import numpy as np
import pytest

from components import Shape
from engine.events import CustomEvent
from systems.triggers import bounding_radius, overlaps
from tests.interchange.helpers import Run

pytest.importorskip("engine.physics.ode3d")


@pytest.mark.parametrize("shape,gap_along", [
    (Shape("sphere", (1.0,)), np.array([1.0, 0, 0])),
    (Shape("box", (2.0, 4.0, 6.0)), np.array([0, 0, 1.0])),
    (Shape("capsule", (0.5, 2.0)), np.array([0, 0, 1.0])),
    (Shape("cylinder", (0.5, 2.0)), np.array([1.0, 0, 0])),
])
def test_a_sphere_overlaps_a_shape_exactly_when_it_reaches_it(shape, gap_along):
    """A ball of radius r at distance d from the surface overlaps iff d <= r."""
    surface = {"sphere": 1.0, "box": 3.0, "capsule": 1.5, "cylinder": 0.5}[shape.kind]
    r = 0.25
    gaps = np.array([0.0, 0.2, 0.249, 0.251, 0.5])
    centres = np.outer(surface + gaps, gap_along)
    np.testing.assert_array_equal(overlaps(shape, centres, np.full(len(gaps), r)),
                                  gaps <= r)


def test_a_cylinder_edge_is_a_circle_not_a_box_corner():
    shape = Shape("cylinder", (1.0, 2.0))
    corner = np.array([[1.0 + 0.3 / math.sqrt(2), 0, 1.0 + 0.3 / math.sqrt(2)]])
    assert overlaps(shape, corner, np.array([0.31]))[0]
    assert not overlaps(shape, corner, np.array([0.29]))[0]


def test_a_body_reaches_as_far_as_its_farthest_shape():
    assert bounding_radius([Shape("sphere", (0.5,), offset=(1.0, 0, 0)),
                            Shape("box", (1.0, 1.0, 1.0))]) == pytest.approx(1.5)


SCRIPT = """
on("trigger", function(e)
  emit("seen", {text = e.trigger .. (e.entered and " < " or " > ") .. e.other})
end)
"""


def test_lua_hears_who_enters_and_leaves(models):
    (models / "scripts").mkdir()
    (models / "scripts" / "zone.lua").write_text(SCRIPT)
    (models / "main.scene").write_text(
        'Model { File "triggers.glb" }\nScript "scripts/zone.lua"\n'
        'Object { ID "passer" Position [0 0 0.6] Velocity [4 0 0]\n'
        '  PhysicalAttributes { Gravity 0 Geometry { Primitive "sphere" Size [0.2] } } }\n')
    seen: list[str] = []
    with Run.start(models / "main.scene") as run:
        run.engine.events.subscribe(CustomEvent, lambda e: e.name == "seen" and seen.append(
            e.data["text"]))
        run.step(2.0)
    # the passer flies through the zone (x -0.5..0.5), then through both gate posts;
    # the dropper falls into the zone and stays, the runner into the gate's second post
    assert seen.count("Zone < passer") == 1 and seen.count("Zone > passer") == 1
    assert seen.count("Gate < passer") == 2 and seen.count("Gate > passer") == 2
    assert "Zone < Dropper" in seen and "Gate < Runner" in seen
    assert not any(s.endswith("Outsider") for s in seen)
