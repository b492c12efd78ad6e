"""Model files for the importer's tests and benchmark, written as Blender's physics add-on
and Godot write them: glTF 2.0 with KHR_physics_rigid_bodies + KHR_implicit_shapes (joint
frames as child nodes ``jointSpaceA``/``jointSpaceB``, collision filters by system name,
mesh colliders by ``geometry.mesh``), OMI_physics_body/shape/joint, Blender custom
properties as ``extras``, and Collada 1.4 ``<physics_scene>``.

``python -m tools.interchange_samples DIR`` writes them all into DIR; the tests call the
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

from engine.interchange.export import GltfWriter, to_gltf
from engine.interchange.gltf_physics import KHR, OMI_BODY, OMI_JOINT, OMI_SHAPE


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
        super().__init__("colosseum tools/interchange_samples.py")

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


def omi(path: Path) -> Path:
    """OMI_physics_body, OMI_physics_shape and OMI_physics_joint as Godot writes them: a
    static ground, a dynamic ball, a kinematic box, a trigger, and a hinged pair."""
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
    b.doc.setdefault("extensions", {})[OMI_SHAPE] = {"shapes": shapes_}
    b.use(OMI_SHAPE)
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
    a door hinged to a static post with limits, a spring and a start spin: 10 rigid bodies,
    1 constraint."""
    axes = _FILE_AXES[up]

    def pos(p: Sequence[float]) -> str:
        return " ".join(f"{x:.9g}" for x in axes @ np.asarray(p, np.float64) / meter)

    def size(p: Sequence[float]) -> str:
        return " ".join(f"{x:.9g}" for x in np.abs(axes @ np.asarray(p, np.float64)) / meter)

    def rotate(axis: Sequence[float], degrees: float) -> str:
        return f"<rotate>{pos(axis)} {degrees}</rotate>"

    def along(direction: Sequence[float]) -> str:
        """The rotate turning the file's local Y (a cylinder's axis) onto ``direction``."""
        d = axes @ np.asarray(direction, np.float64)
        y = np.array([0.0, 1.0, 0.0])
        axis = np.cross(y, d)
        if np.linalg.norm(axis) < 1e-9:
            return ""
        angle = math.degrees(math.acos(float(np.clip(y @ d, -1, 1))))
        return f"<rotate>{' '.join(f'{x:.9g}' for x in axis)} {angle:.9g}</rotate>"

    def geometry(gid: str, vertices: np.ndarray, faces: np.ndarray) -> str:
        v = " ".join(f"{x:.9g}" for x in (vertices @ axes.T / meter).reshape(-1))
        return (f'<geometry id="{gid}"><mesh><source id="{gid}-pos"><float_array '
                f'id="{gid}-arr" count="{vertices.size}">{v}</float_array><technique_common>'
                f'<accessor source="#{gid}-arr" count="{len(vertices)}" stride="3">'
                f'<param name="X" type="float"/><param name="Y" type="float"/>'
                f'<param name="Z" type="float"/></accessor></technique_common></source>'
                f'<vertices id="{gid}-vtx"><input semantic="POSITION" source="#{gid}-pos"/>'
                f'</vertices><triangles count="{len(faces)}"><input semantic="VERTEX" '
                f'source="#{gid}-vtx" offset="0"/><p>{" ".join(map(str, faces.reshape(-1)))}'
                f'</p></triangles></mesh></geometry>')

    bodies = [  # node, position, (rigid body shapes), dynamic, extra technique_common
        ("Ground", (0, 0, 0), f"<shape><plane><equation>{pos((0, 0, 1))} 0</equation></plane>"
                              "</shape>", False, ""),
        ("Slab", (4, 0, 0.1), '<shape><instance_geometry url="#slab"/></shape>', False, ""),
        ("Box", (-4, 0, 1), f"<shape><box><half_extents>{size((0.25, 0.25, 0.25))}"
                            "</half_extents></box></shape>", True, "<mass>2</mass>"),
        ("Ball", (-3, 0, 1), f"<shape><sphere><radius>{0.25 / meter}</radius></sphere></shape>",
         True, ""),
        ("Pill", (-2, 0, 1), f"<shape><capsule><height>{0.6 / meter}</height><radius>"
                             f"{0.2 / meter} {0.2 / meter}</radius></capsule>{along((1, 0, 0))}"
                             "</shape>", True, ""),
        ("Can", (-1, 0, 1), f"<shape><cylinder><height>{0.5 / meter}</height><radius>"
                            f"{0.3 / meter} {0.3 / meter}</radius></cylinder>{along((0, 0, 1))}"
                            "</shape>", True, ""),
        ("Gem", (0, 0, 1), '<shape><instance_geometry url="#gem"/></shape>', True, ""),
        ("Pebble", (4, 0, 2), f"<shape><sphere><radius>{0.2 / meter}</radius></sphere>"
                              "</shape>", True, ""),
        ("Post", (8, 0, 1.5), f"<shape><box><half_extents>{size((0.05, 0.05, 0.5))}"
                              "</half_extents></box></shape>", False, ""),
        ("Door", (8.5, 0, 1.5), f"<shape><box><half_extents>{size((0.4, 0.05, 0.5))}"
                                "</half_extents></box></shape>", True, ""),
    ]
    geometries = [geometry("cube", *box_mesh((0.5, 0.5, 0.5))),
                  geometry("slab", *box_mesh((1, 1, 0.2))),
                  '<geometry id="gem"><convex_mesh convex_hull_of="#cube"/></geometry>']
    nodes = "".join(f'<node id="{n}" name="{n}"><translate>{pos(p)}</translate>'
                    f'<instance_geometry url="#{"slab" if n == "Slab" else "cube"}"/>'
                    + (f'<extra><technique profile="colosseum">{BOX_EXTRAS}</technique></extra>'
                       if n == "Box" else "") + "</node>" for n, p, *_ in bodies)
    rigid = "".join(
        f'<rigid_body sid="{n}-rb" name="{n}"><technique_common><dynamic>'
        f'{"true" if dyn else "false"}</dynamic>{extra}<instance_physics_material '
        f'url="#{"rubber" if n == "Ball" else "stone"}"/>{shape}</technique_common>'
        f'</rigid_body>' for n, _, shape, dyn, extra in bodies)
    hinge = (f'<rigid_constraint sid="hinge" name="DoorHinge"><ref_attachment '
             f'rigid_body="Post-rb"><translate>{pos((0.05, 0, 0))}</translate>'
             f'</ref_attachment><attachment rigid_body="Door-rb"><translate>'
             f'{pos((-0.45, 0, 0))}</translate></attachment><technique_common>'
             f'<enabled>true</enabled><interpenetrate>true</interpenetrate><limits>'
             f'<swing_cone_and_twist><min>{_limits(axes, (0, 0, DOOR_LOW))}</min>'
             f'<max>{_limits(axes, (0, 0, DOOR_HIGH))}</max></swing_cone_and_twist>'
             f'<linear><min>0 0 0</min><max>0 0 0</max></linear></limits><spring><angular>'
             f'<stiffness>2</stiffness><damping>0</damping><target_value>0</target_value>'
             f'</angular></spring></technique_common></rigid_constraint>')
    instances = "".join(
        f'<instance_rigid_body body="{n}-rb" target="#{n}">' +
        (f'<technique_common><angular_velocity>{_limits(axes, (0, 0, DOOR_SPIN))}'
         f'</angular_velocity>'
         f'</technique_common>' if n == "Door" else "") + "</instance_rigid_body>"
        for n, *_ in bodies)
    text = f"""<?xml version="1.0" encoding="utf-8"?>
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
<technique_common><gravity>{pos((0, 0, -9.81))}</gravity><time_step>0.01</time_step>
</technique_common></physics_scene></library_physics_scenes>
<scene><instance_physics_scene url="#PhysicsScene"/><instance_visual_scene url="#Scene"/>
</scene>
</COLLADA>
"""
    path.write_text(text)
    return path


def _limits(axes: np.ndarray, engine_degrees: Sequence[float]) -> str:
    """Per-axis angles (or angular rates) about the engine's X Y Z written on the file's
    axes (a turn about the engine's Z is about the file's Y in a Y-up file)."""
    return " ".join(f"{x:.9g}" for x in axes @ np.asarray(engine_degrees, np.float64))


SAMPLES = {"shapes.glb": shapes, "joints.glb": joints, "materials.glb": materials,
           "filters.glb": filters, "triggers.glb": triggers, "extras.glb": extras,
           "omi.gltf": omi, "physics.dae": collada}


def main(argv: list[str]) -> int:
    if len(argv) != 1:
        print("usage: python -m tools.interchange_samples DIR", file=sys.stderr)
        return 2
    folder = Path(argv[0])
    folder.mkdir(parents=True, exist_ok=True)
    for name, make in SAMPLES.items():
        print(make(folder / name))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
