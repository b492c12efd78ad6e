"""What a server's scripts change in the picture reaches the nodes: a post pass switched and
retuned, a visual anomaly switched on; a node watching sees the change, a node joining
afterwards starts from it. The server is stepped in this process; nodes are processes that
draw headless (Mesa EGL) and save what they show."""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from engine.anomalies import Anomalies
from tests.net.net_helpers import free_port, join_args, local_server, processes

SCENE = """Camera { ID "eye" Position [0 -5 1] LookAt [0 0 1] }
Object { ID "box" Position [0 0 1] Dynamic 0 VisualAttributes { Color [1 1 1]
  Geometry { Primitive "box" Size [2 2 2] } } }
PostPass { ID "tint" File "tint.frag" Enabled 0 Uniform { ID "u_tint" Value [1 1 1] } }
Script "scripts/switch.lua"
"""
TINT = """#version 330
in vec2 v_uv;
uniform sampler2D u_scene;
uniform vec3 u_tint;
out vec4 f_color;
void main() { f_color = vec4(texture(u_scene, v_uv).rgb * u_tint, 1.0); }
"""
# once the first node watches: the post pass on and red, the right half of the view gone
SWITCH = """
on("userJoined", function(user)
  if user ~= "early" then return end
  after(0.3, function()
    enablePost("tint", true)
    setPostUniform("tint", "u_tint", {1, 0, 0})
    setAnomaly("hemianopia", true, {side = "right", onset = 0})
  end)
  after(0.4, function() enablePost("tnit", true) end)
end)
"""


def _content(root: Path) -> Path:
    (root / "scripts").mkdir(parents=True)
    (root / "main.scene").write_text(SCENE)
    (root / "tint.frag").write_text(TINT)
    (root / "scripts" / "switch.lua").write_text(SWITCH)
    return root


@pytest.mark.slow
def test_post_passes_and_anomalies_reach_watching_and_late_nodes(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    folder = _content(tmp_path / "content")
    port = free_port()
    with caplog.at_level(logging.WARNING), local_server(port, content=folder) as server, \
            processes(tmp_path) as procs:
        def node(user: str) -> object:
            return procs.start(user, *join_args(
                port, user, "--frames", 60, "--size", "64x48", "--screenshot",
                tmp_path / f"{user}.png", "--save-state", tmp_path / f"{user}.scene",
                path=folder))

        early = node("early")
        anomalies = server.engine.resource(Anomalies)
        server.step_until(lambda e: "hemianopia" in anomalies.states and
                          anomalies.states["hemianopia"].enabled, 20, "the script's switch")
        late = node("late")
        server.step_until(lambda e: early.poll() is not None and late.poll() is not None, 30,
                          "both nodes finishing")
        for proc in (early, late):
            assert proc.returncode == 0, procs.log(proc)
            assert "cannot be drawn here" not in procs.log(proc), procs.log(proc)
    told = [r.getMessage() for r in caplog.records]
    assert not any("has no attribute" in m for m in told), told
    assert any("switch.lua:9:" in m and "unknown PostPass 'tnit'; did you mean 'tint'?" in m
               for m in told), told
    for user in ("early", "late"):
        image = np.asarray(Image.open(tmp_path / f"{user}.png").convert("RGB"), float)
        left, right = image[:, 4:28], image[:, 36:60]
        box = image[24, 24]  # the lit white box, left of the middle
        assert box[0] > 60 and box[1] < 0.1 * box[0] and box[2] < 0.1 * box[0], (user, box)
        assert left.max() > 60 and right.max() < 8, user  # the right half is not seen
        saved = (tmp_path / f"{user}.scene").read_text()
        assert "Hemianopia {" in saved and 'Side "right"' in saved, saved
