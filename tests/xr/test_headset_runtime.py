"""End to end against a real OpenXR runtime: run where ``XR_RUNTIME_JSON`` names one
(docs/headset.md says how a developer runs Monado's simulated headset), skipped otherwise.
What reaches the runtime is read back from its swapchain images."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from services.input.calibration import openxr_to_engine

ROOT = Path(__file__).resolve().parents[2]
RUNTIME = os.environ.get("XR_RUNTIME_JSON")
pytestmark = pytest.mark.skipif(
    not RUNTIME or not Path(RUNTIME).is_file(),
    reason="no OpenXR runtime: XR_RUNTIME_JSON names none (see docs/headset.md for "
           "Monado's simulated headset)")


def _engine(folder: Path, frames: int):
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import resolve
    from systems import create_engine

    scene = load_content_scene(resolve(folder))
    config = EngineConfig(content_dir=folder, render=True, headless=True, fast=False,
                          options={"xr": True})
    scene.configure(config)
    engine = create_engine(config)
    scene.instantiate(engine)
    return engine


def _scene(tmp_path: Path) -> Path:
    """A red box ahead, a blue one to the right, a green floor: known colours."""
    folder = tmp_path / "known"
    folder.mkdir()
    (folder / "main.scene").write_text(
        'Camera { ID "eyes" Position [0 -2 1.6] LookAt [0 0 1.6] }\n'
        'Display { Kind "openxr" }\n'
        'Light { Type "directional" Direction [0 1 0] Intensity 1 }\n'
        'Object { ID "floor" Dynamic 0 VisualAttributes { Geometry { Primitive "plane" } '
        'Color [0 0.6 0] } }\n'
        'Object { ID "red" Position [0 0.5 1.6] Dynamic 0 Size [0.6 0.1 0.6]\n'
        '  VisualAttributes { Geometry { Primitive "box" } Color [1 0 0] } }\n'
        'Object { ID "blue" Position [1.2 0.5 1.6] Dynamic 0 Size [0.4 0.1 0.4]\n'
        '  VisualAttributes { Geometry { Primitive "box" } Color [0 0 1] } }\n')
    return folder


def test_hands_in_the_headset_reaches_focused_submits_and_ends_cleanly(tmp_path: Path):
    stats = tmp_path / "stats.json"
    result = subprocess.run(
        [sys.executable, "-m", "app.cli", "run", ROOT / "content" / "hands", "--xr",
         "--seconds", "10", "--headless", "--hud", "--stats", stats],
        capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert result.returncode == 0, result.stderr[-3000:]
    import jsonschema

    from engine.stats import STATS_SCHEMA

    jsonschema.validate(json.loads(stats.read_text()), STATS_SCHEMA)
    xr = json.loads(stats.read_text())["xr"]
    assert xr["session_state_max"] == "FOCUSED" and xr["session_end"] == "exiting"
    frames = json.loads(stats.read_text())["frames"]
    # every frame the runtime asked for was ended: drawn, or skipped where it said so
    assert xr["frames_submitted"] + xr["frames_skipped"] >= frames - 2
    assert xr["frames_skipped"] <= 3
    assert xr["frames_with_hud"] >= xr["frames_submitted"] - 2  # the HUD's own layer
    assert "Traceback" not in result.stderr


def test_what_reaches_the_runtime_is_what_the_engine_drew_per_eye(tmp_path: Path):
    from services.xr.display import XrDisplay

    engine = _engine(_scene(tmp_path), 0)
    display = engine.plugins["xr"].display
    display.capture = True
    try:
        engine.run(frames=12)
        assert isinstance(engine.try_resource(XrDisplay), XrDisplay)
        captured = display.captured
        drawn = engine.resource(XrDisplay).target
        assert captured is not None
        ours = np.flipud(np.frombuffer(drawn.fbo.read(components=4, alignment=1), np.uint8)
                         .reshape(drawn.size[1], drawn.size[0], 4))
        assert np.array_equal(captured[:, :, :3], ours[:, :, :3])  # sRGB: written as drawn
        w = captured.shape[1] // 2
        for half in (captured[:, :w], captured[:, w:]):
            red = (half[:, :, 0] > 150) & (half[:, :, 1] < 60) & (half[:, :, 2] < 60)
            green = (half[:, :, 1] > 80) & (half[:, :, 0] < 60)
            assert red.mean() > 0.008 and green.mean() > 0.02
        # the eyes differ by the runtime's eye offset: the red box shifts between them
        columns = [np.flatnonzero(((h[:, :, 0] > 150) & (h[:, :, 1] < 60)).any(axis=0)).mean()
                   for h in (captured[:, :w], captured[:, w:])]
        assert columns[0] > columns[1]  # seen from the left eye it lies further right
        left, right = display.views
        gap = np.linalg.norm(np.subtract(left.position, right.position))
        assert 0.05 < gap < 0.08  # the simulated HMD's 63 mm
    finally:
        engine.close()


def test_the_eyes_drawn_are_the_pose_at_the_predicted_display_time(tmp_path: Path):
    engine = _engine(_scene(tmp_path), 0)
    display = engine.plugins["xr"].display
    try:
        engine.run(frames=10)
        frame_time = int(display.session._frame.predicted_display_time)
        engine.run(frames=1)
        drawn, when = display.views, display.views_time
        assert when is not None and when > frame_time  # the next frame's display time
        again = display.session.locate_views(when)
        assert [v.position for v in again] == [v.position for v in drawn]
        assert [v.orientation for v in again] == [v.orientation for v in drawn]
        earlier = display.session.locate_views(when - 200_000_000)  # 0.2 s before
        moved = max(float(np.abs(np.subtract(a.position, b.position)).max()
                          + np.abs(np.subtract(a.orientation, b.orientation)).max())
                    for a, b in zip(again, earlier, strict=True))
        assert moved > 1e-6  # the simulated head moves: the pose at another time differs
        eye = engine.resource(type(display)).target
        assert eye is not None
        position, _ = openxr_to_engine(drawn[0].position, drawn[0].orientation)
        assert np.isfinite(position).all()
    finally:
        engine.close()


CONTROLLERS = """
import json, sys
from pathlib import Path
from engine.app import EngineConfig
from engine.content import resolve
from services.input.state import InputState
from app.scene_loading import load_content_scene
from engine.services import HeadsetControl
from systems import create_engine

folder = Path(sys.argv[1])
scene = load_content_scene(resolve(folder))
config = EngineConfig(content_dir=folder, render=True, headless=True, options={"xr": True})
scene.configure(config)
engine = create_engine(config)
scene.instantiate(engine)
engine.run(frames=15)
state = engine.resource(InputState)
out = {name: None if state.tracker(name) is None else list(state.tracker(name).position)
       for name in ("hmd", "hand_l", "hand_r", "hand_r_aim")}
out["haptic"] = engine.resource(HeadsetControl).haptic("hand_r", 0.5, 0.1)
out["origin"] = list(engine.plugins["xr"].display.origin.position)
engine.close()
print("RESULT " + json.dumps(out))
"""


def test_the_runtimes_controllers_are_the_hands_trackers_and_take_a_pulse(tmp_path: Path):
    """Monado's simulated controllers (SIMULATED_LEFT/RIGHT) stand 0.2 m to each side,
    1.3 m up and 0.5 m ahead of the stage's origin: they arrive as hand_l/hand_r there,
    in the world, and a haptic pulse is taken."""
    env = dict(os.environ, SIMULATED_LEFT="simple", SIMULATED_RIGHT="simple")
    result = subprocess.run([sys.executable, "-c", CONTROLLERS, _scene(tmp_path)],
                            capture_output=True, text=True, timeout=120, env=env, cwd=ROOT)
    assert result.returncode == 0, result.stderr[-3000:]
    out = json.loads(result.stdout.split("RESULT ")[-1])
    origin = np.array(out["origin"])  # under the camera at (0, -2), facing +y
    assert np.allclose(np.array(out["hand_r"]) - origin, (0.2, 0.5, 1.3), atol=0.05)
    assert np.allclose(np.array(out["hand_l"]) - origin, (-0.2, 0.5, 1.3), atol=0.05)
    assert out["hand_r_aim"] is not None and out["hmd"][2] > 1.4
    assert out["haptic"] is True


SERVICE = os.environ.get("MONADO_SERVICE")


@pytest.mark.skipif(not SERVICE or not Path(SERVICE).is_file(),
                    reason="no out-of-process runtime to kill: MONADO_SERVICE names no "
                           "monado-service (see docs/headset.md)")
def test_a_runtime_killed_mid_run_is_one_message_and_a_clean_exit(tmp_path: Path):
    """The runtime's service killed while the run draws: one message, exit status 1, the
    state and the figures still written, within seconds (XR_RUNTIME_JSON must name the
    service's client runtime)."""
    import signal
    import time

    runtime_dir = tmp_path / "rt"
    runtime_dir.mkdir(mode=0o700)
    env = dict(os.environ, XDG_RUNTIME_DIR=str(runtime_dir), XRT_NO_STDIN="1")
    service = subprocess.Popen([SERVICE], env=env, stdin=subprocess.DEVNULL,
                               stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        deadline = time.monotonic() + 30
        while not (runtime_dir / "monado_comp_ipc").exists():
            assert service.poll() is None and time.monotonic() < deadline, "no service"
            time.sleep(0.1)
        stats, state = tmp_path / "stats.json", tmp_path / "state.scene"
        run = subprocess.Popen(
            [sys.executable, "-m", "app.cli", "run", ROOT / "content" / "hands", "--xr",
             "--seconds", "60", "--headless", "--stats", stats, "--save-state", state],
            env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path)
        time.sleep(6)
        service.send_signal(signal.SIGKILL)
        killed = time.monotonic()
        _, err = run.communicate(timeout=30)
        assert time.monotonic() - killed < 10  # no hang
        assert run.returncode == 1
        told = [line for line in err.splitlines() if "colosseum.xr" in line and "ERROR" in line]
        assert len(told) == 1 and "went away" in told[0], err[-2000:]
        assert "Traceback" not in err
        figures = json.loads(stats.read_text())["xr"]
        assert figures["session_end"] == "lost" and figures["frames_submitted"] > 0
        assert state.is_file()
    finally:
        service.kill()
        service.wait()


def test_the_stroke_simulator_in_the_headset_takes_each_eyes_left_field(tmp_path: Path):
    """Left hemianopia in the headset: each eye loses its own left half of the view."""
    from app.scene_loading import load_content_scene
    from engine.app import EngineConfig
    from engine.content import resolve
    from systems import create_engine

    folder = ROOT / "content" / "stroke"
    scene = load_content_scene(resolve(folder), params={"hemianopia_on": "1"})
    config = EngineConfig(content_dir=folder, render=True, headless=True,
                          options={"xr": True, "sessions": tmp_path})
    scene.configure(config)
    engine = create_engine(config)
    scene.instantiate(engine)
    display = engine.plugins["xr"].display
    display.capture = True
    try:
        engine.run(frames=40)  # 2 s at the simulated headset's 20 Hz: past the 1 s onset
        image = display.captured[:, :, :3].astype(int)
    finally:
        engine.close()
    w = image.shape[1] // 2
    for eye in (image[:, :w], image[:, w:]):
        left, right = eye[:, : w // 2 - 20], eye[:, w // 2 + 8:]  # sparing: 3° kept
        assert left.max() < 40  # blind: black
        assert right.mean() > 80  # seen: the apartment
