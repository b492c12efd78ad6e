"""Export: a scene as glTF with KHR physics, and back: import(export(scene)) has the same
bodies, shapes, masses, materials, filters and joints, and moves the same."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from app.cli import main
from app.scene_loading import export_path
from components import Physical, Transform, Trigger
from engine.assets.gltf import GltfDocument
from engine.rotation import quat_to_matrix
from engine.scene import load_spec
from services.export import export_gltf, volume
from tests.interchange.helpers import Run, import_scene

pytest.importorskip("engine.physics.ode3d")

SCENE = """
Material { ID "rubber" Friction 0.9 Bounce 0.6 }
Material { ID "ice" Friction 0.05 }
Object { ID "ground" Dynamic 0
  VisualAttributes { Color [0.3 0.5 0.3]
                     Geometry { Primitive "box" Size [20 20 0.1] Offset [0 0 -0.05] } }
  PhysicalAttributes { Material "ice" Geometry { Primitive "plane" } } }
Object { ID "crate" Position [0 0 1] Orientation [0 0 30]
  PhysicalAttributes { Mass 3 Material "rubber" Geometry { Primitive "box" Size [0.4 0.6 0.8] } } }
Object { ID "ball" Position [1 0 1] Orientation [0 0 90] Velocity [1 0 2] AngularVelocity [0 90 0]
  PhysicalAttributes { Density 500 Geometry { Primitive "sphere" Size [0.5] } } }
Object { ID "pill" Position [2 0 1] Orientation [90 0 0]
  PhysicalAttributes { Mass 1 Category 2 Mask 3 Geometry { Primitive "capsule" Size [0.4 0.6] } } }
Object { ID "can" Position [3 0 2] Kinematic 1
  PhysicalAttributes { Geometry { Primitive "cylinder" Size [0.6 0.5] } } }
Object { ID "dumbbell" Position [4 0 1]
  PhysicalAttributes { Mass 2
    Geometry { Primitive "sphere" Size [0.3] Offset [-0.3 0 0] }
    Geometry { Primitive "sphere" Size [0.3] Offset [0.3 0 0] }
    Geometry { Primitive "box" Size [0.6 0.1 0.1] Orientation [0 0 45] } } }
Object { ID "gem" Position [5 0 1]
  VisualAttributes { Geometry { File "gem.obj" } }
  PhysicalAttributes { Mass 1 Geometry { File "gem.obj" ParseMethod "ConvexHull" } } }
Object { ID "zone" Position [0 3 0.5] Dynamic 0
  PhysicalAttributes { Trigger 1 Mask 2 Geometry { Primitive "box" Size [1 1 1] } } }
Object { ID "arm" Position [0.5 -3 3]
  PhysicalAttributes { Geometry { Primitive "box" Size [1 0.1 0.1] } } }
Object { ID "wheel" Position [3 -3 3] Orientation [90 0 0]
  PhysicalAttributes { Geometry { Primitive "cylinder" Size [0.8 0.1] } } }
Object { ID "cart" Position [6 -3 3]
  PhysicalAttributes { Geometry { Primitive "box" Size [0.3 0.3 0.3] } } }
Object { ID "bob" Position [-3 -3 2]
  PhysicalAttributes { Geometry { Primitive "sphere" Size [0.2] } } }
Object { ID "a" Position [-6 -3 1]
  PhysicalAttributes { Geometry { Primitive "box" Size [0.4 0.4 0.4] } } }
Object { ID "b" Position [-5.5 -3 1.3]
  PhysicalAttributes { Geometry { Primitive "box" Size [0.4 0.4 0.4] } } }
Object { ID "cross" Position [-9 -3 2]
  PhysicalAttributes { Geometry { Primitive "box" Size [0.2 0.2 0.2] } } }
Joint { ID "hinge" Type "Hinge" Bodies ["arm"] Anchor [0 -3 3] Axis [0 1 0] Low -20 High 45 }
Joint { ID "motor" Type "MotorizedHinge" Bodies ["wheel"] Anchor [3 -3 3] Axis [0 -1 0]
  MotorVelocity 90 MotorMaxForce 50 }
Joint { ID "rail" Type "Slider" Bodies ["cart"] Anchor [6 -3 3] Axis [1 0 0] Low -0.5 High 0.25
  MotorVelocity 0.5 MotorMaxForce 20 }
Joint { ID "pivot" Type "Ball" Bodies ["bob"] Anchor [-3 -2 3] }
Joint { ID "weld" Type "Fixed" Bodies ["b" "a"] Anchor [-5.75 -3 1.15] }
Joint { ID "gimbal" Type "Universal" Bodies ["cross"] Anchor [-9 -3 3] Axis [1 0 0]
  Axis2 [0 1 0] Low -30 High 30 }
Object { ID "weight" Position [8 -3 3] Orientation [0 0 20]
  PhysicalAttributes { Mass 2 CenterOfMass [0.1 0 -0.4] Inertia [0.04 0.03 0.02]
    InertiaOrientation [10 0 45] Geometry { Primitive "sphere" Size [0.1] } } }
Joint { ID "swing" Type "Hinge" Bodies ["weight"] Anchor [8 -3 3] Axis [0 1 0]
  Spring { Stiffness 0.02 Damping 0.001 Target 15 MaxForce 5 } }
Object { ID "slide" Position [10 -3 3]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.2 0.2 0.2] } } }
Joint { ID "spring" Type "Slider" Bodies ["slide"] Anchor [10 -3 3] Axis [1 0 0]
  Low -0.3 High 0.3 Spring { Stiffness 40 Target 0.1 } }
"""

OCTAHEDRON = """v 0.3 0 0\nv -0.3 0 0\nv 0 0.3 0\nv 0 -0.3 0\nv 0 0 0.3\nv 0 0 -0.3
f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6
"""


@pytest.fixture
def scene(tmp_path: Path) -> Path:
    (tmp_path / "gem.obj").write_text(OCTAHEDRON)
    (tmp_path / "main.scene").write_text(SCENE)
    return tmp_path


def round_trip(scene: Path, name: str = "out.glb") -> tuple[Path, Path]:
    out = scene / name
    assert export_path(scene, out) == 0
    return out, import_scene(out, scene / "again.scene")


def parts(spec):
    return {es.id: {type(c): c for c in es.components} for es in spec.entities
            if not es.skipped}


def tensor(p: Physical) -> np.ndarray:
    """A body's given inertia tensor in its frame (principal axes may come back in
    another order; the tensor is the same)."""
    turn = quat_to_matrix(np.asarray(p.inertia_rotation))
    return turn @ np.diag(p.inertia) @ turn.T


def collides(a: Physical, b: Physical) -> bool:
    return bool(a.category & b.mask) and bool(b.category & a.mask)


@pytest.mark.parametrize("name", ["out.glb", "out.gltf"])
def test_import_of_export_keeps_bodies_shapes_masses_materials_and_joints(scene, name):
    original = load_spec(scene)
    _, again_path = round_trip(scene, name)
    again = load_spec(again_path)
    before, after = parts(original), parts(again)
    bodies = [oid for oid, c in before.items() if Physical in c]
    assert sorted(oid for oid, c in after.items() if Physical in c) == sorted(bodies)
    for oid in bodies:
        p, q = before[oid][Physical], after[oid][Physical]
        assert (q.kind, Trigger in after[oid]) == (p.kind, Trigger in before[oid]), oid
        if p.kind == "dynamic":  # the mass the engine gave it (the ball's from its density)
            expected = p.mass if p.mass is not None else 500 * volume(p.shapes[0])
            assert q.mass == pytest.approx(expected), oid
        assert (q.material.friction, q.material.bounce) == (p.material.friction,
                                                            p.material.bounce), oid
        assert [s.kind for s in q.shapes] == [s.kind for s in p.shapes], oid
        for s, t in zip(p.shapes, q.shapes, strict=True):
            if s.kind in ("mesh", "hull"):
                assert volume(t) == pytest.approx(volume(s)), oid
            else:
                np.testing.assert_allclose(t.size, s.size, atol=1e-6, err_msg=oid)
                np.testing.assert_allclose(t.offset, s.offset, atol=1e-6, err_msg=oid)
                assert abs(np.dot(t.rotation, s.rotation)) == pytest.approx(1, abs=1e-6)
        assert (q.center_of_mass is None) == (p.center_of_mass is None), oid
        if p.center_of_mass is not None:
            np.testing.assert_allclose(q.center_of_mass, p.center_of_mass, atol=1e-6)
        assert (q.inertia is None) == (p.inertia is None), oid
        if p.inertia is not None:
            np.testing.assert_allclose(tensor(q), tensor(p), atol=1e-7, err_msg=oid)
        tp, tq = before[oid][Transform], after[oid][Transform]
        np.testing.assert_allclose(tq.position, tp.position, atol=1e-6, err_msg=oid)
        assert abs(tq.orientation @ tp.orientation) == pytest.approx(1, abs=1e-6), oid
        np.testing.assert_allclose(tq.linear_velocity, tp.linear_velocity, atol=1e-6)
        np.testing.assert_allclose(tq.angular_velocity, tp.angular_velocity, atol=1e-6)
    for x in bodies:  # collision filters keep who meets whom (bits may be renumbered)
        for y in bodies:
            pair = (before[x][Physical], before[y][Physical])
            assert collides(after[x][Physical], after[y][Physical]) == collides(*pair), (x, y)
    joints = {js.id: js for js in original.joints}
    again_joints = {js.id: js for js in again.joints}
    assert sorted(again_joints) == sorted(joints)
    for jid, js in joints.items():
        j, k = js.joint, again_joints[jid].joint
        assert (k.kind, again_joints[jid].bodies) == (j.kind, js.bodies), jid
        assert (k.low, k.high) == pytest.approx((j.low, j.high)), jid
        assert (k.motor_velocity, k.motor_max_force) == pytest.approx(
            (j.motor_velocity, j.motor_max_force)), jid
        assert (k.spring is None) == (j.spring is None), jid
        if j.spring is not None:
            assert (k.spring.stiffness, k.spring.damping, k.spring.target,
                    k.spring.max_force) == pytest.approx((
                        j.spring.stiffness, j.spring.damping, j.spring.target,
                        j.spring.max_force), rel=1e-6), jid
        np.testing.assert_allclose(k.anchor, j.anchor, atol=1e-6, err_msg=jid)
        if j.kind not in ("ball", "fixed"):  # those have no axis
            np.testing.assert_allclose(k.axis, j.axis, atol=1e-6, err_msg=jid)


def test_the_exported_file_is_the_khr_extensions_as_blender_reads_them(scene):
    out, _ = round_trip(scene)
    doc = GltfDocument.read(out)
    assert {"KHR_physics_rigid_bodies", "KHR_implicit_shapes"} <= set(
        doc.json["extensionsUsed"])
    khr = doc.json["extensions"]["KHR_physics_rigid_bodies"]
    assert {m["name"] for m in khr["physicsMaterials"]} >= {"rubber", "ice"}
    crate = next(n for n in doc.nodes if n["name"] == "crate")
    assert crate["extensions"]["KHR_physics_rigid_bodies"]["motion"]["mass"] == 3
    assert crate["translation"] == pytest.approx([0, 1, 0])  # Z up here is glTF's Y up
    json.dumps(doc.json)  # plain JSON: no NaN, no numpy values


def test_an_exported_state_moves_like_the_scene(scene):
    """Drop both for a second: the imported export lands where the original does (within
    millimetres: the import writes numbers at a model file's float32 precision, and
    contacts amplify a last-digit difference)."""
    _, again = round_trip(scene)
    ends = []
    for path in (scene / "main.scene", again):
        with Run.start(path) as run:
            run.step(1.0)
            ends.append({oid: run.position(oid) for oid in ("crate", "ball", "pill", "gem",
                                                           "arm", "cart", "bob", "weight",
                                                           "slide")})
    for oid in ends[0]:
        np.testing.assert_allclose(ends[1][oid], ends[0][oid], atol=5e-3, err_msg=oid)


def test_what_gltf_cannot_say_is_told(scene):
    (scene / "main.scene").write_text(SCENE + 'MaterialPair { Material1 "rubber" Material2 '
                                              '"ice" Friction 2 }\n')
    told = export_gltf(load_spec(scene), scene / "out.glb")
    assert any("material pair rubber/ice is not exported" in d.message for d in told)


def test_an_exported_saved_state_keeps_every_bodys_pose_and_velocity(scene):
    """``colosseum run --save-state`` mid-fall, then ``colosseum export`` of the state: the
    file imports with each body where the state has it, moving as it moved then."""
    state = scene / "state.scene"
    assert main(["run", str(scene), "--headless", "--fast", "--seconds", "0.4",
                 "--save-state", str(state)]) == 0
    saved = parts(load_spec(state))
    out = scene / "state.glb"
    assert export_path(state, out) == 0
    again = parts(load_spec(import_scene(out, scene / "again.scene")))
    moving = [oid for oid, c in saved.items() if Physical in c and c[Physical].kind == "dynamic"]
    assert any(np.linalg.norm(saved[oid][Transform].linear_velocity) > 1 for oid in moving)
    for oid, c in saved.items():
        if Physical not in c:
            continue
        tp, tq = c[Transform], again[oid][Transform]
        np.testing.assert_allclose(tq.position, tp.position, rtol=1e-6, atol=1e-6, err_msg=oid)
        assert abs(tq.orientation @ tp.orientation) == pytest.approx(1, abs=1e-6), oid
        np.testing.assert_allclose(tq.linear_velocity, tp.linear_velocity, rtol=1e-5,
                                   atol=1e-6, err_msg=oid)
        np.testing.assert_allclose(tq.angular_velocity, tp.angular_velocity, rtol=1e-5,
                                   atol=1e-6, err_msg=oid)
    # its joints hold where the state's do: limits, springs and motors counted from where
    # each joint was first made (its frames are written there), the bodies elsewhere now
    ends = []
    for path in (state, scene / "again.scene"):
        with Run.start(path) as run:
            run.step(1.0)
            ends.append({oid: run.position(oid) for oid in ("arm", "wheel", "cart", "bob",
                                                           "weight", "slide")})
    for oid in ends[0]:
        np.testing.assert_allclose(ends[1][oid], ends[0][oid], atol=5e-3, err_msg=oid)
