"""Model files for the importer's tests and benchmark, written as Blender's physics add-on
and Godot write them: glTF 2.0 with KHR_physics_rigid_bodies + KHR_implicit_shapes (joint
frames as child nodes ``jointSpaceA``/``jointSpaceB``, collision filters by system name,
mesh colliders by ``geometry.mesh`` as the add-on writes them since 2026, and by
``geometry.node`` on a bare data node as Blender 4.4 wrote the public KHR samples:
:func:`blender`), OMI_physics_body/shape/joint as Godot writes them, Blender custom
properties as ``extras``, and Collada 1.4 ``<physics_scene>`` (:func:`collada`, and as
Blender 2.42's exporter, ColladaMaya and Bullet's ColladaConverter lay it out).

No file another tool wrote is shipped: each function here writes, from this code, a
small scene in the layout that tool gives its files (:func:`blender` as Blender 4.4's KHR
add-on, :func:`godot_omi` as Godot 4.4's OMI export, :func:`blender_collada`,
:func:`maya_collada` and :func:`bullet_collada`), so the tests meet every quirk the
importer reads without carrying anyone else's files.

``python -m app.bench.interchange_samples DIR`` writes them all into DIR; the tests call the
functions into a temporary folder. Positions are given in the engine's axes (Z up) and
written in each format's own (glTF +Y up; Collada says Z_UP).
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from engine.interchange.gltf_physics import KHR, OMI_BODY, OMI_JOINT, OMI_SHAPE
from services.export import GltfWriter, to_gltf


def gl(p: Sequence[float]) -> list[float]:
    """A point in the engine's axes (Z up) in glTF's (+Y up)."""
    return to_gltf(p)


def box_mesh(size: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """A closed box of full extents ``size`` (glTF axes), centred: 8 vertices, 12 triangles."""
    h = np.asarray(size, np.float64) / 2
    v = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)]) * h
    f = np.array([[0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5], [0, 4, 5], [0, 5, 1],
                  [2, 3, 7], [2, 7, 6], [0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3]])
    return v, f


class GltfBuilder(GltfWriter):
    """A glTF document built node by node, nodes placed in the engine's axes."""

    def __init__(self) -> None:
        super().__init__("colosseum app/bench/interchange_samples.py")

    def node(self, name: str, at: Sequence[float] = (0, 0, 0),  # type: ignore[override]
             parent: int | None = None, rotation: Sequence[float] | None = None,
             scale: Sequence[float] | None = None, mesh: int | None = None,
             ext: dict[str, Any] | None = None, extras: dict[str, Any] | None = None,
             in_scene: bool = True) -> int:
        """A node at ``at`` (engine axes, relative to ``parent``); ``rotation`` is glTF's
        ``[x, y, z, w]`` in glTF axes."""
        return super().node(name, gl(at), parent, rotation, scale, mesh, ext, extras,
                            in_scene)


def _quat_about(axis: Sequence[float], angle: float) -> list[float]:
    """glTF's (x, y, z, w) for a turn of ``angle`` rad about ``axis`` (glTF axes)."""
    a = np.asarray(axis, np.float64) / np.linalg.norm(axis)
    s = math.sin(angle / 2)
    return [float(a[0] * s), float(a[1] * s), float(a[2] * s), math.cos(angle / 2)]


# -- KHR samples ------------------------------------------------------------------------
def _body(b: GltfBuilder, name: str, at: Sequence[float], geometry: dict[str, Any],
          size: Sequence[float], mass: float | None = 1.0, material: int | None = None,
          filter_index: int | None = None, rotation: Sequence[float] | None = None,
          **motion: Any) -> int:
    """A dynamic body drawn as a box of ``size`` (glTF axes) with one collider."""
    index = b.node(name, at, rotation=rotation, mesh=b.mesh(*box_mesh(size), f"{name}Mesh"))
    collider: dict[str, Any] = {"geometry": geometry}
    if material is not None:
        collider["physicsMaterial"] = material
    if filter_index is not None:
        collider["collisionFilter"] = filter_index
    parts: dict[str, Any] = {"collider": collider}
    if mass is not None or motion:
        parts["motion"] = {**({"mass": mass} if mass is not None else {}), **motion}
    b.khr(index, **parts)
    return index


def _ground_plane(b: GltfBuilder) -> int:
    ground = b.node("Ground", (0, 0, 0), mesh=b.mesh(*box_mesh((30, 0.02, 30)), "GroundMesh"))
    b.khr(ground, collider={"geometry": b.shape("plane", doubleSided=False)})
    return ground


def shapes(path: Path) -> Path:
    """Every collider kind, dropped onto an infinite plane, a static box and a static
    triangle mesh: 11 bodies (3 static), 12 shapes."""
    b = GltfBuilder()
    _ground_plane(b)
    block = b.node("Block", (8, 0, 0.2), mesh=b.mesh(*box_mesh((1, 0.4, 1)), "BlockMesh"))
    b.khr(block, collider={"geometry": b.shape("box", size=[1, 0.4, 1])})
    slab_mesh = b.mesh(*box_mesh((1, 0.2, 1)), "SlabMesh")
    slab = b.node("Slab", (10, 0, 0.1), mesh=slab_mesh)
    b.khr(slab, collider={"geometry": {"mesh": slab_mesh}})
    _body(b, "Box", (-4, 0, 1), b.shape("box", size=[0.4, 0.6, 0.8]), (0.4, 0.6, 0.8), mass=2)
    _body(b, "Sphere", (-3, 0, 1), b.shape("sphere", radius=0.25), (0.5, 0.5, 0.5))
    _body(b, "Capsule", (-2, 0, 1), b.shape("capsule", height=0.6, radiusTop=0.2,
                                            radiusBottom=0.2), (0.4, 1.0, 0.4),
          rotation=_quat_about((0, 0, 1), math.pi / 2))  # lying along X
    _body(b, "Cylinder", (-1, 0, 1), b.shape("cylinder", height=0.5, radiusTop=0.3,
                                             radiusBottom=0.3), (0.6, 0.5, 0.6))
    hull_mesh = b.mesh(*box_mesh((0.5, 0.5, 0.5)), "HullMesh")
    hull = b.node("Hull", (0, 0, 1), mesh=hull_mesh)
    b.khr(hull, motion={"mass": 1}, collider={"geometry": {"mesh": hull_mesh,
                                                           "convexHull": True}})
    compound = b.node("Compound", (1.5, 0, 1))
    b.khr(compound, motion={"mass": 1})
    for side, x in (("Left", -0.4), ("Right", 0.4)):
        part = b.node(side, (x, 0, 0), parent=compound,
                      mesh=b.mesh(*box_mesh((0.3, 0.3, 0.3)), "PartMesh"))
        b.khr(part, collider={"geometry": b.shape("box", size=[0.3, 0.3, 0.3])})
    _body(b, "Crate", (8, 0, 2), b.shape("box", size=[0.5, 0.5, 0.5]), (0.5, 0.5, 0.5))
    _body(b, "Pebble", (10, 0, 2), b.shape("sphere", radius=0.2), (0.4, 0.4, 0.4))
    return b.write(path)


#: Where each body of :func:`shapes` comes to rest (its centre's height, m): the ground,
#: the static block's top (0.4) or the slab's (0.2), plus the body's half height.
SHAPES_REST = {"Box": 0.3, "Sphere": 0.25, "Capsule": 0.2, "Cylinder": 0.25, "Hull": 0.25,
               "Compound": 0.15, "Crate": 0.65, "Pebble": 0.4}


def _joint(b: GltfBuilder, name: str, owner: int | None, connected: int,
           at_owner: Sequence[float], at_connected: Sequence[float],
           limits: list[dict[str, Any]],
           drives: list[dict[str, Any]] | None = None,
           rotation_b: Sequence[float] | None = None) -> int:
    """A KHR joint as Blender writes it: ``jointSpaceA`` under the first body (or at the
    root for the world) naming ``jointSpaceB`` under the second (turned by
    ``rotation_b`` in its body, so both frames start aligned)."""
    desc: dict[str, Any] = {"limits": limits}
    if drives:
        desc["drives"] = drives
    index = b.top(KHR, "physicsJoints", desc)
    space_b = b.node("jointSpaceB", at_connected, parent=connected, rotation=rotation_b)
    space_a = b.node(name if owner is None else "jointSpaceA", at_owner, parent=owner)
    b.khr(space_a, joint={"connectedNode": space_b, "joint": index})
    return space_a


LOCK_LINEAR = [{"linearAxes": [0, 1, 2], "max": 0}]


def _locked(kind: str, axes: Sequence[int]) -> list[dict[str, Any]]:
    return [{f"{kind}Axes": [a], "min": 0, "max": 0} for a in axes]


#: :func:`joints`' hinge limits (rad, about the hinge axis) and drive targets.
HINGE_LOW, HINGE_HIGH = -0.3, 1.0
MOTOR_SPEED = 2.0  # rad/s
SLIDER_LOW, SLIDER_HIGH = -0.5, 0.3
SLIDER_SPEED = 0.5  # m/s


def joints(path: Path) -> Path:
    """Every joint kind, with limits and drives: a hinged arm that droops to its lower
    limit, a motor-driven wheel, a vertical slider that falls to its lower limit, a
    motor-driven horizontal slider, a ball-joint pendulum, two bodies fixed together and a
    universal joint: 7 joints."""
    b = GltfBuilder()
    _ground_plane(b)
    arm = _body(b, "Arm", (0.5, 0, 3), b.shape("box", size=[1, 0.1, 0.1]), (1, 0.1, 0.1))
    _joint(b, "HingeFrame", None, arm, (0, 0, 3), (-0.5, 0, 0),
           LOCK_LINEAR + _locked("angular", (0, 1)) +
           [{"angularAxes": [2], "min": HINGE_LOW, "max": HINGE_HIGH}])
    wheel = _body(b, "Wheel", (3, 0, 3), b.shape("cylinder", height=0.1, radiusTop=0.4,
                                                 radiusBottom=0.4), (0.8, 0.1, 0.8),
                  rotation=_quat_about((1, 0, 0), math.pi / 2))  # axle along glTF Z
    _joint(b, "WheelAxle", None, wheel, (3, 0, 3), (0, 0, 0),
           LOCK_LINEAR + _locked("angular", (0, 1)),
           [{"type": "angular", "mode": "force", "axis": 2, "velocityTarget": MOTOR_SPEED,
             "maxForce": 100.0, "damping": 1000.0}],
           rotation_b=_quat_about((1, 0, 0), -math.pi / 2))
    lift = _body(b, "Lift", (6, 0, 3), b.shape("box", size=[0.3, 0.3, 0.3]), (0.3, 0.3, 0.3))
    _joint(b, "LiftRail", None, lift, (6, 0, 3), (0, 0, 0),
           _locked("linear", (0, 2)) + _locked("angular", (0, 1, 2)) +
           [{"linearAxes": [1], "min": SLIDER_LOW, "max": SLIDER_HIGH}])
    cart = _body(b, "Cart", (9, 0, 3), b.shape("box", size=[0.3, 0.3, 0.3]), (0.3, 0.3, 0.3))
    _joint(b, "CartRail", None, cart, (9, 0, 3), (0, 0, 0),
           _locked("linear", (1, 2)) + _locked("angular", (0, 1, 2)),
           [{"type": "linear", "mode": "force", "axis": 0, "velocityTarget": SLIDER_SPEED,
             "maxForce": 50.0, "damping": 1000.0}])
    bob = _body(b, "Bob", (-3, 0, 2), b.shape("sphere", radius=0.1), (0.2, 0.2, 0.2))
    _joint(b, "Pivot", None, bob, (-3, 1, 3), (0, 1, 1), LOCK_LINEAR)
    left = _body(b, "FixedA", (-6, 0, 1), b.shape("box", size=[0.4, 0.4, 0.4]), (0.4,) * 3)
    right = _body(b, "FixedB", (-5.5, 0, 1.3), b.shape("box", size=[0.4, 0.4, 0.4]), (0.4,) * 3)
    _joint(b, "Weld", left, right, (0.25, 0, 0.15), (-0.25, 0, -0.15),
           LOCK_LINEAR + [{"angularAxes": [0, 1, 2], "max": 0}])
    cross = _body(b, "Cross", (-9, 0, 2), b.shape("box", size=[0.2, 0.2, 0.2]), (0.2,) * 3)
    _joint(b, "Gimbal", None, cross, (-9, 0, 3), (0, 0, 1),
           LOCK_LINEAR + _locked("angular", (1,)))
    return b.write(path)


#: :func:`materials`' values: the ground's friction and each body's (all "minimum").
GROUND_FRICTION, SLOW_FRICTION, GRIP_FRICTION = 1.0, 0.1, 0.4
SLIDE_SPEED = 3.0  # m/s, the sliders' start
BOUNCY, DROP_HEIGHT = 0.8, 1.0  # restitution ("maximum"); the balls' drop (bottom, m)


def materials(path: Path) -> Path:
    """Two boxes sliding on the ground with different friction, two balls dropped with
    and without restitution: combine modes decide each pair (the lower friction, the
    higher restitution; an unsaid mode would be "average", which wins over both)."""
    b = GltfBuilder()
    ground_mat = b.top(KHR, "physicsMaterials", {"staticFriction": GROUND_FRICTION,
                                                 "dynamicFriction": GROUND_FRICTION,
                                                 "restitution": 0.0,
                                                 "frictionCombine": "minimum",
                                                 "restitutionCombine": "maximum"})
    ground = b.node("Ground", (0, 0, -0.5), mesh=b.mesh(*box_mesh((40, 1, 40)), "GroundMesh"))
    b.khr(ground, collider={"geometry": b.shape("box", size=[40, 1, 40]),
                            "physicsMaterial": ground_mat})
    for name, mu, y in (("Slider", SLOW_FRICTION, -2), ("Gripper", GRIP_FRICTION, 2)):
        mat = b.top(KHR, "physicsMaterials", {"staticFriction": mu, "dynamicFriction": mu,
                                              "restitution": 0.0, "frictionCombine": "minimum"})
        _body(b, name, (-10, y, 0.25), b.shape("box", size=[0.5, 0.5, 0.5]), (0.5,) * 3,
              material=mat, linearVelocity=gl((SLIDE_SPEED, 0, 0)))
    for name, e, y in (("Bouncy", BOUNCY, 6), ("Dead", 0.0, 8)):
        mat = b.top(KHR, "physicsMaterials", {"staticFriction": 0.5, "dynamicFriction": 0.5,
                                              "restitution": e,
                                              "restitutionCombine": "maximum"})
        _body(b, name, (0, y, DROP_HEIGHT + 0.2), b.shape("sphere", radius=0.2), (0.4,) * 3,
              material=mat)
    return b.write(path)


def filters(path: Path) -> Path:
    """Collision filters: a prop the ground holds, a ghost in a system the ground does not
    collide with, and a shy box that will not collide with the ground."""
    b = GltfBuilder()
    ground_filter = b.top(KHR, "collisionFilters", {"collisionSystems": ["Ground"],
                                                    "collideWithSystems": ["Ground", "Props"]})
    ground = b.node("Ground", (0, 0, -0.5), mesh=b.mesh(*box_mesh((20, 1, 20)), "GroundMesh"))
    b.khr(ground, collider={"geometry": b.shape("box", size=[20, 1, 20]),
                            "collisionFilter": ground_filter})
    for name, spec, x in (
            ("Prop", {"collisionSystems": ["Props"], "collideWithSystems": ["Ground"]}, -2),
            ("Ghost", {"collisionSystems": ["Ghosts"], "collideWithSystems": ["Ghosts"]}, 0),
            ("Shy", {"collisionSystems": ["Props"], "notCollideWithSystems": ["Ground"]}, 2)):
        _body(b, name, (x, 0, 1), b.shape("box", size=[0.5, 0.5, 0.5]), (0.5,) * 3,
              filter_index=b.top(KHR, "collisionFilters", spec))
    return b.write(path)


def triggers(path: Path) -> Path:
    """A box trigger a ball falls into, a compound trigger of two boxes (a ball falls into
    the second), and a ball that falls beside them: 2 triggers, 3 balls."""
    b = GltfBuilder()
    _ground_plane(b)
    zone = b.node("Zone", (0, 0, 0.5))
    b.khr(zone, trigger={"geometry": b.shape("box", size=[1, 1, 1])})
    gate = b.node("Gate", (4, 0, 0.5))
    parts = [b.node(f"GatePost{k}", (dx, 0, 0), parent=gate) for k, dx in ((1, -1), (2, 1))]
    for part in parts:
        b.khr(part, trigger={"geometry": b.shape("box", size=[0.6, 1, 0.6])})
    b.khr(gate, trigger={"nodes": parts})
    for name, x in (("Dropper", 0), ("Runner", 5), ("Outsider", -4)):
        _body(b, name, (x, 0, 3), b.shape("sphere", radius=0.2), (0.4,) * 3)
    return b.write(path)


def extras(path: Path) -> Path:
    """The paper's comment-field workflow: scene keys typed as Blender custom properties.
    A door that is a body only through its extras, a lamp with a text field, a crate whose
    extras override its KHR mass, a node whose extras have a typo, and the file's own
    extras declaring materials."""
    b = GltfBuilder()
    b.doc["extras"] = {"colosseum": 'Material { ID "wood" Friction 0.7 }\n'
                                    'Material { ID "metal" Friction 0.3 Bounce 0.2 }'}
    _ground_plane(b)
    b.node("Door", (0, 0, 1), mesh=b.mesh(*box_mesh((1, 2, 0.1)), "DoorMesh"),
           extras={"Mass": 2, "Material": "wood", "Sound": "knock.wav", "Script": "door.lua"})
    b.node("Lamp", (2, 0, 2), mesh=b.mesh(*box_mesh((0.3, 0.3, 0.3)), "LampMesh"),
           extras={"colosseum": 'Color [1 0.9 0.6]\nDynamic 0\n'
                                'PhysicalAttributes { Material "metal" }'})
    crate = _body(b, "Crate", (4, 0, 1), b.shape("box", size=[0.5, 0.5, 0.5]), (0.5,) * 3,
                  mass=5)
    b.doc["nodes"][crate]["extras"] = {"Mass": 7, "prop": "not a scene key"}
    b.node("Typo", (6, 0, 1), mesh=b.mesh(*box_mesh((0.2, 0.2, 0.2)), "TypoMesh"),
           extras={"colosseum": "Mas 3"})
    return b.write(path)


#: :func:`omi`'s turntable drive (rad/s about the vertical axis).
OMI_SPIN = 1.5


def omi(path: Path) -> Path:
    """OMI_physics_body, OMI_physics_shape and OMI_physics_joint as Godot writes them: a
    static ground, a dynamic ball, a kinematic box, a trigger, a hinged pair, two bodies
    welded by one limit over all six axes, and a turntable whose motor has OMI's
    negative (unlimited) maxForce."""
    b = GltfBuilder()
    shapes_: list[dict[str, Any]] = []

    def shape(kind: str, **params: Any) -> int:
        shapes_.append({"type": kind, kind: params})
        return len(shapes_) - 1

    def body(name: str, at: Sequence[float], motion: dict[str, Any] | None, shape_index: int,
             key: str = "collider") -> int:
        parent = b.node(name, at, ext={OMI_BODY: {"motion": motion}} if motion else None)
        b.node(f"{name}Shape", (0, 0, 0), parent=parent,
               ext={OMI_BODY: {key: {"shape": shape_index}}})
        return parent

    ground = b.node("Ground", (0, 0, -0.5), ext={OMI_BODY: {"motion": {"type": "static"}}})
    b.node("GroundShape", (0, 0, 0), parent=ground,
           ext={OMI_BODY: {"collider": {"shape": shape("box", size=[20, 1, 20])}}})
    body("Ball", (0, 0, 2), {"type": "dynamic", "mass": 2.0}, shape("sphere", radius=0.25))
    body("Lifter", (2, 0, 0.5), {"type": "kinematic"}, shape("box", size=[0.5, 0.5, 0.5]))
    zone = b.node("Zone", (0, 0, 0.5), ext={OMI_BODY: {"trigger": {"shape": shape(
        "box", size=[1, 1, 1])}}})
    del zone
    door = body("Door", (-3, 0, 1.5), {"type": "dynamic", "mass": 1.0},
                shape("box", size=[0.8, 1.6, 0.1]))
    frame = body("Frame", (-3.5, 0, 1.5), {"type": "static"}, shape("box", size=[0.1, 2, 0.1]))
    b.top(OMI_JOINT, "physicsJoints", {"limits": [
        {"linearAxes": [0, 1, 2], "min": 0, "max": 0},
        {"angularAxes": [0, 2], "min": 0, "max": 0},
        {"angularAxes": [1], "min": -1.5, "max": 1.5}]})
    hinge_b = b.node("DoorHingeB", (-0.45, 0, 0), parent=door)
    b.node("DoorHinge", (0.05, 0, 0), parent=frame,
           ext={OMI_JOINT: {"connectedNode": hinge_b, "joint": 0}})
    left = body("WeldA", (3, 2, 1), {"type": "dynamic", "mass": 1.0},
                shape("box", size=[0.4, 0.4, 0.4]))
    right = body("WeldB", (3.4, 2, 1), {"type": "dynamic", "mass": 1.0},
                 shape("box", size=[0.4, 0.4, 0.4]))
    weld = b.top(OMI_JOINT, "physicsJoints", {"limits": [
        {"linearAxes": [0, 1, 2], "angularAxes": [0, 1, 2], "min": 0.0, "max": 0.0}]})
    weld_b = b.node("WeldJointB", (-0.2, 0, 0), parent=right)
    b.node("WeldJoint", (0.2, 0, 0), parent=left,
           ext={OMI_JOINT: {"connectedNode": weld_b, "joint": weld}})
    table = body("Turntable", (-3, 3, 0.1), {"type": "dynamic", "mass": 2.0},
                 shape("cylinder", height=0.1, radiusTop=0.5, radiusBottom=0.5))
    spin = b.top(OMI_JOINT, "physicsJoints", {
        "limits": [{"linearAxes": [0, 1, 2], "min": 0, "max": 0},
                   {"angularAxes": [0, 2], "min": 0, "max": 0}],
        "drives": [{"type": "angular", "mode": "force", "axis": 1, "maxForce": -1,
                    "velocityTarget": OMI_SPIN, "damping": 10.0}]})
    table_b = b.node("TurntableAxleB", (0, 0, 0), parent=table)
    b.node("TurntableAxle", (-3, 3, 0.1), ext={OMI_JOINT: {"connectedNode": table_b,
                                                           "joint": spin}})
    b.doc.setdefault("extensions", {})[OMI_SHAPE] = {"shapes": shapes_}
    b.use(OMI_SHAPE)
    return b.write(path)


#: :func:`godot_omi`'s rope links: OMI capsules of one radius, their height over the caps
#: (m); the first link's tilt (rad, its far end down) and the links' start height (m).
LINK_RADIUS, LINK_HEIGHT = 0.05, 0.5
LINK_TILT, LINK_START = -0.35, 0.6


def godot_omi(path: Path) -> Path:
    """OMI physics as Godot 4.4 exports it (and OMI's drafts before September 2024 say):
    one root node (``GODOT_single_root``), bodies that give a motion type and no mass,
    every collider on a child node turned to its shape's axis with the drawn mesh below
    it, capsules as ``{radius, height}`` with the height over the caps, and a weld as one
    limit naming the linear and angular axes at once, its joint node under the first link
    turned back to world axes and its other frame a bare node under the second link. The
    rope's two links fall onto a static floor. Beside them, OMI's other layouts: a
    compound trigger listing two child triggers (a third child trigger is not listed, so
    is a trigger of its own), a kinematic body and a trigger whose shapes sit under a
    bare node between, and a kinematic body and a trigger with the shape on their own
    node."""
    b = GltfBuilder()
    o = _OmiShapes(b)
    root = b.node("Rope")
    _godot_rope(o, root)
    _godot_layouts(o, root)
    b.doc.setdefault("extensions", {})[OMI_SHAPE] = {"shapes": o.shapes}
    b.use(OMI_SHAPE, "GODOT_single_root")
    return b.write(path)


class _OmiShapes:
    """OMI shapes of a file being built, and colliders on child nodes that use them."""

    def __init__(self, b: GltfBuilder) -> None:
        self.b = b
        self.shapes: list[dict[str, Any]] = []

    def shape(self, kind: str, **params: Any) -> int:
        self.shapes.append({"type": kind, kind: params})
        return len(self.shapes) - 1

    def collider(self, owner: int, name: str, index: int, turn: Sequence[float] | None,
                 drawn: Sequence[float], key: str = "collider") -> int:
        """A child node of ``owner`` turned by ``turn`` holding the shape, the drawn mesh
        below it."""
        b = self.b
        node = b.node(name, parent=owner, rotation=turn, ext={OMI_BODY: {key: {"shape": index}}})
        b.node(f"{name}Mesh", parent=node, mesh=b.mesh(*box_mesh(drawn), f"{name}Mesh"))
        return node


def _godot_rope(o: _OmiShapes, root: int) -> None:
    """:func:`godot_omi`'s floor and the rope's two links welded together."""
    b = o.b
    floor = b.node("Floor", (0, 0, -0.1), parent=root,
                   ext={OMI_BODY: {"motion": {"type": "static"}}})
    o.collider(floor, "FloorShape", o.shape("box", size=[4, 0.2, 4]), None, (4, 0.2, 4))
    link = o.shape("capsule", radius=LINK_RADIUS, height=LINK_HEIGHT)
    along_x = _quat_about((0, 0, 1), math.pi / 2)  # a capsule's axis is its node's +Y
    drawn = (2 * LINK_RADIUS, LINK_HEIGHT, 2 * LINK_RADIUS)
    half = LINK_HEIGHT / 2
    # the links lie along their bodies' X; the first is tilted about glTF Z (engine -Y)
    tip = (half * math.cos(LINK_TILT), 0.0, half * math.sin(LINK_TILT))
    first = (-half, 0.0, LINK_START)
    weld_at = tuple(a + d for a, d in zip(first, tip, strict=True))
    second = (weld_at[0] + half, 0.0, weld_at[2])
    link_a = b.node("LinkA", first, parent=root, rotation=_quat_about((0, 0, 1), LINK_TILT),
                    ext={OMI_BODY: {"motion": {"type": "dynamic"}}})
    o.collider(link_a, "LinkAShape", link, along_x, drawn)
    link_b = b.node("LinkB", second, parent=root,
                    ext={OMI_BODY: {"motion": {"type": "dynamic"}}})
    o.collider(link_b, "LinkBShape", link, along_x, drawn)
    weld = b.top(OMI_JOINT, "physicsJoints", {"limits": [
        {"linearAxes": [0, 1, 2], "angularAxes": [0, 1, 2], "min": 0.0, "max": 0.0}]})
    attachment = b.node("LinkBWeldFrame", (-half, 0, 0), parent=link_b)
    b.node("Weld", (half, 0, 0), parent=link_a, rotation=_quat_about((0, 0, 1), -LINK_TILT),
           ext={OMI_JOINT: {"connectedNode": attachment, "joint": weld}})


def _godot_layouts(o: _OmiShapes, root: int) -> None:
    """:func:`godot_omi`'s other layouts: a compound trigger, shapes under a bare node
    between, shapes on their body's own node."""
    b = o.b
    gate = b.node("Gate", (4, 3, 1), parent=root)
    parts = [b.node(name, at, parent=gate, ext={OMI_BODY: {"trigger": {"shape": o.shape(
        "box", size=list(size))}}}) for name, at, size in (
        ("GateFoot", (0.5, 0, 0), (2, 0.5, 0.5)), ("GateStem", (0, 0, 1), (0.5, 2, 0.5)))]
    b.doc["nodes"][gate]["extensions"] = {OMI_BODY: {"trigger": {"nodes": parts}}}
    b.node("GateBell", (0, -2, 0), parent=gate, ext={OMI_BODY: {"trigger": {"shape": o.shape(
        "sphere", radius=0.3)}}})
    cube = o.shape("box", size=[0.5, 0.5, 0.5])
    for n, (name, part) in enumerate((("Lift", {"motion": {"type": "kinematic"}}),
                                      ("Sensor", {"trigger": {}}))):
        owner = b.node(name, (6 + 2 * n, 3, 1), parent=root, ext={OMI_BODY: part})
        between = b.node(f"{name}Pivot", (0, 0, 0.5), parent=owner)
        o.collider(between, f"{name}Shape", cube, None, (0.5, 0.5, 0.5),
                 "collider" if "motion" in part else "trigger")
    b.node("Pusher", (6, 5, 1), parent=root, ext={OMI_BODY: {
        "motion": {"type": "kinematic"}, "collider": {"shape": cube}}})
    b.node("Beam", (8, 5, 1), parent=root, ext={OMI_BODY: {"trigger": {"shape": cube}}})


#: :func:`blender`'s values: the floor's X scale, the kinematic body's velocity (m/s), the
#: wheel drive's target (rad/s) and damping (1/s, acceleration mode).
FLOOR_STRETCH, GLIDE_SPEED = 2.0, 0.5
WHEEL_TARGET, WHEEL_DAMPING = -1.5, 4.0


def blender(path: Path) -> Path:
    """The layout Blender 4.4's glTF exporter with the KHR physics add-on writes (as in the
    public KHR physics samples made with it): every collider with a physics material and
    the filter of Blender's collision collection (``System_0`` in and with), mesh
    colliders by ``geometry.node`` naming a bare ``physicsMeshDataNode`` outside the scene
    that holds the same mesh (the collider node's scale applies to it), ``isKinematic``,
    ``gravityFactor`` 0, ``mass`` 0 for infinite mass, and a hinge as the add-on writes a
    Blender hinge: one 1D limit per axis, ``enableCollision``, and a velocity drive in
    acceleration mode that also names a position target of stiffness 0 and no force
    limit."""
    b = GltfBuilder()
    material = b.top(KHR, "physicsMaterials", {"staticFriction": 0.5, "dynamicFriction": 0.5,
                                               "restitution": 0})
    system = b.top(KHR, "collisionFilters", {"collisionSystems": ["System_0"],
                                             "collideWithSystems": ["System_0"]})

    def collider(geometry: dict[str, Any]) -> dict[str, Any]:
        return {"geometry": geometry, "physicsMaterial": material, "collisionFilter": system}

    def mesh_data(mesh: int) -> int:
        return b.node("physicsMeshDataNode", rotation=[0, 0, 0, 1], mesh=mesh, in_scene=False)

    floor_mesh = b.mesh(*box_mesh((10, 0.2, 10)), "FloorMesh")
    floor = b.node("Floor", (0, 0, -0.1), scale=[FLOOR_STRETCH, 1, 1], mesh=floor_mesh)
    b.khr(floor, collider=collider({"convexHull": False, "node": mesh_data(floor_mesh)}))
    far = b.node("FarBox", (8, 0, 2), mesh=b.mesh(*box_mesh((0.5, 0.5, 0.5)), "BoxMesh"))
    b.khr(far, motion={"mass": 1},  # over the floor only as the floor's node scales it
          collider=collider(b.shape("box", size=[0.5, 0.5, 0.5])))
    gem_mesh = b.mesh(*box_mesh((0.5, 0.5, 0.5)), "GemMesh")
    for name, x, motion in (
            ("Glider", 0.0, {"mass": 1, "isKinematic": True,
                             "linearVelocity": gl((0, GLIDE_SPEED, 0))}),
            ("Floater", 2.0, {"mass": 1, "gravityFactor": 0}),
            ("Anvil", 4.0, {"mass": 0})):
        node = b.node(name, (x, 0, 2), mesh=gem_mesh)
        b.khr(node, motion=motion, collider=collider({"convexHull": True,
                                                      "node": mesh_data(gem_mesh)}))
    wheel = b.node("Wheel", (-3, 0, 2), mesh=b.mesh(*box_mesh((0.6, 0.6, 0.1)), "WheelMesh"))
    b.khr(wheel, motion={"mass": 1}, collider=collider(b.shape("box", size=[0.6, 0.6, 0.1])))
    description = b.top(KHR, "physicsJoints", {
        "limits": [{"linearAxes": [0], "min": 0, "max": 0},
                   {"linearAxes": [2], "min": 0, "max": 0},
                   {"linearAxes": [1], "min": 0, "max": 0},
                   {"angularAxes": [0], "min": 0, "max": 0},
                   {"angularAxes": [1], "min": 0, "max": 0}],
        "drives": [{"type": "angular", "mode": "acceleration", "axis": 2,
                    "positionTarget": 0, "velocityTarget": WHEEL_TARGET, "stiffness": 0,
                    "damping": WHEEL_DAMPING}]})
    space_b = b.node("jointSpaceB", (0, 0, 0), parent=wheel, rotation=[0, 0, 0, 1])
    space_a = b.node("jointSpaceA", (-3, 0, 2), rotation=[0, 0, 0, 1])
    b.khr(space_a, joint={"connectedNode": space_b, "joint": description,
                          "enableCollision": True})
    return b.write(path)


#: :func:`drives`' values: the weight's mass (kg), how far below its pivot its centre of
#: mass lies (m) and its principal moments (kg m^2, glTF axes); the cart's position drive
#: (kg; N/m; m); the flap's, in acceleration mode (1/s^2: the same for any flap); the
#: spinner's damper (N m s; kg, m: a disc about its axle) and start spin (rad/s).
WEIGHT_MASS, WEIGHT_REACH, WEIGHT_INERTIA = 2.0, 0.5, (0.04, 0.02, 0.03)
WEIGHT_SWING = 0.1  # rad, how far it starts turned from hanging straight down
DRIVE_MASS, DRIVE_STIFFNESS, DRIVE_TARGET = 2.0, 50.0, 0.3
FLAP_ACCELERATION = 16.0
SPINNER_DAMPING, SPINNER_MASS, SPINNER_RADIUS, SPINNER_SPIN = 0.05, 1.0, 0.3, 4.0


def drives(path: Path) -> Path:
    """KHR motions and drives the engine now represents: a weight whose only collider is a
    small sphere at its pivot while its motion puts the centre of mass 0.5 m below, with
    principal moments turned by ``inertiaOrientation``, hinged about glTF Z and let go
    0.1 rad from hanging straight down (a pendulum);
    a cart on a rail with a position drive toward 0.3 m; a flap hinged at one end with a
    position drive in acceleration mode; a spinner whose drive only damps (velocity
    target 0). Gravity acts on the weight alone (``gravityFactor`` 0 elsewhere)."""
    b = GltfBuilder()
    eighth = _quat_about((0, 1, 0), math.pi / 4)  # principal axes turned about glTF Y
    weight = b.node("Weight", (0, 0, 3), rotation=_quat_about((0, 0, 1), WEIGHT_SWING))
    b.khr(weight, motion={"mass": WEIGHT_MASS, "centerOfMass": gl((0, 0, -WEIGHT_REACH)),
                          "inertiaDiagonal": list(WEIGHT_INERTIA),
                          "inertiaOrientation": eighth},
          collider={"geometry": b.shape("sphere", radius=0.05)})
    swing = LOCK_LINEAR + _locked("angular", (0, 1))  # free about glTF Z: -Y here
    _joint(b, "WeightPivot", None, weight, (0, 0, 3), (0, 0, 0), swing)
    cart = _body(b, "Cart", (3, 0, 3), b.shape("box", size=[0.2, 0.2, 0.2]), (0.2,) * 3,
                 mass=DRIVE_MASS, gravityFactor=0)
    _joint(b, "CartRail", None, cart, (3, 0, 3), (0, 0, 0),
           _locked("linear", (1, 2)) + _locked("angular", (0, 1, 2)),
           [{"type": "linear", "mode": "force", "axis": 0, "stiffness": DRIVE_STIFFNESS,
             "damping": 0, "positionTarget": DRIVE_TARGET}])
    flap = _body(b, "Flap", (6.5, 0, 3), b.shape("box", size=[1, 0.05, 0.05]), (1, 0.05, 0.05),
                 mass=1.5, gravityFactor=0)
    _joint(b, "FlapHinge", None, flap, (6, 0, 3), (-0.5, 0, 0), swing,
           [{"type": "angular", "mode": "acceleration", "axis": 2,
             "stiffness": FLAP_ACCELERATION, "damping": 0, "positionTarget": 0.2}])
    spinner = _body(b, "Spinner", (9, 0, 3), b.shape(
        "cylinder", height=0.05, radiusTop=SPINNER_RADIUS, radiusBottom=SPINNER_RADIUS),
        (0.6, 0.05, 0.6), mass=SPINNER_MASS, gravityFactor=0,
        rotation=_quat_about((1, 0, 0), math.pi / 2),  # its axle along glTF Z
        angularVelocity=[0, SPINNER_SPIN, 0])
    _joint(b, "SpinnerAxle", None, spinner, (9, 0, 3), (0, 0, 0), swing,
           [{"type": "angular", "mode": "force", "axis": 2, "damping": SPINNER_DAMPING,
             "velocityTarget": 0}], rotation_b=_quat_about((1, 0, 0), -math.pi / 2))
    return b.write(path)


def many_bodies(path: Path, count: int = 10_000) -> Path:
    """``count`` dynamic boxes on a grid over a static ground, each a node with a mesh, a
    KHR motion and a box collider: the import benchmark's file."""
    b = GltfBuilder()
    ground = b.node("Ground", (0, 0, -0.5), mesh=b.mesh(*box_mesh((500, 1, 500)), "Ground"))
    b.khr(ground, collider={"geometry": b.shape("box", size=[500, 1, 500])})
    box = b.mesh(*box_mesh((0.5, 0.5, 0.5)), "Box")
    geometry = b.shape("box", size=[0.5, 0.5, 0.5])
    side = math.ceil(math.sqrt(count))
    for k in range(count):
        node = b.node(f"Box{k}", ((k % side) * 1.0, (k // side) * 1.0, 0.25 + 0.5 * (k % 3)),
                      mesh=box)
        b.khr(node, motion={"mass": 1.0}, collider={"geometry": geometry})
    return b.write(path)


# -- Collada ------------------------------------------------------------------------------
#: A file's axes from the engine's (Z up): the inverse of engine.assets.dae.UP_AXES.
_FILE_AXES = {"Z_UP": np.eye(3), "Y_UP": np.array([[1.0, 0, 0], [0, 0, 1.0], [0, -1.0, 0]])}
#: :func:`collada`'s door hinge limits (degrees about the post's vertical axis) and spin.
DOOR_LOW, DOOR_HIGH, DOOR_SPIN = -30.0, 60.0, 90.0
#: Scene keys typed into :func:`collada`'s Box node (a Collada <extra>).
BOX_EXTRAS = "Color [1 0 0]"
#: Where each body of :func:`collada` comes to rest (its centre's height, m).
COLLADA_REST = {"Box": 0.25, "Ball": 0.25, "Pill": 0.2, "Can": 0.25, "Gem": 0.25,
                "Pebble": 0.4}


def collada(path: Path, up: str = "Z_UP", meter: float = 1.0) -> Path:
    """A Collada 1.4 physics scene written ``up`` in units of ``meter``: a static plane, a
    static triangle-mesh slab, every analytic shape and a convex mesh falling on them, and
    a door hinged to a static post with limits, a start spin and a ``<spring>`` that pulls
    with nothing (stiffness and damping 0; :func:`collada_springs` has springs that pull):
    10 rigid bodies, 1 constraint."""
    f = _DaeAxes(_FILE_AXES[up], meter)
    axes = f.axes
    # node, position, (rigid body shapes), dynamic, extra technique_common
    bodies = [
        ("Ground", (0, 0, 0), f"<shape><plane><equation>{f.pos((0, 0, 1))} 0</equation></plane>"
                              "</shape>", False, ""),
        ("Slab", (4, 0, 0.1), '<shape><instance_geometry url="#slab"/></shape>', False, ""),
        ("Box", (-4, 0, 1), f"<shape><box><half_extents>{f.size((0.25, 0.25, 0.25))}"
                            "</half_extents></box></shape>", True, "<mass>2</mass>"),
        ("Ball", (-3, 0, 1), f"<shape><sphere><radius>{0.25 / meter}</radius></sphere></shape>",
         True, ""),
        ("Pill", (-2, 0, 1), f"<shape><capsule><height>{0.6 / meter}</height><radius>"
                             f"{0.2 / meter} {0.2 / meter}</radius></capsule>{f.along((1, 0, 0))}"
                             "</shape>", True, ""),
        ("Can", (-1, 0, 1), f"<shape><cylinder><height>{0.5 / meter}</height><radius>"
                            f"{0.3 / meter} {0.3 / meter}</radius></cylinder>{f.along((0, 0, 1))}"
                            "</shape>", True, ""),
        ("Gem", (0, 0, 1), '<shape><instance_geometry url="#gem"/></shape>', True, ""),
        ("Pebble", (4, 0, 2), f"<shape><sphere><radius>{0.2 / meter}</radius></sphere>"
                              "</shape>", True, ""),
        ("Post", (8, 0, 1.5), f"<shape><box><half_extents>{f.size((0.05, 0.05, 0.5))}"
                              "</half_extents></box></shape>", False, ""),
        ("Door", (8.5, 0, 1.5), f"<shape><box><half_extents>{f.size((0.4, 0.05, 0.5))}"
                                "</half_extents></box></shape>", True, ""),
    ]
    def geometry(gid: str, vertices: np.ndarray, faces: np.ndarray) -> str:
        return _dae_mesh(gid, vertices @ axes.T / meter, faces)

    geometries = [geometry("cube", *box_mesh((0.5, 0.5, 0.5))),
                  geometry("slab", *box_mesh((1, 1, 0.2))),
                  '<geometry id="gem"><convex_mesh convex_hull_of="#cube"/></geometry>']
    nodes = "".join(f'<node id="{n}" name="{n}"><translate>{f.pos(p)}</translate>'
                    f'<instance_geometry url="#{"slab" if n == "Slab" else "cube"}"/>'
                    + (f'<extra><technique profile="colosseum">{BOX_EXTRAS}</technique></extra>'
                       if n == "Box" else "") + "</node>" for n, p, *_ in bodies)
    rigid = "".join(
        f'<rigid_body sid="{n}-rb" name="{n}"><technique_common><dynamic>'
        f'{"true" if dyn else "false"}</dynamic>{extra}<instance_physics_material '
        f'url="#{"rubber" if n == "Ball" else "stone"}"/>{shape}</technique_common>'
        f'</rigid_body>' for n, _, shape, dyn, extra in bodies)
    hinge = _door_hinge(f)
    instances = "".join(
        f'<instance_rigid_body body="{n}-rb" target="#{n}">' +
        (f'<technique_common><angular_velocity>{_limits(axes, (0, 0, DOOR_SPIN))}'
         f'</angular_velocity>'
         f'</technique_common>' if n == "Door" else "") + "</instance_rigid_body>"
        for n, *_ in bodies)
    path.write_text(_collada_text(up, meter, geometries, nodes, rigid, hinge, instances,
                                  f.pos((0, 0, -9.81))))
    return path


def _door_hinge(f: _DaeAxes) -> str:
    """:func:`collada`'s door hinge: limits, and a spring that pulls with nothing."""
    axes = f.axes
    return (f'<rigid_constraint sid="hinge" name="DoorHinge"><ref_attachment '
             f'rigid_body="Post-rb"><translate>{f.pos((0.05, 0, 0))}</translate>'
             f'</ref_attachment><attachment rigid_body="Door-rb"><translate>'
             f'{f.pos((-0.45, 0, 0))}</translate></attachment><technique_common>'
             f'<enabled>true</enabled><interpenetrate>true</interpenetrate><limits>'
             f'<swing_cone_and_twist><min>{_limits(axes, (0, 0, DOOR_LOW))}</min>'
             f'<max>{_limits(axes, (0, 0, DOOR_HIGH))}</max></swing_cone_and_twist>'
             f'<linear><min>0 0 0</min><max>0 0 0</max></linear></limits><spring><angular>'
             f'<stiffness>0</stiffness><damping>0</damping><target_value>{DOOR_HIGH}'
             f'</target_value></angular></spring></technique_common></rigid_constraint>')


class _DaeAxes:
    """Engine positions, sizes and directions written on a Collada file's axes
    (``axes``: engine to file) in its unit (``meter``)."""

    def __init__(self, axes: np.ndarray, meter: float) -> None:
        self.axes, self.meter = axes, meter

    def pos(self, p: Sequence[float]) -> str:
        return " ".join(f"{x:.9g}" for x in self.axes @ np.asarray(p, np.float64) / self.meter)

    def size(self, p: Sequence[float]) -> str:
        return " ".join(f"{x:.9g}" for x in np.abs(self.axes @ np.asarray(p, np.float64))
                        / self.meter)

    def along(self, direction: Sequence[float]) -> str:
        """The rotate turning the file's local Y (a cylinder's axis) onto ``direction``."""
        d = self.axes @ np.asarray(direction, np.float64)
        y = np.array([0.0, 1.0, 0.0])
        axis = np.cross(y, d)
        if np.linalg.norm(axis) < 1e-9:
            return ""
        angle = math.degrees(math.acos(float(np.clip(y @ d, -1, 1))))
        return f"<rotate>{' '.join(f'{x:.9g}' for x in axis)} {angle:.9g}</rotate>"


def _collada_text(up: str, meter: float, geometries: list[str], nodes: str, rigid: str,
                  hinge: str, instances: str, gravity: str) -> str:
    """:func:`collada`'s document around its parts."""
    return f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit meter="{meter}" name="unit"/><up_axis>{up}</up_axis></asset>
<library_geometries>{"".join(geometries)}</library_geometries>
<library_visual_scenes><visual_scene id="Scene">{nodes}</visual_scene></library_visual_scenes>
<library_physics_materials>
<physics_material id="stone"><technique_common><dynamic_friction>0.6</dynamic_friction>
<restitution>0</restitution><static_friction>0.6</static_friction></technique_common>
</physics_material>
<physics_material id="rubber"><technique_common><dynamic_friction>0.9</dynamic_friction>
<restitution>0</restitution><static_friction>0.9</static_friction></technique_common>
</physics_material>
</library_physics_materials>
<library_physics_models><physics_model id="Physics">{rigid}{hinge}</physics_model>
</library_physics_models>
<library_physics_scenes><physics_scene id="PhysicsScene">
<instance_physics_model url="#Physics">{instances}
<instance_rigid_constraint constraint="hinge"/></instance_physics_model>
<technique_common><gravity>{gravity}</gravity><time_step>0.01</time_step>
</technique_common></physics_scene></library_physics_scenes>
<scene><instance_physics_scene url="#PhysicsScene"/><instance_visual_scene url="#Scene"/>
</scene>
</COLLADA>
"""


#: :func:`collada_springs`' cart (kg; spring N/m, m from where it starts) and flap (a rod
#: of kg and m hinged at one end about the vertical; spring N m per degree, degrees).
CART_MASS, CART_STIFFNESS, CART_TARGET = 2.0, 50.0, 0.3
FLAP_MASS, FLAP_LENGTH, FLAP_STIFFNESS, FLAP_TARGET = 1.5, 1.0, 0.05, 10.0
#: The surfaces :func:`collada_springs` slides and drops its blocks on: the floor's
#: friction, the slow and grippy blocks', restitution of the bouncy and dead balls.
DAE_FLOOR_FRICTION, DAE_SLOW, DAE_GRIP = 1.0, 0.1, 0.5
DAE_BOUNCY = 0.8


def collada_springs(path: Path, up: str = "Z_UP", meter: float = 1.0) -> Path:
    """Collada ``<spring>``s and materials, written ``up`` in units of ``meter``: a cart on a
    rail 1 m above it (a rigid_constraint leaving linear X free within limits) with a
    linear spring toward 0.3 m, and a flap hinged at one end about the vertical with an
    angular spring toward 10 degrees (gravity turns neither); beside them, on a floor of
    friction 1, two blocks sliding at 3 m/s with friction 0.1 and 0.5 (Collada says no
    rule for two materials: the importer's, the average) and a ball of restitution 0.8
    dropped beside one of 0, each apart in X (the 2D backend's plane): 9 rigid bodies, 2
    constraints."""
    f = _DaeAxes(_FILE_AXES[up], meter)
    bodies = [  # node, position, shape, mass (None: static), material, velocity
        ("Rail", (0, 0, 6), (0.05, 0.05, 0.05), None, "steel", None),
        ("Cart", (0, 0, 5), (0.1, 0.1, 0.1), CART_MASS, "steel", None),
        ("Hook", (3, 0, 6), (0.05, 0.05, 0.05), None, "steel", None),
        ("Flap", (3 + FLAP_LENGTH / 2, 0, 5), (FLAP_LENGTH / 2, 0.025, 0.025), FLAP_MASS,
         "steel", None)]
    shapes = "".join(
        f'<rigid_body sid="{n}-rb" name="{n}"><technique_common><dynamic>'
        f'{"false" if m is None else "true"}</dynamic>{"" if m is None else f"<mass>{m}</mass>"}'
        f'<instance_physics_material url="#{mat}"/><shape><box><half_extents>{f.size(h)}'
        f'</half_extents></box></shape></technique_common></rigid_body>'
        for n, _, h, m, mat, _ in bodies)
    floor = [  # node, position, half extents, mass, material, velocity (m/s, engine axes)
        ("Floor", (0, 10, -0.5), (20, 5, 0.5), None, "floor", None),
        ("Slow", (-10, 8, 0.25), (0.25, 0.25, 0.25), 1.0, "slow", (3.0, 0, 0)),
        ("Grip", (-6, 12, 0.25), (0.25, 0.25, 0.25), 1.0, "grip", (3.0, 0, 0)),
        ("Bouncy", (6, 8, 1.2), (0.2, 0.2, 0.2), 1.0, "bouncy", None),
        ("Dead", (8, 12, 1.2), (0.2, 0.2, 0.2), 1.0, "floor", None)]
    drop = "".join(
        f'<rigid_body sid="{n}-rb" name="{n}"><technique_common><dynamic>'
        f'{"false" if m is None else "true"}</dynamic>{"" if m is None else f"<mass>{m}</mass>"}'
        f'<instance_physics_material url="#{mat}"/><shape>'
        + (f"<sphere><radius>{h[0] / meter:.9g}</radius></sphere>" if n in ("Bouncy", "Dead")
           else f"<box><half_extents>{f.size(h)}</half_extents></box>")
        + "</shape></technique_common></rigid_body>" for n, _, h, m, mat, _ in floor)
    nodes = "".join(f'<node id="{n}" name="{n}"><translate>{f.pos(p)}</translate></node>'
                    for n, p, *_ in bodies + floor)
    path.write_text(f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><unit meter="{meter}" name="unit"/><up_axis>{up}</up_axis></asset>
<library_visual_scenes><visual_scene id="Scene">{nodes}</visual_scene></library_visual_scenes>
<library_physics_materials>{_dae_material("steel", 0.5, 0)}
{_dae_material("floor", DAE_FLOOR_FRICTION, 0)}{_dae_material("slow", DAE_SLOW, 0)}
{_dae_material("grip", DAE_GRIP, 0)}{_dae_material("bouncy", 0.5, DAE_BOUNCY)}
</library_physics_materials>
<library_physics_models><physics_model id="Springs">{shapes}{_spring_constraints(f)}\
</physics_model>
<physics_model id="Surfaces">{drop}</physics_model></library_physics_models>
<library_physics_scenes><physics_scene id="PhysicsScene">
<instance_physics_model url="#Springs">{_velocities(f, bodies)}
<instance_rigid_constraint constraint="CartRail"/><instance_rigid_constraint
 constraint="FlapHinge"/></instance_physics_model>
<instance_physics_model url="#Surfaces">{_velocities(f, floor)}</instance_physics_model>
<technique_common><gravity>{f.pos((0, 0, -9.81))}</gravity></technique_common>
</physics_scene></library_physics_scenes>
<scene><instance_physics_scene url="#PhysicsScene"/><instance_visual_scene url="#Scene"/>
</scene>
</COLLADA>
""")
    return path


def _spring_constraints(f: _DaeAxes) -> str:
    """:func:`collada_springs`' two constraints: the cart's linear spring along its rail
    and the flap's angular spring about its hinge."""
    axes, meter = f.axes, f.meter
    free = "<min>0 0 0</min><max>0 0 0</max>"
    cart = (f'<rigid_constraint sid="CartRail" name="CartRail"><ref_attachment rigid_body='
            f'"Rail-rb"><translate>{f.pos((0, 0, -1))}</translate></ref_attachment><attachment '
            f'rigid_body="Cart-rb"><translate>{f.pos((0, 0, 0))}</translate></attachment>'
            f'<technique_common><limits><swing_cone_and_twist>{free}'
            f'</swing_cone_and_twist><linear>'
            f"<min>{_numbers(axes @ np.array([-1.0, 0, 0]) / meter)}</min>"
            f"<max>{_numbers(axes @ np.array([1.0, 0, 0]) / meter)}</max>"
            f'</linear></limits><spring>'
            f"<linear><stiffness>{CART_STIFFNESS * meter:.9g}</stiffness><damping>0</damping>"
            f"<target_value>{CART_TARGET / meter:.9g}</target_value></linear>"
            f'</spring></technique_common></rigid_constraint>')
    flap_at = (-FLAP_LENGTH / 2, 0, 0)  # the flap's end, in the flap
    flap = (f'<rigid_constraint sid="FlapHinge" name="FlapHinge"><ref_attachment rigid_body='
            f'"Hook-rb"><translate>{f.pos((0, 0, -1))}</translate></ref_attachment><attachment '
            f'rigid_body="Flap-rb"><translate>{f.pos(flap_at)}</translate></attachment>'
            f'<technique_common><limits><swing_cone_and_twist><min>'
            f'{_limits(axes, (0, 0, -90))}</min><max>{_limits(axes, (0, 0, 90))}</max>'
            f'</swing_cone_and_twist><linear>{free}</linear></limits><spring><angular>'
            f'<stiffness>{FLAP_STIFFNESS}</stiffness><damping>0</damping><target_value>'
            f'{FLAP_TARGET}</target_value></angular></spring></technique_common>'
            f'</rigid_constraint>')
    return cart + flap


def _velocities(f: _DaeAxes, group: list[tuple[Any, ...]]) -> str:
    """Instances of a group's rigid bodies, with the start velocity of those that have one."""
    return "".join(
        f'<instance_rigid_body body="{n}-rb" target="#{n}">'
        + ("" if v is None else f"<technique_common><velocity>{f.pos(v)}</velocity>"
                                f"</technique_common>") + "</instance_rigid_body>"
        for n, _, _, _, _, v in group)


def _dae_material(mid: str, friction: float, bounce: float) -> str:
    return (f'<physics_material id="{mid}"><technique_common><dynamic_friction>{friction}'
            f'</dynamic_friction><restitution>{bounce}</restitution><static_friction>'
            f'{friction}</static_friction></technique_common></physics_material>')


def _limits(axes: np.ndarray, engine_degrees: Sequence[float]) -> str:
    """Per-axis angles (or angular rates) about the engine's X Y Z written on the file's
    axes (a turn about the engine's Z is about the file's Y in a Y-up file)."""
    return " ".join(f"{x:.9g}" for x in axes @ np.asarray(engine_degrees, np.float64))


def _numbers(values: Any) -> str:
    """Numbers as Collada writes them, space-separated."""
    return " ".join(f"{x:.9g}" for x in np.asarray(values, np.float64).reshape(-1))


def _dae_mesh(gid: str, vertices: np.ndarray, faces: Sequence[Sequence[int]],
              polygons: bool = False) -> str:
    """A ``<geometry>`` holding a ``<mesh>`` of ``vertices`` (in the file's axes and unit):
    one ``<triangles>``, or with ``polygons`` one ``<p>`` per face of any size, as
    ColladaMaya writes."""
    v = np.asarray(vertices, np.float64)
    vertex = f'<input semantic="VERTEX" source="#{gid}-vtx" offset="0"/>'
    if polygons:
        primitives = (f'<polygons count="{len(faces)}">{vertex}' +
                      "".join(f"<p>{' '.join(str(int(i)) for i in f)}</p>" for f in faces) +
                      "</polygons>")
    else:
        primitives = (f'<triangles count="{len(faces)}">{vertex}<p>'
                      f'{" ".join(str(int(i)) for f in faces for i in f)}</p></triangles>')
    return (f'<geometry id="{gid}"><mesh><source id="{gid}-pos"><float_array '
            f'id="{gid}-arr" count="{v.size}">{_numbers(v)}</float_array><technique_common>'
            f'<accessor source="#{gid}-arr" count="{len(v)}" stride="3">'
            f'<param name="X" type="float"/><param name="Y" type="float"/>'
            f'<param name="Z" type="float"/></accessor></technique_common></source>'
            f'<vertices id="{gid}-vtx"><input semantic="POSITION" source="#{gid}-pos"/>'
            f'</vertices>{primitives}</mesh></geometry>')


def _dae(path: Path, layout: str, up: str, unit: float | None, *parts: str) -> Path:
    """A Collada 1.4.1 file: its asset (the tool whose ``layout`` it follows; no
    ``<unit>`` when ``unit`` is None, so metres) and ``parts`` in the order given, which
    differs from tool to tool."""
    tool = f"colosseum app/bench/interchange_samples.py, laid out as {layout} writes it"
    scale = "" if unit is None else f'<unit meter="{unit}" name="unit"/>'
    path.write_text(f"""<?xml version="1.0" encoding="utf-8"?>
<COLLADA xmlns="http://www.collada.org/2005/11/COLLADASchema" version="1.4.1">
<asset><contributor><authoring_tool>{tool}</authoring_tool></contributor>{scale}
<up_axis>{up}</up_axis></asset>
{chr(10).join(parts)}
</COLLADA>
""")
    return path


def _dae_materials(ids: Sequence[str], friction: float) -> str:
    """A ``<library_physics_materials>`` of one material of ``friction`` per id."""
    return "<library_physics_materials>" + "".join(
        f'<physics_material id="{mid}"><technique_common><dynamic_friction>{friction}'
        f"</dynamic_friction><restitution>0</restitution><static_friction>{friction}"
        f"</static_friction></technique_common></physics_material>" for mid in ids
    ) + "</library_physics_materials>"


#: Where each moving body of the Collada layouts comes to rest on its floor (its centre's
#: height, m).
BLENDER_COLLADA_REST = {"Crate": 0.25, "Ball": 0.2, "Rock": 0.2}
MAYA_REST = {"Block": 0.4, "Ball": 0.25, "Barrel": 0.3}
BULLET_REST = {"Crate": 0.5, "Ball": 0.5}


def blender_collada(path: Path) -> Path:
    """Collada physics laid out as Blender 2.42's exporter (Illusoft's, 0.2.x) writes it,
    in centimetres: one physics model per body, its rigid body named and given no sid,
    each ``<instance_rigid_body>`` naming only its node (one names its body by that name
    instead), boxes as ``<half_extends>``, a convex hull whose ``convex_hull_of`` lacks
    its ``#``, ``<dynamic>`` and ``<mass>`` after the shape, and no gravity (the
    engine's). A tilted crate, a ball and a rock fall onto a static slab whose top is at
    0: 4 bodies, 4 shapes."""
    cm = 100.0

    def box(half: Sequence[float]) -> str:
        return f"<box><half_extends>{_numbers(np.asarray(half) * cm)}</half_extends></box>"

    bodies = [  # name, position (m), tilt about X (degrees), shape, drawn size (m), dynamic
        ("Ground", (0, 0, -0.1), 0, box((3, 3, 0.1)), (6, 6, 0.2), False),
        ("Crate", (0, 0, 1.0), 12, box((0.25, 0.25, 0.25)), (0.5, 0.5, 0.5), True),
        ("Ball", (1, 0, 1.5), 0, f"<sphere><radius>{0.2 * cm:g}</radius></sphere>",
         (0.4, 0.4, 0.4), True),
        ("Rock", (-1, 0, 1.2), 0, '<instance_geometry url="#Rock-Convex"/>', (0.4, 0.4, 0.4),
         True)]
    geometries = []
    for n, _, _, _, drawn, _ in bodies:
        vertices, faces = box_mesh(drawn)
        geometries.append(_dae_mesh(f"{n}Mesh", vertices * cm, faces))
    geometries.append('<geometry id="Rock-Convex" name="Rock-Convex">'
                      '<convex_mesh convex_hull_of="RockMesh"/></geometry>')
    nodes = "".join(f'<node id="{n}" name="{n}"><translate>{_numbers(np.asarray(p) * cm)}'
                    f'</translate><rotate>1 0 0 {tilt}</rotate><instance_geometry '
                    f'url="#{n}Mesh"/></node>' for n, p, tilt, *_ in bodies)
    models = "".join(
        f'<physics_model id="{n}-PX" name="{n}-PX"><rigid_body name="{n}-RB">'
        f'<technique_common><instance_physics_material url="#{n}PxMaterial"/><shape>{shape}'
        f'</shape><dynamic>{"true" if dynamic else "false"}</dynamic><mass>1.0</mass>'
        f'</technique_common></rigid_body></physics_model>'
        for n, _, _, shape, _, dynamic in bodies)

    def instance(n: str) -> str:
        named = f'body="{n}-RB" ' if n == "Ball" else ""  # the others name only the node
        return (f'<instance_physics_model url="#{n}-PX"><instance_rigid_body {named}'
                f'target="#{n}"/></instance_physics_model>')

    return _dae(
        path, "Blender 2.42's Illusoft exporter", "Z_UP", 0.01,
        f"<library_geometries>{''.join(geometries)}</library_geometries>",
        f'<library_visual_scenes><visual_scene id="Scene" name="Scene">{nodes}'
        f"</visual_scene></library_visual_scenes>",
        _dae_materials([f"{n}PxMaterial" for n, *_ in bodies], 0.5),
        f"<library_physics_models>{models}</library_physics_models>",
        f'<library_physics_scenes><physics_scene id="Scene-Physics" name="Scene-Physics">'
        f"{''.join(instance(n) for n, *_ in bodies)}</physics_scene></library_physics_scenes>",
        '<scene><instance_visual_scene url="#Scene"/>'
        '<instance_physics_scene url="#Scene-Physics"/></scene>')


def prism_mesh(radius: float, height: float, sides: int) -> tuple[np.ndarray, list[list[int]]]:
    """A closed upright prism (axis Z, centred) of ``sides`` quads and two caps of
    ``sides`` corners, each face listed once, outward."""
    turn = np.linspace(0, 2 * math.pi, sides, endpoint=False)
    ring = np.stack([radius * np.cos(turn), radius * np.sin(turn)], axis=1)
    vertices = np.vstack([np.column_stack([ring, np.full(sides, z)])
                          for z in (-height / 2, height / 2)])
    faces = [[k, (k + 1) % sides, sides + (k + 1) % sides, sides + k] for k in range(sides)]
    faces += [list(range(sides))[::-1], list(range(sides, 2 * sides))]
    return vertices, faces


def maya_collada(path: Path) -> Path:
    """Collada physics laid out as ColladaMaya 0.89 (Maya 7 with its PhysX plug-in) writes
    it, in centimetres: the physics libraries before the visual scene, one physics model
    holding every rigid body by sid alone, ``<mass>`` first (a static body's too), bodies
    of several shapes at their centre, a dynamic body whose shape is its drawn ``<mesh>``
    written as ``<polygons>`` of four and eight corners, nodes placed by a translate and
    three rotates that all carry sids, an empty shape node under each body, a node
    holding nothing, a MAYA ``<extra>``, and gravity and a 1/30 s step in the file's
    unit. A block of two boxes, a ball of two spheres and a barrel fall onto a static
    floor whose top is at 0: 4 bodies, 6 shapes."""
    cm = 100.0

    def box(half: Sequence[float]) -> str:
        return (f"<shape><box><half_extents>{_numbers(np.asarray(half) * cm)}</half_extents>"
                "</box></shape>")

    ball = f"<shape><sphere><radius>{0.25 * cm:g}</radius></sphere></shape>"
    bodies = [  # name, position (m), turn about Z (degrees), shapes, dynamic
        ("Block", (-1, 0, 1.0), 30, box((0.25, 0.25, 0.4)) + box((0.25, 0.25, 0.25)), True),
        ("Ball", (0, 0, 1.4), 0, ball + ball, True),
        ("Barrel", (1, 0, 0.8), 0, '<shape><instance_geometry url="#BarrelShape"/></shape>',
         True),
        ("Floor", (0, 0, -0.5), 0, box((4, 4, 0.5)), False)]
    barrel = prism_mesh(0.3 * cm, 0.6 * cm, 8)
    rigid = "".join(
        f'<rigid_body sid="{n}-RB"><technique_common>'
        f'{"" if dynamic else "<dynamic>false</dynamic>"}<mass>2.0</mass>'
        f'<instance_physics_material url="#{n}-PhysicsMaterial"/>{shapes}</technique_common>'
        f"</rigid_body>" for n, _, _, shapes, dynamic in bodies)

    def place(turn: float) -> str:
        return (f'<rotate sid="rotateZ">0 0 1 {turn}</rotate><rotate sid="rotateY">0 1 0 0'
                f'</rotate><rotate sid="rotateX">1 0 0 0</rotate>')

    nodes = '<node id="nurbsCube1" name="nurbsCube1" sid="nurbsCube1">' + place(0) + "</node>"
    nodes += "".join(
        f'<node id="{n}" name="{n}" sid="{n}"><translate sid="translate">'
        f'{_numbers(np.asarray(p) * cm)}</translate>{place(turn)}'
        + ('<instance_geometry url="#BarrelShape"/>' if n == "Barrel" else "")
        + f'<node id="{n}Shape" name="{n}Shape" sid="{n}Shape">{place(0)}</node></node>'
        for n, p, turn, *_ in bodies)
    return _dae(
        path, "ColladaMaya 0.89", "Z_UP", 0.01,
        f"<library_geometries>{_dae_mesh('BarrelShape', *barrel, polygons=True)}"
        "</library_geometries>",
        _dae_materials([f"{n}-PhysicsMaterial" for n, *_ in bodies], 0.6),
        f'<library_physics_models><physics_model id="PhysXModel">{rigid}</physics_model>'
        "</library_physics_models>",
        '<library_physics_scenes><physics_scene id="PhysXScene"><instance_physics_model '
        'url="#PhysXModel">' + "".join(f'<instance_rigid_body body="{n}-RB" target="#{n}"/>'
                                       for n, *_ in bodies)
        + f"</instance_physics_model><technique_common><gravity>0 0 {-9.81 * cm:g}</gravity>"
        f"<time_step>{1 / 30:.6f}</time_step></technique_common></physics_scene>"
        "</library_physics_scenes>",
        f'<library_visual_scenes><visual_scene id="MayaScene" name="MayaScene">{nodes}<extra>'
        '<technique profile="MAYA"><start_time>0</start_time><end_time>2</end_time>'
        "</technique></extra></visual_scene></library_visual_scenes>",
        '<scene><instance_physics_scene url="#PhysXScene"/>'
        '<instance_visual_scene url="#MayaScene"/></scene>')


#: :func:`bullet_collada`'s pendulums: each bob's pivot (engine axes, m), how far below
#: it the bob hangs (m) and how far it starts turned about its hinge (degrees).
BOB_PIVOTS = {"BobA": (-3.0, 0.0, 3.0), "BobB": (-5.0, 0.0, 3.0)}
BOB_REACH, BOB_SWING = 0.5, 40.0


def _bullet_bodies(axes: np.ndarray) -> list[tuple[Any, ...]]:
    """:func:`bullet_collada`'s bodies: name, position (engine axes), turn about the
    file's Z, shape, mass, and the principal moments Bullet works out and writes."""
    swing = math.radians(BOB_SWING)  # about the file's Z: the bob's centre out and down
    reach = np.array([BOB_REACH * math.sin(swing), -BOB_REACH * math.cos(swing), 0.0])
    return [
        ("Ground", (0, 0, -0.5), 0, "<box><half_extents>5 0.5 5</half_extents></box>", 0,
         0.0),
        ("Crate", (0, 0, 2), 0, '<instance_geometry url="#Crate-Geometry"/>', 5, 5 / 6),
        ("Ball", (2, 0, 3), 0, "<sphere><radius>0.5</radius></sphere>", 5, 0.5),
        *((n, tuple(axes.T @ (axes @ np.asarray(p) + reach)), BOB_SWING,
           "<box><half_extents>0.15 0.15 0.15</half_extents></box>", 1, 0.015)
          for n, p in BOB_PIVOTS.items())]


def bullet_collada(path: Path) -> Path:
    """Collada physics laid out as Bullet 2.6x's ColladaConverter writes it: Y up, no
    ``<unit>``, the physics scenes first, one physics model whose rigid bodies carry a sid
    and the same name, ``<inertia>``, mass 0 for a static body, instances that restate
    zero velocities, and each constraint holding one body to the world by a lone
    ``<attachment>`` (turned by a ``<rotate>``): every constraint has the same sid and is
    instanced by it once each, its free axis written as min 1 over max -1. Two bobs
    swing about horizontal hinges from fixed pivots; a crate (the convex hull of its drawn
    mesh) and a ball fall onto a static slab whose top is at 0: 6 bodies, 2 constraints."""
    axes = _FILE_AXES["Y_UP"]

    def at(p: Sequence[float]) -> str:
        return _numbers(axes @ np.asarray(p, np.float64))

    bodies = _bullet_bodies(axes)
    hold = "".join(
        f'<rigid_constraint sid="Constraint-0" name="Constraint-0"><attachment '
        f'rigid_body="{n}-RigidBody"><translate>0 {BOB_REACH} 0</translate><rotate>0 1 0 90'
        f"</rotate></attachment><technique_common><enabled>true</enabled><interpenetrate>"
        f"false</interpenetrate><limits><swing_cone_and_twist><min>1 0 0</min><max>-1 0 0"
        f"</max></swing_cone_and_twist><linear><min>0 0 0</min><max>0 0 0</max></linear>"
        f"</limits></technique_common></rigid_constraint>" for n in BOB_PIVOTS)
    rigid = "".join(
        f'<rigid_body sid="{n}-RigidBody" name="{n}-RigidBody"><technique_common><dynamic>'
        f'{"true" if mass else "false"}</dynamic><mass>{mass}</mass><inertia>'
        f'{_numbers([moment] * 3)}</inertia><instance_physics_material '
        f'url="#{n}-PhysicsMaterial"/><shape>{shape}</shape></technique_common></rigid_body>'
        for n, _, _, shape, mass, moment in bodies)
    instances = "".join(
        f'<instance_rigid_body body="{n}-RigidBody" target="#{n}"><technique_common>'
        f"<angular_velocity>0 0 0</angular_velocity><velocity>0 0 0</velocity>"
        f"</technique_common></instance_rigid_body>" for n, *_ in bodies)
    instances += '<instance_rigid_constraint constraint="Constraint-0"/>' * len(BOB_PIVOTS)
    nodes = "".join(f'<node id="{n}" name="{n}"><translate>{at(p)}</translate><rotate>0 0 1 '
                    f'{turn}</rotate><instance_geometry url="#RenderMesh{n}"/></node>'
                    for n, p, turn, *_ in bodies)
    drawn = {"Ground": (10, 1, 10), "Crate": (1, 1, 1), "Ball": (1, 1, 1),
             **{n: (0.3, 0.3, 0.3) for n in BOB_PIVOTS}}
    return _dae(
        path, "Bullet's ColladaConverter", "Y_UP", None,
        '<library_physics_scenes><physics_scene id="Scene-Physics" name="PhysicsScene">'
        f'<instance_physics_model url="#PhysicsModel">{instances}</instance_physics_model>'
        "<technique_common><gravity>0 -9.81 0</gravity></technique_common></physics_scene>"
        "</library_physics_scenes>",
        f'<library_visual_scenes><visual_scene id="Scene">{nodes}</visual_scene>'
        "</library_visual_scenes>",
        "<library_geometries>" + "".join(_dae_mesh(f"RenderMesh{n}", *box_mesh(size))
                                         for n, size in drawn.items())
        + '<geometry id="Crate-Geometry"><convex_mesh convex_hull_of="#RenderMeshCrate"/>'
        "</geometry></library_geometries>",
        _dae_materials([f"{n}-PhysicsMaterial" for n, *_ in bodies], 0.5),
        f'<library_physics_models><physics_model id="PhysicsModel">{rigid}{hold}'
        "</physics_model></library_physics_models>",
        '<scene><instance_physics_scene url="#Scene-Physics"/>'
        '<instance_visual_scene url="#Scene"/></scene>')


SAMPLES = {"shapes.glb": shapes, "joints.glb": joints, "drives.glb": drives,
           "materials.glb": materials,
           "filters.glb": filters, "triggers.glb": triggers, "extras.glb": extras,
           "omi.gltf": omi, "godot_omi.gltf": godot_omi, "blender.glb": blender,
           "physics.dae": collada, "springs.dae": collada_springs,
           "blender.dae": blender_collada, "maya.dae": maya_collada,
           "bullet.dae": bullet_collada}


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python -m app.bench.interchange_samples DIR", file=sys.stderr)
        return 2
    folder = Path(argv[0])
    folder.mkdir(parents=True, exist_ok=True)
    for name, make in SAMPLES.items():
        print(make(folder / name))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
