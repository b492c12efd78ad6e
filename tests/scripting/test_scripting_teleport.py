"""Lua moves bodies through the checked physics API."""

from __future__ import annotations

from pathlib import Path

import pytest
from script_helpers import scripted_engine, write_content

from components import Name, Transform


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_lua_script_teleports_a_box(backend, tmp_path: Path):
    scene = """
Object { ID "floor" Position [0 0 0] PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "box" Position [0 0 0.5] Script "scripts/jump.lua"
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [1 1 1] } } }
"""
    lua = """
function onUpdate(dt)
  if time() >= 0.19 and not done then
    done = true
    self:setPosition(-1, 0, 4)
  end
end
"""
    write_content(tmp_path, scene, {"jump.lua": lua})
    with scripted_engine(tmp_path, backend) as eng:
        box = next(e for e, n in eng.world.get_component(Name) if n.id == "box")
        eng.run(seconds=0.2)
        eng.step()
        position = eng.world.component_for_entity(box, Transform).position
        assert position[0] == pytest.approx(-1.0)
        assert position[2] == pytest.approx(4.0, abs=0.01)  # one step after the teleport
        eng.run(seconds=0.3)
        assert position[2] < 3.8  # and it falls from there
