"""Scene keys typed into a model's nodes (extras), and models imported by a scene's Model
block: the same blocks as ``colosseum import`` writes, checked with the scene."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import soundfile

from components import Camera, Physical, Script, Sound, Visual
from engine.assets import Assets
from engine.interchange import import_model
from engine.scene import SceneError, check, load_spec, parse_text, write
from tests.interchange.helpers import Run, import_scene

pytest.importorskip("engine.physics.ode3d")


def with_assets(folder: Path) -> Path:
    """The sound and script the extras sample names."""
    soundfile.write(folder / "knock.wav", np.zeros(800, np.int16), 8000)
    (folder / "door.lua").write_text("function onStart() end\n")
    return folder


def components(spec, oid):
    (es,) = [e for e in spec.entities if e.id == oid]
    return {type(c): c for c in es.components}


def test_extras_produce_the_scene_keys_typed_into_the_nodes(models):
    spec = load_spec(import_scene(with_assets(models) / "extras.glb"))
    door = components(spec, "Door")  # a body only through its extras, as in the paper
    assert door[Physical].mass == 2.0 and door[Physical].kind == "dynamic"
    assert door[Physical].material.name == "wood" and door[Physical].material.friction == 0.7
    assert door[Sound].file == "knock.wav" and door[Script].file == "door.lua"
    lamp = components(spec, "Lamp")  # one text field, several keys
    assert lamp[Visual].color == (1.0, 0.9, 0.6, 1.0) and lamp[Physical].kind == "static"
    assert lamp[Physical].material.bounce == 0.2
    assert components(spec, "Crate")[Physical].mass == 7.0  # extras win over the KHR mass


def test_a_mistake_in_extras_names_the_model_node_line_and_column(models):
    imported = import_model("extras.glb", "extras.glb", Assets(with_assets(models)))
    errors = [d.render(imported.db.sources.get(d.path)) for d in imported.problems
              if d.is_error]
    assert errors[0].startswith("extras.glb node 'Typo' extras:1:1: error: unknown key 'Mas' "
                                "(did you mean 'Mass'?)")
    assert "    Mas 3\n    ^" in errors[0]
    warnings = [d.message for d in imported.problems if not d.is_error]
    assert "node 'Crate': extras 'prop' are no scene keys; left out" in warnings
    # the rest is imported, and the written scene checks clean
    assert {o.id for o in imported.scene.objects} >= {"Door", "Lamp", "Crate", "Typo"}
    out = models / "extras.scene"
    out.write_text(write(imported.db))
    assert not [d for d in check(out) if d.is_error]


def test_extras_naming_an_undeclared_material_declare_it(models):
    from app.bench.interchange_samples import GltfBuilder, box_mesh

    b = GltfBuilder()
    b.node("Stone", (0, 0, 1), mesh=b.mesh(*box_mesh((1, 1, 1)), "StoneMesh"),
           extras={"Mass": 3, "Material": "granite"})
    b.write(models / "stone.glb")
    imported = import_model("stone.glb", "stone.glb", Assets(models))
    assert [m.id for m in imported.scene.materials] == ["granite"]
    assert any("Material 'granite', which is not declared" in d.message
               for d in imported.problems)


HOST = """
Material { ID "wood" Friction 0.2 }
Model { File "extras.glb" }
Model { File "shapes.glb" Prefix "s/" }
Camera { ID "eye" Follow "s/Sphere" Offset [0 -3 1] }
"""


def test_a_model_block_imports_the_same_objects_into_a_scene(models):
    with_assets(models)
    (models / "main.scene").write_text(HOST)
    spec = load_spec(models)
    written = load_spec(import_scene(models / "shapes.glb"))
    ids = [e.id for e in spec.entities]
    assert [f"s/{e.id}" for e in written.entities] == [i for i in ids if i.startswith("s/")]
    for es in written.entities:  # the same shapes and masses as the written scene's
        a, b = components(spec, f"s/{es.id}")[Physical], components(written, es.id)[Physical]
        assert (a.kind, a.mass, [s.kind for s in a.shapes]) == (b.kind, b.mass,
                                                                [s.kind for s in b.shapes])
    # the scene's own material wins over the model's, and a camera follows a model's body
    assert components(spec, "Door")[Physical].material.friction == 0.2
    assert [(k.entity, k.field, k.target) for k in spec.links
            if k.component is Camera] == [("eye", "follow", "s/Sphere")]
    assert isinstance(components(spec, "eye")[Camera], Camera)


def test_a_model_block_runs_and_saves_its_objects_as_blocks(models):
    from engine.scene import write_state

    with_assets(models)
    (models / "main.scene").write_text('Model { File "shapes.glb" }\n')
    with Run.start(models / "main.scene") as run:
        run.step(1.0)
        saved = write_state(run.engine)
    # a saved state holds the model's objects, where they are now, instead of the Model
    db = parse_text(saved, str(models / "state.scene"))
    assert not db.blocks("Model")
    sphere = next(b for b in db.blocks("Object") if b.get("ID") == "Sphere")
    assert sphere.get("Position")[2] == pytest.approx(0.25, abs=0.005)


def test_a_model_clashing_with_the_scenes_ids_is_told_at_the_model_line(models):
    (models / "main.scene").write_text('Object { ID "Sphere" }\nModel { File "shapes.glb" }\n')
    with pytest.raises(SceneError) as caught:
        load_spec(models)
    (error,) = caught.value.errors
    assert error.line == 2 and error.message.startswith("duplicate Object ID 'Sphere'")


def test_import_0_draws_the_whole_file_as_scenery(models):
    (models / "main.scene").write_text('Model { File "shapes.glb" Import 0 }\n')
    spec = load_spec(models)
    (only,) = spec.entities
    assert set(components(spec, only.id)) >= {Visual} and Physical not in components(
        spec, only.id)
    assert components(spec, only.id)[Visual].model == "shapes.glb"


def test_a_model_that_cannot_be_read_leaves_its_objects_out_and_the_run_goes_on(models):
    (models / "broken.glb").write_bytes(b"glTF\x02\x00\x00\x00\xff\xff\xff\x7f")
    (models / "main.scene").write_text('Model { File "broken.glb" }\nObject { ID "ball" }\n')
    spec = load_spec(models)
    assert [e.id for e in spec.entities] == ["ball"]
    (told,) = [d for d in check(models) if d.is_error]
    assert (told.line, told.col) == (1, 14) and "broken.glb" in told.message
    assert "the model's objects are left out" in told.message
