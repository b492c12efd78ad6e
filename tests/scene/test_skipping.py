"""A run leaves out the broken parts of a scene (engine.scene.skipping) and keeps the rest."""

from __future__ import annotations

from pathlib import Path

import pytest

from app.scene_loading import SceneLoadError, load_content_scene
from engine.content import resolve


def _folder(tmp_path: Path) -> Path:
    (tmp_path / "main.scene").write_text(
        'Include "more.scene"\n'
        'Object { ID "a" Position [0 0 1] PhysicalAttributes { Mass 1 } }\n'
        'Joint { ID "on b" Type "Hinge" Bodies ["a" "b"] Axis [0 0 1] }\n'
        'World { Gravity [0 0 -3] Iterations -4 }\n')
    (tmp_path / "more.scene").write_text(
        'Object { ID "b" Position [1 0 1] PhysicalAttributes { Mass -2 } }\n'
        'Object { ID "c" Position [2 0 1] PhysicalAttributes { Mass 2 } }\n')
    return tmp_path


def test_a_run_goes_on_without_the_broken_parts_and_those_that_named_them(tmp_path, capsys):
    scene = load_content_scene(resolve(str(_folder(tmp_path))), skip_broken=True)
    names = {e.id for e in scene.spec.entities}
    assert names == {"a", "c"}  # b broken (in the included file), the joint named it
    assert not scene.spec.joints
    assert scene.spec.world.gravity == (0, 0, -3)  # World kept, its broken key left out
    told = capsys.readouterr().err
    assert "more.scene:1:" in told and "Mass must be positive" in told
    assert "Iterations" in told and "without 3 broken part(s)" in told
    assert 'more.scene:1: Object "b"' in told and 'main.scene:3: Joint "on b"' in told


def test_without_skipping_the_errors_are_raised(tmp_path):
    with pytest.raises(SceneLoadError, match="Mass must be positive"):
        load_content_scene(resolve(str(_folder(tmp_path))))


def _broken_objects(folder: Path, n: int) -> Path:
    """One good object, ``n`` with an unknown key each, and a joint on one of those."""
    folder.mkdir()
    (folder / "main.scene").write_text(
        'Object { ID "good" PhysicalAttributes { } }\n'
        + "".join(f'Object {{ ID "b{i}" Bogus 1 }}\n' for i in range(n))
        + 'Joint { Type "Hinge" Bodies ["b7"] }\n')
    return folder


def test_many_broken_parts_are_left_out_at_once_and_listed_briefly(tmp_path, capsys):
    """Every error's part is left out in one round, the shown ones and those only counted
    (the first 100 of a file are shown): it took a round per 100 before, and 100,000 broken
    objects ran for 37 s in 1.1 GB and printed 3,000 lines."""
    scene = load_content_scene(resolve(str(_broken_objects(tmp_path / "sim", 500))),
                               skip_broken=True)
    assert {e.id for e in scene.spec.entities} == {"good"} and not scene.spec.joints
    told = capsys.readouterr().err
    assert told.count("error: unknown key 'Bogus'") == 100
    assert told.count("400 more errors in this file not shown") == 1  # one round told
    assert "without 501 broken part(s)" in told and "\n  and 401 more\n" in told
    assert len(told.splitlines()) < 420


def test_too_many_broken_parts_do_not_run_and_say_why(tmp_path):
    with pytest.raises(SceneLoadError) as raised:
        load_content_scene(resolve(str(_broken_objects(tmp_path / "sim", 3000))),
                           skip_broken=True)
    report = str(raised.value)
    assert report.count("error: unknown key 'Bogus'") == 100
    assert report.endswith("more than 1000 broken parts of the scene (3000); colosseum check "
                           "lists the errors")
