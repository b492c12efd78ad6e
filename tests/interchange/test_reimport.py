"""Importing a changed model again: what came from the model follows it, what the author
edited or added in the scene file stays."""

from __future__ import annotations

import json
from pathlib import Path

from app.bench import interchange_samples as samples_
from app.scene_loading import import_path
from engine.scene import check, load_scene

KHR = samples_.KHR


def edit_model(path: Path, change) -> None:
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))


def node(doc: dict, name: str) -> dict:
    return next(n for n in doc["nodes"] if n.get("name") == name)


def objects(scene: Path) -> dict[str, object]:
    return {b.get("ID"): b for b in load_scene(scene).blocks("Object")}


def test_reimport_updates_the_model_and_keeps_the_authors_edits(tmp_path, capsys):
    model = samples_.shapes(tmp_path / "room.gltf")
    out = tmp_path / "main.scene"
    assert import_path(model, out) == 0
    text = out.read_text()
    # the author: a heavier box, a comment, an object and world settings of their own
    text = text.replace('  ID "Box"\n', '  ID "Box" // the heavy one\n')
    box_mass = '    Mass 2\n'
    at = text.index(box_mass, text.index('ID "Box"'))
    text = text[:at] + '    Mass 5\n' + text[at + len(box_mass):]
    text += 'Object { ID "mine" Position [0 5 1] }\nWorld { Gravity [0 0 -5] }\n'
    out.write_text(text)

    def change(doc: dict) -> None:  # the modeller moves the sphere, reweighs the box,
        node(doc, "Sphere")["translation"][0] = -3.5  # drops the crate, adds a ball
        node(doc, "Box")["extensions"][KHR]["motion"]["mass"] = 3
        crate = doc["nodes"].index(node(doc, "Crate"))
        doc["scenes"][0]["nodes"].remove(crate)
        ball = dict(node(doc, "Pebble"), name="Ball2", translation=[12, 2, 0])
        doc["nodes"].append(ball)
        doc["scenes"][0]["nodes"].append(len(doc["nodes"]) - 1)

    edit_model(model, change)
    capsys.readouterr()
    assert import_path(model, out) == 0
    said = capsys.readouterr().err
    merged = objects(out)
    assert merged["Box"].get("PhysicalAttributes").get("Mass") == 5  # the author's
    assert "kept: Object 'Box' PhysicalAttributes: your Mass is kept; the model now says " \
           "Mass 3" in said
    assert merged["Sphere"].get("Position") == (-3.5, 0, 1)  # the model's
    assert "Crate" not in merged and "Ball2" in merged
    assert "mine" in merged and load_scene(out).get("World").get("Gravity") == (0, 0, -5)
    assert '"Box" // the heavy one' in out.read_text()
    assert "1 added, 1 updated, 1 removed" in said
    assert not [d for d in check(out) if d.is_error]


def test_an_object_the_author_deleted_stays_deleted(tmp_path):
    model = samples_.shapes(tmp_path / "room.gltf")
    out = tmp_path / "main.scene"
    import_path(model, out)
    blocks = out.read_text().split("\nObject {")
    out.write_text("\nObject {".join(b for b in blocks if 'ID "Pebble"' not in b))
    edit_model(model, lambda doc: node(doc, "Pebble")["translation"].__setitem__(0, 11))
    import_path(model, out)
    assert "Pebble" not in objects(out)


def test_importing_the_same_model_again_changes_nothing(tmp_path):
    model = samples_.joints(tmp_path / "rig.glb")
    out = tmp_path / "rig.scene"
    import_path(model, out)
    first = out.read_text()
    import_path(model, out)
    assert out.read_text() == first and not (tmp_path / "rig.scene.bak").exists()
