"""glTF physics: KHR_physics_rigid_bodies with KHR_implicit_shapes (Khronos; Blender's
physics add-on writes them), OMI_physics_body, OMI_physics_shape and OMI_physics_joint
(Godot, Blender, three.js), and scene keys in nodes' ``extras``, read into an
:class:`~engine.interchange.model.ImportedScene`.

How a file becomes objects (the extensions' own rules): a node with a ``motion`` is a
body; colliders on it and on its descendants (down to the next ``motion``) are its
compound shape; a collider with no ``motion`` above it is a static object (its
descendants' colliders join it); a trigger is an object of its own that detects,
never collides; a node with a mesh and nothing above it is drawn as a visual-only
object. A node's visual is its own mesh and the meshes of the descendants it owns,
referenced from the model file (``Nodes``), never copied into the scene.

Axes: glTF is +Y up; positions, orientations and sizes are turned +Z up so an object
upright in the file is upright here (box ``[x y z]`` becomes ``[x z y]``, capsule and
cylinder axes glTF Y become local Z). KHR velocities are in node space, as the extension
says (its reference importer, Babylon's, turns them by the node's rotation); OMI's in
world axes, as Godot writes them.

A motion's centre of mass and inertia become the body's; a drive's stiffness and
damping its joint's Spring (a velocity drive its motor). What the engine cannot
represent (a gravity factor other than 0 or 1, static friction apart from dynamic,
soft limits, a position drive on a joint with more than one free axis, joint
combinations no joint type here has) is approximated and told, node by node; broken
parts (a collider of zero size, a joint naming a node that does not exist, NaN in a
matrix) are told and skipped, and the rest is imported.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from engine.assets.gltf import (
    Y_UP_TO_Z_UP,
    Frame,
    GltfDocument,
    decompose,
    decompose_many,
    to_z_up,
)
from engine.interchange.extras import Extras, attach, read_extras
from engine.interchange.joints import (
    DOF_NAMES,
    FREE,
    LOCKED,
    Dof,
    Frames,
    WorkingJoint,
    working_joint,
)
from engine.interchange.model import (
    GEOMETRIC_MEAN,
    UNTURNED,
    VOLUME_DENSITY,
    CameraDecl,
    ImportedScene,
    JointDecl,
    MaterialDecl,
    ObjectDecl,
    Problems,
    ShapeDecl,
    quaternion,
    tidy,
    unique_ids,
    unit_quaternion,
    vector,
)
from engine.rotation import matrices_to_quats, quat_to_matrix

KHR = "KHR_physics_rigid_bodies"
KHR_SHAPES = "KHR_implicit_shapes"
KHR_OLD_SHAPES = "KHR_collision_shapes"  # the implicit shapes' name in earlier drafts
OMI_BODY = "OMI_physics_body"
OMI_SHAPE = "OMI_physics_shape"
OMI_JOINT = "OMI_physics_joint"
PHYSICS_EXTENSIONS = (KHR, KHR_SHAPES, KHR_OLD_SHAPES, OMI_BODY, OMI_SHAPE, OMI_JOINT)
#: Extensions that change only how a file looks: the engine draws base colours and
#: textures, so these are drawn approximately (told once, as a list).
LOOKS_PREFIXES = ("KHR_materials_", "KHR_texture_", "EXT_texture_",
                  "KHR_mesh_quantization")

#: Extensions that add nothing an import reads (Godot's says the file has one root node).
_NOTHING_TO_READ = ("GODOT_single_root",)

#: Shape parameter defaults, per extension (they differ).
_DEFAULTS = {
    "KHR": {"box": {"size": [1.0, 1.0, 1.0]}, "sphere": {"radius": 0.5},
            "capsule": {"height": 0.5, "radiusTop": 0.25, "radiusBottom": 0.25},
            "cylinder": {"height": 0.5, "radiusTop": 0.25, "radiusBottom": 0.25}},
    "OMI": {"box": {"size": [1.0, 1.0, 1.0]}, "sphere": {"radius": 0.5},
            "capsule": {"height": 1.0, "radiusTop": 0.5, "radiusBottom": 0.5},
            "cylinder": {"height": 2.0, "radiusTop": 0.5, "radiusBottom": 0.5}},
}
#: A motionless body's stand-in shape: the file gives it no collider, so it collides with
#: nothing (category and mask 0) and only carries mass.
_PHANTOM_DIAMETER = 0.1
#: OMI_physics_body's mass when a motion gives none (KHR leaves it to the shapes' volume).
_OMI_MASS = 1.0
#: A finite plane (sizeX/sizeZ) is a box this thick, its top face on the plane.
_PLANE_THICKNESS = 0.01
#: What a motion may say of its mass's place and spread (in this order).
_MASS_FRAME_KEYS = ("centerOfMass", "inertiaDiagonal", "inertiaOrientation")
#: A node's own place in its object's frame, shared (read only) by every object.
_ORIGIN = np.zeros(3)
_ORIGIN.flags.writeable = False


@dataclass(slots=True)
class _Shape:
    """A shape reference as a file gives it: an implicit shape, a mesh, or a node's meshes."""

    family: str  # "KHR" or "OMI": which defaults apply
    spec: dict[str, Any] | None = None  # {"type": ..., "<type>": {...}}
    mesh: int | None = None
    node: int | None = None
    convex: bool = False


@dataclass(slots=True)
class _Role:
    """What a node is for physics, read from whichever extension it uses."""

    motion: dict[str, Any] | None = None
    kind: str | None = None  # dynamic, kinematic, static (OMI's static body)
    collider: _Shape | None = None
    material: int | None = None
    filter: int | None = None
    trigger: _Shape | None = None
    trigger_nodes: list[int] = field(default_factory=list)
    trigger_filter: int | None = None
    family: str = "KHR"  # which extension's materials and filters the indices name
    joint: dict[str, Any] | None = None
    joint_family: str = "KHR"


def import_gltf(doc: GltfDocument, problems: Problems) -> ImportedScene:
    """Everything ``doc`` declares for physics and drawing, as scene declarations."""
    return _Importer(doc, problems).run()


class _Importer:
    def __init__(self, doc: GltfDocument, problems: Problems) -> None:
        self.doc = doc
        self.problems = problems
        ext = doc.json.get("extensions", {})
        self.ext: dict[str, Any] = ext if isinstance(ext, dict) else {}
        self.scene = ImportedScene(doc.path, "glTF", problems=problems)
        self.roles: dict[int, _Role] = {}
        self.owner: dict[int, ObjectDecl] = {}  # node -> the object it belongs to
        self.object_node: dict[int, int] = {}  # id(object) -> its node
        self.frames: dict[int, np.ndarray] = {}  # id(object) -> its unscaled 4x4 (Z up)
        #: Objects that are bodies only through their extras: shaped like their mesh.
        self.typed_bodies: set[int] = set()
        self._frames: tuple[np.ndarray, ...] | None = None
        self._quats = np.zeros((0, 4))  # every node's world orientation, with _frames
        self.materials: dict[tuple[str, int], str] = {}
        self.systems: dict[str, int] = {}

    # -- top level -----------------------------------------------------------------
    def run(self) -> ImportedScene:
        self._extensions()
        for i, reason in sorted(self.doc.bad_nodes.items()):
            if reason.startswith("its ancestor"):
                continue
            self.problems.error(self._label(i), f"{reason}; it and its children are "
                                                  f"left out")
        order = [i for i in self.doc.scene_nodes if i not in self.doc.bad_nodes]
        for i in order:
            self.roles[i] = self._role(i)
        self._materials()
        self._objects(order)
        self._joints(order)
        ids = unique_ids([o.id for o in self.scene.objects])
        for o, new in zip(self.scene.objects, ids, strict=True):
            o.id = new
        root_extras = read_extras(self.doc.json.get("extras"),
                                  f"{self.doc.path.name} extras", scene_level=True)
        attach(root_extras, None, None, self.scene, self.problems)
        self.scene.scene_extras = root_extras.entries.get("Scene", [])
        return self.scene

    def _extensions(self) -> None:
        used = [e for e in _strings(self.doc.json.get("extensionsUsed"))]
        required = set(_strings(self.doc.json.get("extensionsRequired")))
        read = [e for e in used if e in PHYSICS_EXTENSIONS]
        self.scene.read = read
        looks = [e for e in used if e.startswith(LOOKS_PREFIXES)]
        unknown = [e for e in used if e not in PHYSICS_EXTENSIONS and e not in looks
                   and e not in ("KHR_lights_punctual", *_NOTHING_TO_READ)]
        if looks:
            self.problems.warn(None, f"drawn with base colours and textures only; what "
                                     f"{', '.join(looks)} add to the look is left out")
        for name in unknown:
            what = "required by the file" if name in required else "used by the file"
            self.problems.warn(None, f"extension {name} ({what}) is not read; what it adds "
                                     f"is left out")
        if self.doc.json.get("animations"):
            self.problems.warn(None, "animations are not imported: every node starts where "
                                     "the file puts it at rest")
        if "KHR_lights_punctual" in used:
            self.problems.warn(None, "lights are not imported (KHR_lights_punctual); the "
                                     "scene's own Light blocks light it")

    # -- what each node is -----------------------------------------------------------
    def _role(self, i: int) -> _Role:
        node = self.doc.nodes[i]
        ext = node.get("extensions") if isinstance(node.get("extensions"), dict) else {}
        role = _Role()
        khr = ext.get(KHR)
        if isinstance(khr, dict):
            self._khr_role(i, khr, role)
        omi = ext.get(OMI_BODY)
        if isinstance(omi, dict):
            role.family = "OMI"
            self._omi_role(i, omi, role)
        joint = ext.get(OMI_JOINT)
        if isinstance(joint, dict) and role.joint is None:
            role.joint, role.joint_family = joint, "OMI"
        return role

    def _khr_role(self, i: int, khr: dict[str, Any], role: _Role) -> None:
        motion = khr.get("motion")
        if isinstance(motion, dict):
            role.motion = motion
            role.kind = "kinematic" if motion.get("isKinematic") else "dynamic"
        collider = khr.get("collider")
        if isinstance(collider, dict):
            role.collider = self._khr_geometry(i, collider)
            role.material = collider.get("physicsMaterial")
            role.filter = collider.get("collisionFilter")
        trigger = khr.get("trigger")
        if isinstance(trigger, dict):
            if "geometry" in trigger or "shape" in trigger:
                role.trigger = self._khr_geometry(i, trigger)
            role.trigger_nodes = list(trigger.get("nodes", []))
            role.trigger_filter = trigger.get("collisionFilter")
        if isinstance(khr.get("joint"), dict):
            role.joint, role.joint_family = khr["joint"], "KHR"

    def _khr_geometry(self, i: int, holder: dict[str, Any]) -> _Shape | None:
        geometry = holder.get("geometry")
        if geometry is None and "shape" in holder:  # earlier drafts: the index directly
            geometry = {"shape": holder["shape"]}
        if not isinstance(geometry, dict):
            self.problems.error(self._label(i), "its collider has no geometry; left out")
            return None
        convex = bool(geometry.get("convexHull", False))
        if "shape" in geometry:
            shapes = self._shapes(KHR_SHAPES) or self._shapes(KHR_OLD_SHAPES)
            spec = _index(shapes, geometry["shape"])
            if spec is None:
                self.problems.error(self._label(i), f"its collider names shape "
                                                      f"{geometry['shape']}, which the file "
                                                      f"does not declare; left out")
                return None
            return _Shape("KHR", spec=spec, convex=convex)
        if "mesh" in geometry:
            return _Shape("KHR", mesh=geometry["mesh"], convex=convex)
        if "node" in geometry:
            return _Shape("KHR", node=geometry["node"], convex=convex)
        self.problems.error(self._label(i), "its collider geometry names no shape, mesh or "
                                              "node; left out")
        return None

    def _omi_role(self, i: int, omi: dict[str, Any], role: _Role) -> None:
        motion = omi.get("motion")
        if isinstance(motion, dict):
            kind = motion.get("type")
            if kind not in ("static", "kinematic", "dynamic"):
                said = "has no type" if kind is None else f"type {kind!r} is not static, " \
                                                          f"kinematic or dynamic"
                self.problems.error(self._label(i), f"its OMI motion {said}; taken as dynamic")
                kind = "dynamic"
            role.motion, role.kind = motion, kind
        for key in ("collider", "trigger"):
            holder = omi.get(key)
            if not isinstance(holder, dict):
                continue
            shape = None
            if "shape" in holder and holder["shape"] != -1:
                spec = _index(self._shapes(OMI_SHAPE), holder["shape"])
                if spec is None:
                    self.problems.error(self._label(i), f"its {key} names shape "
                                                          f"{holder['shape']}, which the file "
                                                          f"does not declare; left out")
                else:
                    shape = self._omi_shape(spec)
            if key == "collider":
                role.collider, role.material = shape, holder.get("physicsMaterial")
                role.filter = holder.get("collisionFilter")
            else:
                role.trigger, role.trigger_nodes = shape, list(holder.get("nodes", []))
                role.trigger_filter = holder.get("collisionFilter")
                if shape is None and not role.trigger_nodes:
                    role.trigger_nodes = [-1]  # a compound trigger of its children

    @staticmethod
    def _omi_shape(spec: dict[str, Any]) -> _Shape:
        kind = spec.get("type")
        if kind in ("convex", "trimesh"):
            params = spec.get(kind, {}) if isinstance(spec.get(kind), dict) else {}
            return _Shape("OMI", mesh=params.get("mesh"), convex=kind == "convex")
        return _Shape("OMI", spec=spec)

    def _shapes(self, extension: str) -> list[Any]:
        holder = self.ext.get(extension, {})
        found = holder.get("shapes", []) if isinstance(holder, dict) else []
        return found if isinstance(found, list) else []

    def _top(self, family: str, key: str) -> list[Any]:
        """A top-level array (physicsMaterials, collisionFilters, physicsJoints) of the
        KHR or OMI extension, OMI joints living in their own extension."""
        name = KHR if family == "KHR" else (OMI_JOINT if key == "physicsJoints" else OMI_BODY)
        holder = self.ext.get(name, {})
        found = holder.get(key, []) if isinstance(holder, dict) else []
        return found if isinstance(found, list) else []

    # -- materials and filters ---------------------------------------------------------
    def _materials(self) -> None:
        stem = self.doc.path.stem
        for family in ("KHR", "OMI"):
            for k, m in enumerate(self._top(family, "physicsMaterials")):
                if not isinstance(m, dict):
                    continue
                label = f"{stem}.{'' if family == 'KHR' else 'omi_'}material{k}"
                name = m.get("name") if isinstance(m.get("name"), str) else label
                static = _number(m.get("staticFriction", 0.6))
                dynamic = _number(m.get("dynamicFriction", 0.6))
                bounce = _number(m.get("restitution", 0.0))
                if None in (static, dynamic, bounce):
                    self.problems.error(None, f"physics material {k} has a value that is not "
                                              f"a finite number; the default material is used")
                    continue
                if abs(static - dynamic) > 1e-6:
                    self.problems.warn(None, f"physics material {k}: static friction "
                                             f"{tidy(static)} differs from dynamic friction "
                                             f"{tidy(dynamic)}; contacts here have one Coulomb "
                                             f"coefficient, the dynamic one")
                modes = []
                ours = m.get("extras") if isinstance(m.get("extras"), dict) else {}
                for key in ("frictionCombine", "restitutionCombine"):
                    mode = m.get(key, "average" if family == "OMI" else None)
                    if ours.get(key) == GEOMETRIC_MEAN:  # written by our export
                        mode = GEOMETRIC_MEAN
                    if mode not in (None, "average", "minimum", "maximum", "multiply",
                                    GEOMETRIC_MEAN):
                        self.problems.warn(None, f"physics material {k}: {key} {mode!r} is "
                                                 f"not average, minimum, maximum or multiply; "
                                                 f"average is used")
                        mode = "average"
                    modes.append(mode)
                self.scene.materials.append(MaterialDecl(name, dynamic, bounce, *modes))
                self.materials[family, k] = name
        ids = unique_ids([m.id for m in self.scene.materials], ("default",))
        for m, new in zip(self.scene.materials, ids, strict=True):
            for key, old in self.materials.items():
                if old == m.id:
                    self.materials[key] = new
            m.id = new

    def _filter(self, family: str, index: Any, node: str) -> tuple[int, int] | None:
        """Category and mask bits for collision filter ``index``: one bit per collision
        system name in the file (at most 32)."""
        if index is None or index == -1:
            return None
        spec = _index(self._top(family, "collisionFilters"), index)
        if not isinstance(spec, dict):
            self.problems.error(node, f"it names collision filter {index}, which the file "
                                      f"does not declare; it collides with everything")
            return None
        systems = [s for s in spec.get("collisionSystems", []) if isinstance(s, str)]
        if len(systems) > 1:
            self.problems.once("filter-subset", node, "a collision filter with several "
                               "collision systems: here two colliders meet when one system "
                               "of each is in the other's collide-with list (the extension "
                               "asks for all of them)")
        category = self._bits(systems, node) if systems else 0xFFFFFFFF
        if "collideWithSystems" in spec:
            mask = self._bits(spec["collideWithSystems"], node)
        elif "notCollideWithSystems" in spec:
            mask = ~self._bits(spec["notCollideWithSystems"], node) & 0xFFFFFFFF
        else:
            mask = 0xFFFFFFFF
        return category, mask

    def _bits(self, systems: list[Any], node: str) -> int:
        bits = 0
        for name in systems:
            if not isinstance(name, str):
                continue
            if name not in self.systems:
                if len(self.systems) == 32:
                    self.problems.error(node, f"collision system {name!r} is the 33rd of the "
                                              f"file; collision bits hold 32, so it is left "
                                              f"out of the filter")
                    continue
                self.systems[name] = len(self.systems)
            bits |= 1 << self.systems[name]
        return bits

    # -- objects ------------------------------------------------------------------
    def _objects(self, order: list[int]) -> None:
        consumed: set[int] = set()  # nodes that are part of a compound trigger
        for i in order:
            role, name = self.roles[i], self._label(i)
            parent = int(self.doc.parents[i])
            above = self.owner.get(parent) if parent >= 0 else None
            extras = self._node_extras(i)
            made = None
            if role.motion is not None and role.kind != "static":
                made = self._body(i, role.kind or "dynamic")
            elif role.kind == "static" or (role.collider is not None and (
                    above is None or above.kind is None or above.trigger)):
                made = self._body(i, "static")
            elif (role.trigger is not None or role.trigger_nodes) and i not in consumed:
                made = self._body(i, "static", trigger=True)
                if above is not None and above.kind in ("dynamic", "kinematic"):
                    self.problems.warn(name, f"a trigger moving with body '{above.id}' in the "
                                             f"file stays where it starts here (a trigger is "
                                             f"an object of its own)")
                consumed.update(self._trigger_members(i, role))
            elif extras.physical and (above is None or above.kind is None):
                made = self._body(i, "dynamic")
                self.typed_bodies.add(id(made))
            elif above is None and (self.doc.nodes[i].get("mesh") is not None or
                                    extras.entries):
                made = self._new_object(i, None)
            obj = made or above
            attach(extras, obj, name, self.scene, self.problems)
            if obj is None:
                continue
            self.owner[i] = obj
            if role.collider is not None:
                if obj.trigger:
                    self.problems.warn(name, "a collider inside a trigger detects like the "
                                             "trigger here (it does not collide)")
                self._add_shape(i, obj, role.collider, role.material, role.filter)
            if obj.trigger and role.trigger is not None:
                self._add_shape(i, obj, role.trigger, None, None)
            if self.doc.nodes[i].get("mesh") is not None:
                self._add_visual(i, obj)
            if self.doc.nodes[i].get("skin") is not None:
                self.problems.once("skin", name, "skinned meshes are drawn in their bind "
                                                 "pose (no skinning on import)")
            if self.doc.nodes[i].get("camera") is not None:
                self._camera(i)
        for obj in self.scene.objects:
            if self.systems and obj.kind is not None and obj.category is None:
                obj.category = 0xFFFFFFFF  # unfiltered: meets every system's mask
        for obj in self.scene.objects:  # a file's body without colliders collides with nothing
            if obj.kind in ("dynamic", "kinematic") and not obj.shapes and not obj.trigger and \
                    id(obj) not in self.typed_bodies and not any(
                        e.key == "Geometry" for e in obj.extras.get("Physical", [])):
                self._phantom(obj)

    def _label(self, i: int) -> str:
        """A node as messages name it: its name, with its index when the name repeats."""
        ref = self.doc.node_ref(i)
        return self.doc.name(i) if not ref.startswith("#") else f"{self.doc.name(i)} {ref}"

    def _frame(self, i: int) -> Frame:
        """Node ``i``'s world frame, Z up (all nodes' taken apart at once, when first asked)."""
        if self._frames is None:
            self._frames = decompose_many(to_z_up(self.doc.world))
            self._quats = matrices_to_quats(self._frames[1])
        t, r, s, sheared = self._frames
        return Frame(t[i], r[i], s[i], bool(sheared[i]))

    def _new_object(self, i: int, kind: str | None, trigger: bool = False) -> ObjectDecl:
        f = self._frame(i)
        name = self.doc.name(i)
        if f.sheared:
            self.problems.warn(name, "its parents' non-uniform scale shears it; its shapes "
                                     "and mesh are the nearest unsheared ones")
        obj = ObjectDecl(name, name, vector(f.translation), unit_quaternion(self._quats[i]),
                         kind, trigger=trigger)
        self.scene.objects.append(obj)
        self.object_node[id(obj)] = i
        self.frames[id(obj)] = f.unscaled()
        return obj

    def _body(self, i: int, kind: str, trigger: bool = False) -> ObjectDecl:
        obj = self._new_object(i, kind, trigger)
        role = self.roles[i]
        if trigger:  # detects the bodies its filter's mask names; nothing collides with it
            found = self._filter(role.family, role.trigger_filter, obj.node)
            obj.category, obj.mask = 0, (0xFFFFFFFF if found is None else found[1])
        if role.motion is not None and kind != "static":
            self._motion(i, obj, role.motion, role.family)
        return obj

    def _motion(self, i: int, obj: ObjectDecl, motion: dict[str, Any], family: str) -> None:
        name = obj.node
        mass = _number(motion.get("mass", _OMI_MASS if family == "OMI" else None))
        if "mass" in motion and mass is None:
            self.problems.error(name, "its mass is not a finite number; the mass comes from "
                                      "the shapes' volume")
        if mass is not None and mass <= 0:
            if mass == 0:
                self.problems.warn(name, "its mass is 0, which the extension reads as "
                                         "infinite: imported as a kinematic body")
                obj.kind = "kinematic"
            else:
                self.problems.error(name, f"its mass {mass} is negative; the mass comes "
                                          f"from the shapes' volume")
            mass = None
        obj.mass = mass
        if mass is None:  # KHR: "calculated by the simulation engine", from the volume
            obj.density = VOLUME_DENSITY
        self._mass_frame(i, obj, motion)
        gravity = _number(motion.get("gravityFactor", 1.0))
        if gravity is None or abs(gravity) > 1e3:
            self.problems.error(name, f"gravityFactor {motion.get('gravityFactor')} is not a "
                                      f"finite number up to 1000; full gravity")
            gravity = 1.0
        obj.gravity = gravity != 0.0
        obj.gravity_factor = tidy(gravity) if gravity not in (0.0, 1.0) else 1.0
        # KHR gives velocities in node space (the node's rotation, not its scale); OMI
        # says nothing, and Godot writes its bodies' velocities in world axes
        turn = self._frame(i).rotation if family == "KHR" else UNTURNED
        for key, attr in (("linearVelocity", "velocity"), ("angularVelocity",
                                                            "angular_velocity")):
            if key in motion:
                v = _vector(motion[key], 3)
                if v is None:
                    self.problems.error(name, f"its {key} is not 3 finite numbers; it starts "
                                              f"at rest")
                else:
                    setattr(obj, attr, vector(turn @ (Y_UP_TO_Z_UP @ np.array(v))))

    def _mass_frame(self, i: int, obj: ObjectDecl, motion: dict[str, Any]) -> None:
        """The motion's centre of mass (node space: its scale applies) and principal
        inertia with their axes, turned Z up: glTF's Y moment is the engine's Z one."""
        if not _MASS_FRAME_KEYS & motion.keys():
            return  # most bodies: mass from the file or their shapes, no more
        name = obj.node
        given = {key: motion.get(key) for key in _MASS_FRAME_KEYS}
        found = {key: _vector(value, 4 if key == "inertiaOrientation" else 3)
                 for key, value in given.items() if value is not None}
        for key, value in found.items():
            if value is None:
                n = 4 if key == "inertiaOrientation" else 3
                self.problems.error(name, f"its {key} {given[key]} is not {n} finite numbers; "
                                          f"left out (the shapes' is used)")
        com, diagonal, turn = (found.get(k) for k in given)
        extras = motion.get("extras") if isinstance(motion.get("extras"), dict) else {}
        infinite = extras.get("infiniteInertia")  # our export's: those moments are 0
        if diagonal is not None and isinstance(infinite, list) and len(infinite) == 3:
            diagonal = [0.0 if flag is True else x for x, flag in zip(diagonal, infinite,
                                                                      strict=True)]
        if com is not None and any(com):
            obj.center_of_mass = vector(self._frame(i).scale * (Y_UP_TO_Z_UP @ np.array(com)))
        if diagonal is not None:  # a 0 is infinite: the body never turns about that axis
            if min(diagonal) < 0:
                self.problems.error(name, f"its inertiaDiagonal {given['inertiaDiagonal']} is "
                                          f"not 3 moments of 0 or more; left out (the shapes' "
                                          f"inertia is used)")
                return
            obj.inertia = vector(np.abs(Y_UP_TO_Z_UP) @ np.array(diagonal))
            norm = math.hypot(*turn) if turn is not None else 0.0
            if turn is not None and norm == 0:
                self.problems.error(name, "its inertiaOrientation is a zero quaternion; its "
                                          "inertia's axes are the node's")
            elif turn is not None:
                x, y, z, w = (c / norm for c in turn)
                obj.inertia_rotation = unit_quaternion((w, *(Y_UP_TO_Z_UP @ [x, y, z])))
        elif turn is not None and not _trivial("inertiaOrientation", given["inertiaOrientation"]):
            self.problems.once(f"inertia-axes-{name}", name, "its inertiaOrientation without an "
                               "inertiaDiagonal turns nothing (the shapes' inertia is used)")

    def _phantom(self, obj: ObjectDecl) -> None:
        self.problems.warn(obj.node, "a body without colliders: it gets a small sphere that "
                                     "collides with nothing, so it has mass and inertia")
        obj.shapes.append(ShapeDecl("sphere", (_PHANTOM_DIAMETER,)))
        obj.category, obj.mask = 0, 0

    def _trigger_members(self, i: int, role: _Role) -> list[int]:
        members = role.trigger_nodes
        if members == [-1]:  # OMI: the trigger's children with trigger shapes
            members = self._descendants(i)
        out = []
        for m in members:
            if not isinstance(m, int) or not 0 <= m < len(self.doc.nodes):
                self.problems.error(self._label(i), f"its compound trigger names node {m}, "
                                                      f"which does not exist; left out")
                continue
            out.append(m)
        return out

    def _descendants(self, i: int) -> list[int]:
        out, stack = [], list(self.doc.children[i])
        while stack:
            k = stack.pop()
            out.append(k)
            stack.extend(self.doc.children[k])
        return out

    # -- shapes and visuals -------------------------------------------------------------
    def _relative(self, obj: ObjectDecl, i: int) -> Frame:
        """Node ``i``'s frame in its object's (the object's own node: its scale alone)."""
        if self.object_node[id(obj)] == i:
            return Frame(_ORIGIN, UNTURNED, self._frame(i).scale, False)
        base = np.linalg.inv(self.frames[id(obj)])
        return decompose(base @ to_z_up(self.doc.world[i]))

    def _add_shape(self, i: int, obj: ObjectDecl, shape: _Shape | None, material: Any,
                   filter_index: Any) -> None:
        if shape is None:
            return
        name = self._label(i)
        family = shape.family
        if material is not None and material != -1:
            found = self.materials.get((family, material))
            if found is None:
                self.problems.error(name, f"its collider names physics material {material}, "
                                          f"which the file does not declare; the default "
                                          f"material is used")
            elif obj.material is None:
                obj.material = found
            elif obj.material != found:
                self.problems.warn(name, f"a body has one material here: '{obj.id}' keeps "
                                         f"'{obj.material}', this collider's '{found}' is not "
                                         f"used")
        own_filter = None
        if not obj.trigger:
            found_filter = self._filter(family, filter_index, name)
            if found_filter is not None:
                if obj.category is not None and (obj.category, obj.mask) != found_filter:
                    own_filter = found_filter  # a compound's colliders filter apart
                else:
                    obj.category, obj.mask = found_filter
        rel = self._relative(obj, i)
        if shape.spec is not None:
            decl = self._implicit(name, shape, rel, obj, i)
        else:
            decl = self._mesh_shape(i, shape, rel)
        if decl is not None:
            if own_filter is not None:
                decl.category, decl.mask = own_filter
            obj.shapes.append(decl)

    def _implicit(self, name: str, shape: _Shape, rel: Frame, obj: ObjectDecl,
                  i: int) -> ShapeDecl | None:
        spec = shape.spec or {}
        kind = spec.get("type")
        defaults = _DEFAULTS[shape.family]
        if kind == "plane":
            return self._plane(name, spec.get("plane", {}), rel, obj, i)
        if kind not in defaults:
            self.problems.error(name, f"shape type {kind!r} is not box, sphere, capsule, "
                                      f"cylinder or plane; its collider is left out")
            return None
        params = dict(defaults[kind])
        given = spec.get(kind, {})
        if isinstance(given, dict):
            params.update({k: v for k, v in given.items() if k in params})
            if kind in ("capsule", "cylinder") and "radius" in given and not (
                    {"radiusTop", "radiusBottom"} & set(given)):
                params.update(_one_radius(shape.family, kind, given))
        scale = np.abs(rel.scale)
        if not scale.any():
            return None  # a zero-scaled node disables its shape (the extension says)
        zero = _zero_size(kind, params)
        if zero is not None:
            self.problems.error(name, f"its {kind} collider has zero size ({zero}); left out")
            return None
        try:
            if kind == "box":
                size = _vector(params["size"], 3)
                if size is None or min(size) < 0:
                    raise ValueError(f"box size {params['size']} is not 3 positive numbers")
                dims: tuple[float, ...] = vector(np.abs(Y_UP_TO_Z_UP @ np.array(size)) * scale)
            elif kind == "sphere":
                radius = _positive(params["radius"], "sphere radius")
                if not np.allclose(scale, scale[0], rtol=1e-6):
                    self.problems.warn(name, f"a sphere scaled unevenly {vector(scale)} stays "
                                             f"a sphere, of the largest scale")
                dims = (2 * radius * float(scale.max()),)
            else:
                dims = self._round(name, kind, params, scale)
        except ValueError as exc:
            self.problems.error(name, f"{exc}; its collider is left out")
            return None
        if min(dims) <= 0:
            self.problems.error(name, f"its {kind} collider is scaled to nothing by its node "
                                      f"{vector(rel.scale)}; left out")
            return None
        return ShapeDecl(kind, dims, vector(rel.translation), quaternion(rel.rotation))

    def _round(self, name: str, kind: str, params: dict[str, Any],
               scale: np.ndarray) -> tuple[float, ...]:
        """A capsule's or cylinder's (diameter, length) along local Z (glTF's Y)."""
        top = _positive(params["radiusTop"], f"{kind} radiusTop", zero=True)
        bottom = _positive(params["radiusBottom"], f"{kind} radiusBottom", zero=True)
        height = _positive(params["height"], f"{kind} height", zero=True)
        if abs(top - bottom) > 1e-6:
            self.problems.warn(name, f"a tapered {kind} (radii {tidy(top)} and "
                                     f"{tidy(bottom)}) is a {kind} of the larger radius here")
        if not math.isclose(scale[0], scale[1], rel_tol=1e-6):
            self.problems.warn(name, f"a {kind} scaled unevenly across its axis stays round, "
                                     f"of the larger scale")
        radius = max(top, bottom) * float(max(scale[0], scale[1]))
        return (2 * radius, height * float(scale[2]))

    def _plane(self, name: str, params: Any, rel: Frame, obj: ObjectDecl,
               i: int) -> ShapeDecl | None:
        params = params if isinstance(params, dict) else {}
        if obj.kind in ("dynamic", "kinematic"):
            self.problems.error(name, "a plane collider cannot move; left out")
            return None
        if "sizeX" in params or "sizeZ" in params:
            sx = _positive(params.get("sizeX", 1e3), "plane sizeX")
            sz = _positive(params.get("sizeZ", 1e3), "plane sizeZ")
            scale = np.abs(rel.scale)
            offset = np.array(rel.translation) - rel.rotation @ np.array(
                [0.0, 0.0, _PLANE_THICKNESS / 2])
            return ShapeDecl("box", (tidy(sx * scale[0]), tidy(sz * scale[1]),
                                     _PLANE_THICKNESS), vector(offset), quaternion(rel.rotation))
        if self.object_node[id(obj)] != i or obj.shapes:
            plane = self._new_object(i, "static")
            plane.id = f"{name}.plane"
            plane.shapes.append(ShapeDecl("plane"))
            plane.material = obj.material
            return None
        return ShapeDecl("plane")

    def _mesh_shape(self, i: int, shape: _Shape, rel: Frame) -> ShapeDecl | None:
        """A mesh or hull collider: a glTF mesh (the collider node's own, or any, placed at
        the node with its scale) or a node's meshes (``geometry.node``)."""
        name = self._label(i)
        kind = "hull" if shape.convex else "mesh"
        offset, rotation = vector(rel.translation), quaternion(rel.rotation)
        if shape.node is not None:
            if not isinstance(shape.node, int) or not 0 <= shape.node < len(self.doc.nodes):
                self.problems.error(name, f"its collider names node {shape.node}, which does "
                                          f"not exist; left out")
                return None
            holders = [shape.node, *(k for k in self._descendants(shape.node)
                                     if self.doc.nodes[k].get("mesh") is not None)]
            meshes = [self.doc.nodes[k]["mesh"] for k in holders
                      if self.doc.nodes[k].get("mesh") is not None]
            # placed in the collider node's space, its scale too (Blender 4 writes the
            # mesh on a bare node beside it and scales the collider node); the node's own
            # mesh has its scale already
            decl = ShapeDecl(kind, (), offset, rotation, "",
                             tuple(self.doc.node_ref(k) for k in holders),
                             scale=(1.0, 1.0, 1.0) if shape.node == i else
                             vector(np.abs(rel.scale)))
        else:
            meshes = [shape.mesh]
            if self.doc.nodes[i].get("mesh") == shape.mesh:  # the node's own: as it is drawn
                decl = ShapeDecl(kind, (), offset, rotation, "", (self.doc.node_ref(i),))
            elif isinstance(shape.mesh, int) and 0 <= shape.mesh < len(self.doc.meshes):
                decl = ShapeDecl(kind, (), offset, rotation, "",
                                 mesh=self.doc.mesh_ref(shape.mesh),
                                 scale=vector(np.abs(rel.scale)))
            else:
                self.problems.error(name, f"its collider names mesh {shape.mesh}, which the "
                                          f"file does not have; left out")
                return None
        try:
            for mesh in meshes:
                self.doc.mesh_parts(mesh)
        except ValueError as exc:
            self.problems.error(name, f"its collider mesh cannot be read: {exc}; left out")
            return None
        return decl

    def _add_visual(self, i: int, obj: ObjectDecl) -> None:
        try:
            self.doc.mesh_parts(self.doc.nodes[i]["mesh"])
        except ValueError as exc:
            self.problems.error(self._label(i), f"its mesh cannot be read: {exc}; it is not "
                                                  f"drawn")
            return
        ref = self.doc.node_ref(i)
        if obj.visual is None:
            first = self.doc.node_ref(self.object_node[id(obj)])
            obj.visual = ("", (first,) if first == ref else (first, ref))
        elif ref not in obj.visual[1]:
            obj.visual = (obj.visual[0], (*obj.visual[1], ref))

    def _camera(self, i: int) -> None:
        cameras = self.doc.json.get("cameras", [])
        spec = _index(cameras, self.doc.nodes[i]["camera"])
        if not isinstance(spec, dict):
            return
        persp = spec.get("perspective", {})
        yfov = _number(persp.get("yfov", 0.8)) if isinstance(persp, dict) else None
        f = self._frame(i)
        forward = f.rotation @ (Y_UP_TO_Z_UP @ np.array([0.0, 0.0, -1.0]))
        self.scene.cameras.append(CameraDecl(
            self.doc.name(i), vector(f.translation), vector(f.translation + forward),
            tidy(math.degrees(yfov or 0.8))))
        if spec.get("type") == "orthographic":
            self.problems.warn(self._label(i), "an orthographic camera is imported as a "
                                                 "perspective one")

    # -- extras -------------------------------------------------------------------
    def _node_extras(self, i: int) -> Extras:
        return read_extras(self.doc.nodes[i].get("extras"),
                           f"{self.doc.path.name} node '{self._label(i)}' extras")

    # -- joints --------------------------------------------------------------------
    def _joints(self, order: list[int]) -> None:
        ids: list[str] = []
        made: list[JointDecl] = []
        for i in order:
            role = self.roles[i]
            if role.joint is None:
                continue
            decl = self._joint(i, role.joint, role.joint_family)
            if decl is not None:
                made.append(decl)
                ids.append(decl.id)
        for decl, new in zip(made, unique_ids(ids, (o.id for o in self.scene.objects)),
                             strict=True):
            decl.id = new
        self.scene.joints = made

    def _body_of(self, i: int) -> ObjectDecl | None:
        """The moving body node ``i`` belongs to (None: the static world)."""
        obj = self.owner.get(i)
        return obj if obj is not None and obj.kind in ("dynamic", "kinematic") else None

    def _joint(self, i: int, spec: dict[str, Any], family: str) -> JointDecl | None:
        name = self._label(i)
        connected = spec.get("connectedNode")
        if not isinstance(connected, int) or not 0 <= connected < len(self.doc.nodes):
            self.problems.error(name, f"its joint names connected node {connected}, which does "
                                      f"not exist; the joint is left out")
            return None
        if connected in self.doc.bad_nodes or connected not in self.roles:
            self.problems.error(name, f"its joint's connected node "
                                      f"'{self._label(connected)}' is not in the scene (or "
                                      f"unusable); the joint is left out")
            return None
        desc = _index(self._top(family, "physicsJoints"), spec.get("joint"))
        if not isinstance(desc, dict):
            self.problems.error(name, f"its joint names joint description {spec.get('joint')}, "
                                      f"which the file does not declare; left out")
            return None
        body_a, body_b = self._body_of(i), self._body_of(connected)
        if body_a is None and body_b is None:
            self.problems.warn(name, "its joint connects nothing that moves; left out")
            return None
        if body_a is body_b:
            self.problems.warn(name, "its joint connects a body to itself; left out")
            return None
        if spec.get("enableCollision") and body_a is not None and body_b is not None:
            self.problems.once("enable-collision", name, "jointed bodies never collide here "
                                                         "(enableCollision is not represented)")
        # the attachment frames: their axes are the file's local axes, seen in Z-up world
        fj = decompose(to_z_up(self.doc.world[i]))
        fc = decompose(to_z_up(self.doc.world[connected]))
        frames = Frames(fj.rotation @ Y_UP_TO_Z_UP, fj.translation,
                        fc.rotation @ Y_UP_TO_Z_UP, fc.translation)
        made = working_joint(name, _dofs(desc, name, self.problems, family), frames,
                             body_a.id if body_a else None, body_b.id if body_b else None,
                             self.problems)
        if made is None:
            return None
        # joined to a static body: named after the moving one (the world's side, as when
        # left out), so the two never touch unless the file asks (enableCollision)
        other = self.owner.get(connected if body_b is None else i)
        if (body_a is None or body_b is None) and other is not None and \
                other.kind == "static" and not spec.get("enableCollision"):
            made.bodies = (*made.bodies, other.id)
        self._drive(name, desc, made, body_b or body_a)
        unique = not self.doc.node_ref(i).startswith("#")
        return made.decl(name if unique else "+".join(
            [*made.bodies, *(["world"] if len(made.bodies) == 1 else [])]))

    def _drive(self, name: str, desc: dict[str, Any], joint: WorkingJoint,
               driven: ObjectDecl) -> None:
        """The file's drives on the joint's free axis: a position drive (stiffness) or one
        that only damps is the joint's Spring; a velocity drive its motor, of at most
        maxForce (unlimited: what damping x target velocity asks from rest). In
        acceleration mode stiffness and damping are per unit of the driven body's mass or
        moment about the axis."""
        for drive in desc.get("drives", []) or []:
            if not isinstance(drive, dict):
                continue
            axis = drive.get("axis", 0)
            if not isinstance(axis, int) or not 0 <= axis <= 2:
                self.problems.error(name, f"a drive's axis {axis!r} is not 0, 1 or 2; left out")
                continue
            angular = drive.get("type") == "angular"
            dof = (3 if angular else 0) + axis
            if dof != joint.free:
                self.problems.warn(name, f"a drive on the joint's {DOF_NAMES[dof]} axis, "
                                         f"which is not its free axis, is left out")
                continue
            stiffness = _number(drive.get("stiffness", 0.0)) or 0.0
            velocity = _number(drive.get("velocityTarget", 0.0)) or 0.0
            damping = _number(drive.get("damping", 0.0)) or 0.0
            target = _number(drive.get("positionTarget", 0.0)) or 0.0
            force = _number(drive.get("maxForce"))
            if force is not None and force < 0:  # OMI: negative is not force-limited
                force = None
            if min(stiffness, damping) < 0:
                self.problems.error(name, f"a drive's stiffness {tidy(stiffness)} or damping "
                                          f"{tidy(damping)} is negative; left out")
                continue
            scale, what = 1.0, ""
            if drive.get("mode") == "acceleration":  # force per unit of acceleration
                scale, what = _effective_inertia(driven, joint, angular)
            if stiffness > 0 or (damping > 0 and not velocity):
                self._spring(name, joint, stiffness * scale, damping * scale, target,
                             velocity, force)
                continue
            if not velocity:
                continue
            if force is None:
                force = damping * abs(velocity) * scale
                self.problems.warn(name, f"a drive without a force limit: a motor of at most "
                                         f"{tidy(force)} {'N m' if angular else 'N'} (damping x "
                                         f"target velocity{what})")
            if force > 0:
                joint.motor(velocity, force)
            else:
                self.problems.warn(name, "a drive that can apply no force (maxForce or damping "
                                         "0) is left out")

    def _spring(self, name: str, joint: WorkingJoint, stiffness: float, damping: float,
                target: float, velocity: float, force: float | None) -> None:
        """A position drive as the joint's spring: its pull ``k (target - x) + d (v - x')``
        is the spring's toward ``target + d v / k``, exactly."""
        if joint.type not in ("Hinge", "MotorizedHinge", "Slider"):
            self.problems.warn(name, f"a position drive on a {joint.type} joint is not "
                                     f"represented: springs act on hinges and sliders here")
            return
        if joint.spring is not None:
            self.problems.warn(name, "a second position drive on the same axis is left out")
            return
        if force == 0:
            self.problems.warn(name, "a position drive that can apply no force (maxForce 0) is "
                                     "left out")
            return
        if velocity and stiffness > 0:
            target += damping * velocity / stiffness
        joint.pull(stiffness, damping, target, force)


def _effective_inertia(body: ObjectDecl, joint: WorkingJoint,
                       angular: bool) -> tuple[float, str]:
    """What an acceleration-mode drive scales its force by, and how it was found: the
    driven body's mass, or its moment of inertia about the joint's axis (its primitive
    shapes as solids of one density; mesh shapes, whose volume the file does not say
    here, are left out of it)."""
    solids = [(s, _volume(s)) for s in body.shapes]
    solids = [(s, v) for s, v in solids if v > 0]
    total = sum(v for _, v in solids)
    mass = body.mass if body.mass is not None else (
        (body.density or VOLUME_DENSITY) * total if total > 0 else 1.0)
    if not angular:
        return mass, " x the body's mass"
    n = np.asarray(joint.axis, np.float64)
    n = n / np.linalg.norm(n)
    turn = quat_to_matrix(np.asarray(body.rotation, np.float64))

    def across(offset: Any) -> float:
        """The squared distance from the joint's axis of a point in the body's frame."""
        arm = np.asarray(body.position) + turn @ np.asarray(offset) - np.asarray(joint.anchor)
        arm = arm - (arm @ n) * n
        return float(arm @ arm)

    what = " x the body's moment of inertia about the axis"
    if body.inertia is not None:  # the file's: about its centre of mass
        local = (turn @ quat_to_matrix(np.asarray(body.inertia_rotation, np.float64))).T @ n
        return (float(local @ (np.asarray(body.inertia) * local))
                + mass * across(body.center_of_mass or (0.0, 0.0, 0.0)), what)
    if not solids:
        return mass, " x the body's mass, as if 1 m from the axis (its shapes are meshes)"
    moment, centroid = 0.0, np.zeros(3)
    for s, v in solids:
        m = mass * v / total
        local = (turn @ quat_to_matrix(np.asarray(s.rotation, np.float64))).T @ n
        moment += float(local @ (_principal(s, m) * local)) + m * across(s.offset)
        centroid += m * np.asarray(s.offset) / mass
    if body.center_of_mass is not None:  # the shapes' inertia about their centroid, moved
        moment += mass * (across(body.center_of_mass) - across(centroid))
    return moment, what


def _volume(s: ShapeDecl) -> float:
    """A primitive's volume (m^3) from its scene size; 0 for meshes and planes."""
    if s.kind == "box":
        return float(np.prod(s.size))
    if s.kind == "sphere":
        return math.pi * s.size[0] ** 3 / 6
    if s.kind in ("cylinder", "capsule"):
        r, length = s.size[0] / 2, s.size[1]
        return math.pi * r * r * (length + (4 * r / 3 if s.kind == "capsule" else 0.0))
    return 0.0


def _principal(s: ShapeDecl, m: float) -> np.ndarray:
    """A solid primitive's principal moments of inertia (kg m^2) in its own frame; a
    capsule as the cylinder of its volume."""
    if s.kind == "box":
        x, y, z = (float(v) ** 2 for v in s.size)
        return m / 12 * np.array([y + z, x + z, x + y])
    if s.kind == "sphere":
        return np.full(3, m * s.size[0] ** 2 / 10)
    r, length = s.size[0] / 2, s.size[1] + (2 * s.size[0] / 3 if s.kind == "capsule" else 0)
    side = m * (3 * r * r + length * length) / 12
    return np.array([side, side, m * r * r / 2])


def _dofs(desc: dict[str, Any], name: str, problems: Problems, family: str) -> list[Dof]:
    """Each of the six degrees of freedom: free, locked, or limited (low, high).

    A limit may name linear and angular axes at once (OMI's weld). Over several axes KHR
    bounds a distance or a cone (held here only when the bound is 0); OMI bounds each
    axis alone, as if each had a limit of its own."""
    dofs: list[Dof] = [FREE] * 6
    for limit in desc.get("limits", []) or []:
        if not isinstance(limit, dict):
            continue
        groups = [(base, [a for a in limit[key] if isinstance(a, int) and 0 <= a <= 2])
                  for base, key in ((0, "linearAxes"), (3, "angularAxes"))
                  if isinstance(limit.get(key), list)]
        if not any(axes for _, axes in groups):
            problems.error(name, "a joint limit names no linear or angular axis 0, 1 or 2; "
                                 "left out")
            continue
        low = _number(limit.get("min", -math.inf)) if "min" in limit else -math.inf
        high = _number(limit.get("max", math.inf)) if "max" in limit else math.inf
        if low is None or high is None:
            problems.error(name, "a joint limit has a min or max that is not a number; left out")
            continue
        if low == -math.inf and high == math.inf:
            problems.once(f"no-range-{name}", name, "a joint limit with neither min nor max "
                                                    "holds nothing (the axes it names are free)")
            continue
        stiffness = _number(limit.get("stiffness"))
        if stiffness is not None and stiffness != math.inf and not (
                family == "OMI" and stiffness < 0):  # OMI: negative is infinitely stiff
            problems.once(f"soft-{name}", name, f"soft joint limits (stiffness "
                                                f"{tidy(stiffness)}) are hard here")
        for base, axes in groups:
            if len(axes) == 1 or family == "OMI":
                state = "locked" if low == high else "limited"
                if state == "locked" and low != 0:
                    problems.warn(name, f"a limit that holds the "
                                        f"{', '.join(DOF_NAMES[base + a] for a in axes)} "
                                        f"axis at {low}, not 0, holds it where it starts here")
                for a in axes:
                    dofs[base + a] = (state, low, high)
            elif high == 0 or (high <= 0 and low <= 0):
                for a in axes:
                    dofs[base + a] = LOCKED
            else:
                kind = "distance" if base == 0 else "cone"
                problems.warn(name, f"a {kind} limit over {len(axes)} axes (up to "
                                    f"{tidy(high)}) is not represented: those axes are free")
    return dofs


def _one_radius(family: str, kind: str, given: dict[str, Any]) -> dict[str, Any]:
    """A capsule or cylinder of one ``radius``, as OMI's drafts before September 2024 (and
    Godot 4.4, which writes them) give it: an OMI capsule's ``height`` then is its full
    height, caps included (default 2 m), which the present form counts between the caps."""
    radius = given["radius"]
    out = {"radiusTop": radius, "radiusBottom": radius}
    if family == "OMI":
        height = given.get("height", 2.0)
        out["height"] = height
        if kind == "capsule" and _number(height) is not None and _number(radius) is not None:
            out["height"] = max(height - 2 * radius, 0.0)
    return out


def _zero_size(kind: str, params: dict[str, Any]) -> str | None:
    """What makes an implicit shape degenerate, in the file's own terms (None: nothing)."""
    if kind == "box":
        size = params.get("size")
        return f"size {size}" if isinstance(size, list) and 0 in size else None
    if kind == "sphere":
        return "radius 0" if params.get("radius") == 0 else None
    if params.get("height") == 0:
        return "height 0"
    if params.get("radiusTop") == 0 and params.get("radiusBottom") == 0:
        return "both radii 0"
    return None


def _trivial(key: str, value: Any) -> bool:
    """Whether ``value`` says nothing (zero offset, identity orientation, unset inertia)."""
    v = _vector(value, 4 if key == "inertiaOrientation" else 3)
    if v is None:
        return False
    if key == "inertiaOrientation":
        return np.allclose(v, (0, 0, 0, 1)) or np.allclose(v, (0, 0, 0, -1))
    return not any(v)


def _strings(items: Any) -> list[str]:
    return [x for x in items if isinstance(x, str)] if isinstance(items, list) else []


def _index(items: Any, index: Any) -> Any:
    if isinstance(items, list) and isinstance(index, int) and 0 <= index < len(items):
        return items[index]
    return None


def _number(value: Any) -> float | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return None
    return float(value) if math.isfinite(value) else None


def _positive(value: Any, what: str, zero: bool = False) -> float:
    x = _number(value)
    if x is None or x < 0 or (x == 0 and not zero):
        raise ValueError(f"{what} {value} is not a positive number")
    return x


def _vector(value: Any, n: int) -> list[float] | None:
    if not isinstance(value, list) or len(value) != n:
        return None
    out = [_number(v) for v in value]
    return None if None in out else out  # type: ignore[return-value]
