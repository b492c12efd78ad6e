"""The blocks and keys on the registry that are not entities: settings built from their
defaults where unwritten (World), blocks built before the objects that name them
(Material), blocks written once, the last replacing the first (Session), and keys a
feature adds to another block (Script, Graspable, User; a content folder's own)."""

from __future__ import annotations

from pathlib import Path

import pytest

from components.blocks import BuildContext, Key, KeyDeclaration, declare_key
from engine.physics.backend import WorldSettings
from engine.realtime import TIME_STEP
from engine.scene import blocks, spec_from_text
from engine.scene.diagnostics import SceneError


def _errors(text: str, folder: Path) -> list[str]:
    with pytest.raises(SceneError) as caught:
        spec_from_text(text, folder)
    return [f"{d.line}: {d.message}" for d in caught.value.diagnostics]


def test_a_scene_without_a_world_block_has_the_world_s_defaults(tmp_path: Path):
    spec = spec_from_text('Object { ID "a" Position [0 0 1] }\n', tmp_path)
    assert spec.time_step == TIME_STEP and spec.backend == "ode"
    assert spec.world.iterations == WorldSettings().iterations
    assert spec.world.material_pairs is spec.material_pairs  # pairs written later join it


def test_world_is_written_once_and_told_at_its_keys(tmp_path: Path):
    twice = spec_from_text("World { Iterations 0 }\nWorld { Iterations 12 }\n", tmp_path)
    assert twice.world.iterations == 12  # the last replaces the first, which is not built
    bad = _errors("World {\n  TimeStep 0\n  Iterations 0\n}\n", tmp_path)
    assert any(e.startswith("2: TimeStep must be more than 0") for e in bad), bad
    assert any(e.startswith("3: Iterations must be") for e in bad), bad
    long = spec_from_text("World { TimeStep 0.08 }\n", tmp_path)
    assert [p.severity for p in long.problems] == ["warning"]
    assert "TimeStep 0.08 s is long" in long.problems[0].message


def test_a_material_written_after_its_objects_still_gives_their_mass(tmp_path: Path):
    spec = spec_from_text(
        'Object { ID "cube" Size [0.1 0.1 0.1] PhysicalAttributes { Material "steel" } }\n'
        'Material { ID "steel" Density 8000 }\n', tmp_path)
    body = next(c for e in spec.entities if e.id == "cube" for c in e.components
                if type(c).__name__ == "Physical")
    assert body.mass is None  # from the material's density, when the body is made
    assert (body.material.name, body.material.density) == ("steel", 8000.0)


def test_a_session_block_is_a_setting_written_once(tmp_path: Path):
    spec = spec_from_text('Session { Name "trial" PoseRate 5 }\n', tmp_path)
    assert spec.settings["Session"].name == "trial"
    assert spec.settings["Session"].pose_rate == 5.0
    twice = spec_from_text('Session { Name "a" }\nSession { Name "b" }\n', tmp_path)
    assert twice.settings["Session"].name == "b"


def test_a_key_declared_on_the_object_is_checked_built_and_documented(tmp_path: Path):
    from engine.scene import keys

    def build(value: float, ctx: BuildContext) -> list[object]:
        if value < 0:
            ctx.error("Drag", f"Drag must not be negative, got {value:g}")
        return [] if value == 0 else [("drag", value)]

    declare_key(KeyDeclaration(Key("Drag", "float", 0.0, "N·s/m, air drag"), build))
    try:
        spec = spec_from_text('Object { ID "a" Drag 0.5 }\nObject { ID "b" }\n', tmp_path)
        made = {e.id: [c for c in e.components if isinstance(c, tuple)]
                for e in spec.entities}
        assert made == {"a": [("drag", 0.5)], "b": []}
        assert _errors('Object {\n  ID "a"\n  Drag -1\n}\n', tmp_path) == [
            "3: Drag must not be negative, got -1"]
        wrong = _errors('Object {\n  ID "a"\n  Drag "much"\n}\n', tmp_path)
        assert wrong and wrong[0].startswith("3:"), wrong
        assert "air drag" in keys.block_text("Object")
    finally:
        blocks.unregister_key("Object", "Drag")
    assert "Drag" not in keys.block_text("Object")


def test_the_importer_writes_blocks_as_their_declarations_type_them():
    """A writer out of step with the scene format fails here, not in a user's scene."""
    from engine.interchange.model import _Blocks
    from engine.scene.db import FLOAT, STRING, STRINGVECTOR, VECTOR
    from engine.scene.diagnostics import Loc

    b = _Blocks(Loc("model.gltf", 0, 0))
    entry = b.declared("Joint", {"ID": "j", "Type": "Hinge", "Bodies": ["a", "b"],
                                 "Axis": (0.0, 1.0, 0.0), "Low": -30.5, "High": None})
    kinds = {e.key: e.value.kind for e in entry.value.data.entries}
    assert kinds == {"ID": STRING, "Type": STRING, "Bodies": STRINGVECTOR, "Axis": VECTOR,
                     "Low": FLOAT}
    with pytest.raises(KeyError, match="declares no key 'Lo'"):
        b.declared("Joint", {"Lo": 1.0})
