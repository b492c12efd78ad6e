"""--param: a scene variable set from outside acts as if the author had typed it."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from engine.scene.params import ParamError, with_params
from tests.net.net_helpers import MULTIUSER, ROOT, object_block

SCENE = """size 1.0      // metres
drop 2 + size  // an expression of it
Object { ID "box" Position [0 0 drop] Size [size]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" } } }
"""


def test_a_variable_and_what_uses_it_change(tmp_path: Path) -> None:
    scene = tmp_path / "main.scene"
    scene.write_text(SCENE)
    text = with_params(scene, {"size": "0.5"})
    assert text.splitlines()[0] == "size 0.5   // metres"
    assert text.splitlines()[1:] == SCENE.splitlines()[1:]


def test_unknown_variables_get_a_suggestion(tmp_path: Path) -> None:
    scene = tmp_path / "main.scene"
    scene.write_text(SCENE)
    with pytest.raises(ParamError, match="did you mean 'size'"):
        with_params(scene, {"sise": "2"})
    with pytest.raises(ParamError, match="variables: drop, size"):
        with_params(scene, {"Mass": "2"})


def test_a_variable_sharing_its_line_is_refused(tmp_path: Path) -> None:
    scene = tmp_path / "main.scene"
    scene.write_text("a 1 b 2\nObject { ID \"x\" Position [a b 0] }\n")
    with pytest.raises(ParamError, match="line of its own"):
        with_params(scene, {"a": "3"})


def test_run_param_reaches_the_simulation(tmp_path: Path) -> None:
    out = tmp_path / "state.scene"
    done = subprocess.run([sys.executable, "-m", "app.cli", "run", MULTIUSER, "--frames",
                           "1", "--fast", "--param", "crate_mass=60", "--save-state", out],
                          cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert "crate_mass 60" in out.read_text()
    assert object_block(out.read_text(), "crate")["Position"][2] == pytest.approx(0.75, abs=0.01)
    bad = subprocess.run([sys.executable, "-m", "app.cli", "run", MULTIUSER, "--frames",
                          "1", "--param", "crate_mas=60"], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert bad.returncode == 1 and "did you mean 'crate_mass'" in bad.stderr, bad.stderr
