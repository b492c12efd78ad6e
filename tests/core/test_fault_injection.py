"""The fault-injection matrix: every way a value reaches a backend, fed bad values.

Entry points: scene keys (checked by ``check`` and ``run`` at their line), each Lua
object method and global (those whose checks need their plugin — hands, sound,
anomalies, post passes, shader uniforms — with the plugins loaded; avatars' methods with
theirs), the Python API (commands, ``set_pose``, Transform writes), input recordings
replayed, and input events a node sends the server. Bad values: NaN, +inf, -inf, 1e30,
0, a negative, one body twice, a zero vector, a wrong type, a wrong number of arguments.
On both backends, serial and threaded, the run must end normally with no traceback;
every call that a value makes meaningless is refused at the script's line, naming the
object it acts on; a neighbouring object falls exactly as theory says (semi-implicit
Euler, the backends' integrator), as in a run without faults; and the state saved at the
end holds no NaN. A node's bad events are counted and dropped, told once per node.
"""

from __future__ import annotations

import json
import logging
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from components import MaterialProps, Physical, Shape, Transform
from engine.app import Engine, EngineConfig
from engine.physics.commands import (
    AddBody,
    ApplyForce,
    CommandError,
    SetKinematicTarget,
    SetPose,
    SetVelocity,
)
from engine.scene import check, instantiate, load_spec, write_state
from services.scripting.runtime import ScriptRuntime
from systems import RegistryPlugin, load_plugin
from systems.dynamics import DynamicsSystem
from systems.scripting import ScriptingPlugin

REPO = Path(__file__).resolve().parents[2]

#: Bad values, as Lua expressions.
VALUES = {"nan": "0/0", "inf": "1/0", "-inf": "-1/0", "1e30": "1e30", "zero": "0",
          "negative": "-1", "string": '"x"', "boolean": "true"}
NUMBERS_BAD = {"nan", "inf", "-inf", "string", "boolean"}  # never a number a backend takes
FAR = NUMBERS_BAD | {"1e30"}  # ... or past the world or the speed limit

#: Lua entry points: (name, statement with @ for the value, values it must refuse).
#: ``self`` is the culprit object (dynamic, 1 kg), ``partner`` its own second body,
#: joint "j" is a motorized hinge between two bodies of their own.
LUA_CALLS: list[tuple[str, str, set[str]]] = [
    ("setPosition", "self:setPosition(@, 0, 300)", FAR),
    ("setOrientation", "self:setOrientation(@, @, @, @)", NUMBERS_BAD | {"zero"}),
    ("setVelocity", "self:setVelocity(0, @, 0)", FAR),
    ("setAngularVelocity", "self:setAngularVelocity(@, 0, 0)", FAR),
    ("addForce", "self:addForce(@, 0, 0)", FAR),
    ("addForce at", "self:addForce(0, 0, 1, @, 0, 0)", FAR),
    ("addTorque", "self:addTorque(0, @, 0)", NUMBERS_BAD),
    ("addImpulse", "self:addImpulse(0, 0, @)", FAR),
    ("setKinematicTarget", "kinematic:setKinematicTarget(@, 0, 300)", FAR),
    ("setGain", "self:setGain(@)", NUMBERS_BAD | {"1e30", "negative"}),
    ("getPosition", "self:getPosition(@)", set()),
    ("delete extra", "partner:delete(@)", set()),
    ("spawn position", "spawn('Object { ID \"n\" Position [' .. @ .. ' 70 300] "
                       "PhysicalAttributes { } }')", FAR),
    ("spawn mass", "spawn('Object { ID \"n\" Position [0 80 300] PhysicalAttributes "
                   "{ Mass ' .. @ .. ' } }')", NUMBERS_BAD | {"zero", "negative"}),
    ("spawn size", "spawn('Object { ID \"n\" Position [0 90 300] Size [' .. @ .. '] "
                   "PhysicalAttributes { } }')", FAR | {"zero", "negative"}),
    ("find", "find(@)", set()),
    ("delete", "delete(@)", set()),
    ("setMotor velocity", 'setMotor("j", @, 10)', FAR),
    ("setMotor force", 'setMotor("j", 1, @)', NUMBERS_BAD | {"negative"}),
    ("createJoint axis", 'createJoint{kind="hinge", a=self, b=partner, axis={@, @, @}}',
     NUMBERS_BAD | {"zero"}),
    ("createJoint anchor", 'createJoint{kind="ball", a=self, b=partner, anchor={@, 0, 300}}',
     FAR),
    ("createJoint limits", 'createJoint{kind="hinge", a=self, b=partner, low=@}',
     NUMBERS_BAD),
    ("createJoint spring", 'createJoint{kind="hinge", a=self, b=partner, '
                           "spring={stiffness=@, damping=1}}", NUMBERS_BAD | {"negative"}),
    ("createJoint spring target", 'createJoint{kind="slider", a=self, b=partner, '
                                  "spring={stiffness=1, target=@}}", NUMBERS_BAD),
    ("createJoint spring bound", 'createJoint{kind="hinge", a=self, b=partner, '
                                 "spring={stiffness=1, maxForce=@}}",
     NUMBERS_BAD - {"inf"} | {"zero", "negative"}),
    ("breakJoint", "breakJoint(@)", set(VALUES)),
    ("setCamera", "setCamera{position={@, 0, 300}}", NUMBERS_BAD),
    ("setUniform", 'setUniform("s", "u", @)', set()),
    ("after", "after(@, function() end)", NUMBERS_BAD),
    ("every", "every(@, function() end)", NUMBERS_BAD | {"zero", "negative"}),
    ("cancel", "cancel(@)", set()),
    ("on", "on(@, function() end)", set()),
    ("emit", "emit(@, {v = @})", set()),
    ("requestPlugin", "requestPlugin(@)", set(VALUES)),
    ("time", "time(@)", set()),
    ("log", "log(@)", set()),
    ("input", "input.tracker(@); input.wheel(@); input.button(@, @); input.axis(@, @); "
              "input.key(@)", set()),
    # a bad value where the object goes (obj.method(value)): an integer is an entity id,
    # and 0 and -1 name none
    ("getName", "self.getName(@)", set(VALUES)),
    ("getOrientation", "self.getOrientation(@)", set(VALUES)),
    ("getVelocity", "self.getVelocity(@)", set(VALUES)),
    ("getAngularVelocity", "self.getAngularVelocity(@)", set(VALUES)),
    ("getHandState", "self.getHandState(@)", set(VALUES)),
    ("getHeld", "self.getHeld(@)", set(VALUES)),
    ("grasp", "self:grasp(@)", set(VALUES)),
    # without the sound plugin an existing object's sound is a no-op: ids are not refused
    ("playSound method", "self.playSound(@)", FAR),
    ("stopSound method", "self.stopSound(@)", FAR),
    ("playSound", "playSound(@)", FAR),
    ("stopSound", "stopSound(@)", FAR),
    ("setGain global", "setGain(self, @)", NUMBERS_BAD | {"1e30", "negative"}),
    ("setAnomaly id", "setAnomaly(@, true)", set(VALUES) - {"string"}),
    ("setAnomaly on", 'setAnomaly("blur", @)', set(VALUES) - {"boolean"}),
    ("setAnomaly params", 'setAnomaly("blur", true, @)', set(VALUES)),
    ("getAnomaly", "getAnomaly(@)", set()),  # (no anomalies plugin: the services test)
    ("enablePost", "enablePost(@, @)", set()),
    ("setPostUniform", 'setPostUniform(@, "u", @)', set()),
    ("measure name", "measure(@, 1)", set(VALUES) - {"string"}),
    ("measure value", 'measure("m", @)', NUMBERS_BAD),
]
#: Wrong numbers of arguments, and one body twice: (name, statement, refused).
LUA_SHAPES: list[tuple[str, str, bool]] = [
    ("setPosition()", "self:setPosition()", True),
    ("setVelocity(1)", "self:setVelocity(1)", True),
    ("addForce()", "self:addForce()", True),
    ("setOrientation(1)", "self:setOrientation(1)", True),
    ("setMotor()", "setMotor()", True),
    ("createJoint()", "createJoint()", True),
    ("spawn()", "spawn()", True),
    ("every(1)", "every(1)", True),
    ("setGain()", "self:setGain()", True),
    ("same body", 'createJoint{kind="hinge", a=self, b=self}', True),
    ("spring on a ball joint", 'createJoint{kind="ball", a=self, b=partner, '
                               "spring={stiffness=1}}", True),
    ("spring of nothing", 'createJoint{kind="hinge", a=self, b=partner, spring={}}', True),
    ("spring, a misspelt field", 'createJoint{kind="hinge", a=self, b=partner, '
                                 "spring={stifness=1}}", True),
    ("spring not a table", 'createJoint{kind="hinge", a=self, b=partner, spring=3}', True),
    ("same body, fixed", 'createJoint{kind="fixed", a=partner, b=partner}', True),
    ("hinge2 on one body", 'createJoint{kind="hinge2", a=self}', True),
    ("hinge2, parallel axes", 'createJoint{kind="hinge2", a=self, b=partner, axis={0, 0, 1}, '
                              "axis2={0, 0, -1}}", True),
    ("universal, parallel axes", 'createJoint{kind="universal", a=self, b=partner, '
                                 "axis={0, 1, 0}, axis2={0, 2, 0}}", True),
    ("self:delete(); then a call", "self:delete(); self:setPosition(0, 0, 0)", False),
]

#: The neighbour that must fall as in a run without faults.
WITNESS_Z = 500.0


def _cases() -> list[tuple[str, str, bool]]:
    """(case id, Lua statement, must it be refused)."""
    cases = []
    for name, statement, refused in LUA_CALLS:
        for value, expression in VALUES.items():
            cases.append((f"{name} / {value}", statement.replace("@", f"({expression})"),
                          value in refused))
    cases.extend(LUA_SHAPES)
    return cases


CASES = _cases()


def _content(root: Path) -> Path:
    """One culprit (with a partner and a kinematic helper) per case, far apart; the
    witness far from all of them; a motorized joint of its own."""
    scripts = root / "scripts"
    scripts.mkdir(parents=True)
    lines = ['Camera { ID "eye" Position [0 -30 310] LookAt [0 0 300] }',
             f'Object {{ ID "witness" Position [-5000 0 {WITNESS_Z}] Size [1] '
             'PhysicalAttributes { Mass 2 Geometry { Primitive "sphere" } } }',
             'Object { ID "ja" Position [5000 0 300] PhysicalAttributes { Mass 1 } }',
             'Object { ID "jb" Position [5002 0 300] PhysicalAttributes { Mass 1 } }',
             'Joint { ID "j" Type "MotorizedHinge" Bodies ["ja" "jb"] Axis [0 1 0] '
             'MotorMaxForce 5 }']
    for i, (_, statement, _) in enumerate(CASES):
        x = 40.0 * i - 4000.0
        lines += [f'Object {{ ID "c{i}" Position [{x} 0 300] Script "scripts/c{i}.lua" '
                  'PhysicalAttributes { Mass 1 } }',
                  f'Object {{ ID "p{i}" Position [{x + 3} 0 300] PhysicalAttributes {{ }} }}',
                  f'Object {{ ID "k{i}" Position [{x + 6} 0 300] Kinematic 1 '
                  'PhysicalAttributes { } }']
        (scripts / f"c{i}.lua").write_text(
            f'local partner, kinematic = find("p{i}"), find("k{i}")\n'
            f"function onStart()\n  {statement}\nend\n")
    (root / "main.scene").write_text("\n".join(lines) + "\n")
    return root


def _engine(content: Path, backend: str, mode: str) -> Engine:
    spec = load_spec(content)
    config = EngineConfig(backend=backend, mode=mode, fast=True, content_dir=content,
                          dt=0.01, world=spec.world)
    engine = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                     ScriptingPlugin()])
    instantiate(engine, spec)
    return engine


def _fallen(steps: int, dt: float, backend: str, g: float = 9.81) -> float:
    """Height of the witness after ``steps`` steps of free fall from rest: semi-implicit
    Euler, velocity first under ODE (z_n = z0 - g dt² n(n+1)/2), position first under
    chipmunk, which moves bodies by last step's velocity (z_n = z0 - g dt² n(n-1)/2)."""
    lag = 1 if backend == "ode" else -1
    return WITNESS_Z - g * dt * dt * steps * (steps + lag) / 2


@pytest.fixture(scope="module")
def content(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return _content(tmp_path_factory.mktemp("faults") / "sim")


@pytest.mark.parametrize("mode", ["serial", "threaded"])
@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_bad_values_from_lua_are_refused_at_the_line_and_the_world_goes_on(
        content: Path, backend: str, mode: str, caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.INFO)
    engine = _engine(content, backend, mode)
    try:
        engine.run(seconds=0.3)  # threaded: until the physics thread has stepped that far
        step = engine.resource(DynamicsSystem).snapshot.step
        assert len(engine.resource(ScriptRuntime).scripts) >= len(CASES) - 2  # (deleted)
        witness = _ids(engine)["witness"]
        z = float(engine.world.component_for_entity(witness, Transform).position[2])
        saved = write_state(engine)
    finally:
        engine.close()
    text = caplog.text
    assert "Traceback" not in text
    for i, (case, _, refused) in enumerate(CASES):
        at = f"scripts/c{i}.lua:3:"
        told = [r.getMessage() for r in caplog.records if r.getMessage().startswith(at)]
        if refused:
            assert told, f"{case}: not refused at its line ({at})"
        acted_on = _ACTED_ON.get(case.split(" / ")[0])
        if refused and acted_on:  # names what it acts on
            acted_on = acted_on.replace("#", str(i))
            assert acted_on in told[0], f"{case}: {told[0]}"
    # the neighbour fell exactly as theory says, as if nothing had happened beside it
    assert step > 0
    assert z == pytest.approx(_fallen(step, 0.01, backend), abs=1e-9)
    assert not re.search(r"\b(nan|inf)\b", saved, re.IGNORECASE)


#: What a refusal must name, by entry point (# is the case's number): the object a method
#: or a global acts on, or the joint.
_ACTED_ON = {**dict.fromkeys(
    ("setPosition", "setOrientation", "setVelocity", "setAngularVelocity", "addForce",
     "addForce at", "addTorque", "addImpulse", "setGain", "setGain global", "createJoint axis",
     "createJoint anchor", "createJoint limits", "createJoint spring",
     "createJoint spring target", "createJoint spring bound"), '"c#"'),
    "setKinematicTarget": '"k#"', "setMotor velocity": '"j"', "setMotor force": '"j"'}


def _ids(engine: Engine) -> dict[str, int]:
    from engine.scene import SceneIds

    return engine.resource(SceneIds).entities


# -- calls whose checks need their plugin: hands, sound, anomalies, post passes, shaders --
#: (name, statement with @, values it must refuse, what the refusal names; # is the case).
#: ``hand`` is a virtual hand, ``mate`` a box, ``self`` an object with a Sound.
SERVICE_CALLS: list[tuple[str, str, set[str], str | None]] = [
    ("setGain", "self:setGain(@)", NUMBERS_BAD | {"1e30", "negative"}, '"c#"'),
    ("setGain global", "setGain(self, @)", NUMBERS_BAD | {"1e30", "negative"}, '"c#"'),
    ("playSound", "playSound(@)", set(VALUES), None),
    ("stopSound", "stopSound(@)", set(VALUES), None),
    ("grasp", "hand:grasp(@)", set(VALUES), "hand_r"),
    ("getHandState", "hand.getHandState(@)", set(VALUES) - {"zero", "negative"}, None),
    ("getHeld", "hand.getHeld(@)", set(VALUES) - {"zero", "negative"}, None),
    ("setAnomaly motion", 'setAnomaly("blur", true, {motion = @})', set(), None),  # clamped
    ("setAnomaly onset", 'setAnomaly("blur", true, {onset = @})', set(), None),
    ("getAnomaly", "getAnomaly(@)", set(VALUES), None),
    ("enablePost", "enablePost(@, true)", set(VALUES), None),
    ("setPostUniform pass", 'setPostUniform(@, "u_tint", {1, 1, 1})', set(VALUES), None),
    ("setPostUniform uniform", 'setPostUniform("tint", @, {1, 1, 1})', set(VALUES), None),
    ("setPostUniform value", 'setPostUniform("tint", "u_tint", {@, 1, 1})', NUMBERS_BAD,
     None),
    ("setPostUniform scalar", 'setPostUniform("tint", "u_tint", @)', set(VALUES), None),
    ("setUniform value", 'setUniform("toon", "Edge", @)', NUMBERS_BAD, None),
]
#: (name, statement, refused, what the refusal names).
SERVICE_SHAPES: list[tuple[str, str, bool, str | None]] = [
    ("grasp itself", "hand:grasp(hand)", True, "hand_r"),
    ("grasp by a non-hand", "self:grasp(mate)", True, "c#"),
    ("getHandState of a non-hand", "self:getHandState()", True, "c#"),
    ("getHeld of a non-hand", "self:getHeld()", True, "c#"),
    ("grasp()", "hand:grasp()", True, "hand_r"),
    ("setGain without a Sound", "mate:setGain(1)", True, '"mate"'),
    ("setAnomaly()", "setAnomaly()", True, None),
    ("getAnomaly()", "getAnomaly()", True, None),
    ("enablePost()", "enablePost()", True, None),
    ("setPostUniform()", "setPostUniform()", True, None),
    ("setUniform()", "setUniform()", True, None),
    ("grasp and release", "hand:grasp(mate); hand:release()", False, None),
]
TINT = ("#version 330\nin vec2 v_uv;\nuniform sampler2D u_scene;\nuniform vec3 u_tint;\n"
        "out vec4 f_color;\nvoid main() { f_color = vec4(texture(u_scene, v_uv).rgb * u_tint, "
        "1.0); }\n")


def _service_content(root: Path) -> tuple[Path, list[tuple[str, bool, str | None]]]:
    """One culprit (with a Sound) per case; a virtual hand, a box, a post pass and a
    shader state; the witness falling far away. Each call is made once, in the culprit's
    onUpdate after the first frames (a hand holds from its first physics frame on)."""
    import shutil
    import wave

    cases = [(f"{name} / {value}", statement.replace("@", f"({expression})"),
              value in refused, named)
             for name, statement, refused, named in SERVICE_CALLS
             for value, expression in VALUES.items()] + SERVICE_SHAPES
    (root / "scripts").mkdir(parents=True)
    with wave.open(str(root / "beep.wav"), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(22050)
        w.writeframes(b"\0\0" * 2205)
    (root / "tint.frag").write_text(TINT)
    shutil.copytree(REPO / "tests" / "render" / "content" / "shaders", root / "shaders")
    lines = ['Camera { ID "eye" Position [0 -30 310] LookAt [0 0 300] }',
             f'Object {{ ID "witness" Position [-5000 0 {WITNESS_Z}] Size [1] '
             'PhysicalAttributes { Mass 2 Geometry { Primitive "sphere" } } }',
             'Object { ID "hand_r" Position [0 0 300] Hand { Tracker "hand_r" } }',
             'Object { ID "mate" Position [0 0.2 300] Size [0.1] PhysicalAttributes { } }',
             'PostPass { ID "tint" File "tint.frag" Enabled 0 '
             'Uniform { ID "u_tint" Value [1 1 1] } }',
             'VertexShader { ID "tv" File "shaders/toon.vert" }',
             'FragmentShader { ID "tf" File "shaders/toon.frag" }',
             'ShaderProgram { ID "toon" VertexShader "tv" FragmentShader "tf" }',
             'ShaderState { ID "toon" ShaderProgram "toon" Uniform { ID "Edge" Value 0.0 } }']
    for i, (_, statement, _, _) in enumerate(cases):
        lines.append(f'Object {{ ID "c{i}" Position [{40.0 * i - 4000.0} 0 300] Script '
                     f'"scripts/c{i}.lua" PhysicalAttributes {{ }} Sound {{ File "beep.wav" }} '
                     '}')
        (root / "scripts" / f"c{i}.lua").write_text(
            'local hand, mate = find("hand_r"), find("mate")\n'
            "function onUpdate()\n  if done or time() < 0.03 then return end; done = true; "
            f"{statement}\nend\n")
    (root / "main.scene").write_text("\n".join(lines) + "\n")
    return root, [(case, refused, named) for case, _, refused, named in cases]


def test_bad_values_to_hands_sound_anomalies_and_post_passes_are_refused_at_the_line(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """With the plugins whose checks these calls reach (hands, sound, anomalies, a
    headless renderer): each bad value refused at the script's line, naming the object a
    call is on; a clamped parameter told at its line; the run goes on, the witness falls
    as theory says and the saved state holds no NaN."""
    from systems import create_engine

    content, cases = _service_content(tmp_path / "sim")
    spec = load_spec(content)
    config = EngineConfig(backend="ode", fast=True, content_dir=content, world=spec.world,
                          dt=0.01, render=True, sound=f"wave:{tmp_path / 'out.wav'}",
                          options={"size": "64x48"})
    caplog.set_level(logging.INFO)
    with create_engine(config) as engine:
        instantiate(engine, spec)
        engine.run(frames=8)
        step = engine.resource(DynamicsSystem).snapshot.step
        tick = 0.01 / max(engine.controller.substeps, 1)  # (the hands substep physics)
        z = float(engine.world.component_for_entity(_ids(engine)["witness"],
                                                    Transform).position[2])
        saved = write_state(engine)
    assert "Traceback" not in caplog.text
    for i, (case, refused, named) in enumerate(cases):
        at = f"scripts/c{i}.lua:3:"
        told = [r.getMessage() for r in caplog.records if r.getMessage().startswith(at)]
        if refused:
            assert told, f"{case}: not refused at its line ({at})"
        if refused and named:
            assert named.replace("#", str(i)) in told[0], f"{case}: {told[0]}"
        if not refused and case.startswith(("grasp and", "setPostUniform value / zero")):
            assert not told, f"{case}: {told}"
    clamped = [r.getMessage() for r in caplog.records if "setAnomaly('blur'): blur Motion"
               in r.getMessage()]
    assert clamped and re.match(r"scripts/c\d+\.lua:3: ", clamped[0])
    assert step > 0 and z == pytest.approx(_fallen(step, tick, "ode"), abs=1e-9)
    bodies = saved.split("ScriptState")[0]
    assert not re.search(r"\b(nan|inf)\b", bodies, re.IGNORECASE)


# -- scene keys --------------------------------------------------------------------------
#: (block text with @ for the value, values that must be an error at the value's line).
SCENE_KEYS: list[tuple[str, set[str]]] = [
    ('Object { ID "o" Position [@ 0 1] }', {"1e30", "-1e30"}),
    ('Object { ID "o" Velocity [0 @ 0] PhysicalAttributes { } }', {"1e30", "-1e30"}),
    ('Object { ID "o" AngularVelocity [0 0 @] PhysicalAttributes { } }', {"1e30", "-1e30"}),
    ('Object { ID "o" Quaternion [@ @ @ @] }', {"zero"}),
    ('Object { ID "o" Size [@] PhysicalAttributes { } }', {"zero", "negative", "1e30"}),
    ('Object { ID "o" PhysicalAttributes { Mass @ } }', {"zero", "negative", "1e30"}),
    ('Object { ID "o" PhysicalAttributes { Density @ } }', {"zero", "negative", "1e30"}),
    ('Material { ID "m" Density @ }', {"zero", "negative", "1e30"}),
    ('Object { ID "a" PhysicalAttributes { } }\n'
     'Joint { Type "Hinge" Bodies ["a"] Axis [@ @ @] }', {"zero"}),
    ('Object { ID "a" PhysicalAttributes { } }\n'
     'Joint { Type "Ball" Bodies ["a"] Anchor [0 @ 0] }', {"1e30", "-1e30"}),
    ('Object { ID "a" PhysicalAttributes { } }\nObject { ID "b" PhysicalAttributes { } }\n'
     'Joint { Type "Universal" Bodies ["a" "b"] Axis [0 0 1] Axis2 [0 0 @] }',
     {"zero", "negative", "1e30", "-1e30"}),
    ('Object { ID "a" PhysicalAttributes { } }\n'
     'Joint { Type "Hinge" Bodies ["a"] ReferencePose1 [@ 0 0 1 0 0 0] }', {"1e30", "-1e30"}),
    ("World { TimeStep @ }", {"zero", "negative", "1e30"}),
    ("World { Extent @ }", {"zero", "negative", "1e30"}),
    ("World { Iterations @ }", {"zero", "negative"}),
    ("World { MaxContacts @ }", {"zero", "negative"}),
]
SCENE_VALUES = {"zero": "0", "negative": "-1", "1e30": "1e30", "-1e30": "-1e30",
                "inf": "1e999", "nan": "0/0", "string": '"x"', "arity": ""}


@pytest.mark.parametrize("template,bad", SCENE_KEYS, ids=[t[:40] for t, _ in SCENE_KEYS])
def test_bad_scene_values_are_errors_at_their_line(tmp_path: Path, template: str,
                                                   bad: set[str]) -> None:
    for value, text in SCENE_VALUES.items():
        scene = tmp_path / f"{value}.scene"
        body = template.replace("@", text)
        scene.write_text("// faults\n" + body + "\n")
        report = check(scene)  # must not raise, whatever the value
        errors = report.errors
        line = 2 + template.split("@")[0].count("\n")
        if value in bad | {"inf", "nan", "string", "arity"}:
            assert errors, f"{body!r} passed check"
            assert any(e.line == line for e in errors), [e.render() for e in errors]
        assert "Traceback" not in report.render()


def test_a_long_step_is_a_warning_and_the_extent_is_the_files(tmp_path: Path) -> None:
    scene = tmp_path / "main.scene"
    scene.write_text("World { TimeStep 0.2 }\nObject { ID \"a\" }\n")
    report = check(scene)
    assert not report.errors
    (warning,) = [d for d in report.diagnostics if d.severity == "warning"]
    assert (warning.line, warning.col) == (1, 18) and "TimeStep 0.2 s is long" in warning.message
    scene.write_text("World { Extent 50 }\nObject { ID \"a\" Position [0 60 0] }\n"
                     "Object { ID \"b\" Position [0 40 0] }\n")
    (error,) = check(scene).errors
    assert error.line == 2 and "y = 60 is outside the world (±50 m" in error.message


def test_a_same_body_joint_and_a_far_object_never_reach_a_backend(tmp_path: Path) -> None:
    (tmp_path / "main.scene").write_text(
        'Object { ID "a" Position [1e30 0 1] PhysicalAttributes { } }\n'
        'Object { ID "b" PhysicalAttributes { } }\n'
        'Joint { Type "Hinge" Bodies ["b" "b"] }\n'
        "World { TimeStep 0 }\n"
        'Object { ID "c" Position [3 0 0] PhysicalAttributes { } }\n'
        'Joint { Type "Hinge2" Bodies ["c"] }\n')  # ODE aborted on a hinge2 on one body
    result = subprocess.run([sys.executable, "-m", "app.cli", "run", str(tmp_path),
                             "--frames", "5", "--headless"], capture_output=True, text=True,
                            timeout=120, cwd=REPO)
    # the rest runs without the broken parts, and the exit status says there were some
    assert result.returncode == 1, result.stderr
    assert "Traceback" not in result.stderr
    for line, what in ((1, "outside the world"), (3, "two different bodies"),
                       (4, "TimeStep must be"), (6, "hinge2 joint joins two bodies")):
        assert re.search(rf"main\.scene:{line}:\d+: error: .*{what}", result.stderr), what
    assert re.search(r'without 4 broken part\(s\).*\n  \S*main\.scene:1: Object "a"\n'
                     r'  \S*main\.scene:3: Joint\n  \S*main\.scene:4: TimeStep\n'
                     r'  \S*main\.scene:6: Joint\n',
                     result.stderr), result.stderr
    assert "ran 5 frames" in result.stderr


# -- the Python API ----------------------------------------------------------------------
@pytest.mark.parametrize("mode", ["serial", "threaded"])
@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_python_systems_get_an_exception_from_the_call(backend: str, mode: str) -> None:
    """Threaded, the calls are made on the main thread while physics steps on its own:
    each is refused there, at once, and nothing bad reaches the stepping thread."""
    config = EngineConfig(backend=backend, fast=True, mode=mode)
    with Engine(config, plugins=[RegistryPlugin(), load_plugin("physics")]) as engine:
        body = engine.spawn(Transform((0.0, 0.0, 1.0)), Physical())
        witness = engine.spawn(Transform((50.0, 0.0, WITNESS_Z)),
                               Physical(shapes=[Shape("sphere", (0.5,))]))
        engine.run(frames=1)
        physics = engine.physics
        nan, inf = math.nan, math.inf
        bad = [lambda: physics.push(SetPose(body, (nan, 0, 0), (1, 0, 0, 0))),
               lambda: physics.push(SetPose(body, (1e30, 0, 0), (1, 0, 0, 0))),
               lambda: physics.push(SetPose(body, (0, 0, 0), (0, 0, 0, 0))),
               lambda: physics.push(SetVelocity(body, (inf, 0, 0), (0, 0, 0))),
               lambda: physics.push(SetVelocity(body, (1e30, 0, 0), (0, 0, 0))),
               lambda: physics.push(ApplyForce(body, (-inf, 0, 0))),
               lambda: physics.push(ApplyForce(body, (1, 0, 0), (1e30, 0, 0))),
               lambda: physics.push(SetKinematicTarget(body, (1e30, 0, 0), (1, 0, 0, 0),
                                                       0.01)),
               lambda: physics.push(SetKinematicTarget(body, (0, 0, 0), (1, 0, 0, 0), 0)),
               lambda: physics.push(AddBody(99, Physical(mass=-1.0))),
               lambda: physics.push(AddBody(99, Physical(mass=1e160))),
               lambda: physics.push(AddBody(99, Physical(mass=None, material=MaterialProps(
                   density=-1.0)))),
               lambda: physics.push(AddBody(99, Physical(material=MaterialProps(
                   friction=nan)))),
               lambda: physics.push(AddBody(99, Physical(shapes=[Shape("box", (0, 0, 0))]))),
               lambda: physics.push(AddBody(99, Physical(shapes=[Shape("sphere", (1e30,))]))),
               lambda: physics.set_pose(body, (nan, 0, 0), (1, 0, 0, 0)),
               lambda: physics.set_velocity(body, ("x", 0, 0), (0, 0, 0)),
               lambda: physics.set_pose(body, (0, 0), (1, 0, 0, 0))]
        for call in bad:
            with pytest.raises(CommandError):
                call()
        engine.run(seconds=0.2)  # threaded: until the physics thread has stepped that far
        steps = engine.resource(DynamicsSystem).snapshot.step  # (the poses' step, threaded)
        z = float(engine.world.component_for_entity(witness, Transform).position[2])
    assert steps > 1 and z == pytest.approx(_fallen(steps, engine.config.dt, backend), abs=1e-9)


@pytest.mark.parametrize("mode", ["serial", "threaded"])
@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_bad_transform_write_every_frame_is_told_once_then_counted(
        backend: str, mode: str, caplog: pytest.LogCaptureFixture) -> None:
    """A Python system writing NaN or a far position into a body's Transform every
    frame: each write is undone; one line, then a count, not 300 lines."""
    from engine.system import Phase, System

    class Vandal(System):
        phase = Phase.SCRIPT
        reads = (Transform,)
        writes = (Transform,)

        def __init__(self, target: int) -> None:
            self.target = target
            self.frames = 0

        def run(self, engine: Engine, dt: float) -> None:
            self.frames += 1
            t = engine.world.component_for_entity(self.target, Transform)
            t.position[0] = math.nan if self.frames % 2 else 1e30

    caplog.set_level(logging.INFO)
    config = EngineConfig(backend=backend, fast=True, mode=mode)
    with Engine(config, plugins=[RegistryPlugin(), load_plugin("physics")]) as engine:
        from components import Name

        body = engine.spawn(Name("crate"), Transform((0.0, 0.0, 1.0)), Physical())
        engine.run(frames=1)
        engine.add_system(Vandal(body))
        engine.run(frames=300)
        position = engine.world.component_for_entity(body, Transform).position.copy()
    undone = [r.getMessage() for r in caplog.records if "the write is undone" in
              r.getMessage()]
    # NaN and 1e30: each told once, then counted (at the end, or every 5 s of a slow run)
    assert 2 <= len(undone) <= 6, undone
    assert sum("repeated" in m for m in undone) >= 2
    assert "'crate'" in undone[0] and np.isfinite(position).all()
    assert abs(position[0]) < 1.0


def test_the_cli_run_saves_a_clean_state_with_every_fault_threaded(content: Path,
                                                                    tmp_path: Path) -> None:
    """The same content through ``colosseum run`` in its own process: it ends normally,
    prints no traceback, and its saved state runs again."""
    saved, stats = tmp_path / "state.scene", tmp_path / "stats.json"
    result = subprocess.run([sys.executable, "-m", "app.cli", "run", str(content),
                             "--frames", "40", "--headless", "--mode", "threaded", "--fast",
                             "--save-state", str(saved), "--stats", str(stats)],
                            capture_output=True, text=True, timeout=300, cwd=REPO)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "Traceback" not in result.stderr
    text = saved.read_text()
    assert not re.search(r"\b(nan|inf)\b", text, re.IGNORECASE)
    assert json.loads(stats.read_text())["frames"] == 40
    assert not check(saved).errors


@pytest.mark.parametrize("mode", ["serial", "threaded"])
def test_a_script_sending_a_load_physics_refuses_every_frame_is_one_line_and_a_count(
        tmp_path: Path, mode: str, caplog: pytest.LogCaptureFixture) -> None:
    """A torque too large for the body is known only where the body's inertia is: in
    the physics step. Sent every frame for 300 frames, it is told once, then counted."""
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "spin.lua").write_text(
        "function onUpdate(dt)\n  self:addTorque(0, 0, 1e30)\nend\n")
    (tmp_path / "main.scene").write_text(
        'Object { ID "spinner" Position [0 0 5] Script "scripts/spin.lua" '
        'PhysicalAttributes { Mass 1 } }\n')
    caplog.set_level(logging.INFO)
    engine = _engine(tmp_path, "ode", mode)
    engine.run(frames=300)
    engine.close()
    told = [r.getMessage() for r in caplog.records if "ApplyTorque on object 'spinner'" in
            r.getMessage()]
    assert 2 <= len(told) <= 4, told  # the first, then counts (at the end, or every 5 s)
    assert "would push it past" in told[0] and "entity" not in told[0]
    assert told[0].count("'spinner'") == 1
    counted = sum(int(n) for n in re.findall(r"repeated (\d+) more times", " ".join(told)))
    if mode == "serial":
        assert counted == 299  # every frame's, each applied before the next step
    else:  # the physics thread applies what it has when the run ends
        assert counted >= 100


def test_a_warning_a_script_causes_every_frame_is_one_line_and_a_count(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A value clamped every frame (the call goes on) is told once at the calling line,
    and its repeats counted when the run ends (the count was never told)."""
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "dim.lua").write_text(
        'function onUpdate(dt)\n  setAnomaly("blur", true, {motion = 1.2})\nend\n')
    (tmp_path / "main.scene").write_text('Script "scripts/dim.lua"\n')
    caplog.set_level(logging.INFO)
    config = EngineConfig(backend="ode", fast=True, content_dir=tmp_path)
    engine = Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                     load_plugin("anomalies"), ScriptingPlugin()])
    instantiate(engine, load_spec(tmp_path))
    engine.run(frames=50)
    engine.close()
    told = [r.getMessage() for r in caplog.records if "Motion 1.2 is out of range" in
            r.getMessage()]
    assert len(told) == 2 and told[0].startswith("scripts/dim.lua:2: setAnomaly('blur')")
    assert told[1].endswith("(repeated 49 more times)")


# -- input events ------------------------------------------------------------------------
def _recording(path: Path, positions: list[str]) -> Path:
    lines = ['{"format": "colosseum-input", "version": 1, "devices": []}']
    for frame, position in enumerate(positions, 1):
        lines.append(f'{{"frame": {frame}, "type": "tracker", "device": "hand", "position": '
                     f'{position}, "orientation": [1, 0, 0, 0], "velocity": null, '
                     f'"timestamp": {frame / 100}}}')
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("backend,mode", [("ode", "serial"), ("ode", "threaded"),
                                          ("pymunk", "threaded")])
def test_tracked_input_far_outside_the_world_is_not_applied(tmp_path: Path, backend: str,
                                                            mode: str) -> None:
    """A tracker pose 1e8 m away (past the world's ±1e6 m, short of the ±1e9 m the input
    layer takes from a device), replayed into a controller that moves a kinematic paddle
    and into an object that follows the tracker: the value is not applied (one message
    naming the controller), the run ends normally, its saved state is clean. A recording
    holding NaN is refused at its line before the run starts (as is one holding 1e30)."""
    content = tmp_path / "sim"
    content.mkdir()
    (content / "main.scene").write_text(
        'Object { ID "paddle" Position [0 0 1] Kinematic 1 PhysicalAttributes { } }\n'
        'Object { ID "cursor" Position [0 0 2] PhysicalAttributes { } }\n'
        'Controller { Input "tracker:hand" Target "kinematic:paddle" }\n'
        'Input { Tracker { ID "hand" Object "cursor" } }\n')
    far = _recording(tmp_path / "far.jsonl", ["[0, 0, 1]", "[1e8, 0, 0]", "[0, 1e8, 1]"] * 5)
    saved = tmp_path / "state.scene"
    result = subprocess.run([sys.executable, "-m", "app.cli", "run", str(content),
                             "--replay", str(far), "--frames", "20", "--headless", "--fast",
                             "--mode", mode, "--backend", backend, "--save-state", str(saved)],
                            capture_output=True, text=True, timeout=300, cwd=REPO)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "Traceback" not in result.stderr
    assert "controller 'tracker:hand' -> 'kinematic:paddle'" in result.stderr
    assert "outside the world" in result.stderr
    assert result.stderr.count("the value is not applied") <= 3  # told, then counted
    # the far value as a number of its own (a clock of 0.41000000000000003 s holds the digits)
    assert not re.search(r"\b(nan|inf)\b|(?<![\d.])(1e\+?0?8|100000000)(?![\d])",
                         saved.read_text(), re.IGNORECASE)
    if (backend, mode) != ("ode", "serial"):
        return  # (refused while the recording is read, before any backend: once is enough)
    nan = _recording(tmp_path / "nan.jsonl", ["[0, 0, 1]", "[NaN, 0, 0]"])
    result = subprocess.run([sys.executable, "-m", "app.cli", "run", str(content),
                             "--replay", str(nan), "--frames", "5", "--headless"],
                            capture_output=True, text=True, timeout=300, cwd=REPO)
    assert result.returncode == 1 and "Traceback" not in result.stderr
    assert f"{nan}:3:" in result.stderr


def _bad_node_events() -> list[object]:
    """Input events a node might send that are not events: each field of each kind fed
    NaN, ±inf, 1e30, a wrong type, null and a wrong arity; a wrong kind, a missing field,
    an extra one, and records that are not objects at all."""
    nan, inf = math.nan, math.inf
    pose = {"type": "tracker", "device": "hand_r", "position": [0, 0, 1],
            "orientation": [1, 0, 0, 0]}
    bad_numbers = [nan, inf, -inf, 1e30, "x", True, None]
    events: list[object] = []
    for field, good in (("position", [0, 0, 1]), ("orientation", [1, 0, 0, 0]),
                        ("velocity", [0, 0, 0])):
        events += [{**pose, field: [v, *good[1:]]} for v in bad_numbers if
                   not (field == "orientation" and v == 1e30)]  # (1e30: not unit: refused)
        events += [{**pose, field: good[:-1]}, {**pose, field: 7}]
    events += [{**pose, "orientation": [0, 0, 0, 0]}, {**pose, "timestamp": nan}]
    events += [{"type": "axis", "device": "stick", "name": "x", "value": v}
               for v in (nan, inf, -inf, "x", True, None)]
    events += [{"type": "button", "device": "glove", "name": "index", "pressed": v}
               for v in (1, "x", None, nan)]
    events += [{"type": "button", "device": "glove", "name": v, "pressed": True}
               for v in ("", 5, None)]
    events += [{"type": "wheel", "device": "chair", "count": v}
               for v in (1.5, "x", True, nan, inf)]
    events += [{"type": "key", "key": v, "pressed": True} for v in ("", 5, None)]
    events += [{"type": "pointer", "device": "mouse", "x": v, "y": 0} for v in (nan, "x", None)]
    events += [{**pose, "device": v} for v in ("", 5, None)]
    events += [{"type": "launch", "device": "x"}, {"device": "x"}, {"type": "tracker"},
               {**pose, "extra": 1}, 5, "x", [], None]
    return events


def test_bad_input_events_from_a_node_are_counted_and_dropped(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    """A joined node sends, in its input messages, every kind of event with each field
    bad: each is counted as malformed and dropped with one message naming the node (told
    once, then counted), none reaches the input state, no traceback, and the good event
    sent after them arrives; the server's world goes on."""

    from services.input.state import InputState
    from services.net import protocol
    from tests.net.net_helpers import free_port, hello, local_server, raw_control

    bad = _bad_node_events()
    port = free_port()
    caplog.set_level(logging.INFO)
    with local_server(port) as server:
        with raw_control(port) as node:
            node.send(hello("eve", server.server.content))
            server.step_until(lambda e: server.server.peers, 10, "eve joining")
            counts = server.server.counts
            before = counts["malformed"]
            for start in range(0, len(bad), 20):  # several messages, as a node sends them
                node.send(protocol.encode({"type": "input", "events": bad[start:start + 20]}))
            node.send(protocol.encode({"type": "input", "events": [
                {"type": "button", "device": "glove", "name": "index", "pressed": True}]}))
            state = server.engine.resource(InputState)
            server.step_until(lambda e: state.buttons.get(("eve/glove", "index")), 10,
                              "eve's good event arriving after the bad ones")
            malformed = counts["malformed"] - before
            oversized = counts["oversized"]  # more events in one message than are taken
            node.send(protocol.encode({"type": "input", "events": [
                {"type": "key", "key": "a", "pressed": i % 2 == 0} for i in range(1001)]}))
            server.step_until(lambda e: counts["oversized"] > oversized, 10,
                              "the long message arriving")
            time_now = server.engine.time
            server.run_for(0.1)
            assert server.engine.time > time_now  # still stepping
        trackers = [state.tracker(name) for name in ("eve/hand_r",)]
    assert malformed == len(bad), (malformed, len(bad))
    assert trackers == [None]  # not one bad pose reached the input state
    assert "eve/stick" not in str(state.axes) and "eve/chair" not in str(state.wheels)
    assert "Traceback" not in caplog.text
    told = [r.getMessage() for r in caplog.records if "input events that are not ones"
            in r.getMessage()]
    assert len(told) == 1 and told[0].startswith("node 'eve' sends")  # then counted
    assert "the first: position and orientation: nan is not finite" in told[0]
    assert any("node 'eve' sent 1001 input events in one message; the first 1000 were "
               "taken" in r.getMessage() for r in caplog.records)


def test_a_time_step_flag_out_of_range_is_a_usage_error(tmp_path: Path, capsys) -> None:
    from app.cli import main

    (tmp_path / "main.scene").write_text('Object { ID "a" }\n')
    assert main(["run", str(tmp_path), "--dt", "10", "--frames", "1", "--headless"]) == 2
    assert "--dt 10: the time step is at most 1 s" in capsys.readouterr().err
    with pytest.raises(SystemExit):  # argparse: --dt must be positive
        main(["run", str(tmp_path), "--dt", "0", "--frames", "1"])


#: Avatar methods (the avatars plugin's): statements on ``a`` with @ for the value.
AVATAR_CALLS: list[tuple[str, str, set[str]]] = [
    ("play fade", 'a:play("Walk", {fade = @})', NUMBERS_BAD | {"negative"}),
    ("play speed", 'a:play("Walk", {speed = @})', NUMBERS_BAD | {"negative"}),
    ("blend", "a:blend{Walk = @}", NUMBERS_BAD | {"negative"}),
    ("setPath", "a:setPath({{@, 0, 0}})", FAR),
    ("driveBone", 'a:driveBone("hand.L", {@, 0, 1}, {1, 0, 0, 0})', FAR),
    ("driveBone turn", 'a:driveBone("hand.L", {0, 0, 1}, {@, @, @, @})',
     NUMBERS_BAD | {"zero"}),
    ("bonePose", "a:bonePose(@)", set(VALUES)),
    ("queue", "a:queue(@)", set(VALUES)),
    ("queue fade", 'a:queue("Walk", {fade = @})', NUMBERS_BAD | {"negative"}),
    ("stopAnimation", "a:stopAnimation{fade = @}", NUMBERS_BAD | {"negative", "1e30"}),
    ("hold", 'a:hold(@, "hand.L")', set(VALUES)),
    ("release", "a:release(@)", set()),
    ("releaseBone", "a:releaseBone(@)", set()),
]


#: Wrong numbers of arguments, and the avatar itself where an object goes.
AVATAR_SHAPES: list[tuple[str, str, bool]] = [
    ("hold itself", 'a:hold(a, "hand.L")', True),
    ("play()", "a:play()", True),
    ("driveBone(bone)", 'a:driveBone("hand.L")', True),
    ("setPath()", "a:setPath()", True),
    ("blend()", "a:blend()", True),
]


def test_bad_values_to_avatar_methods_are_refused_at_the_line(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    (tmp_path / "scripts").mkdir()
    statements = [(f"{name} / {value}", statement.replace("@", f"({expression})"),
                   value in refused)
                  for name, statement, refused in AVATAR_CALLS
                  for value, expression in VALUES.items()] + AVATAR_SHAPES
    (tmp_path / "scripts" / "probe.lua").write_text(
        'local a = find("walker")\nlocal tries = {\n' + "".join(
            f"  function() {s} end,\n" for _, s, _ in statements) +
        "}\nresults = {}\nfunction onStart()\n  for i, f in ipairs(tries) do\n"
        "    local ok, e = pcall(f)\n    results[i] = ok and 'ok' or tostring(e)\n"
        "  end\nend\n")
    model = REPO / "content" / "avatars" / "models" / "walker.glb"
    (tmp_path / "walker.glb").write_bytes(model.read_bytes())
    (tmp_path / "main.scene").write_text(
        'Avatar { ID "walker" Model "walker.glb" Animation "Walk" }\n'
        'Script "scripts/probe.lua"\n')
    spec = load_spec(tmp_path)
    config = EngineConfig(backend="ode", fast=True, content_dir=tmp_path, world=spec.world)
    with Engine(config, plugins=[RegistryPlugin(), load_plugin("physics"),
                                 load_plugin("avatars"), ScriptingPlugin()]) as engine:
        instantiate(engine, spec)
        engine.run(frames=10)
        env = engine.resource(ScriptRuntime).scripts[0].env
        results = [env.results[i + 1] for i in range(len(statements))]
        saved = write_state(engine)
    assert "Traceback" not in caplog.text
    for (case, _, refused), result in zip(statements, results, strict=True):
        if refused:
            assert result != "ok", f"{case}: accepted"
        if refused and case.split(" / ")[0] in ("setPath", "driveBone", "driveBone turn"):
            assert 'for object "walker"' in result, f"{case}: {result}"
        if case == "hold itself":
            assert "avatar 'walker' cannot hold itself" in result, result
    bodies = saved.split("ScriptState")[0]  # (the script's own strings hold "nan")
    assert not re.search(r"\b(nan|inf)\b", bodies, re.IGNORECASE)
