"""Lua reads a hand's tracked joints and curls, and hears which fingers hold what it grasps."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from hand_helpers import Rig

from components import HandState
from engine import Phase, system
from engine.events import HandGrasped, HandReleased
from engine.rotation import euler_to_quat, quat_multiply, quat_to_matrix
from services.input.events import HAND_JOINTS
from services.input.hand_pose import GESTURES, pose_hand
from services.input.hand_query import joint, tracked_hand
from services.input.state import InputState
from services.scripting.runtime import ScriptRuntime

WRIST = (0.1, -0.2, 1.0)
TURN = euler_to_quat((0.0, 0.0, 40.0))
READER = """
function onUpdate()
  local hand = find("hand_r")
  tip = {hand:joint("index_tip")}
  palm = {hand:joint("palm")}
  curls = {}
  for _, f in ipairs({"thumb", "index", "middle", "ring", "little"}) do
    curls[f] = hand:curl(f)
  end
  ok_joint, bad_joint = pcall(function() return hand:joint("index_tp") end)
  ok_curl, bad_curl = pcall(function() return hand:curl("pinky") end)
  ok_table, not_hand = pcall(function() return find("table"):curl("index") end)
end
"""
SCENE = ('Object { ID "table" Position [0 0 0.5] Dynamic 0\n'
         '  PhysicalAttributes { Geometry { Primitive "box" Size [1 1 0.05] } } }\n'
         'Object { ID "hand_r" Position [0.1 -0.2 1.0] Hand { Tracker "hand_r" } }\n'
         'Script "scripts/reader.lua"\n')


def _feed(rig: Rig, curls: dict[str, float]) -> None:
    """Every frame, the input hand ``hand_r`` as a tracker would send it (injected)."""
    @system(Phase.INPUT, before=("InputSystem",))
    def joints(engine, dt):
        rig.hub.inject(pose_hand("hand_r", WRIST, TURN, curls, timestamp=engine.time))

    rig.engine.add_system(joints)


def _scripts(folder: Path, text: str) -> None:
    (folder / "scripts").mkdir(exist_ok=True)
    (folder / "scripts" / "reader.lua").write_text(text)


def test_lua_reads_tracked_joints_and_curls_and_is_told_a_wrong_name(tmp_path: Path):
    """hand:joint gives the tracked joint (position, orientation, radius, valid) as the
    input layer has it; hand:curl the finger's curl read back from the joints; a wrong
    joint or finger name fails at the script's line with the nearest name."""
    _scripts(tmp_path, READER)
    with Rig(SCENE, tmp_path, paths={"hand_r": lambda t: np.array(WRIST)}) as rig:
        _feed(rig, GESTURES["point"])
        rig.run(0.1)
        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        tip, palm = list(env.tip.values()), list(env.palm.values())
        want = pose_hand("hand_r", WRIST, TURN, GESTURES["point"])
        i = HAND_JOINTS.index("index_tip")
        np.testing.assert_allclose(tip[:3], want.positions[i], atol=1e-12)
        np.testing.assert_allclose(tip[3:7], want.orientations[i], atol=1e-12)
        assert tip[7:] == [pytest.approx(want.radii[i]), True]
        np.testing.assert_allclose(palm[:3], want.positions[0], atol=1e-12)
        assert dict(env.curls) == pytest.approx(GESTURES["point"], abs=2e-3)
        assert (env.ok_joint, env.ok_curl, env.ok_table) == (False, False, False)
        assert str(env.bad_joint) == ("joint (object \"hand_r\"): no hand joint "
                                      "'index_tp'; did you mean 'index_tip'?")
        assert str(env.bad_curl) == ("curl (object \"hand_r\"): no hand finger 'pinky' "
                                     "(known: thumb, index, middle, ring, little)")
        assert str(env.not_hand) == "curl: object \"table\" is not a hand"


def test_a_wrong_joint_name_is_told_at_the_scripts_line(tmp_path: Path):
    _scripts(tmp_path, 'function onUpdate()\n  local x = find("hand_r"):joint("thumb_tipp")\n'
                       'end\n')
    with Rig(SCENE, tmp_path, paths={"hand_r": lambda t: np.array(WRIST)}) as rig:
        rig.run(0.02)
        messages = rig.engine.resource(ScriptRuntime).messages
    assert messages[0].startswith("scripts/reader.lua:2: joint (object \"hand_r\"): no "
                                  "hand joint 'thumb_tipp'; did you mean 'thumb_tip'?")


def test_before_its_hand_is_seen_a_joint_is_nil(tmp_path: Path):
    _scripts(tmp_path, 'function onUpdate() seen = find("hand_r"):joint("wrist") == nil\n'
                       '  bent = find("hand_r"):curl("index") end\n')
    with Rig(SCENE, tmp_path) as rig:
        rig.run(0.05)
        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        assert env.seen is True and env.bent is None


def test_a_hand_tracked_relative_to_a_frame_gives_its_joints_in_the_world(tmp_path: Path):
    """``Hand { Frame "chair" }``: the joints are the input hand's carried by the chair's
    pose (Lua and the Python accessor agree)."""
    _scripts(tmp_path, READER)
    scene = SCENE.replace('Hand { Tracker "hand_r" }', 'Hand { Tracker "hand_r" Frame "chair" }')
    scene += ('Object { ID "chair" Position [1 2 0.3] Orientation [0 0 90] Kinematic 1\n'
              '  PhysicalAttributes { Geometry { Primitive "box" Size [0.6 0.6 0.1] } } }\n')
    with Rig(scene, tmp_path, paths={"hand_r": lambda t: np.array(WRIST)}) as rig:
        _feed(rig, GESTURES["fist"])
        rig.run(0.1)
        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        chair = quat_to_matrix(np.array(euler_to_quat((0.0, 0.0, 90.0))))
        local = pose_hand("hand_r", WRIST, TURN, GESTURES["fist"])
        i = HAND_JOINTS.index("index_tip")
        world = chair @ np.array(local.positions[i]) + (1.0, 2.0, 0.3)
        np.testing.assert_allclose(list(env.tip.values())[:3], world, atol=1e-9)
        q = quat_multiply(np.array(euler_to_quat((0.0, 0.0, 90.0))),
                          np.array(local.orientations[i]))
        got = np.array(list(env.tip.values())[3:7])
        assert abs(got @ q) == pytest.approx(1.0, abs=1e-9)  # the same rotation
        joints = tracked_hand(rig.engine.world, rig.ids["hand_r"],
                              rig.engine.resource(InputState))
        assert joints is not None
        np.testing.assert_allclose(joint(joints, "index_tip").position, world, atol=1e-9)
        assert dict(env.curls) == pytest.approx(GESTURES["fist"], abs=2e-3)


GRIP = """
heard = {}
local function note(what, hand, object, fingers)
  heard[#heard + 1] = what .. " " .. object:getName() .. " " .. table.concat(fingers, ",")
end
function onGrasp(h, o, fingers) note("grasp", h, o, fingers); during = h.grip end
function onRelease(h, o, fingers) note("release", h, o, fingers) end
"""


def test_grasp_and_release_name_the_fingers_that_hold(tmp_path: Path):
    """onGrasp hears the hand's grip (HandState.grip) as its third argument, and hand.grip
    reads it; onRelease names the fingers that held, though the grip has opened by
    then. (The grip and the events are fed here as the fingered hand's physics makes
    them.)"""
    _scripts(tmp_path, GRIP)
    with Rig(SCENE, tmp_path) as rig:
        hand, table = rig.ids["hand_r"], rig.ids["table"]

        @system(Phase.SCRIPT, before=("ScriptingSystem",), reads=(HandState,),
                writes=(HandState,))
        def grips(engine, dt):
            state = engine.world.component_for_entity(hand, HandState)
            if engine.frame == 3:
                state.grip = ("thumb", "index", "palm")
                engine.events.emit(HandGrasped(hand, table))
            elif engine.frame == 6:
                state.grip = ()
                engine.events.emit(HandReleased(hand, table))

        rig.engine.add_system(grips)
        rig.engine.run(frames=8)
        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        assert list(env.heard.values()) == ["grasp table thumb,index,palm",
                                            "release table thumb,index,palm"]
        assert list(env.during.values()) == ["thumb", "index", "palm"]


def test_the_desktop_keys_shape_the_hand_a_script_reads(tmp_path: Path):
    """No hardware: the desktop device's mouse places the hand, V makes a fist, and the
    hand's script reads the fist's curls and its index tip in the world."""
    from services.input.desktop import WindowDevice

    _scripts(tmp_path, READER)
    scene = ('Camera { Position [0 -1 1.2] LookAt [0 0 1.0] }\n'
             'Input { Device { Kind "desktop" } }\n' + SCENE)
    with Rig(scene, tmp_path) as rig:
        window = rig.engine.resource(WindowDevice)
        window.pointer(0.5, 0.5)
        window.key("v", True)
        rig.run(0.3)
        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        assert dict(env.curls) == pytest.approx(GESTURES["fist"], abs=2e-3)
        joints = rig.engine.resource(InputState).hand("hand_r")
        assert joints is not None
        np.testing.assert_allclose(list(env.tip.values())[:3],
                                   joints.positions[HAND_JOINTS.index("index_tip")], atol=1e-12)
