"""Others' files and the bundled demo, exported and imported again (issue 31): the same
world (bodies and their kinds, masses, joints, poses to 1e-6 m), and every export valid
against the extensions' JSON schemas (tests/conftest.py checks each file an export
writes; here also the demo's, written by the command line).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from components import Physical, Transform
from services.export import export_gltf
from tests.interchange import gltf_schema
from tests.interchange.conformance import ROOT, SHARED

FILES = [SHARED / "khr" / name for name in (
    "ShapeTypes.glb", "JointTypes.glb", "Filtering.glb", "Materials_Friction.glb",
    "MotionProperties.glb", "Triggers.glb")] + [
    SHARED / "khr_tests" / "RigidBodies_Joint" / f"RigidBodies_Joint_{n:02d}.gltf"
    for n in (0, 5, 9, 10)] + [
    SHARED / "omi" / "OMI_physics_joint" / "rope_railing.gltf",
    SHARED / "collada" / "Havok5.5toColladaPhysics.dae"]


def load(scene_dir: Path, model: Path | None = None):
    """The spec of ``scene_dir``'s scene (made to import ``model`` when given)."""
    from app.scene_loading import load_content_scene
    from engine.content import resolve

    allow = []
    if model is not None:
        scene_dir.mkdir(parents=True, exist_ok=True)
        (scene_dir / "main.scene").write_text(
            f'Model {{ File "{model.resolve().as_posix()}" }}\n')
        allow = [model.resolve().parent]
    return load_content_scene(resolve(scene_dir), allow=allow).spec


def world(spec) -> dict[str, tuple]:
    """Per physical object: kind, mass (kg), position, orientation, inertia."""
    out = {}
    for es in spec.entities:
        if es.skipped:
            continue
        parts = {type(c): c for c in es.components}
        if Physical in parts:
            p, t = parts[Physical], parts[Transform]
            out[es.id] = (str(p.kind), p.mass, np.asarray(t.position, float),
                          np.asarray(t.orientation, float), p.inertia)
    return out


def same_world(before, after) -> None:
    a, b = world(before), world(after)
    assert sorted(b) == sorted(a)
    for oid, (kind, mass, pos, quat, inertia) in a.items():
        kind2, mass2, pos2, quat2, inertia2 = b[oid]
        if inertia is not None and kind == "dynamic":  # zeros (infinite) stay zeros
            assert inertia2 is not None and [x == 0 for x in inertia2] == [
                x == 0 for x in inertia], oid
        assert kind2 == kind, oid
        if kind == "dynamic" and mass:
            assert mass2 == pytest.approx(mass, rel=1e-6), oid
        np.testing.assert_allclose(pos2, pos, atol=1e-6, err_msg=oid)
        assert abs(float(quat2 @ quat)) == pytest.approx(1.0, abs=1e-6), oid
    assert len(after.joints) == len(before.joints)
    assert sorted(str(j.joint.kind) for j in after.joints) == sorted(
        str(j.joint.kind) for j in before.joints)


@pytest.mark.parametrize("model", FILES, ids=lambda p: p.name)
def test_a_file_exported_and_imported_again_is_the_same_world(model: Path, tmp_path: Path):
    if not model.is_file():
        pytest.skip(f"{model} is not here")
    before = load(tmp_path / "first", model)
    out = tmp_path / "out.glb"
    export_gltf(before, out)
    assert gltf_schema.problems(out) == []
    after = load(tmp_path / "again", out)
    same_world(before, after)


def test_the_demo_exported_by_the_command_line_validates(tmp_path: Path) -> None:
    """``colosseum export content/demo`` (the issue's example): its mesh colliders name a
    node holding the mesh (the schema allows ``shape`` or ``node``, not ``mesh``)."""
    from app.cli import main

    if not gltf_schema.available():
        pytest.skip("the schemas are not here")
    out = tmp_path / "demo.glb"
    assert main(["export", str(ROOT / "content" / "demo"), "-o", str(out)]) == 0
    assert gltf_schema.problems(out) == []
    doc = gltf_schema.document(out)
    geometries = [n["extensions"]["KHR_physics_rigid_bodies"]["collider"]["geometry"]
                  for n in doc["nodes"]
                  if "collider" in n.get("extensions", {}).get("KHR_physics_rigid_bodies", {})]
    assert geometries and all(("shape" in g) != ("node" in g) for g in geometries)


def test_avatars_are_exported_with_skins_clips_and_capsules(tmp_path: Path) -> None:
    """content/avatars: each avatar's model goes into the file whole (skinned meshes,
    skeleton, clips), and its Capsule as a kinematic capsule collider; the file validates
    and the engine's own skinned-model reader reads every skin and clip back."""
    from app.cli import main
    from engine.assets.skinned import load_skinned

    out = tmp_path / "avatars.glb"
    assert main(["export", str(ROOT / "content" / "avatars"), "-o", str(out)]) == 0
    if gltf_schema.available():
        assert gltf_schema.problems(out) == []
    doc = gltf_schema.document(out)
    walker = gltf_schema.document(ROOT / "content" / "avatars" / "models" / "walker.glb")
    hound = gltf_schema.document(ROOT / "content" / "avatars" / "models" / "hound.glb")
    assert len(doc["skins"]) == 4  # leader, buddy, porter (walker.glb), hound
    assert len(doc["animations"]) == 3 * len(walker["animations"]) + len(hound["animations"])
    by_name: dict = {}
    for n in doc["nodes"]:  # the avatars' own nodes come first (a model may reuse a name)
        by_name.setdefault(n.get("name"), n)
    for oid in ("leader", "buddy", "porter", "hound"):
        body = by_name[oid]["extensions"]["KHR_physics_rigid_bodies"]
        assert body["motion"] == {"isKinematic": True}
        capsule = by_name[f"{oid}.capsule"]["extensions"]["KHR_physics_rigid_bodies"]
        shape = doc["extensions"]["KHR_implicit_shapes"]["shapes"][
            capsule["collider"]["geometry"]["shape"]]
        assert shape["type"] == "capsule"
    model = load_skinned(out)
    assert model.skin_count == 4 and "Walk" in model.clip_names
    # imported again: the four capsules are kinematic bodies where the avatars stand
    again = load(tmp_path / "again", out)
    kinds = {oid: kind for oid, (kind, *_) in world(again).items()}
    assert all(kinds.get(oid) == "kinematic" for oid in ("leader", "buddy", "porter", "hound"))
