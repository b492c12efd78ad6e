"""A uniform changed from a Lua script changes the pixels (paper section 4.3)."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np

from app.scene_loading import load_content_scene
from engine import EngineConfig
from engine.content import resolve
from systems import create_engine
from systems.render import RenderSystem

SHADERS = Path(__file__).parent / "content" / "shaders"

SCENE = """
VertexShader { ID "toon_vertex" File "shaders/toon.vert" }
FragmentShader { ID "toon_fragment" File "shaders/toon.frag" }
ShaderProgram { ID "toon" VertexShader "toon_vertex" FragmentShader "toon_fragment" }
ShaderState { ID "toon" ShaderProgram "toon"
  Uniform { ID "DiffuseColor" Value [0 0.25 1] }
  Uniform { ID "PhongColor" Value [0.75 0.75 1] }
  Uniform { ID "Edge" Value 0.0 }
  Uniform { ID "Phong" Value 2.0 }
}
Object { ID "ball" Dynamic 0 Size [2]
  VisualAttributes { Geometry { Primitive "sphere" } ShaderState "toon" } }
Camera { Position [0 -6 0] LookAt [0 0 0] }
Script "scripts/tint.lua"
"""

TINT = """
function onUpdate(dt)
  if time() > 0.1 then setUniform("toon", "DiffuseColor", {1, 0, 0}) end
end
"""


def centre_after(folder: Path, seconds: float) -> np.ndarray:
    scene = load_content_scene(resolve(folder))
    cfg = EngineConfig(content_dir=folder, backend="ballistic", fast=True, render=True,
                       options={"size": "160x120"})
    scene.configure(cfg)
    with create_engine(cfg) as engine:
        scene.instantiate(engine)
        engine.run(seconds=seconds)
        return engine.resource(RenderSystem).renderer.read_pixels()[60, 80].astype(int)


def test_set_uniform_from_lua_recolours_the_object(tmp_path: Path):
    folder = tmp_path / "toon"
    (folder / "scripts").mkdir(parents=True)
    shutil.copytree(SHADERS, folder / "shaders")
    (folder / "main.scene").write_text(SCENE)
    (folder / "scripts" / "tint.lua").write_text(TINT)
    before = centre_after(folder, 0.05)
    after = centre_after(folder, 0.3)
    assert before[2] > 200 and before[0] < 30  # the scene's blue
    assert after[0] > 200 and after[2] < 30  # red, set by the script
