"""``--save-state`` writes what scripts made at run time too (issue 3, ODE, serial mode).

Objects and joints from ``spawn(text)`` and joints from ``createJoint`` follow the
file's own in the saved state, so running it continues the motion as if it had never
stopped; IDs stay unique, and what was deleted is left out. Driven through the CLI.
"""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest

from app.scene_loading import check_path
from engine.scene import load_scene

pytest.importorskip("engine.physics.ode3d")

#: An arm swinging on a hinge of the file; the script adds what the file does not have.
SCENE = """\
World { TimeStep 0.01 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "arm" Position [0.5 0 2]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [1 0.1 0.1] } } }
Joint { ID "shoulder" Type "Hinge" Bodies ["arm"] Anchor [0 0 2] Axis [0 1 0] }
Script "scripts/maker.lua"
"""

#: Acts as the clock crosses a time, so a state saved later does not act again: a ball at
#: 0.2 s, a motorized hinge (limits, motor, spring) from it to the file's arm at 0.3 s, and at
#: 0.5 s a pendulum bob on a hinge to the world, in a snippet that may hold ``{more}``.
MAKER = """\
local last = time()
local function crosses(t, now) return last < t and t <= now end
function onUpdate(dt)
  local now = time()
  if crosses(0.2, now) then
    spawn([[Object { ID "ball" Position [1.2 0 2.3] Velocity [0 0.5 0]
      PhysicalAttributes { Mass 0.5 Geometry { Primitive "sphere" Size [0.3] } } }]])
  end
  if crosses(0.3, now) then
    local x, y, z = find("ball"):getPosition()
    createJoint{kind = "motorized_hinge", a = find("ball"), b = find("arm"),
                anchor = {x - 0.2, y, z}, axis = {0, 1, 0}, low = -0.5, high = 0.7,
                velocity = 1.3, maxForce = 5, id = "wrist",
                spring = {stiffness = 2, damping = 0.1, target = 0.2}}
  end
  if crosses(0.5, now) then
    spawn([[Object { ID "bob" Position [-2 0.8 2]
        PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.2] } } }
      Joint { ID "string" Type "Hinge" Bodies ["bob"] Anchor [-2 0 2] Axis [1 0 0] }
      {more}]])
  end
  last = now
end
"""


def colosseum(*args: object) -> subprocess.CompletedProcess[str]:
    result = subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)],
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    return result


def content(folder: Path, scene: str, script: str) -> Path:
    (folder / "scripts").mkdir(parents=True)
    (folder / "main.scene").write_text(scene)
    (folder / "scripts" / "maker.lua").write_text(script)
    (folder / "scripts" / "idle.lua").write_text("function onUpdate(dt) end\n")
    return folder


def saved(path: Path, seconds: float, out: Path, *flags: str) -> dict[str, dict[str, object]]:
    """Run ``path`` for ``seconds`` saving the state to ``out``; its blocks by ID."""
    colosseum("run", path, "--seconds", seconds, "--fast", "--save-state", out, *flags)
    db = load_scene(out)
    return {str(b.get("ID")): {e.key: e.value.py() for e in b}
            for key in ("Object", "Joint") for b in db.blocks(key)}


#: A weight in the pendulum's snippet on a ball joint to the file's arm.
WEIGHT = """Object { ID "weight" Position [0.9 0.3 1.2]
        PhysicalAttributes { Mass 0.3 Geometry { Primitive "box" Size [0.1] } } }
      Joint { ID "cord" Type "Ball" Bodies ["weight" "arm"] Anchor [0.9 0.3 1.5] }"""


@pytest.mark.parametrize("more", [
    pytest.param("", id="spawn-and-createJoint"),
    # joints reach the backend in the order they were made, whatever esper's set order
    pytest.param(WEIGHT, id="snippet-joint-on-a-file-body")])
def test_spawned_objects_and_joints_continue_exactly(tmp_path: Path, more: str) -> None:
    """Saved at 2 s with a spawned ball, a createJoint on it and a spawned pendulum,
    1 s more is the uninterrupted 3 s run."""
    folder = content(tmp_path / "sim", SCENE, MAKER.replace("{more}", more))
    whole = saved(folder, 3, tmp_path / "whole.scene")
    first = saved(folder, 2, tmp_path / "first.scene")
    rest = saved(tmp_path / "first.scene", 1, tmp_path / "rest.scene")
    weight = ["weight"] if more else []
    objects = ["arm", "ball", "bob", *weight]
    assert list(first) == list(rest) == list(whole) == [
        "ground", *objects, "shoulder", "wrist", "string", *(["cord"] if more else [])]
    deviation = max(abs(a - b) for name in objects
                    for a, b in zip(rest[name]["Position"], whole[name]["Position"], strict=True))
    assert deviation <= 1e-6
    assert math.dist(whole["bob"]["Position"], (-2, 0.8, 2)) > 0.5  # the pendulum swung
    wrist = first["wrist"]
    assert wrist["Bodies"] == ("ball", "arm") and wrist["Type"] == "MotorizedHinge"
    assert wrist["Low"] == pytest.approx(-28.6479, abs=1e-4)  # -0.5 rad, in degrees
    assert wrist["MotorVelocity"] == pytest.approx(74.4845, abs=1e-4)  # 1.3 rad/s
    assert len(wrist["ReferencePose2"]) == 7  # the arm's pose when the script made it
    spring = {e.key: e.value.py() for e in wrist["Spring"]}  # per degree, in degrees
    assert spring == pytest.approx({"Stiffness": 2 / math.degrees(1), "Target": 11.4592,
                                    "Damping": 0.1 / math.degrees(1)}, abs=1e-4)


#: The same snippet three times: a named ball on a world joint, and an object without ID.
TRIPLE = """\
function onStart()
  for i = 1, 3 do
    spawn(string.format([[
      Object { ID "ball" Position [%d 0 1]
        PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.2] } } }
      Object { Position [%d 2 0.5] PhysicalAttributes { Geometry { Primitive "box" } } }
      Joint { ID "tie" Type "Ball" Bodies ["ball"] Anchor [%d 0 2] }
    ]], i, i, i))
  end
end
"""


def test_spawning_a_snippet_again_writes_unique_ids(tmp_path: Path) -> None:
    scene = SCENE.replace('Object { ID "arm"', 'Object {\n  Dynamic 0 }\nObject { ID "arm"')
    folder = content(tmp_path / "sim", scene, TRIPLE)
    state = saved(folder, 0.1, tmp_path / "state.scene")
    # the object without an ID is "object1" by its place, in the file and in each snippet
    assert list(state) == [
        "ground", "object1", "arm", "ball", "object1~2", "ball~2", "object1~3", "ball~3",
        "object1~4", "shoulder", "tie", "tie~2", "tie~3"]
    assert [state[j]["Bodies"] for j in ("tie", "tie~2", "tie~3")] == [
        ("ball",), ("ball~2",), ("ball~3",)]
    assert [state[b]["Position"][0] for b in ("ball", "ball~2", "ball~3")] == pytest.approx(
        [1, 2, 3], abs=1e-9)
    assert check_path(tmp_path / "state.scene") == 0  # what `colosseum check` runs


#: Spawns objects and joints and deletes or breaks some; keeps one object (with its own
#: material and script) and two joints.
DELETER = """\
function onStart()
  spawn([[Material { ID "rubber" Bounce 0.8 }
          Object { ID "keep" Position [0 3 1] Script "scripts/idle.lua"
            PhysicalAttributes { Mass 1 Material "rubber" } }
          Object { ID "temp" Position [0 5 1] PhysicalAttributes { Mass 1 } }
          Object { ID "gone" Position [0 7 1] PhysicalAttributes { Mass 1 } }
          Joint { ID "leash" Type "Ball" Bodies ["gone"] Anchor [0 7 2] }
          Joint { ID "tether" Type "Ball" Bodies ["keep"] Anchor [0 3 2] }]])
  createJoint{kind = "ball", a = find("temp"), anchor = {0, 5, 2}, id = "snapped"}
  createJoint{kind = "ball", a = find("keep"), b = find("arm"), anchor = {0, 2, 1},
              id = "kept"}
end
local frames = 0
function onUpdate(dt)
  frames = frames + 1
  if frames == 3 then delete(find("temp")); find("gone"):delete(); breakJoint("snapped") end
end
"""


@pytest.mark.parametrize("mode", ["serial", "threaded"])
def test_deleted_spawns_are_not_written(tmp_path: Path, mode: str) -> None:
    folder = content(tmp_path / "sim", SCENE, DELETER)
    state = saved(folder, 0.2, tmp_path / "state.scene", "--mode", mode)
    assert list(state) == ["ground", "arm", "keep", "shoulder", "tether", "kept"]
    assert state["kept"]["Bodies"] == ("keep", "arm")
    # names stay the content folder's, which the file names relative to itself; the
    # material comes along
    assert state["keep"]["Script"] == "scripts/idle.lua"
    assert load_scene(tmp_path / "state.scene").get("Content") == "sim"
    assert load_scene(tmp_path / "state.scene").find("Material[rubber]/Bounce").data == 0.8
    assert check_path(tmp_path / "state.scene") == 0  # what `colosseum check` runs


def test_a_spawned_material_redeclaring_the_files_keeps_its_own_values(tmp_path: Path) -> None:
    """Spawned twice, a snippet's slippery "wood" is written once, as wood~2, and its
    planks refer to it; the file's own wood keeps its name and friction."""
    scene = SCENE.replace("World {", 'Material { ID "wood" Friction 0.9 }\nWorld {')
    script = """\
local last = time()
function onUpdate(dt)
  local now = time()
  for _, t in ipairs({0.1, 0.2}) do
    if last < t and t <= now then
      spawn([[Material { ID "wood" Friction 0.1 }
        Object { ID "plank" Position [3 0 0.3]
          PhysicalAttributes { Material "wood" Geometry { Primitive "box" Size [1 1 0.2] } } }]])
    end
  end
  last = now
end
"""
    folder = content(tmp_path / "sim", scene, script)
    out = tmp_path / "state.scene"
    blocks = saved(folder, 0.5, out)
    db = load_scene(out)
    frictions = {str(b.get("ID")): b.get("Friction") for b in db.blocks("Material")}
    assert frictions == {"wood": 0.9, "wood~2": 0.1}
    for plank in ("plank", "plank~2"):
        assert blocks[plank]["PhysicalAttributes"].get("Material") == "wood~2"
    assert check_path(out) == 0
