"""Hostile and broken model files: each problem told with the file and the node, the broken
part skipped, the rest imported; nothing an author wrote is overwritten unasked."""

from __future__ import annotations

import json
import struct
from pathlib import Path
from typing import Any

import pytest

from app.bench.interchange_samples import GltfBuilder, box_mesh, collada
from app.scene_loading import import_path
from components import Physical
from engine.assets import AssetError, Assets
from engine.interchange import import_model
from engine.interchange.gltf_physics import KHR, KHR_SHAPES
from engine.scene import load_spec
from tests.interchange.helpers import import_scene


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


# -- found by the fuzzer (tools/fuzz.py --kind models) -------------------------------------

def test_fields_of_the_wrong_json_type_are_told_not_raised(tmp_path):
    """A material whose pbrMetallicRoughness is a number is drawn white; an accessor whose
    byteOffset is a list, and a scene whose node list is null, are messages naming the file."""
    b, path = two_boxes(tmp_path)
    b.doc.setdefault("materials", []).append({"pbrMetallicRoughness": 7})
    for mesh in b.doc["meshes"]:
        for prim in mesh["primitives"]:
            prim["material"] = len(b.doc["materials"]) - 1
    b.write(path)
    assert [o.id for o in imported(path).scene.objects] == ["Good", "Other"]
    doc = json.loads(path.read_text())
    doc["accessors"][0]["byteOffset"] = [1]
    said = messages(imported(path, json.dumps(doc)))
    assert any("accessor 0 is malformed" in m for m in said)
    doc["scenes"] = [{"nodes": None}]
    with pytest.raises(AssetError) as caught:
        imported(path, json.dumps(doc))
    assert caught.value.message.startswith('cannot import model "boxes.gltf"')
    assert "it is malformed" in caught.value.reason


def test_a_body_at_a_position_that_is_no_number_is_told_not_raised(tmp_path):
    b, path = two_boxes(tmp_path)
    b.write(path)
    doc = json.loads(path.read_text())
    doc["nodes"][0]["translation"] = [float("nan"), 0, 0]
    path.write_text(json.dumps(doc))
    out = tmp_path / "boxes.scene"
    assert import_path(path, out, force=True) == 1  # told on stderr, no traceback


# -- Collada ----------------------------------------------------------------------------

def collada_with(folder: Path, old: str, new: str) -> Path:
    """:func:`app.bench.interchange_samples.collada`'s file with ``old`` replaced by ``new``."""
    path = collada(folder / "physics.dae")
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    return path


def test_malformed_collada_xml_is_refused_naming_the_file_and_line(tmp_path):
    path = collada(tmp_path / "broken.dae")
    path.write_text(path.read_text()[:2000])
    with pytest.raises(AssetError) as caught:
        imported(path)
    assert caught.value.message.startswith('cannot load model "broken.dae"')
    assert "XML Parsing Error" in caught.value.reason and "line" in caught.value.reason


def test_nan_in_a_collada_matrix_leaves_that_node_and_its_body_out(tmp_path):
    path = collada_with(tmp_path, '<node id="Ball" name="Ball"><translate>-3 0 1</translate>',
                        '<node id="Ball" name="Ball"><matrix>1 0 0 -3 0 1 0 nan 0 0 1 1 '
                        '0 0 0 1</matrix>')
    result = imported(path)
    assert messages(result) == ["error: node 'Ball': its transform holds a value that is not a "
                                "finite number; it and its children are left out"]
    ids = [o.id for o in result.scene.objects]
    assert "Ball" not in ids and {"Box", "Pill", "Door"} <= set(ids)


def test_collada_geometry_that_is_missing_is_told_at_its_node(tmp_path):
    """A shape naming a geometry the file lacks leaves the body a stand-in sphere; a
    node drawing one is drawn without it (pycollada drops it without a word)."""
    path = collada_with(tmp_path, '<shape><instance_geometry url="#gem"/></shape>',
                        '<shape><instance_geometry url="#nothing"/></shape>')
    text = path.read_text().replace(
        '<node id="Pill" name="Pill"><translate>-2 0 1</translate><instance_geometry '
        'url="#cube"/>', '<node id="Pill" name="Pill"><translate>-2 0 1</translate>'
                         '<instance_geometry url="#nowhere"/>')
    path.write_text(text)
    said = messages(imported(path))
    assert ("error: node 'Gem': its shape names geometry 'nothing', which the file does not "
            "have; left out") in said
    assert ("error: node 'Pill': its <instance_geometry> names geometry 'nowhere', which the "
            "file does not have; it is not drawn") in said
    spec = load_spec(import_scene(path))
    pill = next(es for es in spec.entities if es.id == "Pill")
    assert any(isinstance(c, Physical) for c in pill.components)  # its body stays


def test_a_collada_constraint_naming_a_missing_body_is_told_and_left_out(tmp_path):
    path = collada_with(tmp_path, '<attachment rigid_body="Door-rb">',
                        '<attachment rigid_body="Ghost-rb">')
    result = imported(path)
    assert messages(result) == ["error: rigid_constraint 'DoorHinge': its <attachment> names "
                                "rigid body 'Ghost-rb', which its physics model does not "
                                "have; left out"]
    assert result.scene.joints == [] and len(result.scene.objects) == 10


# -- what the engine cannot represent: told once, naming the file and the node ----------

def unrepresentable(folder: Path) -> Path:
    """A glTF file of things the engine approximates: static friction apart from dynamic
    (a material two bodies use), tapered capsules on two nodes
    of one body, a joint limit of several soft axes, enableCollision on two joints, a
    cone limit, and a position drive on a universal joint."""
    b = GltfBuilder()
    sticky = b.top(KHR, "physicsMaterials", {"staticFriction": 0.9, "dynamicFriction": 0.4})
    box = b.shape("box", size=[0.4] * 3)
    for name, x in (("Left", 0), ("Right", 2)):
        b.khr(b.node(name, (x, 0, 1)), motion={"mass": 1},
              collider={"geometry": box, "physicsMaterial": sticky})
    b.khr(b.node("Floaty", (4, 0, 1)), motion={"mass": 1, "gravityFactor": 0.5},
          collider={"geometry": box})
    cone = b.shape("capsule", height=0.4, radiusTop=0.1, radiusBottom=0.2)
    pair = b.node("Pair", (6, 0, 1))
    b.khr(pair, motion={"mass": 1})
    for k in (0, 1):
        b.khr(b.node(f"Tip{k}", (0.3 * k, 0, 0), parent=pair), collider={"geometry": cone})

    def joint(name: str, body: int, limits: list[dict[str, Any]], **extra: Any) -> None:
        """Body ``body`` (the 0th, 1st, ... made above, 2 m apart) jointed to the world
        where it stands."""
        desc = b.top(KHR, "physicsJoints", {"limits": limits, **extra.pop("desc", {})})
        space_b = b.node("jointSpaceB", parent=body)
        b.khr(b.node(name, (2 * body, 0, 1)), joint={"connectedNode": space_b, "joint": desc,
                                                     **extra})

    soft = {"min": -0.5, "max": 0.5, "stiffness": 100.0}
    joint("Soft", 0, [{"linearAxes": [0, 1, 2], "max": 0}, {"angularAxes": [0], **soft},
                      {"angularAxes": [1], "min": 0, "max": 0},
                      {"angularAxes": [2], "min": 0, "max": 0}], enableCollision=True)
    # enableCollision between two moving bodies (Left and Right); to the world (Soft) it
    # is what happens here anyway (a body and the static body it is joined to touch only
    # when the file asks)
    ball = b.top(KHR, "physicsJoints", {"limits": [{"linearAxes": [0, 1, 2], "max": 0}]})
    b.khr(b.node("Touchy", (1, 0, 0), parent=0),
          joint={"connectedNode": b.node("jointSpaceB", (-1, 0, 0), parent=1), "joint": ball,
                 "enableCollision": True})
    joint("Cone", 2, [{"linearAxes": [0, 1, 2], "max": 0},
                      {"angularAxes": [0, 1], "max": 0.5}])
    joint("Gimbal", 3, [{"linearAxes": [0, 1, 2], "max": 0},
                        {"angularAxes": [2], "min": 0, "max": 0}],
          desc={"drives": [{"type": "angular", "axis": 0, "stiffness": 5.0}]})
    return b.write(folder / "odd.gltf")


def test_each_thing_the_engine_cannot_represent_is_told_once_naming_file_and_node(tmp_path):
    result = imported(unrepresentable(tmp_path))
    told = [d for d in result.problems if d.severity == "warning"]
    assert {d.path for d in told} == {"odd.gltf"}
    expected = {
        "physics material 0: static friction 0.9 differs from dynamic friction 0.4; contacts "
        "here have one Coulomb coefficient, the dynamic one": None,
        "a tapered capsule (radii 0.1 and 0.2) is a capsule of the larger radius here": "Tip0",
        "soft joint limits (stiffness 100) are hard here": "Soft",
        "jointed bodies never collide here (enableCollision is not represented)": "Touchy",
        "a cone limit over 2 axes (up to 0.5) is not represented: those axes are free": "Cone",
        "a position drive on a Universal joint is not represented": "Gimbal",
    }
    for text, node in expected.items():
        found = [d for d in told if text in d.message and (
            node is None or d.message.startswith(f"node '{node}': "))]
        assert len(found) == 1, (text, [d.message for d in told])
        if node is not None:
            assert found[0].head().startswith(f"odd.gltf: warning: node '{node}': ")
    # the second tapered capsule is told too (a different node), but nothing twice
    assert any(d.message.startswith("node 'Tip1': a tapered capsule") for d in told)
    assert len({d.message for d in told}) == len(told)
    # a gravity factor of 0.5 is represented now (issue 31): nothing to tell
    assert not [d for d in told if "gravityFactor" in d.message]


def test_static_friction_is_told_once_and_the_dynamic_one_used(tmp_path):
    """Two bodies of the material, one warning; both slide with the dynamic coefficient."""
    path = unrepresentable(tmp_path)
    result = imported(path)
    assert sum("static friction" in d.message for d in result.problems) == 1
    spec = load_spec(import_scene(path))
    frictions = {es.id: c.material.friction for es in spec.entities for c in es.components
                 if isinstance(c, Physical)}
    assert frictions["Left"] == frictions["Right"] == 0.4


def test_colladas_static_friction_and_spring_on_the_wrong_joint_are_told_once(tmp_path):
    path = collada_with(tmp_path, "<static_friction>0.6</static_friction>",
                        "<static_friction>0.8</static_friction>")
    text = path.read_text().replace(
        "<stiffness>0</stiffness><damping>0</damping>",
        "<stiffness>0</stiffness><damping>0</damping></angular><linear><stiffness>5"
        "</stiffness><damping>0</damping><target_value>0</target_value></linear><angular>"
        "<stiffness>0</stiffness><damping>0</damping>")
    path.write_text(text)
    said = messages(imported(path))
    assert said.count("warning: physics material stone: static friction 0.8 differs from "
                      "dynamic friction 0.6; contacts here have one Coulomb coefficient, the "
                      "dynamic one") == 1
    assert said.count("warning: rigid_constraint 'DoorHinge': its linear spring (stiffness 5) "
                      "is not represented: springs here act on a hinge's or slider's free "
                      "axis, and this joint is a Hinge") == 1
