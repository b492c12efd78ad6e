"""XR_EXT_hand_tracking against a real OpenXR runtime (run where ``XR_RUNTIME_JSON``
names one; ``. /opt/monado/env.sh`` for Monado's simulated headset), skipped otherwise.

What Monado 24's simulated devices really do: the runtime offers the extension (it is
enabled), but its system reports ``supportsHandTracking`` false — its simulated
controllers synthesize no hands. So both OpenXR paths, the headset's session and the
headless input device, tell that in one line, make no hand tracker and emit no hand
events, while the head and the controllers go on arriving. (The joints' conversion is
checked on arrays in tests/input/test_openxr_hands.py.) Each run is its own process:
the runtime lives in the process that loads it."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RUNTIME = os.environ.get("XR_RUNTIME_JSON")
pytestmark = pytest.mark.skipif(
    not RUNTIME or not Path(RUNTIME).is_file(),
    reason="no OpenXR runtime: XR_RUNTIME_JSON names none (see docs/headset.md for "
           "Monado's simulated headset)")

HEADSET = """
import json, logging, sys
from pathlib import Path
from engine.app import EngineConfig
from engine.content import resolve
from services.input.events import HandJoints
from services.input.state import InputState
from app.scene_loading import load_content_scene
from systems import create_engine

logging.basicConfig(level=logging.INFO, stream=sys.stderr)
folder = Path(sys.argv[1])
scene = load_content_scene(resolve(folder))
config = EngineConfig(content_dir=folder, render=True, headless=True, options={"xr": True})
scene.configure(config)
engine = create_engine(config)
scene.instantiate(engine)
hands = []
engine.events.subscribe(HandJoints, hands.append)
engine.run(frames=15)
state = engine.resource(InputState)
out = {"extensions": sorted(engine.plugins["xr"].display.session.extensions),
       "hand_events": len(hands), "hands": sorted(state.hands),
       "hand_r": None if state.tracker("hand_r") is None
       else list(state.tracker("hand_r").position)}
engine.close()
print("RESULT " + json.dumps(out))
"""

HEADLESS = """
import json, logging, sys, time
from services.input.events import HandJoints, TrackerPose
from services.input.openxr import OpenXRDevice

logging.basicConfig(level=logging.INFO, stream=sys.stderr)
device = OpenXRDevice()
device.open()
events = []
deadline = time.monotonic() + 20.0
while time.monotonic() < deadline and not any(
        isinstance(e, TrackerPose) and e.device == "hmd" for e in events):
    events += device.poll(time.monotonic())
    time.sleep(0.02)
time.sleep(0.3)
events += device.poll(time.monotonic())
device.close()
print("RESULT " + json.dumps({"hmd": sum(isinstance(e, TrackerPose) and e.device == "hmd"
                                         for e in events),
                              "hands": sum(isinstance(e, HandJoints) for e in events),
                              "status": device.status().state}))
"""

NO_HANDS = "offers XR_EXT_hand_tracking but its system tracks no hands: no tracked hands"


def _scene(tmp_path: Path) -> Path:
    folder = tmp_path / "hands"
    folder.mkdir()
    (folder / "main.scene").write_text(
        'Camera { ID "eyes" Position [0 -2 1.6] LookAt [0 0 1.6] }\n'
        'Display { Kind "openxr" }\n'
        'Object { ID "floor" Dynamic 0 VisualAttributes { Geometry { Primitive "plane" } } }\n')
    return folder


def _run(script: str, *args: object) -> tuple[dict, str]:
    env = dict(os.environ, SIMULATED_LEFT="wmr", SIMULATED_RIGHT="wmr")
    result = subprocess.run([sys.executable, "-c", script, *map(str, args)],
                            capture_output=True, text=True, timeout=120, env=env, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-3000:]
    assert "Traceback" not in result.stderr
    return json.loads(result.stdout.split("RESULT ")[-1]), result.stderr


def test_the_headset_enables_hand_tracking_and_says_once_that_there_are_no_hands(tmp_path):
    out, log = _run(HEADSET, _scene(tmp_path))
    assert "XR_EXT_hand_tracking" in out["extensions"]
    assert log.count(NO_HANDS) == 1 and "the headset: the OpenXR runtime" in log
    assert out["hand_events"] == 0 and out["hands"] == []
    assert out["hand_r"] is not None  # the controllers go on arriving


def test_the_headless_device_says_once_that_there_are_no_hands_and_reads_the_head():
    out, log = _run(HEADLESS)
    assert log.count(NO_HANDS) == 1 and "input device 'openxr' (openxr)" in log
    assert out["hmd"] > 0 and out["hands"] == 0 and out["status"] == "closed"
