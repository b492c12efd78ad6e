"""``colosseum new NAME``: a content folder that runs as soon as it is created."""

from __future__ import annotations

from pathlib import Path

MAIN_SCENE = """\
// {name}: a ground, a ball and a box. Units: metres, kilograms, seconds; Z is up.
World {{ Gravity [0 0 -9.81] TimeStep 0.01 }}

mass 5  // a scene variable: colosseum sweep {name} --param mass=1,2 varies it

Material {{ ID "rubber" Friction 0.8 Bounce 0.6 }}

Object {{
  ID "ground"
  Dynamic 0
  VisualAttributes {{ Geometry {{ Primitive "plane" }} Color [0.4 0.5 0.4] }}
  PhysicalAttributes {{ Geometry {{ Primitive "plane" }} }}
}}

Object {{
  ID "ball"
  Position [0 0 3]
  Size [0.5]
  VisualAttributes {{ Geometry {{ Primitive "sphere" }} Color [0.9 0.3 0.2] }}
  PhysicalAttributes {{ Mass 1 Material "rubber" Geometry {{ Primitive "sphere" }} }}
  Script "scripts/ball.lua"
  Report {{ Every 1 }}   // declared in systems/height.py
}}

Object {{
  ID "crate"
  Position [1.5 0 0.5]
  Size [1 1 1]
  VisualAttributes {{ Geometry {{ Primitive "box" }} }}
  PhysicalAttributes {{ Mass mass Geometry {{ Primitive "box" }} }}
}}

Camera {{ ID "main" Position [0 -8 2.5] LookAt [0 0 0.5] }}
Light {{ Type "directional" Direction [-0.4 0.3 -1] }}
"""

BALL_LUA = """\
-- Runs on the object "ball". See the scripting API in services/scripting/api.py.
local bounces = 0

function onCollision(other, impulse)
  if impulse > 1 then
    bounces = bounces + 1
    log("bounce " .. bounces .. " off " .. other:getName())
  end
end
"""

SYSTEM_PY = '''\
"""A custom system with its own scene block: ``Report { Every 1 }`` on an object prints
its height every second.

Each module in systems/ defines build(engine), which adds systems or plugins. A block is
declared beside its component (engine.scene.blocks): the scene checks its keys (try
``Report { Evry 1 }`` and ``colosseum check``), ``colosseum keys Report --content .``
documents it, and a saved state writes it back.
"""

from dataclasses import dataclass

from components import Name, Transform
from engine import Phase, system
from engine.scene.blocks import key, scene_block


@scene_block("Report", doc="print this object's height now and then")
@dataclass
class Report:
    every: float = key(1.0, "s, how often", low=0.01)


@system(Phase.POST_PHYSICS, reads=(Report, Name, Transform))
def report_height(engine, dt):
    for _, (report, name, transform) in engine.world.get_components(Report, Name, Transform):
        if engine.time % report.every < dt:
            print(f"t={engine.time:5.2f}s {name.id} z={transform.position[2]:.2f} m")


def build(engine):
    engine.add_system(report_height)
'''


class ScaffoldError(Exception):
    pass


def write_clink(path: Path, rate: int = 22050) -> Path:
    """A short clink (a decaying 1.8 kHz tone, 0.2 s) as 16-bit mono WAV: a sound to play
    from a script, made here so a new folder has one (the tutorial's cup plays it)."""
    import math
    import struct
    import wave

    samples = (int(12000 * math.exp(-25.0 * i / rate) * math.sin(2 * math.pi * 1800 * i / rate))
               for i in range(rate // 5))
    with wave.open(str(path), "wb") as out:
        out.setnchannels(1)
        out.setsampwidth(2)
        out.setframerate(rate)
        out.writeframes(b"".join(struct.pack("<h", s) for s in samples))
    return path


def scaffold(folder: Path) -> Path:
    """Create ``folder`` with a working scene, a script, a sound and a custom system.

    Never touches an existing folder, so nothing an author wrote is overwritten.
    """
    if folder.exists():
        raise ScaffoldError(f"{folder} already exists; choose a new name")
    for sub in ("scripts", "models", "sounds", "shaders", "systems"):
        (folder / sub).mkdir(parents=True)
    (folder / "main.scene").write_text(MAIN_SCENE.format(name=folder.name))
    (folder / "scripts" / "ball.lua").write_text(BALL_LUA)
    (folder / "systems" / "height.py").write_text(SYSTEM_PY)
    write_clink(folder / "sounds" / "clink.wav")
    return folder
