"""Nothing fails silently (issue 20): mistakes that used to give no message, or a wrong
one, each reproduced through the command line an author uses."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from engine.scene import check


def colosseum(*args: object) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "app.cli", *map(str, args)],
                          capture_output=True, text=True, timeout=120)


def content(folder: Path, scene: str, scripts: dict[str, str] | None = None) -> Path:
    (folder / "scripts").mkdir(parents=True)
    (folder / "main.scene").write_text(scene)
    for name, text in (scripts or {}).items():
        (folder / "scripts" / name).write_text(text)
    return folder


CAMERAS = """\
Object { ID "box" PhysicalAttributes { Geometry { Primitive "box" } } }
Camera { ID "eye" Position [1 2 3] LookAt [1 2 3] }
Camera { ID "top" Position [0 0 10] LookAt [0 0 0] Active 0 }
Camera { ID "chase" Follow "box" Offset [0 -3 1] LookAt [0 -3 1] Active 0 }
Camera { ID "head" Follow "box" Offset [0 -3 1] Active 0 }
Camera { ID "fine" Position [0 -8 3] LookAt [0 0 1] Active 0 }
"""


def test_a_camera_looking_nowhere_or_along_up_is_told_by_check_and_run(tmp_path: Path) -> None:
    folder = content(tmp_path / "sim", CAMERAS)
    told = [(d.line, d.col, d.severity, d.message) for d in check(folder)]
    assert [(line, col, severity) for line, col, severity, _ in told] == [
        (2, 43, "warning"), (3, 44, "warning"), (4, 57, "warning")]
    assert "camera 'eye': it looks at its own position" in told[0][3]
    assert "camera 'top': it looks straight down, along the up axis (Z)" in told[1][3]
    assert "camera 'chase': it looks at its own position" in told[2][3]  # offset = look-at
    assert all("3D sound unpanned" in message for *_, message in told)
    result = colosseum("run", folder, "--frames", "3", "--fast", "--headless")
    assert result.returncode == 0, result.stderr
    assert f"{folder / 'main.scene'}:2:43: warning: camera 'eye'" in result.stderr
    # and at run time, where the sound listener follows it (once, not every frame)
    assert result.stderr.count("colosseum.audio: camera 'eye': it looks at its own") == 1


def test_a_camera_a_script_turns_to_look_at_itself_is_told_once(tmp_path: Path) -> None:
    scene = CAMERAS.splitlines()[0] + "\nCamera { ID \"fine\" Position [0 -8 3] }\n" \
        'Script "scripts/aim.lua"\n'
    folder = content(tmp_path / "sim", scene,
                     {"aim.lua": "function onUpdate() setCamera{lookAt = {0, -8, 3}} end\n"})
    assert list(check(folder)) == []
    result = colosseum("run", folder, "--frames", "5", "--fast", "--headless")
    assert result.stderr.count("camera 'fine': it looks at its own position") == 1


def test_2d_backend_messages_name_the_scene_object(tmp_path: Path) -> None:
    scene = ('World { Dynamics "pymunk" }\n'
             'Object { ID "tilted" Position [0 0 1] Orientation [30 0 0] '
             'PhysicalAttributes { Mass 1 } }\n')
    result = colosseum("run", content(tmp_path / "sim", scene), "--frames", "3", "--fast",
                       "--headless")
    assert result.returncode == 0, result.stderr
    assert "object 'tilted': orientation tilts out of the X–Z plane" in result.stderr
    assert "body " not in result.stderr


@pytest.mark.parametrize(("dt", "frames", "reports"), [
    ("0.01", 400, ["t=  1 s", "t=  2 s", "t=  3 s", "t=  4 s"]),
    ("0.005", 400, ["t=  1 s", "t=  2 s"]),  # the same frames are half the time
    ("0.02", 100, ["t=  1 s", "t=  2 s"]),
])
def test_the_demo_reports_once_a_simulated_second_whatever_the_step(
        dt: str, frames: int, reports: list[str]) -> None:
    result = colosseum("run", "--frames", frames, "--dt", dt, "--fast", "--headless")
    assert result.returncode == 0, result.stderr
    assert [line[:7] for line in result.stdout.splitlines() if "tower top" in line] == reports
