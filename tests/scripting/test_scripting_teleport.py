"""Lua moves bodies through the checked physics API."""

from __future__ import annotations

from pathlib import Path

import pytest
from script_helpers import LIMITS, scripted_engine, write_content

from components import Name, Transform
from engine.app import Engine, EngineConfig
from engine.physics.driver import DetachedPhysics
from engine.scene import instantiate, load_spec
from systems import RegistryPlugin
from systems.scripting import ScriptingPlugin


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


def test_without_the_physics_plugin_scripts_run_and_their_teleport_is_kept_as_a_command(
        tmp_path: Path):
    """A process with no local physics (a network node): the ECS and the scripts run, a
    script's teleport is checked and kept for whoever forwards it, nothing simulates."""
    scene = """
Object { ID "box" Position [0 0 1] Script "scripts/jump.lua"
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [1 1 1] } } }
"""
    lua = "function onUpdate(dt) if time() > 0.05 and not done then done = true\n" \
          "  self:setPosition(3, 0, 4); bad = pcall(self.setPosition, self, 0/0, 0, 0) end end\n"
    write_content(tmp_path, scene, {"jump.lua": lua})
    config = EngineConfig(fast=True, content_dir=tmp_path)
    with Engine(config, plugins=[RegistryPlugin(), ScriptingPlugin(LIMITS)]) as eng:
        instantiate(eng, load_spec(tmp_path / "main.scene", eng.rng))
        eng.run(frames=20)
        assert isinstance(eng.physics, DetachedPhysics)
        [command] = eng.physics.outbox  # the NaN one was refused at the script's line
        assert type(command).__name__ == "SetPose" and command.position == (3.0, 0.0, 4.0)
        box = next(e for e, n in eng.world.get_component(Name) if n.id == "box")
        # the Transform shows the teleport, and stays there: nothing falls
        assert eng.world.component_for_entity(box, Transform).position.tolist() == [3, 0, 4]
