"""glTF physics imported and run: what the file declares is what the scene has, and the
motion it produces is the motion physics predicts (both backends, several time steps)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from app.bench import interchange_samples as samples_
from components import Joint, Physical, Trigger, Visual
from engine.assets import Assets
from engine.assets.gltf import GltfDocument
from engine.interchange import import_model
from engine.rotation import quat_to_matrix
from engine.scene import load_spec
from systems.triggers import TriggerEvent
from tests.interchange.helpers import Run, import_scene

pytest.importorskip("engine.physics.ode3d")

GRAVITY = 9.81
KHR = samples_.KHR


def declared(path: Path) -> dict[str, int]:
    """What a KHR file declares, counted from its JSON: bodies that move (a motion), static
    bodies (a collider with no motion or collider above it), shapes (colliders and
    trigger geometries), triggers (roots of trigger geometry) and joints."""
    doc = GltfDocument.read(path)
    ext = [n.get("extensions", {}).get(KHR, {}) for n in doc.nodes]

    def above(i: int, key: str) -> bool:
        p = int(doc.parents[i])
        while p >= 0:
            if key in ext[p]:
                return True
            p = int(doc.parents[p])
        return False

    members = {m for e in ext for m in e.get("trigger", {}).get("nodes", [])}
    return {
        "moving": sum("motion" in e for e in ext),
        "static": sum("collider" in e and "motion" not in e and not above(i, "motion")
                      and not above(i, "collider") for i, e in enumerate(ext)),
        "shapes": sum("collider" in e or "geometry" in e.get("trigger", {}) for e in ext),
        "triggers": sum("trigger" in e and i not in members for i, e in enumerate(ext)),
        "joints": sum("joint" in e for e in ext),
    }


def built(path: Path) -> dict[str, int]:
    spec = load_spec(import_scene(path))
    comps = [{type(c): c for c in es.components} for es in spec.entities]
    bodies = [c[Physical] for c in comps if Physical in c]
    return {
        "moving": sum(p.kind != "static" for p in bodies),
        "static": sum(p.kind == "static" for p, c in zip(bodies, [c for c in comps
                                                                   if Physical in c],
                                                          strict=True) if Trigger not in c),
        "shapes": sum(len(p.shapes) for p in bodies),
        "triggers": sum(Trigger in c for c in comps),
        "joints": len(spec.joints),
    }


@pytest.mark.parametrize("name", ["shapes.glb", "joints.glb", "materials.glb", "filters.glb",
                                  "triggers.glb", "blender.glb"])
def test_the_scene_has_the_bodies_shapes_and_joints_the_file_declares(models, name):
    assert built(models / name) == declared(models / name)


def test_every_shape_kind_becomes_its_primitive_or_mesh(models):
    spec = load_spec(import_scene(models / "shapes.glb"))
    kinds = {es.id: [s.kind for s in c.shapes] for es in spec.entities
             for c in es.components if isinstance(c, Physical)}
    assert kinds == {"Ground": ["plane"], "Block": ["box"], "Slab": ["mesh"], "Box": ["box"],
                     "Sphere": ["sphere"], "Capsule": ["capsule"], "Cylinder": ["cylinder"],
                     "Hull": ["hull"], "Compound": ["box", "box"], "Crate": ["box"],
                     "Pebble": ["sphere"]}
    box = next(c for es in spec.entities if es.id == "Box" for c in es.components
               if isinstance(c, Physical))
    # glTF [x y z] with y up is [x z y] here, Z up; the KHR mass is kept
    assert box.shapes[0].size == (0.4, 0.8, 0.6) and box.mass == 2.0
    compound = next(c for es in spec.entities if es.id == "Compound" for c in es.components
                    if isinstance(c, Physical))
    assert [s.offset for s in compound.shapes] == [(-0.4, 0.0, 0.0), (0.4, 0.0, 0.0)]


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_bodies_dropped_on_the_imported_ground_come_to_rest_on_it(models, backend, dt):
    with Run.start(import_scene(models / "shapes.glb"), backend, dt) as run:
        run.step(3.0)
        for oid, height in samples_.SHAPES_REST.items():
            assert run.position(oid)[2] == pytest.approx(height, abs=0.005), oid
            assert np.linalg.norm(run.velocity(oid)) < 1e-3, oid


@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_joints_hold_their_limits_and_drive_their_motors(models, dt):
    with Run.start(import_scene(models / "joints.glb"), "ode", dt) as run:
        weld = run.position("FixedB") - run.position("FixedA")
        run.step(4.0)
        # the arm, hinged at (0 0 3) and 0.5 m to its centre, droops to its lower limit
        arm = run.position("Arm")
        assert math.asin((3 - arm[2]) / 0.5) == pytest.approx(-samples_.HINGE_LOW, abs=2e-3)
        # the wheel turns about its axle (glTF +Z is -Y here) at the drive's velocity
        np.testing.assert_allclose(run.spin("Wheel"), (0, -samples_.MOTOR_SPEED, 0), atol=1e-3)
        # the lift slides down its rail to the lower limit; the cart rides at the drive's speed
        assert run.position("Lift")[2] == pytest.approx(3 + samples_.SLIDER_LOW, abs=1e-3)
        np.testing.assert_allclose(run.velocity("Cart"), (samples_.SLIDER_SPEED, 0, 0),
                                   atol=1e-3)
        assert run.position("Cart")[2] == pytest.approx(3, abs=1e-3)
        # the ball joint keeps the bob at its distance; the gimbal its cross
        bob = np.linalg.norm(run.position("Bob") - (-3, 1, 3))
        assert bob == pytest.approx(math.sqrt(2), rel=0.015)
        assert np.linalg.norm(run.position("Cross") - (-9, 0, 3)) == pytest.approx(1, rel=1e-3)
        # the welded pair fell and tumbled as one: the offset in the first body's frame holds
        rotation = quat_to_matrix(run.transform("FixedA").orientation)
        offset = rotation.T @ (run.position("FixedB") - run.position("FixedA"))
        np.testing.assert_allclose(offset, weld, atol=5e-3)


def test_joint_kinds_limits_and_motors_as_written(models):
    spec = load_spec(import_scene(models / "joints.glb"))
    joints = {js.id: js.joint for js in spec.joints}
    kinds = {jid: j.kind for jid, j in joints.items()}
    assert kinds == {"HingeFrame": "hinge", "WheelAxle": "motorized_hinge",
                     "LiftRail": "slider", "CartRail": "slider", "Pivot": "ball",
                     "jointSpaceA": "fixed", "Gimbal": "universal"}
    hinge: Joint = joints["HingeFrame"]
    assert (hinge.low, hinge.high) == pytest.approx((samples_.HINGE_LOW, samples_.HINGE_HIGH))
    lift = joints["LiftRail"]
    assert (lift.low, lift.high) == pytest.approx((samples_.SLIDER_LOW, samples_.SLIDER_HIGH))
    assert joints["WheelAxle"].motor_velocity == pytest.approx(samples_.MOTOR_SPEED)
    assert joints["WheelAxle"].motor_max_force == 100.0


@pytest.mark.parametrize("backend,tolerance", [("ode", 0.03), ("pymunk", 0.25)])
@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_friction_and_restitution_from_the_file_change_the_motion(models, backend, tolerance,
                                                                  dt):
    """Sliding boxes stop after v^2 / (2 mu g), mu the lower friction (the file's
    "minimum"); a ball dropped from h rebounds to e^2 h, e the higher restitution. pymunk
    solves friction iteratively on two contact points, so it is held to less."""
    with Run.start(import_scene(models / "materials.glb"), backend, dt) as run:
        start = {oid: run.position(oid)[0] for oid in ("Slider", "Gripper")}
        peak = {"Bouncy": 0.0, "Dead": 0.0}
        rising = dict.fromkeys(peak, False)
        for _ in range(int(round(2.0 / dt))):
            run.engine.step()
            for oid in peak:
                rising[oid] |= run.velocity(oid)[2] > 0.05
                if rising[oid]:
                    peak[oid] = max(peak[oid], run.position(oid)[2] - 0.2)
        run.step(2.0)
        for oid, mu in (("Slider", samples_.SLOW_FRICTION), ("Gripper",
                                                            samples_.GRIP_FRICTION)):
            slid = run.position(oid)[0] - start[oid]
            assert slid == pytest.approx(samples_.SLIDE_SPEED ** 2 / (2 * mu * GRAVITY),
                                         rel=tolerance), oid
        assert peak["Bouncy"] == pytest.approx(samples_.BOUNCY ** 2 * samples_.DROP_HEIGHT,
                                               rel=0.03)
        assert peak["Dead"] < 0.01


def test_combine_modes_become_material_pairs(models):
    spec = load_spec(import_scene(models / "materials.glb"))
    frictions = {frozenset((p.a, p.b)): p.friction for p in spec.material_pairs}
    assert frictions[frozenset(("materials.material0", "materials.material1"))] == 0.1
    assert frictions[frozenset(("materials.material0", "materials.material2"))] == 0.4
    bounces = {frozenset((p.a, p.b)): p.bounce for p in spec.material_pairs}
    assert bounces[frozenset(("materials.material0", "materials.material3"))] == 0.8


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_collision_filters_decide_who_meets_the_ground(models, backend):
    with Run.start(import_scene(models / "filters.glb"), backend) as run:
        run.step(1.5)
        assert run.position("Prop")[2] == pytest.approx(0.25, abs=0.005)
        free_fall = 1 - GRAVITY * 1.5 ** 2 / 2
        for oid in ("Ghost", "Shy"):  # fell through the ground as if it were not there
            assert run.position(oid)[2] == pytest.approx(free_fall, abs=0.2), oid


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_triggers_tell_who_enters_and_collide_with_nothing(models, backend):
    with Run.start(import_scene(models / "triggers.glb"), backend) as run:
        told: list[tuple[str, str, bool]] = []
        names = {entity: oid for oid, entity in run.ids.items()}
        run.engine.events.subscribe(TriggerEvent, lambda e: told.append(
            (names[e.trigger], names[e.other], e.entered)))
        run.step(2.0)
        assert sorted(told) == [("Gate", "Runner", True), ("Zone", "Dropper", True)]
        for oid in ("Dropper", "Runner", "Outsider"):  # fell through the triggers to the floor
            assert run.position(oid)[2] == pytest.approx(0.2, abs=0.005)


def test_the_visual_is_the_nodes_own_mesh_from_the_model(models):
    spec = load_spec(import_scene(models / "shapes.glb"))
    visual = next(c for es in spec.entities if es.id == "Box" for c in es.components
                  if isinstance(c, Visual))
    assert visual.model == 'shapes.glb#["Box"]'
    model = Assets(models).model(visual.model)
    # the box mesh, 0.4 x 0.6 x 0.8 in glTF (Y up), is 0.4 x 0.8 x 0.6 here, in the node's frame
    np.testing.assert_allclose(model.bounds, [[-0.2, -0.4, -0.3], [0.2, 0.4, 0.3]], atol=1e-6)


def test_omi_physics_bodies_shapes_and_joints(models):
    imported = import_model("omi.gltf", "omi.gltf", Assets(models))
    assert not [d for d in imported.problems if d.is_error]
    scene = imported.scene
    kinds = {o.id: (o.kind, o.trigger) for o in scene.objects}
    assert kinds == {"Ground": ("static", False), "Ball": ("dynamic", False),
                     "Lifter": ("kinematic", False), "Zone": ("static", True),
                     "Door": ("dynamic", False), "Frame": ("static", False),
                     "WeldA": ("dynamic", False), "WeldB": ("dynamic", False),
                     "Turntable": ("dynamic", False)}
    joints = {j.id: j for j in scene.joints}
    hinge = joints["DoorHinge"]
    # joined to the static frame: it is named after the door (the world's side), so the
    # two never touch (issue 31: jointed bodies do not collide unless the file asks)
    assert (hinge.type, hinge.bodies) == ("Hinge", ("Door", "Frame"))
    assert (hinge.low, hinge.high) == pytest.approx((-math.degrees(1.5), math.degrees(1.5)))
    # one limit naming linear and angular axes at once is a weld (it was read as a ball)
    assert (joints["WeldJoint"].type, joints["WeldJoint"].bodies) == ("Fixed",
                                                                      ("WeldB", "WeldA"))
    # OMI's negative maxForce is "not force-limited" (the motor was dropped in silence):
    # the motor gets what damping x target velocity asks
    table = joints["TurntableAxle"]
    assert table.type == "MotorizedHinge" and table.motor_max_force == pytest.approx(
        10.0 * samples_.OMI_SPIN)
    with Run.start(import_scene(models / "omi.gltf")) as run:
        weld = run.position("WeldB") - run.position("WeldA")
        run.step(2.0)
        assert run.position("Ball")[2] == pytest.approx(0.25, abs=0.005)
        # the welded pair landed as one body; the turntable turns at the drive's rate
        # (glTF +Y is +Z here)
        np.testing.assert_allclose(run.position("WeldB") - run.position("WeldA"), weld,
                                   atol=2e-3)
        np.testing.assert_allclose(run.spin("Turntable"), (0, 0, samples_.OMI_SPIN),
                                   atol=1e-3)


def test_khr_velocities_are_in_node_space_omi_velocities_in_world_axes(tmp_path):
    """KHR: "initial linear velocity of the rigid body in node space" (its reference
    importer turns it by the node's rotation); OMI says nothing and Godot writes world
    velocities. A node turned 90 degrees about glTF Y sends its local X to glTF -Z, which
    is +Y here (Z up)."""
    b = samples_.GltfBuilder()
    turned = samples_._quat_about((0, 1, 0), math.pi / 2)
    ball = b.node("Ball", (0, 0, 5), rotation=turned)
    b.khr(ball, motion={"mass": 1, "linearVelocity": [1, 0, 0],
                        "angularVelocity": [0, 0, 2]},
          collider={"geometry": b.shape("sphere", radius=0.2)})
    b.node("Godot", (2, 0, 5), rotation=turned, ext={samples_.OMI_BODY: {
        "motion": {"type": "dynamic", "linearVelocity": [1, 0, 0]}}})
    path = b.write(tmp_path / "spin.gltf")
    scene = import_model(path.name, path.name, Assets(tmp_path)).scene
    by_id = {o.id: o for o in scene.objects}
    np.testing.assert_allclose(by_id["Ball"].velocity, (0, 1, 0), atol=1e-9)
    # local glTF Z turns to glTF +X: the spin is about X here
    np.testing.assert_allclose(by_id["Ball"].angular_velocity, (2, 0, 0), atol=1e-9)
    np.testing.assert_allclose(by_id["Godot"].velocity, (1, 0, 0), atol=1e-9)
    with Run.start(import_scene(path)) as run:
        np.testing.assert_allclose(run.velocity("Ball"), (0, 1, 0), atol=1e-9)


def test_an_omi_body_without_mass_weighs_one_kilogram(tmp_path):
    """OMI_physics_body's mass defaults to 1 kg; KHR leaves a missing mass to the shapes'
    volume (at water's density here)."""
    b = samples_.GltfBuilder()
    b.doc.setdefault("extensions", {})[samples_.OMI_SHAPE] = {
        "shapes": [{"type": "box", "box": {"size": [1, 1, 1]}}]}
    b.use(samples_.OMI_SHAPE)
    b.node("Crate", (0, 0, 1), ext={samples_.OMI_BODY: {"motion": {"type": "dynamic"},
                                                        "collider": {"shape": 0}}})
    khr = b.node("Block", (3, 0, 1))
    b.khr(khr, motion={}, collider={"geometry": b.shape("box", size=[1, 1, 1])})
    path = b.write(tmp_path / "masses.gltf")
    spec = load_spec(import_scene(path))
    bodies = {es.id: c for es in spec.entities for c in es.components
              if isinstance(c, Physical)}
    assert bodies["Crate"].mass == 1.0
    assert bodies["Block"].mass is None and bodies["Block"].material.density == 1000.0


@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_an_acceleration_drive_without_force_limit_accelerates_as_damping_asks(tmp_path, dt):
    """An "acceleration" drive scales its force by the driven axis's inertia: from rest it
    turns the body at damping x target velocity (rad/s^2) whatever the body weighs. The
    motor gets that torque: the bar's moment of inertia about the hinge (m (x^2 + z^2) /
    12 + m d^2) times damping x target velocity, and ODE, which weighs the bar itself,
    spins it up at that rate."""
    damping, target, mass = 2.0, 1.0, 3.0
    b = samples_.GltfBuilder()
    bar = b.node("Bar", (0.5, 0, 1))
    b.khr(bar, motion={"mass": mass}, collider={"geometry": b.shape("box",
                                                                    size=[1, 0.2, 0.2])})
    samples_._joint(b, "Hinge", None, bar, (0, 0, 1), (-0.5, 0, 0),
                    samples_.LOCK_LINEAR + samples_._locked("angular", (0, 2)),
                    [{"type": "angular", "mode": "acceleration", "axis": 1,
                      "velocityTarget": target, "damping": damping}])
    path = b.write(tmp_path / "bar.gltf")
    (joint,) = import_model(path.name, path.name, Assets(tmp_path)).scene.joints
    inertia = mass * (1 + 0.04) / 12 + mass * 0.5 ** 2
    assert joint.motor_max_force == pytest.approx(damping * target * inertia, rel=1e-6)
    with Run.start(import_scene(path), dt=dt) as run:
        run.step(0.2)
        assert np.linalg.norm(run.spin("Bar")) == pytest.approx(damping * target * 0.2,
                                                                rel=0.02)


@pytest.mark.parametrize("dt", [0.01, 0.005])
def test_a_file_laid_out_as_blender_writes_it_moves_as_it_declares(models, dt):
    """Blender 4.4's layout: mesh colliders on bare data nodes, scaled by the collider's
    node; a kinematic glider, a weightless floater, an infinitely heavy anvil; a wheel
    driven in acceleration mode with no force limit."""
    with Run.start(import_scene(models / "blender.glb"), "ode", dt) as run:
        glider = run.position("Glider")
        run.step(1.5)
        # the floor reaches x = 10 (5 m scaled by 2): the far box rests on it
        assert run.position("FarBox")[2] == pytest.approx(0.25, abs=0.005)
        np.testing.assert_allclose(run.position("Glider") - glider,
                                   (0, samples_.GLIDE_SPEED * 1.5, 0), atol=1e-6)
        for oid in ("Floater", "Anvil"):  # neither falls
            assert run.position(oid)[2] == pytest.approx(2, abs=1e-6), oid
        # the wheel turns about glTF Z (-Y here) at the drive's target, the file's sense
        np.testing.assert_allclose(run.spin("Wheel"), (0, -samples_.WHEEL_TARGET, 0),
                                   atol=1e-3)
