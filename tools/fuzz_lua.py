"""The Lua target of the fuzzer (``python -m tools.fuzz --kind lua``): generated and
mutated scripts run in the sandbox against a small live world.

Each input is a script attached to an object of a small scene (a floor, a crate, a
hinged door) built as ``colosseum run --fast --headless`` builds it, run for a few
frames: the script's top level, ``onStart``, ``onUpdate`` and its timers and handlers,
calling the API with odd arguments (NaN, huge numbers, wrong types, objects that are
gone), and now and then running away (endless loops, huge strings, deep recursion),
which the sandbox's own instruction and memory limits must stop. A script's error
must be a message, never a traceback.
"""

from __future__ import annotations

import random
import shutil
from dataclasses import dataclass
from pathlib import Path

from app.scene_loading import SceneLoadError, content_engine
from services.scripting.runtime import ScriptRuntime
from tools.fuzz_core import Outcome, Target
from tools.fuzz_scene import ASSETS, ROOT, mutate

FRAMES = 6
SEED_SCRIPTS = sorted([*ROOT.glob("content/*/scripts/*.lua"),
                       *ROOT.glob("tests/scripting/data/*.lua"),
                       *ROOT.glob("tests/scene/data/**/*.lua")])
SCENE = """\
World { Gravity [0 0 -9.81] Dynamics "%s" }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "crate" Position [1 2 0.5] PhysicalAttributes { Mass 1 Geometry { Primitive "box" } }
  Sound { File "sounds/knock.wav" } }
Object { ID "door" Position [0 0 1] Script "scripts/fuzz.lua"
  PhysicalAttributes { Mass 4 Geometry { Primitive "box" Size [1 0.05 2] } } }
Joint { ID "hinge" Type "MotorizedHinge" Bodies ["door"] Anchor [0.5 0 1] Axis [0 0 1] }
"""
_VALUES = ["0", "1", "-1", "0.5", "0/0", "1/0", "-1/0", "1e308", "math.huge", "-math.huge",
           "2^53", "math.mininteger", "nil", '"x"', '""', "{}", "{1, 2, 3}", "true", "self",
           "find('crate')", "find('nope')", "string.rep('a', 1000)", "function() end"]
_OBJECTS = ["self", "find('crate')", "find('door')", "find('ground')", "find('nope')", "nil",
            "1", "{}", "find(1)"]
_CALLS = ["{o}:setPosition({v}, {v}, {v})", "{o}:setVelocity({v}, {v}, {v})",
          "{o}:addForce({v}, {v}, {v})", "{o}:addTorque({v}, {v}, {v})",
          "{o}:addImpulse({v}, {v}, {v}, {v}, {v}, {v})", "{o}:setOrientation({v}, {v}, {v}, {v})",
          "{o}:setKinematicTarget({v}, {v}, {v})", "{o}:delete()", "{o}:playSound()",
          "{o}:setGain({v})", "local x, y, z = {o}:getPosition()", "{o}:getName()",
          "delete({o})", "setMotor('hinge', {v}, {v})", "setMotor({v}, {v}, {v})",
          "breakJoint('hinge')", "createJoint{{kind={s}, a={o}, b={o}, anchor={{{v}, 0, 0}}}}",
          "spawn({s})", "spawn('Object {{ ID \"new\" Position [0 0 {v}] }}')",
          "after({v}, function() {c} end)", "every({v}, function() {c} end)", "cancel({v})",
          "on({s}, function(d) {c} end)", "emit({s}, {v})", "log({v})", "warn({v})",
          "measure({s}, {v})", "setCamera{{position={{{v}, 0, 0}}}}", "requestPlugin({s})",
          "setAnomaly({s}, {v})", "getAnomaly({s})", "setUniform({s}, {s}, {v})", "time()",
          "math.random({v})", "require({s})", "print(string.format({s}, {v}))"]
_STRINGS = ['"hinge"', '"x"', '""', '"Hinge"', '"ball"', '"../../etc/passwd"', "nil", "1",
            '"Object { ID 1 }"', '"%d"', '"%s%s%s"']
#: What the sandbox must stop: endless, deep or huge.
_RUNAWAYS = ["while true do end", "local function f() return f() + 1 end f()",
             "local t = {} for i = 1, 1e9 do t[i] = i end", "local s = string.rep('x', 2^31)",
             "local s = 'x' while true do s = s .. s end", "repeat until false",
             "coroutine.wrap(function() while true do end end)()", "os.exit()", "io.open('x')",
             "debug.sethook()", "load('return 1')()", "setmetatable(_G, nil)",
             "collectgarbage('stop')", "string.rep('x', 1e6):rep(1e4)"]
_FRAGMENTS = list("()[]{}.,:;=+-*/%^#<>~'\"\\\n ") + [
    "end", "function", "local", "then", "do", "nil", "self", "..", "...", "--", "--[[", "]]",
    "0/0", "1e999", "while true do end", "onUpdate", "find", "goto", "::x::"]


def _call(rng: random.Random, depth: int = 0) -> str:
    template = rng.choice(_CALLS)
    inner = _call(rng, depth + 1) if depth < 2 else "x = 1"
    out = template
    for slot, pick in (("{o}", lambda: rng.choice(_OBJECTS)), ("{v}", lambda: rng.choice(_VALUES)),
                       ("{s}", lambda: rng.choice(_STRINGS)), ("{c}", lambda: inner)):
        while slot in out:
            out = out.replace(slot, pick(), 1)
    return out.replace("{{", "{").replace("}}", "}")


def script(rng: random.Random) -> str:
    """A script of API calls at its top level and in its callbacks, now and then a
    runaway; or a real script; either mutated now and then."""
    if rng.random() < 0.25 and SEED_SCRIPTS:
        text = rng.choice(SEED_SCRIPTS).read_text(encoding="utf-8")
    else:
        lines = [_call(rng) for _ in range(rng.randrange(4))]
        for callback in rng.sample(["onStart()", "onUpdate(dt)", "onCollide(other, impulse)",
                                    "onResume()"], rng.randrange(1, 4)):
            body = "\n  ".join(_call(rng) for _ in range(rng.randrange(1, 4)))
            lines.append(f"function {callback}\n  {body}\nend")
        if rng.random() < 0.1:
            lines.insert(rng.randrange(len(lines) + 1), rng.choice(_RUNAWAYS))
        text = "\n".join(lines)
    if rng.random() < 0.3:
        text = mutate(rng, text, rng.randrange(1, 6), _FRAGMENTS)
    return text


@dataclass(slots=True)
class LuaInput:
    """A script and the physics backend of its world."""

    source: str
    backend: str = "ode"


def make_script(rng: random.Random) -> LuaInput:
    return LuaInput(script(rng).encode("utf-8", "replace").decode("utf-8"),
                    rng.choice(["ode", "pymunk"]))


def prepare(folder: Path) -> None:
    for name in ("scripts", "sounds"):
        shutil.copytree(ASSETS[name], folder / name, dirs_exist_ok=True)


def exercise(inp: LuaInput, folder: Path) -> Outcome:
    """The world built with the script and run for :data:`FRAMES` frames; "ok" when the
    script loaded and did not stop, else "message" (its error, told at its line)."""
    (folder / "main.scene").write_text(SCENE % inp.backend, encoding="utf-8")
    (folder / "scripts" / "fuzz.lua").write_text(inp.source, encoding="utf-8")
    try:
        engine = content_engine(folder)
    except SceneLoadError:
        return "message"
    try:
        for _ in range(FRAMES):
            engine.step()
        runtime = engine.resource(ScriptRuntime)
        ours = [s for s in runtime.scripts if s.name.endswith("fuzz.lua")]
        return "ok" if ours and not any(s.stopped for s in ours) else "message"
    finally:
        engine.close()


def _files(inp: LuaInput, stem: str) -> dict[str, str]:
    return {f"{stem}.{inp.backend}.lua": inp.source}


TARGET = Target("lua", make_script, exercise, _files, prepare)
