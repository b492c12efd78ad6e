"""Hostile and broken model files: each problem told with the file and the node, the broken
part skipped, the rest imported; nothing an author wrote is overwritten unasked."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import pytest

from engine.assets import AssetError, Assets
from engine.interchange import import_model
from engine.interchange.gltf_physics import KHR_SHAPES
from engine.scene_loading import import_path
from tools.interchange_samples import GltfBuilder, box_mesh


def two_boxes(folder: Path, name: str = "boxes.gltf") -> tuple[GltfBuilder, Path]:
    """A file with two falling boxes, 'Good' and 'Other', drawn from one mesh."""
    b = GltfBuilder()
    mesh = b.mesh(*box_mesh((0.5, 0.5, 0.5)), "BoxMesh")
    for oid, x in (("Good", 0), ("Other", 2)):
        node = b.node(oid, (x, 0, 1), mesh=mesh)
        b.khr(node, motion={"mass": 1}, collider={"geometry": b.shape("box", size=[0.5] * 3)})
    return b, folder / name


def imported(path: Path, text: str | None = None) -> Any:
    if text is not None:
        path.write_text(text)
    return import_model(path.name, path.name, Assets(path.parent))


def messages(result: Any) -> list[str]:
    return [f"{d.severity}: {d.message}" for d in result.problems]


def test_unknown_and_future_extensions_are_named_and_the_rest_imported(tmp_path):
    b, path = two_boxes(tmp_path)
    b.use("EXT_teleporters", "KHR_materials_sheen")
    b.doc["extensionsRequired"] = ["EXT_teleporters"]
    b.write(path)
    result = imported(path)
    said = messages(result)
    assert ("warning: extension EXT_teleporters (required by the file) is not read; what it "
            "adds is left out") in said
    assert any("KHR_materials_sheen" in m and "base colours" in m for m in said)
    assert [o.id for o in result.scene.objects] == ["Good", "Other"]


def test_invalid_json_is_refused_naming_the_file(tmp_path):
    path = tmp_path / "bad.gltf"
    path.write_text('{"asset": {"version": "2.0"}, "nodes": [')
    with pytest.raises(AssetError) as caught:
        imported(path)
    assert caught.value.message.startswith('cannot load model "bad.gltf"')
    assert "not a glTF file: it is not JSON" in caught.value.reason


def test_a_missing_buffer_leaves_the_meshes_out_and_keeps_the_bodies(tmp_path):
    b, path = two_boxes(tmp_path)
    b.write(path)
    doc = json.loads(path.read_text())
    doc["buffers"][0]["uri"] = "boxes.bin"  # never written
    result = imported(path, json.dumps(doc))
    errors = [m for m in messages(result) if m.startswith("error")]
    assert errors == [f"error: node '{n}': its mesh cannot be read: buffer 0 is missing: "
                      f"boxes.bin (looked for {tmp_path / 'boxes.bin'}); it is not drawn"
                      for n in ("Good", "Other")]
    assert [(o.id, o.kind, len(o.shapes), o.visual) for o in result.scene.objects] == [
        ("Good", "dynamic", 1, None), ("Other", "dynamic", 1, None)]


def test_a_collider_of_zero_size_is_told_and_left_out(tmp_path):
    b, path = two_boxes(tmp_path)
    b.doc["extensions"][KHR_SHAPES]["shapes"][0]["box"]["size"] = [0.5, 0, 0.5]
    b.write(path)
    result = imported(path)
    said = messages(result)
    assert ("error: node 'Good': its box collider has zero size (size [0.5, 0, 0.5]); left "
            "out") in said
    good = result.scene.objects[0]
    assert good.category == 0 and good.mask == 0  # no collider: it only carries its mass
    assert len(result.scene.objects[1].shapes) == 1


def test_a_joint_naming_a_missing_node_is_told_and_left_out(tmp_path):
    b, path = two_boxes(tmp_path)
    joint = b.top("KHR_physics_rigid_bodies", "physicsJoints", {"limits": []})
    b.khr(0, joint={"connectedNode": 99, "joint": joint})
    b.khr(1, joint={"connectedNode": 0, "joint": 7})
    b.write(path)
    result = imported(path)
    said = messages(result)
    assert ("error: node 'Good': its joint names connected node 99, which does not exist; the "
            "joint is left out") in said
    assert ("error: node 'Other': its joint names joint description 7, which the file does not "
            "declare; left out") in said
    assert not result.scene.joints and len(result.scene.objects) == 2


@pytest.mark.parametrize("key,value", [
    ("matrix", [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, float("nan"), 0, 0, 1]),
    ("translation", [0, float("nan"), 0]),
    ("rotation", [0, 0, 0, 0]),
])
def test_nan_in_a_matrix_leaves_that_node_out(tmp_path, key, value):
    """JSON has no NaN, but writers write it and readers read it: the node is refused."""
    b, path = two_boxes(tmp_path)
    del b.doc["nodes"][0]["translation"]
    b.doc["nodes"][0][key] = value
    b.write(path)
    result = imported(path)
    reason = ("its rotation quaternion is all zeros" if key == "rotation" else
              f"its {key} holds a value that is not a finite number (nan)")
    assert (f"error: node 'Good': {reason}; it and its children are left out"
            in messages(result))
    assert [o.id for o in result.scene.objects] == ["Other"]



def test_a_file_claiming_more_than_it_holds_is_refused(tmp_path):
    path = tmp_path / "huge.glb"
    header = struct.pack("<4sII", b"glTF", 2, 1 << 31) + struct.pack("<II", 1 << 30, 0x4E4F534A)
    path.write_bytes(header + b"{}")
    with pytest.raises(AssetError) as caught:
        imported(path)
    assert "claims 2147483648 bytes but the file has 22" in caught.value.reason


def test_an_accessor_claiming_a_huge_count_is_told_at_its_node(tmp_path):
    b, path = two_boxes(tmp_path)
    b.doc["accessors"][0]["count"] = 10 ** 12
    b.write(path)
    result = imported(path)
    assert any("accessor 0 claims 1000000000000 items" in m and "node 'Good'" in m
               for m in messages(result))


def test_a_scene_file_no_import_wrote_is_not_overwritten_without_force(tmp_path, capsys):
    b, model = two_boxes(tmp_path, "boxes.glb")
    b.write(model)
    out = tmp_path / "main.scene"
    out.write_text('Object { ID "mine" }\n')
    assert import_path(model, out) == 1
    assert out.read_text() == 'Object { ID "mine" }\n'
    assert "nothing is overwritten: give --force" in capsys.readouterr().err
    assert import_path(model, out, force=True) == 0
    assert (tmp_path / "main.scene.bak").read_text() == 'Object { ID "mine" }\n'
    assert 'ID "Good"' in out.read_text()
