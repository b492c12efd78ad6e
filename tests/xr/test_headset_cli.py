"""``--xr`` and ``Display { Kind "openxr" }`` as a user meets them on a machine without a
headset: one clear message and exit 1, or the window where a fallback is asked for; the
scene's headset block checked at its line."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
HANDS = ROOT / "content" / "hands"


def colosseum(*args: object, runtime: str | None = "/nonexistent/runtime.json",
              cwd: Path | None = None) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ)
    env.pop("XR_RUNTIME_JSON", None)
    if runtime is not None:
        env["XR_RUNTIME_JSON"] = runtime
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)], env=env,
                          capture_output=True, text=True, cwd=cwd or ROOT, timeout=120)


def test_no_runtime_is_one_message_and_exit_1(tmp_path: Path):
    stats = tmp_path / "stats.json"
    result = colosseum("run", HANDS, "--xr", "--seconds", "5", "--headless", "--stats", stats)
    assert result.returncode == 1, result.stderr
    errors = [line for line in result.stderr.splitlines() if "ERROR" in line]
    assert len(errors) == 1 and "headset:" in errors[0], result.stderr
    assert "/nonexistent/runtime.json" in errors[0]  # the runtime it tried is named
    assert "Traceback" not in result.stderr
    assert json.loads(stats.read_text())["frames"] == 0  # it ended, it did not hang


def test_the_fallback_runs_in_the_window_instead(tmp_path: Path):
    stats = tmp_path / "stats.json"
    result = colosseum("run", HANDS, "--xr", "--xr-fallback", "--frames", "20", "--headless",
                       "--fast", "--stats", stats)
    assert result.returncode == 0, result.stderr
    assert "running without the headset" in result.stderr
    assert json.loads(stats.read_text())["frames"] == 20


def _headset_scene(tmp_path: Path, extra: str = "") -> Path:
    folder = tmp_path / "vr"
    folder.mkdir()
    (folder / "main.scene").write_text(
        'Camera { ID "eyes" Position [0 -2 1.5] LookAt [0 0 0.8] }\n'
        f'Display {{ Kind "openxr" Space "local" {extra}}}\n'
        'Object { ID "box" Position [0 0 1] Size [0.3 0.3 0.3]\n'
        '  VisualAttributes { Geometry { Primitive "box" } Color [1 0 0] } }\n')
    return folder


def test_a_scene_that_asks_for_the_headset_uses_it_and_no_xr_does_not(tmp_path: Path):
    folder = _headset_scene(tmp_path)
    asked = colosseum("run", folder, "--frames", "5", "--headless", "--fast")
    assert asked.returncode == 1 and "headset:" in asked.stderr
    refused = colosseum("run", folder, "--no-xr", "--frames", "5", "--headless", "--fast")
    assert refused.returncode == 0, refused.stderr
    assert "headset" not in refused.stderr


def test_check_tells_a_bad_binding_at_its_line(tmp_path: Path):
    folder = _headset_scene(tmp_path, 'Bind { Action "sqeeze" Profile "oculus/touch_controller"'
                                      ' Path "/user/hand/right/input/trigger/value" } ')
    result = colosseum("check", folder)
    assert result.returncode == 1
    assert "main.scene:2:" in result.stdout + result.stderr
    assert "did you mean 'squeeze'" in result.stdout + result.stderr


def test_keys_documents_the_headset_display():
    result = colosseum("keys", "Display")
    assert result.returncode == 0
    for key in ("Kind", "Space", "WhenHidden", "Mirror", "RecenterKey", "HapticGrasp", "Bind"):
        assert key in result.stdout


def test_a_screen_display_still_needs_its_id(tmp_path: Path):
    folder = tmp_path / "wall"
    folder.mkdir()
    (folder / "main.scene").write_text("Display { LowerLeft [0 0 0] }\n")
    result = colosseum("check", folder)
    assert result.returncode == 1 and "needs an ID" in result.stdout + result.stderr


@pytest.mark.parametrize("flag", ["--xr", "--xr-fallback"])
def test_serve_has_no_headset_flags(flag: str):
    result = colosseum("serve", HANDS, flag)
    assert result.returncode == 2
