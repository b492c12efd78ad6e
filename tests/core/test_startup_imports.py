"""Start-up loads only what a scene uses: ``colosseum check`` and ``keys`` import no heavy
library, and a run of a scene without models, shaders, sound or devices imports none of
theirs. Each case runs in a fresh interpreter and reads its ``sys.modules`` at the end, so
an eager import added back anywhere on the path fails here."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]

#: Loaded only by a scene (or a command) that uses them.
HEAVY = ("trimesh", "scipy", "moderngl", "lupa", "openal", "matplotlib", "zmq", "dask",
         "pythonosc", "soundfile", "PIL", "pymunk", "pylsl", "serial")
#: Our own modules (and the standard library's, numpy's) that reading a scene file without
#: models, shaders or random numbers does not need: they come with a run, a model, a
#: shader, a command that writes.
NOT_FOR_READING = ("engine.app", "engine.events", "engine.physics.commands",
                   "engine.physics.driver", "engine.interchange.importer",
                   "engine.assets.gltf", "engine.assets.dae", "engine.assets.skinned",
                   "services.render", "app.experiments.cli", "engine.experiments.session",
                   "components.avatar_saved", "numpy.random", "subprocess", "tempfile",
                   "hashlib")
#: A scene with boxes and a ground: no model, script, sound, shader or device.
PLAIN = """World { Gravity [0 0 -9.81] }
Object { ID "ground" Dynamic 0 VisualAttributes { Geometry { Primitive "plane" } }
  PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "box" Position [0 0 1]
  VisualAttributes { Geometry { Primitive "box" } }
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" } } }
"""


def loaded_by(code: str, cwd: Path, whole: bool = False) -> set[str]:
    """Top-level modules (``whole``: every module, by its full name) in ``sys.modules``
    after ``code`` ran in a fresh interpreter."""
    name = "m" if whole else "m.split('.')[0]"
    probe = (f"{code}\nimport json, sys\n"
             f"print(json.dumps(sorted({{{name} for m in sys.modules}})))")
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    done = subprocess.run([sys.executable, "-c", probe], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=120, check=False)
    assert done.returncode == 0, done.stderr
    return set(json.loads(done.stdout.splitlines()[-1]))


def cli(*argv: str) -> str:
    """Code running ``colosseum ARGV`` in-process, failing on a non-zero exit."""
    return f"from app.cli import main\nassert main({list(argv)!r}) == 0"


@pytest.fixture
def plain(tmp_path: Path) -> Path:
    (tmp_path / "plain").mkdir()
    (tmp_path / "plain" / "main.scene").write_text(PLAIN, encoding="utf-8")
    return tmp_path / "plain"


def test_importing_the_cli_loads_no_heavy_library_nor_the_runtime(tmp_path: Path) -> None:
    loaded = loaded_by("import app.cli\nimport sys\n"
                       "assert 'engine.app' not in sys.modules, 'the runtime was imported'\n"
                       "assert 'engine.scene.factory' not in sys.modules", tmp_path)
    assert loaded.isdisjoint(HEAVY), sorted(loaded & set(HEAVY))
    assert "esper" not in loaded


@pytest.mark.parametrize("command", ["check", "keys"])
def test_check_and_keys_load_no_heavy_library(command: str, plain: Path) -> None:
    argv = ("check", str(plain)) if command == "check" else ("keys", "Object")
    loaded = loaded_by(cli(*argv), plain.parent)
    assert loaded.isdisjoint(HEAVY), sorted(loaded & set(HEAVY))
    assert "esper" not in loaded  # reading a scene needs no ECS world


@pytest.mark.parametrize("command", ["check", "keys"])
def test_reading_a_plain_scene_loads_none_of_our_runtime(command: str, plain: Path) -> None:
    """Nor the engine's runtime, its model importers, the renderer, the experiment runner
    or numpy.random (parse draws no number from a scene that has none)."""
    argv = ("check", str(plain)) if command == "check" else ("keys",)
    loaded = loaded_by(cli(*argv), plain.parent, whole=True)
    assert loaded.isdisjoint(NOT_FOR_READING), sorted(loaded & set(NOT_FOR_READING))
    assert "engine.scene.blocks" in loaded  # it did read the blocks


def test_a_run_of_a_plain_scene_loads_none_of_what_it_does_not_use(plain: Path) -> None:
    loaded = loaded_by(cli("run", str(plain), "--frames", "1", "--headless", "--fast"),
                       plain.parent)
    assert loaded.isdisjoint(HEAVY), sorted(loaded & set(HEAVY))  # Lua only for scripts
    assert "esper" in loaded and "numpy" in loaded  # it did run


def test_a_scene_with_a_model_loads_the_model_library(plain: Path) -> None:
    """The other side: what the demo uses is loaded when it is used."""
    demo = ROOT / "content" / "demo"
    loaded = loaded_by(cli("check", str(demo)), plain.parent)
    assert {"trimesh", "soundfile"} <= loaded


def test_a_scene_with_a_script_starts_lua(plain: Path) -> None:
    """Lua comes with the scene's first script, also one added to a plain scene."""
    (plain / "scripts").mkdir()
    (plain / "scripts" / "scene.lua").write_text("x = 1\n", encoding="utf-8")
    (plain / "main.scene").write_text(PLAIN + 'Script "scripts/scene.lua"\n', encoding="utf-8")
    loaded = loaded_by(cli("run", str(plain), "--frames", "1", "--headless", "--fast"),
                       plain.parent)
    assert "lupa" in loaded


#: Our modules for features a plain scene does not have: avatars (animation, skinned
#: models, a saved avatar), hands (fingers), the scripting API and runtime, saving a state.
NOT_IN_A_PLAIN_RUN = ("systems.avatars", "engine.animation", "engine.assets.skinned",
                      "components.avatar_saved",
                      "systems.hands", "systems.hand_fingers", "systems.hand_ghost",
                      "services.scripting.api", "services.scripting.runtime",
                      "engine.scene.snapshot")


def test_a_run_of_a_plain_scene_loads_no_feature_it_does_not_have(plain: Path) -> None:
    loaded = loaded_by(cli("run", str(plain), "--frames", "1", "--headless", "--fast"),
                       plain.parent, whole=True)
    assert loaded.isdisjoint(NOT_IN_A_PLAIN_RUN), sorted(loaded & set(NOT_IN_A_PLAIN_RUN))
    assert {"systems.dynamics", "systems.scripting", "systems.sound"} <= loaded


@pytest.mark.parametrize(("folder", "plugin"), [("hands", "systems.hands"),
                                                ("avatars", "systems.avatars")])
def test_a_scene_with_the_feature_loads_its_plugin(folder: str, plugin: str,
                                                   plain: Path) -> None:
    loaded = loaded_by(cli("run", str(ROOT / "content" / folder), "--frames", "2",
                           "--headless", "--fast"), plain.parent, whole=True)
    assert plugin in loaded


#: A hand on a body, for an engine whose scene had none.
HAND = """Object { ID "palm" Position [0 0 1]
  PhysicalAttributes { Mass 0.4 Geometry { Primitive "box" Size [0.09 0.18 0.03] } }
  Hand { Tracker "hand_r" } }
"""


@pytest.mark.parametrize("told", [True, False])
def test_a_feature_plugin_waits_for_its_first_component(told: bool, tmp_path: Path) -> None:
    """An engine told its scene has no hand builds the hands plugin when the first Hand is
    added (as a script's spawn adds one); one told nothing builds it at once."""
    from engine import EngineConfig, Phase
    from engine.scene import instantiate, spec_from_text
    from systems import create_engine

    options = {"components": frozenset({"Transform", "Physical"})} if told else {}
    with create_engine(EngineConfig(backend="ode", fast=True, options=options)) as engine:
        engine.step()
        assert ("hands" in engine.plugins) is not told
        instantiate(engine, spec_from_text(HAND, tmp_path))
        engine.step()
        assert "hands" in engine.plugins
        names = [s.name for s in engine.systems[Phase.PRE_PHYSICS]]
        assert names.count("HandDriveSystem") == 1, names
        engine.step()
