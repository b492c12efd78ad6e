"""Hostile asset files: each told at the scene line that named it, the object (or just its
texture or sound) left out, the run going on; nothing half-made, nothing saved that is not."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hostile import CASES, Case, case, cube, flat_obj, knock

from components import Name, Sound, Transform, Visual
from engine.app import Engine, EngineConfig
from engine.scene import instantiate, load_spec, spec_from_text, write_state
from systems import load_plugin
from systems.render import RenderOptions, RenderPlugin, RenderSystem
from systems.sound import SoundPlugin

GROUND = 'Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }'
BALL = 'Object { ID "ball" Position [3 0 1] Size [0.5] }'
CAMERA = 'Camera { ID "cam" Position [0 -9 3] LookAt [0 0 1] }'


def content(folder: Path, lines: list[str], files: dict[str, object]) -> Path:
    """A content folder: ``main.scene`` of ``lines`` and the files ``name -> maker``."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, make in files.items():
        make(folder / name)  # type: ignore[operator]
    (folder / "main.scene").write_text("\n".join(lines) + "\n")
    return folder


def place(scene: Path, file: str) -> tuple[int, int]:
    """Line and column of ``"file"`` in ``scene`` (where the error must point)."""
    for number, text in enumerate(scene.read_text().splitlines(), start=1):
        if f'"{file}"' in text:
            return number, text.index(f'"{file}"') + 1
    raise AssertionError(f"{file} is not in {scene}")


def engine_for(folder: Path, backend: str = "ode") -> Engine:
    """Physics, scripts, sound (silent device) and headless rendering: every user of an
    asset."""
    return Engine(EngineConfig(backend=backend, fast=True, content_dir=folder),
                  plugins=[load_plugin("physics"), load_plugin("scripting"), SoundPlugin("null"),
                           RenderPlugin(RenderOptions(backend="headless", size=(64, 48)))])


def names(engine: Engine) -> set[str]:
    return {n.id for _, n in engine.world.get_component(Name)}


@pytest.mark.parametrize("case", CASES, ids=lambda c: c.file)
def test_each_hostile_file_is_told_at_its_line_and_the_rest_runs(tmp_path: Path, case: Case):
    folder = content(tmp_path / "sim", [GROUND, BALL, case.use.format(file=case.file), CAMERA],
                     {case.file: case.make})
    scene = folder / "main.scene"
    spec = load_spec(folder)
    (problem,) = spec.problems
    assert (problem.path, problem.line, problem.col) == (str(scene), *place(scene, case.file))
    assert problem.is_error
    assert problem.message.startswith(
        f'cannot {case.action} "{case.file}" ({folder / case.file}): ')
    assert case.reason in problem.message
    (bad,) = [es for es in spec.entities if es.id == "bad"]
    assert bad.skipped == case.left_out
    with engine_for(folder) as engine:
        instantiate(engine, spec)
        engine.run(frames=30)
        ball = engine.world.component_for_entity(_entity(engine, "ball"), Transform)
        assert ball.position[2] < 0.95  # the fine body fell: the run went on
        assert ("bad" in names(engine)) != case.left_out
        renderer = engine.resource(RenderSystem).renderer
        assert renderer is not None and renderer.read_pixels().std() > 0


def _entity(engine: Engine, name: str) -> int:
    (entity,) = [e for e, n in engine.world.get_component(Name) if n.id == name]
    return entity


def test_a_broken_texture_is_drawn_as_a_checker_and_told_once(tmp_path: Path):
    folder = content(tmp_path / "sim", [
        'Object { ID "a" Position [-1 0 1] Dynamic 0 VisualAttributes { Texture "bomb.png" '
        'Geometry { Primitive "box" } } }',
        'Object { ID "b" Position [1 0 1] Dynamic 0 VisualAttributes { Texture "bomb.png" '
        'Geometry { Primitive "box" } } }', CAMERA], {"bomb.png": case("bomb.png").make})
    spec = load_spec(folder)
    assert [(p.line, "bomb.png" in p.message) for p in spec.problems] == [(1, True), (2, True)]
    with engine_for(folder) as engine:
        instantiate(engine, spec)
        engine.run(frames=2)
        assert all(_visual(engine, n).texture == "bomb.png" for n in ("a", "b"))
        errors = engine.resource(RenderSystem).renderer.errors
        assert len(errors) == 1 and "drawing a checker placeholder" in errors[0]


def _visual(engine: Engine, name: str) -> Visual:
    return engine.world.component_for_entity(_entity(engine, name), Visual)


def test_an_object_whose_sound_fails_keeps_everything_but_the_sound(tmp_path: Path):
    buzz, cut = case("buzz.wav"), case("cut.wav")
    folder = content(tmp_path / "sim", [GROUND, BALL, buzz.use.format(file=buzz.file),
                                        'Sound { ID "music" File "cut.wav" Loop 1 }'],
                     {buzz.file: buzz.make, cut.file: cut.make})
    spec = load_spec(folder)
    assert [p.message.split(";")[1].strip() for p in spec.problems] == [
        "object 'bad' has no sound", "sound 'music' is left out"]
    with engine_for(folder) as engine:
        instantiate(engine, spec)
        engine.run(frames=5)
        assert "music" not in names(engine)
        assert engine.world.try_component(_entity(engine, "bad"), Sound) is None


def test_a_body_left_out_takes_its_joint_and_camera_follow_and_is_not_saved(tmp_path: Path):
    folder = content(tmp_path / "sim", [
        GROUND, BALL,
        'Object { ID "rock" Position [0 0 2] PhysicalAttributes { Geometry { File "flat.obj" '
        'ParseMethod "ConvexHull" } } }',
        'Object { ID "box" Position [0 0 4] PhysicalAttributes { Geometry { File "cube.obj" '
        'ParseMethod "ConvexHull" } } }',
        'Joint { ID "hinge" Type "Hinge" Bodies ["rock" "ball"] Axis [0 1 0] }',
        'Joint { ID "pin" Type "Ball" Bodies ["box"] Anchor [0 0 5] }',
        'Camera { ID "cam" Position [0 -9 3] Follow "rock" }'],
        {"flat.obj": flat_obj, "cube.obj": cube})
    spec = load_spec(folder)
    told = [(p.line, p.message) for p in spec.problems]
    assert [line for line, _ in told] == [3, 5, 7]
    assert "joint 'hinge' is left out: its body 'rock' was" in told[1][1]
    assert "camera 'cam' follows nothing: object 'rock' was left out" in told[2][1]
    with engine_for(folder) as engine:
        instantiate(engine, spec)
        engine.run(frames=20)
        assert {"rock", "hinge"}.isdisjoint(names(engine))
        assert len(engine.physics.snapshot.bodies.keys) == 3  # ground, ball, box: no husk
        saved = write_state(engine, tmp_path / "saved.scene")
    assert '"rock"' not in saved and '"hinge"' not in saved
    assert 'ID "box"' in saved and 'ID "pin"' in saved
    (tmp_path / "saved.scene").write_text(saved)
    again = load_spec(tmp_path / "saved.scene")
    assert again.problems == [] and {"box", "pin", "ball"} <= {
        *(es.id for es in again.entities), *(js.id for js in again.joints)}


def test_a_spawned_object_with_a_broken_model_is_left_out_and_saving_still_works(
        tmp_path: Path, caplog: pytest.LogCaptureFixture):
    folder = content(tmp_path / "sim", [GROUND, BALL,
                                        'Script "scripts/spawner.lua"'],
                     {"flat.obj": flat_obj, "cube.obj": cube})
    (folder / "scripts").mkdir()
    (folder / "scripts" / "spawner.lua").write_text(
        "function onStart()\n"
        "  made = spawn([[\n"
        "Object { ID \"crate\" Position [0 0 3] PhysicalAttributes { Geometry {\n"
        "  File \"cube.obj\" ParseMethod \"ConvexHull\" } } }\n"
        "Object { ID \"slab\" Position [2 0 3] PhysicalAttributes { Geometry {\n"
        "  File \"flat.obj\" ParseMethod \"ConvexHull\" } } }\n"
        "Joint { ID \"weld\" Type \"Fixed\" Bodies [\"slab\" \"crate\"] }\n"
        "]])\n"
        "  count = #made\n"
        "end\n")
    spec = load_spec(folder)
    with engine_for(folder) as engine:
        instantiate(engine, spec)
        engine.run(frames=10)
        assert "crate" in names(engine) and {"slab", "weld"}.isdisjoint(names(engine))
        saved = write_state(engine, tmp_path / "saved.scene")
    assert 'cannot build a convex hull of model "flat.obj"' in caplog.text
    assert "<spawn>:4:" in caplog.text  # the snippet's line that named it
    assert '"crate"' in saved and '"slab"' not in saved and '"weld"' not in saved


def test_the_command_line_runs_on_and_check_lists_every_broken_file(tmp_path: Path):
    """Every hostile file at once, end to end: a run that saves a screenshot and its state
    exits 0 and tells each file with its line; ``check`` lists the same and exits 1."""
    lines, files = [GROUND, BALL, CAMERA], {"knock.wav": knock}
    for i, each in enumerate(CASES):
        lines.append(each.use.format(file=each.file).replace('"bad"', f'"bad{i}"'))
        files[each.file] = each.make
    folder = content(tmp_path / "sim", lines, files)
    shot, state = tmp_path / "shot.png", tmp_path / "state.scene"
    run = subprocess.run(
        [sys.executable, "-m", "app.cli", "run", str(folder), "--headless", "--frames", "20",
         "--fast", "--sound", "null", "--size", "64x48", "--screenshot", str(shot),
         "--save-state", str(state)], capture_output=True, text=True, timeout=180)
    assert run.returncode == 1, run.stderr  # ran on without them; the content had errors
    assert "Traceback" not in run.stderr and shot.is_file()
    scene = folder / "main.scene"
    for each in CASES:
        line, col = place(scene, each.file)
        assert f'{scene}:{line}:{col}: error: cannot {each.action} "{each.file}"' in run.stderr
    saved = state.read_text()
    for i, each in enumerate(CASES):
        assert (f'"bad{i}"' in saved) != each.left_out
    check = subprocess.run([sys.executable, "-m", "app.cli", "check", str(folder)],
                           capture_output=True, text=True, timeout=180)
    assert check.returncode == 1 and "Traceback" not in check.stderr
    assert f"{len(CASES)} error(s)" in check.stderr
    for each in CASES:
        assert f'cannot {each.action} "{each.file}"' in check.stderr


def test_a_snippet_naming_a_bad_model_twice_is_told_at_both_lines(tmp_path: Path):
    flat_obj(tmp_path / "flat.obj")
    text = ('Object { ID "a" PhysicalAttributes { Geometry { File "flat.obj" } } }\n'
            'Object { ID "b" VisualAttributes { Geometry { File "flat.obj" } }\n'
            '  PhysicalAttributes { Geometry { File "flat.obj" } } }\n')
    (tmp_path / "main.scene").write_text(text)
    spec = spec_from_text(text, tmp_path)
    lines = text.splitlines()
    assert [(p.line, p.col) for p in spec.problems] == [
        (1, lines[0].index('"flat.obj"') + 1), (3, lines[2].index('"flat.obj"') + 1)]
    assert all("enclose no volume" in p.message for p in spec.problems)
    assert [es.skipped for es in spec.entities] == [True, True]
    assert spec.assets is not None and list(spec.assets.loads.values()) == [1]
