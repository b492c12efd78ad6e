"""``colosseum run --watch``: a change to the scene, a file it includes or a model it
imports starts the run again from the new files."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from pathlib import Path

import pytest

from app.bench import interchange_samples as samples_
from app.cli import main
from app.scene_loading import SceneWatcher, import_path
from components import Physical
from engine.scene import load_spec

pytest.importorskip("engine.physics.ode3d")


def touch(path: Path, text: str | None = None) -> None:
    """Rewrite ``path`` (or just move its time on), so its stamp surely changes."""
    if text is not None:
        path.write_text(text)
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))


def run_watching(target: Path, change: Callable[[], None]) -> int:
    """``colosseum run TARGET --watch`` for 250 frames, ``change`` made a second in."""

    def editor() -> None:
        time.sleep(1.0)
        change()

    thread = threading.Thread(target=editor)
    thread.start()
    try:
        return main(["run", str(target), "--headless", "--watch", "--frames", "250"])
    finally:
        thread.join()


def test_the_watcher_sees_the_scene_its_includes_and_its_models(models):
    (models / "extra.scene").write_text('Object { ID "ball" Position [0 0 5] }\n')
    (models / "main.scene").write_text('Include "extra.scene"\nModel { File "shapes.glb" }\n')
    watcher = SceneWatcher(load_spec(models))
    assert watcher.changed() == []
    for name in ("main.scene", "extra.scene", "shapes.glb"):
        touch(models / name)
        assert [p.name for p in watcher.changed()] == [name]
        watcher = SceneWatcher(load_spec(models))


def test_run_watch_starts_again_when_the_model_changes(models, capsys):
    (models / "main.scene").write_text('Model { File "shapes.glb" }\n')

    def change_the_model() -> None:
        samples_.triggers(models / "shapes.glb")  # another model under the same name
        touch(models / "shapes.glb")

    assert run_watching(models, change_the_model) == 0
    assert "colosseum: shapes.glb changed; starting again" in capsys.readouterr().err


def test_run_watch_keeps_the_last_good_scene_when_the_new_one_has_errors(models, capsys):
    scene = models / "main.scene"
    scene.write_text('Object { ID "ball" }\n')

    code = run_watching(models, lambda: touch(scene, 'Object { ID "ball" Mas 2 }\n'))
    err = capsys.readouterr().err
    assert code == 0 and "unknown key 'Mas'" in err
    assert "main.scene changed but has errors; running the last good scene" in err


def two_bodies(path: Path, crate_mass: float, ball_mass: float) -> Path:
    """A crate and a ball of the given masses (kg) over a ground plane."""
    b = samples_.GltfBuilder()
    samples_._ground_plane(b)
    samples_._body(b, "Crate", (0, 0, 1), b.shape("box", size=[0.4] * 3), (0.4,) * 3,
                   mass=crate_mass)
    samples_._body(b, "Ball", (2, 0, 1), b.shape("sphere", radius=0.2), (0.4,) * 3,
                   mass=ball_mass)
    return b.write(path)


def masses(scene: Path) -> dict[str, float | None]:
    return {es.id: c.mass for es in load_spec(scene).entities for c in es.components
            if isinstance(c, Physical) and c.kind == "dynamic"}


def imported_and_edited(folder: Path) -> tuple[Path, Path]:
    """``colosseum import`` of the crate and ball into main.scene, then the crate's mass
    edited by hand to 5 kg."""
    model = two_bodies(folder / "room.glb", 1.0, 1.0)
    scene = folder / "main.scene"
    assert import_path(model, scene) == 0
    touch(scene, scene.read_text().replace("ID \"Crate\"", "ID \"Crate\" // edited", 1)
          .replace("Mass 1", "Mass 5", 1))
    assert masses(scene) == {"Crate": 5.0, "Ball": 1.0}
    return model, scene


def test_the_watcher_imports_a_changed_model_again_into_the_scene_it_wrote(tmp_path):
    """A scene ``colosseum import`` wrote depends on its model like a Model block: when
    the model changes, its bodies are imported again and merged, the hand edit kept."""
    model, scene = imported_and_edited(tmp_path)
    watcher = SceneWatcher(load_spec(scene))
    assert watcher.imports == {model.resolve(): [scene.resolve()]}
    assert watcher.reimport() == []  # nothing changed: nothing imported
    two_bodies(model, 2.0, 3.0)
    touch(model)
    assert [p.name for p in watcher.changed()] == ["room.glb"]
    assert watcher.reimport() == [scene.resolve()]
    # the ball's mass comes from the model again; the crate keeps the author's 5 kg
    assert masses(scene) == {"Crate": 5.0, "Ball": 3.0}
    assert "// edited" in scene.read_text()


def test_a_scene_written_by_hand_is_never_imported_into(tmp_path):
    model = two_bodies(tmp_path / "room.glb", 1.0, 1.0)
    scene = tmp_path / "main.scene"
    assert import_path(model, scene) == 0
    (tmp_path / "main.scene.imported").unlink()  # no base: nothing tells edits from imports
    watcher = SceneWatcher(load_spec(scene))
    two_bodies(model, 2.0, 3.0)
    touch(model)
    assert watcher.imports == {} and watcher.reimport() == []
    assert masses(scene) == {"Crate": 1.0, "Ball": 1.0}


def test_run_watch_brings_a_changed_models_physics_into_the_imported_scene(tmp_path, capsys):
    _, scene = imported_and_edited(tmp_path)

    def change_the_model() -> None:
        two_bodies(tmp_path / "room.glb", 2.0, 3.0)
        touch(tmp_path / "room.glb")

    code = run_watching(scene, change_the_model)
    err = capsys.readouterr().err
    assert code == 0 and "colosseum: main.scene imported again from its changed model" in err
    assert "colosseum: room.glb changed; starting again" in err
    assert masses(scene) == {"Crate": 5.0, "Ball": 3.0}
