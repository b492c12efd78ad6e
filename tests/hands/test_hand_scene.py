"""Hands in scene files, saved states, scripts, frames, outputs and pictures."""

from __future__ import annotations

import json
import wave
from pathlib import Path

import numpy as np
import pytest
from hand_helpers import Rig, between, waypoints

from components import Hand, HandState, Name, Physical, Shape, Transform, Visual
from components.hand import HandMode
from engine import Phase
from engine.assets.generated import MARKER_BALL
from engine.scene import SceneError, check, spec_from_text, write_state
from systems.hands import MARKER_SIZE, Hands
from systems.input import Outputs
from systems.sound import SoundSystem
from tests.input.input_helpers import osc_receiver, received

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


def test_a_hand_naming_a_glove_the_scene_lacks_is_an_error_with_the_known_names(
        tmp_path: Path):
    hand = 'Object { ID "h" Hand { Tracker "hand_r" Glove "pinch_glove_l" } }'
    scene = ('Input { Tracker { ID "hand_r" }\n'
             '  Button { ID "pinch" Device "pinch_glove_r" Name "index" } }\n' + hand + '\n')
    with pytest.raises(SceneError) as caught:
        spec_from_text(scene, tmp_path, path="hands.scene")
    (error,) = caught.value.errors
    assert (error.path, error.line, error.col) == ("hands.scene", 3,
                                                   hand.index('"pinch_glove_l"') + 1)
    assert error.head().startswith(f"hands.scene:3:{error.col}: error: hand ")
    assert "hand 'h': no glove 'pinch_glove_l' in this scene's Input (known: glove_l, " \
           "glove_r, pinch_glove_r) (did you mean 'pinch_glove_r'?)" in error.message


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


def test_a_hands_drive_settings_out_of_range_are_errors_at_their_place(tmp_path: Path):
    lines = ['Object { ID "h" Hand { Tracker "hand_r" MaxForce -5 MaxTorque 0 TimeConstant -1',
             '  MaxSpeed 0 MaxSpin -2 DeviationDistance 0 BreakForce -3 } }']
    (tmp_path / "main.scene").write_text("\n".join(lines) + "\n")

    def at(line: int, key: str) -> tuple[int, int]:  # where the key's value is
        return line, lines[line - 1].index(key + " ") + len(key) + 2

    found = {(d.line, d.col, d.message) for d in check(tmp_path) if d.is_error}
    assert found == {
        (*at(1, "MaxForce"), "hand 'h': MaxForce must be >= 0, got -5"),
        (*at(1, "TimeConstant"), "hand 'h': TimeConstant must be >= 0, got -1"),
        (*at(2, "MaxSpeed"), "hand 'h': MaxSpeed must be positive, got 0"),
        (*at(2, "MaxSpin"), "hand 'h': MaxSpin must be positive, got -2"),
        (*at(2, "DeviationDistance"), "hand 'h': DeviationDistance must be positive, got 0"),
        (*at(2, "BreakForce"), "hand 'h': BreakForce must be positive, got -3")}


def test_a_hand_made_in_python_with_a_bad_bound_is_told_and_the_run_goes_on(
        tmp_path: Path, caplog):
    with Rig(TABLE, tmp_path) as rig:
        engine = rig.engine
        bad = engine.spawn(Name("bad hand"), Transform((0.5, 0.0, 1.0)),
                           Physical(mass=0.45, shapes=[Shape("box", (0.09, 0.18, 0.03))],
                                    gravity=False),
                           Hand(tracker="hand_r", max_force=-5.0), HandState())
        rig.run(0.2)
        assert "hand 'bad hand': SetDriveLimits: max_force must be a finite number >= 0, " \
               "got -5.0; it is not driven" in caplog.text
        assert bad not in engine.resource(Hands).rigs
        assert engine.time == pytest.approx(0.2)  # the run went on


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


def test_a_saved_state_keeps_a_hands_mass_and_looks(tmp_path: Path):
    for name in ("relaxed", "open", "fist"):
        (tmp_path / f"{name}.obj").write_text(OBJ)
    scene = TABLE + HAND.replace('Glove "glove_r"', f'Glove "glove_r" Mass 0.6 {LOOKS}')
    with Rig(scene, tmp_path, paths={"hand_r": GRAB}) as first:
        first.run(0.2)
        saved = write_state(first.engine, tmp_path / "state.scene")
    with Rig(saved, tmp_path, paths={"hand_r": GRAB}) as again:
        world, hand = again.engine.world, again.ids["hand_r"]
        assert world.component_for_entity(hand, Physical).mass == 0.6
        looks = world.component_for_entity(hand, Hand)
        assert (looks.neutral_model, looks.contact_model, looks.grasp_model) == (
            "relaxed.obj", "open.obj", "fist.obj")


#: A small tetrahedron: a model file a hand's look can name.
OBJ = "v 0 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
LOOKS = 'NeutralModel "relaxed.obj" ContactModel "open.obj" GraspModel "fist.obj"'


def test_a_hand_is_drawn_with_its_neutral_contact_and_grasp_models(tmp_path: Path):
    for name in ("relaxed", "open", "fist"):
        (tmp_path / f"{name}.obj").write_text(OBJ)
    scene = TABLE + HAND.replace('Glove "glove_r"', f'Glove "glove_r" {LOOKS}')
    drawn: list[tuple[str, str | None]] = []
    with Rig(scene, tmp_path, paths={"hand_r": GRAB},
             gloves={"glove_r": between(0.5, 1.0)}) as rig:
        # the look follows the mode the last step left, written as the frame begins
        rig.every_frame(lambda e, h: drawn.append((rig.state("hand_r").mode,
                                                   rig.visual("hand_r").model)),
                        phase=Phase.PRE_PHYSICS, after=("HandDriveSystem",))
        rig.run(1.4)
    models = {HandMode.NEUTRAL: "relaxed.obj", HandMode.CONTACT: "open.obj",
              HandMode.GRASP: "fist.obj"}
    assert {mode for mode, _ in drawn} == set(models)  # every mode was shown
    assert all(model == models[mode] for mode, model in drawn)


def test_a_hands_mass_is_its_bodys_and_given_once(tmp_path: Path):
    spec = spec_from_text(HAND.replace('Glove "glove_r"', 'Mass 0.6'), tmp_path)
    (hand,) = spec.entities
    assert next(c for c in hand.components if isinstance(c, Physical)).mass == 0.6
    line = ('Object { ID "h" PhysicalAttributes { Mass 0.5 } Hand { Tracker "hand_r" '
            'Mass 0.6 } }')
    with pytest.raises(SceneError) as caught:
        spec_from_text(line + "\n", tmp_path, path="hands.scene")
    (error,) = caught.value.errors
    assert (error.line, error.col) == (1, line.index("Mass 0.6") + len("Mass ") + 1)
    assert error.message == ("hand 'h': Mass 0.6 kg here and Mass 0.5 in its "
                             "PhysicalAttributes: give the hand's weight once")
    with pytest.raises(SceneError, match=r"Mass must be positive, got -1"):
        spec_from_text(HAND.replace('Glove "glove_r"', 'Mass -1'), tmp_path)


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
        from services.scripting.runtime import ScriptRuntime

        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        # (the cup, let go, may touch the hand again as it falls away: a new touch)
        assert list(env.heard.values())[:3] == ["touch hand_r cup", "grasp hand_r cup",
                                                "release hand_r cup"]
        assert env.state in ("neutral", "contact")  # let go by the script


def test_a_script_grasps_what_a_hand_touches_and_is_told_what_it_cannot(tmp_path: Path):
    """No glove: onTouch grasps the cup from Lua (hand:grasp), getHeld names it at once,
    the hand lifts it; grasping the static table is refused with the reason."""
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "cup.lua").write_text(
        'function onTouch(hand, object)\n'
        '  hand:grasp(object)\n'
        '  held = hand:getHeld()[1]:getName()\n'
        '  field_held, field_state = hand.held[1]:getName(), hand.state\n'
        '  not_a_hand = select(2, pcall(function() return object.state end))\n'
        '  ok, why = pcall(function() hand:grasp(find("table")) end)\n'
        'end\n')
    scene = TABLE.replace('ID "cup"', 'ID "cup" Script "scripts/cup.lua"') + HAND
    with Rig(scene, tmp_path, paths={"hand_r": GRAB}) as rig:
        rig.run(1.4)
        from services.scripting.runtime import ScriptRuntime

        env = rig.engine.resource(ScriptRuntime).scripts[0].env
        assert env.held == "cup" and env.ok is False
        # the same as fields read: hand.held, hand.state; a non-hand has none
        assert (env.field_held, env.field_state) == ("cup", "grasp")
        assert "getHandState" in str(env.not_a_hand)
        assert "grasp: object 'table' is not a dynamic body; a hand holds only what can " \
               "move" in str(env.why)
        assert rig.state("hand_r").mode == HandMode.GRASP
        # lifted with the hand: 0.3 m up from the table, 0.065 m under the hand's centre
        assert rig.position("cup")[2] == pytest.approx(rig.position("hand_r")[2] - 0.065,
                                                       abs=5e-3)
        assert rig.position("cup")[2] > 0.8 + 0.25


def test_an_object_that_is_not_graspable_is_neither_pinched_nor_grasped_from_lua(
        tmp_path: Path, caplog):
    """``Graspable 0``: touching the cup does not open the hand, the pinch holds nothing
    (the hand rises without it), and Lua's hand:grasp(cup) is refused at its line."""
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "cup.lua").write_text(
        'function onUpdate()\n'
        '  if time() > 0.45 and not tried then tried = true\n'
        '    find("hand_r"):grasp(find("cup"))\n'
        '  end\n'
        'end\n')
    scene = TABLE.replace('ID "cup"', 'ID "cup" Graspable 0 Script "scripts/cup.lua"') + HAND
    modes = []
    with Rig(scene, tmp_path, paths={"hand_r": GRAB},
             gloves={"glove_r": between(0.5)}) as rig:
        rig.every_frame(lambda e, h: modes.append(rig.state("hand_r").mode),
                        after=("HandContactSystem",))
        rig.run(1.4)
        assert rig.state("hand_r").held == ()
        cup, hand = rig.position("cup"), rig.position("hand_r")
    assert set(modes) == {HandMode.NEUTRAL}
    assert cup[2] == pytest.approx(0.8, abs=2e-3) and hand[2] > 1.0  # left on the table
    refused = [r.getMessage() for r in caplog.records if "not graspable" in r.getMessage()]
    assert len(refused) == 1 and "scripts/cup.lua:3:" in refused[0]
    assert "grasp: object 'cup' is not graspable (its scene says Graspable 0)" in refused[0]


@pytest.mark.parametrize("marker", [1, 0])
def test_the_marker_is_a_textured_ball_where_the_real_hand_is(tmp_path: Path, marker):
    """Figure 7: pushed into the table the hand stops on it, the marker goes on to where
    the tracker is; ``Marker 0`` draws none."""
    scene = TABLE + HAND.replace('Glove "glove_r"', f'Marker {marker}')
    down = waypoints((0.0, (0.3, 0, 0.9)), (0.5, (0.3, 0, 0.70)))
    with Rig(scene.replace("[0 0 0.9]", "[0.3 0 0.9]"), tmp_path,
             paths={"hand_r": down}) as rig:
        rig.run(0.6)
        world = rig.engine.world
        control = rig.engine.resource(Hands).rigs[rig.ids["hand_r"]].control
        ball = world.try_component(control, Visual)
        where = world.component_for_entity(control, Transform).position
        assert np.allclose(where, (0.3, 0, 0.70), atol=1e-9)
        assert rig.position("hand_r")[2] > 0.75 + 0.015 - 2e-3  # on the table top
    if marker:
        assert (ball.texture, ball.shapes[0].kind) == (MARKER_BALL, "sphere")
        assert ball.shapes[0].size == (MARKER_SIZE / 2,)
    else:
        assert ball is None


def test_a_scene_may_name_the_marker_texture_and_a_saved_state_keeps_it(tmp_path: Path):
    """A network server writes the objects it spawned, the markers among them, into the
    state its nodes load: the made texture is no file to look for, nor to rebase."""
    ball = ('Object { ID "ball" Position [0 0 1] VisualAttributes { Texture '
            f'"{MARKER_BALL}" Geometry {{ Primitive "sphere" }} }} }}\n')
    (tmp_path / "main.scene").write_text(ball)
    assert [d.message for d in check(tmp_path)] == []
    with Rig(ball + HAND, tmp_path, paths={"hand_r": GRAB}) as rig:
        rig.run(0.1)
        saved = write_state(rig.engine, tmp_path / "states" / "s.scene")
    assert f'Texture "{MARKER_BALL}"' in saved


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
    back with is published, and the grasp state, to the Output that names them (over OSC
    here, as a glove's driver would receive them); a value no Output names is not made."""
    with osc_receiver() as sock:
        output = (f'Output {{ Kind "osc" Port {sock.getsockname()[1]} Markers 0\n'
                  '  Value "hand:hand_r/force" Value "hand:hand_r/grasp" }\n')
        with Rig(TABLE + HAND + output, tmp_path, paths={"hand_r": GRAB},
                 gloves={"glove_r": between(0.5)}) as rig:
            rig.run(0.45)
            outputs = rig.engine.resource(Outputs)
            force = outputs.values["hand:hand_r/force"][0]
            assert force > 0.0 and outputs.values["hand:hand_r/grasp"] == (0.0,)
            sent = received(sock)
            assert sent[-2:] == [("/colosseum/out/hand/hand_r/force", [pytest.approx(force)]),
                                 ("/colosseum/out/hand/hand_r/grasp", [0.0])]
            rig.run(0.2)
            assert outputs.values["hand:hand_r/grasp"] == (1.0,)
            assert received(sock)[-1] == ("/colosseum/out/hand/hand_r/grasp", [1.0])
    with Rig(TABLE + HAND, tmp_path, paths={"hand_r": GRAB}) as rig:
        rig.run(0.45)
        assert not [name for name in rig.engine.resource(Outputs).values
                    if name.startswith("hand:")]


@pytest.mark.parametrize("logged", [False, True], ids=["no session", "session logged"])
def test_grasps_and_releases_go_out_as_markers_once_with_or_without_a_session(
        tmp_path: Path, logged):
    """The issue's outlet for the engine's markers: a grasp and a release reach an Output
    stream whether or not a session log runs (which logs them too, and does not send
    them a second time)."""
    with osc_receiver() as sock:
        scene = TABLE + HAND + f'Output {{ Kind "osc" Port {sock.getsockname()[1]} }}\n'
        options = {}
        if logged:
            scene += 'Session { Name "grasps" Ground ["table"] }\n'
            options = {"sessions": tmp_path / "logs"}
        content = tmp_path / "content"
        content.mkdir()
        with Rig(scene, content, paths={"hand_r": GRAB}, gloves={"glove_r": between(0.5, 1.0)},
                 options=options) as rig:
            rig.run(1.3)
        markers = [args for address, args in received(sock) if address == "/colosseum/marker"]
    assert markers == [["grasp hand_r cup"], ["release hand_r cup"]]
    if logged:
        (log,) = (tmp_path / "logs").glob("*.jsonl")
        kinds = [json.loads(line)["kind"] for line in log.read_text().splitlines()]
        assert [k for k in kinds if k in ("grasp", "release")] == ["grasp", "release"]


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
