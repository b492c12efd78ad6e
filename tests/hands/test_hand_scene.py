"""Hands in scene files, saved states, scripts, frames, outputs and pictures."""

from __future__ import annotations

import wave
from pathlib import Path

import numpy as np
import pytest
from hand_helpers import Rig, between, waypoints

from components import Transform
from components.hand import HandMode
from engine.scene import SceneError, check, spec_from_text, write_state
from systems.input import Outputs
from systems.sound import SoundSystem

TABLE = ('Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
         '  PhysicalAttributes { Geometry { Primitive "box" Size [1.2 1.2 0.05] } } }\n'
         'Object { ID "cup" Position [0 0 0.8]\n'
         '  PhysicalAttributes { Mass 0.3 Geometry { Primitive "cylinder" Size [0.08 0.1] } } }\n')
HAND = 'Object { ID "hand_r" Position [0 0 0.9] Hand { Tracker "hand_r" Glove "glove_r" } }\n'
GRAB = waypoints((0.0, (0, 0, 0.9)), (0.4, (0, 0, 0.852)), (0.6, (0, 0, 0.852)),
                 (1.4, (0, 0, 1.152)), (3.0, (0.3, 0, 1.0)))


def test_a_hand_naming_a_tracker_the_scene_lacks_is_an_error_with_the_known_names(
        tmp_path: Path):
    scene = ('Input { Tracker { ID "left_glove_sensor" } Tracker { ID "right_glove_sensor" } }\n'
             'Object { ID "h" Hand { Tracker "right_glove_sensr" } }\n')
    with pytest.raises(SceneError) as caught:
        spec_from_text(scene, tmp_path, path="hands.scene")
    (error,) = caught.value.errors
    assert (error.line, error.col) == (2, 32)
    assert "hand 'h': no tracker 'right_glove_sensr' in this scene's Input (known: hand_l, " \
           "hand_r, left_glove_sensor, right_glove_sensor) (did you mean " \
           "'right_glove_sensor'?)" in error.message


def test_an_undeclared_tracker_is_a_warning_and_a_hand_without_a_body_an_error(
        tmp_path: Path):
    (tmp_path / "main.scene").write_text(
        'Object { ID "h" Hand { Tracker "mocap_7" } }\n'
        'Object { ID "ghost" VisualAttributes { Geometry { Primitive "sphere" } }\n'
        '  Hand { Tracker "hand_l" } }\n')
    found = [(d.severity, d.line, d.message.split(";")[0]) for d in check(tmp_path)]
    assert ("warning", 1, "hand 'h': tracker 'mocap_7' is declared nowhere") in found
    assert ("error", 3, "object 'ghost' has a Hand but no PhysicalAttributes: a virtual hand "
            "is a body (leave both Visual- and PhysicalAttributes out for the default hand "
            "box)") in found


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_saved_state_with_a_held_cup_reloads_held_and_continues(tmp_path: Path, backend):
    """Saved at 2 s while carrying the cup: the file says the hand holds it; the reload
    holds it again where it is and carries it on as the uninterrupted run does."""
    def carry(scene: str, seconds: float, start: float = 0.0) -> Rig:
        rig = Rig(scene, tmp_path, backend, paths={"hand_r": lambda t: GRAB(t + start)},
                  gloves={"glove_r": lambda t: t + start >= 0.5})
        rig.run(seconds)
        return rig

    with carry(TABLE + HAND, 3.0) as straight:
        end = straight.position("cup")
    with carry(TABLE + HAND, 2.0) as first:
        saved = write_state(first.engine, tmp_path / "state.scene")
    assert 'Holding ["cup"]' in saved
    with carry(saved, 1.0, start=2.0) as resumed:
        assert resumed.state("hand_r").mode == HandMode.GRASP
        assert np.allclose(resumed.position("cup"), end, atol=1e-4)


def test_scripts_hear_touch_grasp_and_release_and_drive_a_hand(tmp_path: Path):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "cup.lua").write_text(
        'heard = {}\n'
        'local function note(what, hand, object)\n'
        '  heard[#heard + 1] = what .. " " .. hand:getName() .. " " .. object:getName()\n'
        'end\n'
        'function onTouch(h, o) note("touch", h, o) end\n'
        'function onGrasp(h, o) note("grasp", h, o) end\n'
        'function onRelease(h, o) note("release", h, o) end\n'
        'function onUpdate()\n'
        '  local hand = find("hand_r")\n'
        '  state = hand:getHandState()\n'
        '  if time() > 1.0 and not dropped then dropped = true; hand:release() end\n'
        'end\n')
    scene = TABLE.replace('ID "cup"', 'ID "cup" Script "scripts/cup.lua"') + HAND
    with Rig(scene, tmp_path, paths={"hand_r": GRAB},
             gloves={"glove_r": between(0.5)}) as rig:
        rig.run(1.2)
        from engine.scripting.runtime import ScriptRuntime

        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        # (the cup, let go, may touch the hand again as it falls away: a new touch)
        assert list(env.heard.values())[:3] == ["touch hand_r cup", "grasp hand_r cup",
                                                "release hand_r cup"]
        assert env.state in ("neutral", "contact")  # let go by the script


def test_a_hand_tracked_relative_to_a_moving_frame_rides_along(tmp_path: Path):
    """A tracker calibrated to a wheelchair: a still tracker keeps the hand still relative
    to the chair while the chair rolls."""
    scene = ('World { Gravity [0 0 0] }\n'
             'Object { ID "chair" Position [0 0 0.5] Velocity [1 0 0] Kinematic 1\n'
             '  PhysicalAttributes { Geometry { Primitive "box" Size [0.6 0.6 0.1] } } }\n'
             'Object { ID "hand_r" Position [0.2 0.3 1.2]\n'
             '  Hand { Tracker "hand_r" Frame "chair" } }\n')
    with Rig(scene, tmp_path, paths={"hand_r": lambda t: np.array([0.2, 0.3, 0.7])}) as rig:
        rig.run(1.0)
        chair, hand = rig.position("chair"), rig.position("hand_r")
    assert chair[0] == pytest.approx(1.0, abs=1e-6)
    assert np.allclose(hand - chair, (0.2, 0.3, 0.7), atol=2e-3)


def test_a_hand_publishes_its_contact_force_for_a_haptic_glove(tmp_path: Path):
    """Resting on the cup with the drive pressing 1 cm into it: the force the contacts push
    back with is published, and the grasp state."""
    with Rig(TABLE + HAND, tmp_path, paths={"hand_r": GRAB},
             gloves={"glove_r": between(0.5)}) as rig:
        rig.run(0.45)
        outputs = rig.engine.resource(Outputs)
        force = outputs.values["hand:hand_r/force"][0]
        assert force > 0.0 and outputs.values["hand:hand_r/grasp"] == (0.0,)
        rig.run(0.2)
        assert outputs.values["hand:hand_r/grasp"] == (1.0,)
        held = rig.engine.world.component_for_entity(rig.ids["cup"], Transform)
        assert held is not None


def test_a_hand_knocking_a_cup_rings_its_contact_sound(tmp_path: Path):
    """Hand contacts are contacts like any other: a swing into a cup of a material with a
    ContactSound plays it (once or twice: the knock, maybe a rebound), resting does not."""
    with wave.open(str(tmp_path / "knock.wav"), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(22050)
        tone = (np.sin(np.arange(2205) * 2 * np.pi * 900 / 22050) * 2e4).astype("<i2")
        w.writeframes(tone.tobytes())
    scene = ('Material { ID "ceramic" ContactSound "knock.wav" }\n'
             + TABLE.replace('Mass 0.3', 'Mass 0.3 Material "ceramic"')
             + HAND.replace("[0 0 0.9]", "[-0.3 0 0.8]"))
    swing = waypoints((0.0, (-0.3, 0, 0.8)), (0.5, (-0.3, 0, 0.8)), (0.8, (0.0, 0, 0.8)))
    with Rig(scene, tmp_path, paths={"hand_r": swing}) as rig:
        rig.run(0.45)
        sounds = rig.engine.resource(SoundSystem)
        assert sounds.contact_sounds == 0  # the cup at rest on the table is silent
        rig.run(1.0)
        assert 1 <= sounds.contact_sounds <= 3
        assert rig.position("cup")[0] > 0.02  # knocked along
