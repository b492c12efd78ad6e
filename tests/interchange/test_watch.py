"""``colosseum run --watch``: a change to the scene, a file it includes or a model it
imports starts the run again from the new files."""

from __future__ import annotations

import os
import threading
import time
from pathlib import Path

import pytest

from engine.cli import main
from engine.scene import load_spec
from engine.scene_loading import SceneWatcher
from tools import interchange_samples as samples_

pytest.importorskip("engine.physics.ode3d")


def touch(path: Path, text: str | None = None) -> None:
    """Rewrite ``path`` (or just move its time on), so its stamp surely changes."""
    if text is not None:
        path.write_text(text)
    stat = path.stat()
    os.utime(path, ns=(stat.st_atime_ns, stat.st_mtime_ns + 10**9))


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
        time.sleep(1.0)
        samples_.triggers(models / "shapes.glb")  # another model under the same name
        touch(models / "shapes.glb")

    editor = threading.Thread(target=change_the_model)
    editor.start()
    try:
        code = main(["run", str(models), "--headless", "--watch", "--frames", "250"])
    finally:
        editor.join()
    assert code == 0
    assert "colosseum: shapes.glb changed; starting again" in capsys.readouterr().err


def test_run_watch_keeps_the_last_good_scene_when_the_new_one_has_errors(models, capsys):
    scene = models / "main.scene"
    scene.write_text('Object { ID "ball" }\n')

    def break_the_scene() -> None:
        time.sleep(1.0)
        touch(scene, 'Object { ID "ball" Mas 2 }\n')

    editor = threading.Thread(target=break_the_scene)
    editor.start()
    try:
        code = main(["run", str(models), "--headless", "--watch", "--frames", "250"])
    finally:
        editor.join()
    err = capsys.readouterr().err
    assert code == 0 and "unknown key 'Mas'" in err
    assert "main.scene changed but has errors; running the last good scene" in err
