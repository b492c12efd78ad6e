"""Anomalies in a running engine: declared in the scene, switched by keys, any input binding
and Lua, each switch an AnomalySwitched event and a marker on the Output stream (OSC to a
loopback receiver); severities out of range clamped, said at the scene line or the Lua
call, and the run goes on."""

from __future__ import annotations

import logging
import socket
import time
from pathlib import Path

import numpy as np
import pytest
from pythonosc.osc_packet import OscPacket

from engine.anomalies import Anomalies
from engine.app import EngineConfig
from engine.events import AnomalySwitched
from engine.scene import instantiate, spec_from_text
from services.input import Button, InputHub, Key
from systems import create_engine
from systems.render import RenderSystem

SCRIPT = """
function onUpdate(dt)
  if time() > 0.145 and not done then
    done = true
    setAnomaly("contrast_loss", true, {loss = 1.7, onset = 0})
  end
end
"""


def markers(sock: socket.socket) -> list[str]:
    """The marker texts that reached ``sock`` (waiting at most a second for the first)."""
    out = []
    deadline = time.monotonic() + 1.0
    while time.monotonic() < deadline:
        try:
            data = sock.recv(65536)
        except TimeoutError:
            if out:
                return out
            continue
        out += [m.message.params[0] for m in OscPacket(data).messages
                if m.message.address == "/colosseum/marker"]
    return out


def test_scene_keys_inputs_and_lua_switch_anomalies_and_every_switch_is_told(
        tmp_path: Path, caplog):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as receiver:
        receiver.bind(("127.0.0.1", 0))
        receiver.settimeout(0.01)
        switches_told(tmp_path, receiver, caplog)


def switches_told(tmp_path: Path, receiver: socket.socket, caplog) -> None:
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "switch.lua").write_text(SCRIPT)
    port = receiver.getsockname()[1]
    scene = f"""
Camera {{ Position [0 -5 1] LookAt [0 0 1] }}
Object {{ ID "ball" Position [0 0 1] Dynamic 0 VisualAttributes {{ Color [1 1 1]
  Geometry {{ Primitive "sphere" Size [0.5] }} }} }}
Hemianopia {{ Side "left" Enabled 0 Onset 0 Input "key:number_1" }}
DoubleVision {{ ID "ghost" Offset [3 0] Eye "right" }}
Blur {{ Enabled 0 Onset 0.05 Input "key:b/n" }}
Neglect {{ Enabled 0 Input "button:glove_r/thumb" }}
Output {{ Kind "osc" Port {port} }}
Script "scripts/switch.lua"
"""
    config = EngineConfig(backend="ballistic", fast=True, dt=0.01, headless=True,
                          render=True, content_dir=tmp_path, options={"size": "96x72"})
    told: list[AnomalySwitched] = []
    with caplog.at_level(logging.WARNING), create_engine(config) as engine:
        instantiate(engine, spec_from_text(scene, tmp_path))
        engine.events.subscribe(AnomalySwitched, told.append)
        engine.start()
        hub, anomalies = engine.resource(InputHub), engine.resource(Anomalies)

        def press(event_down, event_up) -> None:
            hub.inject(event_down)
            engine.run(frames=1)
            hub.inject(event_up)
            engine.run(frames=1)

        engine.run(frames=2)
        assert [a.id for a in engine.resource(RenderSystem).renderer.anomalies] == ["ghost"]
        press(Key("number_1", True), Key("number_1", False))  # toggles on
        assert anomalies.get("hemianopia").enabled and anomalies.get("hemianopia").level == 1
        press(Key("b", True), Key("b", False))  # key:b/n: b switches on
        press(Key("b", True), Key("b", False))  # ... and stays on
        assert anomalies.get("blur").enabled
        press(Key("n", True), Key("n", False))  # n switches off
        press(Button("glove_r", "thumb", True), Button("glove_r", "thumb", False))
        press(Key("number_1", True), Key("number_1", False))  # toggles off
        engine.run(frames=4)  # the script's call falls in here
        drawn = engine.resource(RenderSystem).renderer.anomalies
    switches = [(e.anomaly, e.enabled, e.source) for e in told]
    assert switches == [
        ("ghost", True, "scene"),
        ("hemianopia", True, "input:key:number_1"),
        ("blur", True, "input:key:b/n"),
        ("blur", False, "input:key:b/n"),
        ("neglect", True, "input:button:glove_r/thumb"),
        ("hemianopia", False, "input:key:number_1"),
        ("contrast_loss", True, "lua:scripts/switch.lua:5"),
    ]
    contrast = told[-1]
    assert dict(contrast.severity)["Loss"] == 1.0 and contrast.onset == 0.0
    assert any("scripts/switch.lua:5: setAnomaly('contrast_loss'): contrast_loss Loss 1.7 is "
               "out of range (0 to 1); clamped to 1" in r.getMessage() for r in caplog.records)
    assert {a.id for a in drawn} == {"ghost", "neglect", "contrast_loss"}  # the run went on
    sent = markers(receiver)
    assert "anomaly hemianopia on hemianopia Side=left Sparing=0 Border=1 Depth=1 Fill=0,0,0 " \
           "onset=0 source=input:key:number_1" in sent
    assert len([m for m in sent if m.startswith("anomaly ")]) == len(told)


def test_a_scene_severity_out_of_range_is_clamped_with_a_warning_at_its_line(tmp_path):
    scene = 'Camera { Position [0 -5 1] LookAt [0 0 1] }\n' \
            'Neglect { Side "right"\n  Depth 3 Width -5 }\n'
    spec = spec_from_text(scene, tmp_path)
    told = [(d.line, d.col, d.message) for d in spec.problems]
    assert (3, 9, "neglect Depth 3 is out of range (0 to 1); clamped to 1") in told
    assert (3, 17, "neglect Width -5 is out of range (0 to 90 deg); clamped to 0") in told
    (anomaly,) = spec.anomalies
    assert anomaly.values["Depth"] == 1.0 and anomaly.values["Side"] == "right"


def test_a_bad_input_binding_is_told_with_its_line_and_the_anomaly_still_works(
        tmp_path, caplog):
    scene = 'Hemianopia { Enabled 0\n  Input "tracker:head" }\n'
    config = EngineConfig(backend="ballistic", fast=True, headless=True, content_dir=tmp_path)
    with caplog.at_level(logging.ERROR), create_engine(config) as engine:
        instantiate(engine, spec_from_text(scene, tmp_path))
        engine.run(frames=1)
        engine.resource(Anomalies).switch("hemianopia", True, "python")
        engine.run(frames=300)  # the default onset, 2 s
        assert engine.resource(Anomalies).get("hemianopia").level == 1.0
    assert any(":2: anomaly 'hemianopia': Input a tracker cannot switch an anomaly" in
               r.getMessage() for r in caplog.records)


def test_stereo_sbs_from_the_command_line_options(tmp_path):
    scene = 'Camera { Position [0 -5 1] LookAt [0 0 1] }\n' \
            'Object { Position [0 0 1] Dynamic 0 VisualAttributes { Color [1 1 1] ' \
            'Geometry { Primitive "sphere" Size [0.3] } } }\n'
    images = {}
    for stereo in (None, "sbs"):
        config = EngineConfig(backend="ballistic", fast=True, headless=True, render=True,
                              content_dir=tmp_path, options={"size": "128x64",
                                                             "stereo": stereo})
        with create_engine(config) as engine:
            instantiate(engine, spec_from_text(scene, tmp_path))
            engine.run(frames=1)
            renderer = engine.resource(RenderSystem).renderer
            images[stereo] = renderer.read_pixels().astype(float).mean(axis=2)
            eyes = renderer.camera.eyes(128, 64)
            assert len(eyes) == (2 if stereo else 1)
    bright = images["sbs"] > 100
    assert bright[:, :64].any() and bright[:, 64:].any()  # the ball in each eye
    assert np.nonzero(images[None] > 100)[1].mean() == pytest.approx(64, abs=1)


GAIN = """#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
uniform float u_gain;
out vec4 f_color;
void main() { f_color = vec4(texture(u_scene, v_uv).rgb * u_gain, 1.0); }
"""

READER = """
function onStart()
  setAnomaly("hemianopia", nil, {side = "right", sparing = 4})
  local a = getAnomaly("hemianopia")
  log(a.kind, a.side, a.sparing, tostring(a.enabled), a.onset)
  enablePost("dim", true)
  setPostUniform("dim", "u_gain", 0.5)
end
function onUpdate(dt)
  setAnomaly("hemianopa", true)
end
"""


def test_lua_reads_anomalies_and_drives_the_scene_post_passes(tmp_path, caplog):
    (tmp_path / "scripts").mkdir()
    (tmp_path / "scripts" / "reader.lua").write_text(READER)
    (tmp_path / "gain.frag").write_text(GAIN)
    scene = """
Camera { Position [0 -5 1] LookAt [0 0 1] }
Object { Position [0 0 1] Dynamic 0 VisualAttributes { Color [1 1 1]
  Geometry { Primitive "box" Size [2 2 2] } } }
PostPass { ID "dim" File "gain.frag" Enabled 0 Uniform { ID "u_gain" Value 1 } }
Script "scripts/reader.lua"
"""
    config = EngineConfig(backend="ballistic", fast=True, headless=True, render=True,
                          content_dir=tmp_path, options={"size": "64x48"})
    with caplog.at_level(logging.INFO), create_engine(config) as engine:
        instantiate(engine, spec_from_text(scene, tmp_path))
        engine.run(frames=1)
        dimmed = engine.resource(RenderSystem).renderer.read_pixels()[24, 32].astype(float)
        engine.resource(RenderSystem).enable_post("dim", False)
        engine.run(frames=1)
        full = engine.resource(RenderSystem).renderer.read_pixels()[24, 32].astype(float)
        state = engine.resource(Anomalies).get("hemianopia")
    assert dimmed == pytest.approx(full * 0.5, abs=2) and full.min() > 100
    assert any("hemianopia\tright\t4.0\tfalse\t2.0" in r.getMessage() for r in caplog.records)
    assert state.values["Side"] == "right" and not state.enabled
    assert any("reader.lua:10:" in r.getMessage() and "no anomaly 'hemianopa'; did you mean "
               "'hemianopia'?" in r.getMessage() for r in caplog.records)


def test_a_saved_state_keeps_the_anomalies_as_the_run_left_them(tmp_path):
    from engine.scene.snapshot import write_state

    scene = 'Hemianopia { Side "left" Sparing 3 Enabled 1 }\n' \
            'DoubleVision { ID "ghost" Enabled 0 Input "key:g" }\n'
    config = EngineConfig(backend="ballistic", fast=True, headless=True, content_dir=tmp_path)
    with create_engine(config) as engine:
        instantiate(engine, spec_from_text(scene, tmp_path))
        engine.run(frames=1)
        anomalies = engine.resource(Anomalies)
        anomalies.set("hemianopia", "python", enabled=False, values={"Side": "right"})
        anomalies.set("ghost", "python", enabled=True, values={"Offset": (1.5, -0.5)},
                      eye="left")
        anomalies.set("contrast_loss", "python", enabled=True, values={"Loss": 0.3})
        text = write_state(engine, tmp_path / "state.scene")
    saved = {a.id: a for a in spec_from_text(text, tmp_path).anomalies}
    assert not saved["hemianopia"].enabled and saved["hemianopia"].values["Side"] == "right"
    assert saved["hemianopia"].values["Sparing"] == 3.0
    assert saved["ghost"].enabled and saved["ghost"].eye == "left"
    assert saved["ghost"].values["Offset"] == (1.5, -0.5) and saved["ghost"].input == "key:g"
    assert saved["contrast_loss"].enabled and saved["contrast_loss"].values["Loss"] == 0.3
