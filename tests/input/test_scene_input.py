"""The Input and Output scene keys: read into specs, mistakes reported at their line."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from app.cli import main
from engine.scene import SceneError, spec_from_text
from engine.scene.inputs import IDENTITY_AXES
from services.input.config import parse_input_option


def test_input_blocks_become_specs(tmp_path: Path):
    spec = spec_from_text("""
Input {
  LostAfter 0.25
  Device { ID "mocap" Kind "osc" Port 9100 Address "0.0.0.0" Timeout 1 }
  Device { Kind "serial" Path "/dev/ttyUSB0" Line "W {name} {count}" }
  Tracker { ID "hand_r" Device "mocap" Offset [0 0 1] Rotation [0 0 90] Scale 0.001
            Axes "x -z y" Filter "oneeuro" MinCutoff 0.5 Beta 4 Predict 15 }
  Wheel { ID "left" CountsPerTurn 2048 Wrap 65536 Invert 1 }
  Button { ID "grab" Device "glove_r" Name "index" Invert 1 }
}
Output { Kind "osc" Port 9200 Value "wheel:left" Value "position:hand" Markers 0 }
""", tmp_path).input
    assert spec.lost_after == 0.25
    mocap, serial = spec.devices
    assert (mocap.id, mocap.port, mocap.address, mocap.timeout) == ("mocap", 9100, "0.0.0.0", 1.0)
    assert (serial.id, serial.path, serial.line) == ("serial", "/dev/ttyUSB0", "W {name} {count}")
    hand = spec.trackers[0]
    assert hand.axes != IDENTITY_AXES and hand.predict == pytest.approx(0.015)
    assert (hand.scale, hand.filter, hand.min_cutoff, hand.beta) == (0.001, "oneeuro", 0.5, 4.0)
    assert spec.wheels[0].wrap == 65536 and spec.wheels[0].invert
    assert spec.buttons[0].id == "grab" and spec.buttons[0].invert
    assert spec.outputs[0].values == ("wheel:left", "position:hand")
    assert not spec.outputs[0].markers


@pytest.mark.parametrize(("text", "message"), [
    ('Input { Device { Kind "osc" } Tracker { ID "h" Device "osk" } }',
     "unknown input device 'osk' (did you mean 'osc'?"),
    ('Input { Device { Kind "osc" } Device { Kind "osc" Port 9001 } }',
     "duplicate input device 'osc'"),
    ('Input { Device { Kind "usb" } }', 'unknown Kind "usb"'),
    ('Input { Device { Kind "serial" } }', "a serial Device needs a Path"),
    ('Input { Device { Kind "serial" Path "/dev/x" Line "{name} {speed}" } }',
     "unknown field {speed} in Line"),
    ('Input { Tracker { ID "h" Axes "x y y" } }', "names a device axis twice"),
    ('Input { Tracker { ID "h" Predict -5 } }', "Predict must not be negative"),
    ('Input { Tracker { ID "h" Filter "kalman" } }', 'unknown Filter "kalman"'),
    ('Input { Wheel { ID "w" CountsPerTurn 0 } }', "CountsPerTurn must be at least 1"),
    ('Input { Device { Kind "osc" Port 70000 } }', "Port must be 0..65535"),
    ('Input { Trackr { ID "h" } }', "unknown key 'Trackr' in Input (did you mean 'Tracker'?"),
    ('Input { Tracker { ID "h" Object "nobody" } }', "unknown Object 'nobody'"),
    ('Input { Tracker { ID "h" Camera "eye" } }', "unknown Camera 'eye'"),
    ('Input { Tracker { ID "h" Object "o" Camera "c" } }\nObject { ID "o" }\nCamera { ID "c" }',
     "moves one Object or one Camera, not both"),
])
def test_mistakes_are_reported_at_their_line(tmp_path: Path, text: str, message: str):
    with pytest.raises(SceneError) as caught:
        spec_from_text("\n" + text, tmp_path)
    rendered = caught.value.render()
    assert message in rendered
    assert ":2:" in rendered  # the line of the mistake, not just the file


def test_the_command_line_adds_devices_and_refuses_bad_ones(tmp_path: Path, capsys):
    assert parse_input_option("osc:0.0.0.0:9001").address == "0.0.0.0"
    assert parse_input_option("lsl:hand,type:Wheel").streams == ("hand", "type:Wheel")
    assert parse_input_option("desktop").kind == "desktop"
    for bad in ("osc:none", "osc:99999", "serial:", "lsl:", "desktop:1", "usb:1"):
        with pytest.raises(ValueError, match="--input"):
            parse_input_option(bad)
    with pytest.raises(SystemExit) as exited:
        main(["run", "--input", "osc:port", "--frames", "1"])
    assert exited.value.code == 2
    assert "argument --input: bad --input 'osc:port'" in capsys.readouterr().err


def test_input_devices_from_the_command_line_are_opened(tmp_path: Path):
    content = tmp_path / "content"
    content.mkdir()
    (content / "main.scene").write_text('Input { Device { Kind "osc" Port 0 } }\n')
    stats = tmp_path / "stats.json"
    code = main(["run", str(content), "--headless", "--frames", "3", "--fast",
                 "--input", "osc:127.0.0.1:0", "--input", "desktop", "--stats", str(stats)])
    assert code == 0
    devices = json.loads(stats.read_text())["input"]["devices"]
    # the command line's osc replaces the scene's (same ID); desktop is added; only devices
    # that opened are listed, and --stats is written after the run closed them
    assert [(d["name"], d["kind"], d["state"]) for d in devices] == [
        ("osc", "osc", "closed"), ("desktop", "desktop", "closed")]


def test_several_input_blocks_are_one_setup_told_at_file_line_with_did_you_mean(
        tmp_path: Path):
    """The Input blocks' finish step reads every block: a tracker may name a device
    another Input block declares, a second device of one ID is told wherever it stands,
    and a hand naming a tracker no block declares is told at its own line; each with
    file:line:col and a did-you-mean."""
    from engine.scene import check

    good = spec_from_text('Input { LostAfter 2 Device { ID "mocap" Kind "osc" } }\n'
                          'Input { Tracker { ID "hand_x" Device "mocap" } }\n'
                          'Output { Value "a" }\nOutput { Value "b" Value "c" }\n',
                          tmp_path).input
    assert [d.id for d in good.devices] == ["mocap"] and good.trackers[0].device == "mocap"
    assert good.lost_after == 0.5  # the last Input block's (its default)
    assert [o.values for o in good.outputs] == [("a",), ("b", "c")]
    scene = tmp_path / "main.scene"
    scene.write_text('Input { Device { ID "mocap" Kind "osc" } }\n'
                     'Input { Tracker { ID "hand_x" Device "mocapp" } }\n'
                     'Input { Device { ID "mocap" Kind "osc" Port 9001 } }\n'
                     'Object { ID "h" Hand { Tracker "hand_y" } }\n')
    told = [(d.line, d.col, d.severity, d.message) for d in check(scene)
            if d.path == str(scene)]
    assert told == [
        (2, 38, "error", "unknown input device 'mocapp' (did you mean 'mocap'?) "
                         "(declared: mocap)"),
        (3, 16, "error", f"duplicate input device 'mocap' (first declared at {scene}:1:16)"),
        (4, 32, "error", "hand 'h': no tracker 'hand_y' in this scene's Input (known: "
                         "hand_l, hand_r, hand_x) (did you mean 'hand_x'?)")]


def test_the_blocks_inside_input_are_documented_by_the_key_they_are_written_as():
    from engine.scene import keys

    assert keys.find_block("Tracker") == "InputTracker"
    text = keys.block_text(keys.find_block("Device") or "")
    assert text.startswith("InputDevice  (inside Input as Device: a device to open)")
    assert "Kind" in text and "required" in text
