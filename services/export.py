"""Export: a scene (or a saved state) as glTF 2.0 with KHR_physics_rigid_bodies and
KHR_implicit_shapes, so it opens in Blender (with the physics add-on) or Godot.

Every object is a node where it is now, drawn with its model or primitives; a body's
shapes are its colliders (on the node, or on child nodes when offset), its material a
physics material, its ``Category``/``Mask`` a collision filter (one system per bit), a
trigger a ``trigger``; each joint is a pair of attachment frames (``jointSpaceA`` under
its second body, ``jointSpaceB`` under its first, as Blender writes them) with the limits
and velocity drive its type means, a spring a position drive; a body's given centre of
mass and inertia its motion's. Importing the file again gives the same bodies, shapes,
masses, materials and joints (:mod:`engine.interchange.gltf_physics` reads it).

What glTF cannot say is told, not dropped: material pairs (KHR has per-material combine
modes only), ``hinge2`` (exported as a universal joint) and ``six_dof`` tracking joints
(left out). Velocities are written in node space, as the extension says.
"""

from __future__ import annotations

import base64
import json
import math
import struct
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from components import Avatar, Joint, Physical, Shape, Transform, Trigger, Visual
from components.joint import JointKind
from engine.assets import AssetError, Assets
from engine.assets.gltf import Y_UP_TO_Z_UP
from engine.interchange.gltf_physics import KHR, KHR_SHAPES
from engine.interchange.model import GEOMETRIC_MEAN, Problems
from engine.physics.backend import locked_inertia
from engine.rotation import matrix_to_quat, quat_to_matrix
from engine.scene.diagnostics import Diagnostic
from engine.scene.factory import SceneSpec
from services.render.meshes import primitive

#: A velocity drive as stiff as a motor: force = damping x velocity error, up to maxForce.
MOTOR_DAMPING = 1e6
_ALL_BITS = 0xFFFFFFFF
_TO_GLTF = Y_UP_TO_Z_UP.T  # the engine's axes -> glTF's


def to_gltf(v: Sequence[float]) -> list[float]:
    """A vector in the engine's axes (Z up) in glTF's (+Y up)."""
    return [float(x) for x in _TO_GLTF @ np.asarray(v, np.float64)]


def gltf_rotation(q: Sequence[float]) -> list[float]:
    """An orientation ``(w, x, y, z)`` (engine axes, local axes turned with it) as glTF's
    ``[x, y, z, w]``."""
    w, x, y, z = (float(c) for c in q)
    gx, gy, gz = to_gltf((x, y, z))
    return [gx, gy, gz, w]



class _Shift:
    """Moves a merged file's indices past what the document already held (``base``:
    how many of each kind it had)."""

    def __init__(self, base: dict[str, int]) -> None:
        self.base = base

    def __call__(self, item: dict[str, Any], key: str, kind: str) -> None:
        if key in item:
            item[key] += self.base[kind]


def _carry_looks(doc: dict[str, Any], d: dict[str, Any], shift: _Shift) -> None:
    """A merged file's accessors, embedded images, samplers, textures and materials."""
    for acc in doc.get("accessors", []):
        acc = json.loads(json.dumps(acc))
        shift(acc, "bufferView", "bufferViews")
        for part in ("indices", "values"):
            if part in acc.get("sparse", {}):
                shift(acc["sparse"][part], "bufferView", "bufferViews")
        d["accessors"].append(acc)
    for image in doc.get("images", []):
        image = dict(image)
        if "uri" in image and not str(image["uri"]).startswith("data:"):
            continue  # an external image is not carried (the model keeps its colours)
        shift(image, "bufferView", "bufferViews")
        d["images"].append(image)
    d["samplers"] += doc.get("samplers", [])
    for texture in doc.get("textures", []):
        texture = dict(texture)
        shift(texture, "source", "images")
        shift(texture, "sampler", "samplers")
        d["textures"].append(texture)
    for material in doc.get("materials", []):
        material = json.loads(json.dumps(material))
        for holder in (material, material.get("pbrMetallicRoughness", {})):
            for key, info in holder.items():
                if key.endswith("Texture") and isinstance(info, dict):
                    shift(info, "index", "textures")
        material.pop("extensions", None)
        d["materials"].append(material)


def _carry_meshes(doc: dict[str, Any], d: dict[str, Any], shift: _Shift) -> None:
    accessors = shift.base["accessors"]
    for mesh in doc.get("meshes", []):
        mesh = json.loads(json.dumps(mesh))
        for prim in mesh.get("primitives", []):
            prim["attributes"] = {k: v + accessors for k, v in prim["attributes"].items()}
            shift(prim, "indices", "accessors")
            shift(prim, "material", "materials")
            prim["targets"] = [{k: v + accessors for k, v in t.items()}
                               for t in prim.get("targets", [])] or None
            if prim["targets"] is None:
                del prim["targets"]
            prim.pop("extensions", None)
        d["meshes"].append(mesh)


def _carry_nodes(doc: dict[str, Any], d: dict[str, Any], shift: _Shift) -> None:
    """A merged file's nodes (without cameras or extensions), skins and animations."""
    nodes = shift.base["nodes"]
    for node in doc.get("nodes", []):
        node = json.loads(json.dumps(node))
        shift(node, "mesh", "meshes")
        shift(node, "skin", "skins")
        node.pop("camera", None)
        node.pop("extensions", None)
        if "children" in node:
            node["children"] = [c + nodes for c in node["children"]]
        d["nodes"].append(node)
    for skin in doc.get("skins", []):
        skin = dict(skin)
        skin["joints"] = [j + nodes for j in skin["joints"]]
        shift(skin, "skeleton", "nodes")
        shift(skin, "inverseBindMatrices", "accessors")
        d["skins"].append(skin)
    for animation in doc.get("animations", []):
        animation = json.loads(json.dumps(animation))
        for channel in animation["channels"]:
            shift(channel["target"], "node", "nodes")
        for sampler in animation["samplers"]:
            sampler["input"] += shift.base["accessors"]
            sampler["output"] += shift.base["accessors"]
        d["animations"].append(animation)

class GltfWriter:
    """A glTF document built node by node; written as .glb, or .gltf with a data URI."""

    def __init__(self, generator: str) -> None:
        self.doc: dict[str, Any] = {"asset": {"version": "2.0", "generator": generator},
                                    "scene": 0, "scenes": [{"nodes": []}], "nodes": [],
                                    "meshes": [], "accessors": [], "bufferViews": [],
                                    "extensionsUsed": []}
        self.bin = bytearray()
        self._meshes: dict[tuple, int] = {}

    def use(self, *extensions: str) -> None:
        for e in extensions:
            if e not in self.doc["extensionsUsed"]:
                self.doc["extensionsUsed"].append(e)

    def top(self, extension: str, key: str, item: dict[str, Any]) -> int:
        """Append ``item`` to the document-level array ``key`` of ``extension``."""
        self.use(extension)
        items = self.doc.setdefault("extensions", {}).setdefault(extension, {}).setdefault(
            key, [])
        items.append(item)
        return len(items) - 1

    def _view(self, data: bytes, target: int) -> int:
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": len(self.bin),
                                        "byteLength": len(data), "target": target})
        self.bin += data
        return len(self.doc["bufferViews"]) - 1

    def mesh(self, vertices: np.ndarray, faces: np.ndarray, name: str,
             color: Sequence[float] | None = (0.8, 0.8, 0.8, 1.0)) -> int:
        """A triangle mesh in glTF axes (``color`` None: no material, a collider's); the
        same geometry given twice is stored once."""
        v = np.ascontiguousarray(vertices, np.float32).reshape(-1, 3)
        f = np.ascontiguousarray(faces, np.uint32 if len(v) >= 65536 else np.uint16)
        key = (v.tobytes(), f.tobytes(), None if color is None else tuple(color))
        if key in self._meshes:
            return self._meshes[key]
        pos = self._view(v.tobytes(), 34962)
        idx = self._view(f.tobytes(), 34963)
        acc = self.doc["accessors"]
        acc.append({"bufferView": pos, "componentType": 5126, "count": len(v), "type": "VEC3",
                    "min": v.min(axis=0).tolist(), "max": v.max(axis=0).tolist()})
        acc.append({"bufferView": idx, "componentType": 5123 if f.dtype == np.uint16 else 5125,
                    "count": int(f.size), "type": "SCALAR"})
        primitive_: dict[str, Any] = {"attributes": {"POSITION": len(acc) - 2},
                                      "indices": len(acc) - 1}
        if color is not None:
            materials = self.doc.setdefault("materials", [])
            materials.append({"pbrMetallicRoughness": {"baseColorFactor": list(color)}})
            primitive_["material"] = len(materials) - 1
        self.doc["meshes"].append({"name": name, "primitives": [primitive_]})
        self._meshes[key] = len(self.doc["meshes"]) - 1
        return self._meshes[key]

    def node(self, name: str, translation: Sequence[float] = (0.0, 0.0, 0.0),
             parent: int | None = None, rotation: Sequence[float] | None = None,
             scale: Sequence[float] | None = None, mesh: int | None = None,
             extensions: dict[str, Any] | None = None, extras: dict[str, Any] | None = None,
             in_scene: bool = True) -> int:
        """A node (glTF axes: ``rotation`` is ``[x, y, z, w]``) under ``parent`` or at the
        scene's root."""
        node: dict[str, Any] = {"name": name}
        if any(translation):
            node["translation"] = [float(t) for t in translation]
        if rotation is not None and list(rotation) != [0.0, 0.0, 0.0, 1.0]:
            node["rotation"] = [float(r) for r in rotation]
        if scale is not None:
            node["scale"] = [float(s) for s in scale]
        if mesh is not None:
            node["mesh"] = mesh
        if extensions:
            node["extensions"] = extensions
            self.use(*extensions)
        if extras is not None:
            node["extras"] = extras
        self.doc["nodes"].append(node)
        index = len(self.doc["nodes"]) - 1
        if parent is not None:
            self.doc["nodes"][parent].setdefault("children", []).append(index)
        elif in_scene:
            self.doc["scenes"][0]["nodes"].append(index)
        return index

    def merge(self, source: Path, parent: int, scale: float = 1.0) -> list[int]:
        """Copy the glTF file ``source`` whole (nodes, meshes, skins, animations, materials,
        textures and images, its buffers' bytes) under node ``parent``, its scene's roots in
        a node of ``scale`` (glTF axes as the file has them: a skinned model keeps its own
        frame); the new nodes' indices. Raises ValueError for a file it cannot read."""
        doc, buffers = _read_gltf(source)
        d = self.doc
        base = {key: len(d.setdefault(key, [])) for key in (
            "nodes", "meshes", "accessors", "bufferViews", "materials", "textures", "images",
            "samplers", "skins", "animations")}
        starts = []
        for data in buffers:
            while len(self.bin) % 8:
                self.bin.append(0)
            starts.append(len(self.bin))
            self.bin += data
        for view in doc.get("bufferViews", []):
            view = dict(view)
            view["byteOffset"] = starts[view.get("buffer", 0)] + view.get("byteOffset", 0)
            view["buffer"] = 0
            d["bufferViews"].append(view)
        shift = _Shift(base)
        _carry_looks(doc, d, shift)
        _carry_meshes(doc, d, shift)
        _carry_nodes(doc, d, shift)
        scene = (doc.get("scenes") or [{}])[doc.get("scene", 0)]
        roots = [r + base["nodes"] for r in scene.get("nodes", [])]
        holder = self.node(f"{d['nodes'][parent].get('name', 'model')}.model", parent=parent,
                           scale=None if scale == 1.0 else [scale] * 3)
        d["nodes"][holder]["children"] = roots
        for key in ("materials", "textures", "images", "samplers", "skins", "animations"):
            if not d[key]:
                del d[key]
        return list(range(base["nodes"], base["nodes"] + len(doc.get("nodes", []))))

    def khr(self, index: int, **parts: Any) -> None:
        """Set ``KHR_physics_rigid_bodies`` parts (motion, collider, trigger, joint)."""
        self.use(KHR)
        self.doc["nodes"][index].setdefault("extensions", {}).setdefault(KHR, {}).update(parts)

    def shape(self, kind: str, **params: Any) -> dict[str, Any]:
        """A collider geometry naming a new KHR_implicit_shapes shape."""
        return {"shape": self.top(KHR_SHAPES, "shapes", {"type": kind, kind: params})}

    def write(self, path: Path) -> Path:
        doc = json.loads(json.dumps(self.doc))
        if not doc["extensionsUsed"]:
            del doc["extensionsUsed"]
        if self.bin:
            doc["buffers"] = [{"byteLength": len(self.bin)}]
        else:
            for key in ("meshes", "accessors", "bufferViews"):
                doc.pop(key)
        if path.suffix.lower() == ".gltf":
            if self.bin:
                doc["buffers"][0]["uri"] = ("data:application/octet-stream;base64," +
                                            base64.b64encode(bytes(self.bin)).decode())
            path.write_text(json.dumps(doc, indent=1))
            return path
        text = json.dumps(doc, separators=(",", ":")).encode()
        text += b" " * (-len(text) % 4)
        data = bytes(self.bin) + b"\0" * (-len(self.bin) % 4)
        chunks = struct.pack("<II", len(text), 0x4E4F534A) + text
        if data:
            chunks += struct.pack("<II", len(data), 0x004E4942) + data
        path.write_bytes(struct.pack("<4sII", b"glTF", 2, 12 + len(chunks)) + chunks)
        return path


def export_gltf(spec: SceneSpec, out: Path, assets: Assets | None = None) -> list[Diagnostic]:
    """Write ``spec`` (a built scene or saved state) to ``out`` (.glb or .gltf); returns
    what glTF could not say, told."""
    problems = Problems(str(spec.db.path if spec.db is not None else out))
    exporter = _Exporter(spec, assets or spec.assets or Assets(spec.content_dir or "."),
                         problems)
    exporter.run()
    exporter.w.write(out)
    return problems.items


class _Exporter:
    def __init__(self, spec: SceneSpec, assets: Assets, problems: Problems) -> None:
        self.spec, self.assets, self.problems = spec, assets, problems
        self.w = GltfWriter("colosseum export")
        self.nodes: dict[str, int] = {}  # object ID -> node
        self.poses: dict[str, np.ndarray] = {}  # object ID -> 4x4 pose (engine axes)
        self.materials: dict[str, int] = {}
        self.filters: dict[tuple[int, int], int] = {}

    def run(self) -> None:
        for es in self.spec.entities:
            if es.skipped:
                continue
            comps = {type(c): c for c in es.components}
            t = comps.get(Transform)
            if t is None or (Visual not in comps and Physical not in comps
                             and Avatar not in comps):
                continue
            self._object(es.id, t, comps)
        for js in self.spec.joints:
            if not js.skipped:
                self._joint(js.id, js.joint, js.bodies)
        for pair in self.spec.material_pairs:
            self.problems.warn(None, f"material pair {pair.a}/{pair.b} is not exported: "
                                     f"KHR_physics_rigid_bodies combines materials by mode, "
                                     f"not by pair")
        if self.materials:
            self.problems.once("combine", None, "the engine combines two materials' friction "
                                                "by their geometric mean, which KHR cannot "
                                                "name: written in each material's extras "
                                                "(colosseum reads it back; other tools use "
                                                "their own rule)")

    # -- objects ------------------------------------------------------------------
    def _object(self, oid: str, t: Transform, comps: dict[type, Any]) -> None:
        pose = np.eye(4)
        pose[:3, :3] = quat_to_matrix(np.asarray(t.orientation, np.float64))
        pose[:3, 3] = t.position
        self.poses[oid] = pose
        node = self.w.node(oid, to_gltf(t.position), rotation=gltf_rotation(t.orientation))
        self.nodes[oid] = node
        visual = comps.get(Visual)
        avatar = comps.get(Avatar)
        if avatar is not None:
            self._avatar(oid, node, avatar)
        elif visual is not None and visual.visible:
            self._visual(oid, node, visual)
        physical = comps.get(Physical)
        if physical is not None:
            self._physical(oid, node, physical, t, comps.get(Trigger))

    def _avatar(self, oid: str, node: int, avatar: Avatar) -> None:
        """An avatar as its model file is: skinned meshes, skeleton and clips, copied
        whole under its node (at its Scale); its Capsule as a kinematic capsule collider
        standing on the avatar's origin (the body the avatars plugin moves)."""
        try:
            self.w.merge(self.assets.resolve(avatar.model, self.spec.content_dir), node,
                         float(avatar.scale))
        except (OSError, ValueError, KeyError, IndexError, struct.error) as exc:
            self.problems.error(oid, f"its model {avatar.model} is not exported ({exc})")
        if avatar.capsule is not None:
            radius, length = (float(x) for x in avatar.capsule)
            holder = self.w.node(f"{oid}.capsule", to_gltf((0.0, 0.0, radius + length / 2)),
                                 parent=node)
            self.w.khr(node, motion={"isKinematic": True})
            self.w.khr(holder, collider={"geometry": self.w.shape(
                "capsule", radiusTop=radius, radiusBottom=radius, height=length)})

    def _visual(self, oid: str, node: int, visual: Visual) -> None:
        parts: list[tuple[np.ndarray, np.ndarray, Sequence[float]]] = []
        if visual.model:
            try:
                model = self.assets.model(visual.model, root=self.spec.content_dir)
            except AssetError as exc:
                self.problems.error(oid, f"its model is not exported: {exc.message}")
                return
            scale = np.asarray(visual.scale, np.float64)
            parts += [(p.vertices * scale, p.faces, p.color) for p in model.parts]
        for s in visual.shapes:
            # a plane is infinite: drawn, as the renderer draws it, as a large square
            mesh = primitive(s.kind, s.size)
            placed = mesh.positions @ quat_to_matrix(np.asarray(s.rotation)).T + s.offset
            parts.append((placed, mesh.indices.reshape(-1, 3), visual.color))
        for k, (vertices, faces, color) in enumerate(parts):
            mesh_index = self.w.mesh(vertices @ _TO_GLTF.T, faces, f"{oid}.mesh{k}",
                                     list(color))
            if k == 0:
                self.w.doc["nodes"][node]["mesh"] = mesh_index
            else:
                self.w.node(f"{oid}.part{k}", parent=node, mesh=mesh_index)

    def _physical(self, oid: str, node: int, body: Physical, t: Transform,
                  trigger: Trigger | None) -> None:
        if body.kind != "static" and trigger is None:
            motion: dict[str, Any] = {}
            if body.kind == "kinematic":
                motion["isKinematic"] = True
            # the mass the engine gives it: the file's, or its shapes' volume x density
            motion["mass"] = float(body.mass if body.mass else
                                   body.material.density * sum(map(volume, body.shapes)))
            if not motion["mass"] > 0:  # infinite: as KHR says it, which its schema refuses
                motion.pop("mass")
            # KHR velocities are in node space: the world's turned into the body's frame
            turn = quat_to_matrix(np.asarray(t.orientation, np.float64)).T
            if np.any(t.linear_velocity):
                motion["linearVelocity"] = to_gltf(turn @ t.linear_velocity)
            if np.any(t.angular_velocity):
                motion["angularVelocity"] = to_gltf(turn @ t.angular_velocity)
            if not body.gravity:
                motion["gravityFactor"] = 0.0
            elif body.gravity_factor != 1.0:
                motion["gravityFactor"] = float(body.gravity_factor)
            if body.center_of_mass is not None:
                motion["centerOfMass"] = to_gltf(body.center_of_mass)
            if body.inertia is not None:  # glTF's X Y Z moments are the engine's X Z Y
                moments = np.abs(_TO_GLTF) @ np.asarray(body.inertia, np.float64)
                if np.any(moments <= 0):
                    # infinite (0): the extension's text says 0, its schema wants more
                    # than 0; the file gets the large moment the backends use, and its
                    # extras the axes that are infinite, which our import reads back
                    motion["extras"] = {"infiniteInertia": [bool(x <= 0) for x in moments]}
                    moments = locked_inertia(moments, float(motion["mass"]))
                motion["inertiaDiagonal"] = [float(x) for x in moments]
                motion["inertiaOrientation"] = gltf_rotation(body.inertia_rotation)
            self.w.khr(node, motion=motion)
        own = len(body.shapes) == 1 and _at_origin(body.shapes[0])
        for k, shape in enumerate(body.shapes):
            geometry = self._geometry(oid, shape)
            if geometry is None:
                continue
            holder = node if own or shape.kind == "plane" else self.w.node(
                f"{oid}.shape{k}", to_gltf(shape.offset), parent=node,
                rotation=gltf_rotation(shape.rotation))
            part: dict[str, Any] = {"geometry": geometry}
            if trigger is not None:
                if trigger.mask != _ALL_BITS:  # which bodies it detects
                    part["collisionFilter"] = self.w.top(KHR, "collisionFilters", {
                        "collideWithSystems": _systems(trigger.mask)})
                self.w.khr(holder, trigger=part)
                continue
            part["physicsMaterial"] = self._material(body)
            bits = self._filter(body.category if shape.category is None else shape.category,
                                body.mask if shape.mask is None else shape.mask)
            if bits is not None:
                part["collisionFilter"] = bits
            self.w.khr(holder, collider=part)

    def _geometry(self, oid: str, s: Shape) -> dict[str, Any] | None:
        if s.kind == "box":
            return self.w.shape("box", size=[abs(x) for x in to_gltf(s.size)])
        if s.kind == "sphere":
            return self.w.shape("sphere", radius=float(s.size[0]))
        if s.kind in ("capsule", "cylinder"):
            return self.w.shape(s.kind, radiusTop=float(s.size[0]),
                                radiusBottom=float(s.size[0]), height=float(s.size[1]))
        if s.kind == "plane":
            return self.w.shape("plane")
        if s.vertices is None or s.faces is None:
            self.problems.error(oid, f"a {s.kind} shape without triangles is not exported")
            return None
        mesh = self.w.mesh(np.asarray(s.vertices) @ _TO_GLTF.T, np.asarray(s.faces),
                           f"{oid}.collider", None)
        # the schema names mesh geometry by a node that holds the mesh: one outside the
        # scene, in the collider node's frame (as Blender 4.4's add-on writes it)
        holder = self.w.node(f"{oid}.collider", mesh=mesh, in_scene=False)
        return {"node": holder, "convexHull": s.kind == "hull"}

    def _material(self, body: Physical) -> int:
        m = body.material
        found = self.materials.get(m.name)
        if found is None:
            found = self.materials[m.name] = self.w.top(KHR, "physicsMaterials", {
                "name": m.name, "staticFriction": float(m.friction),
                "dynamicFriction": float(m.friction), "restitution": float(m.bounce),
                "restitutionCombine": "maximum",
                "extras": {"frictionCombine": GEOMETRIC_MEAN}})
        return found

    def _filter(self, category: int, mask: int) -> int | None:
        """A collision filter for category/mask bits (None: collides with everything)."""
        if category in (1, _ALL_BITS) and mask == _ALL_BITS:
            return None
        key = (category, mask)
        if key not in self.filters:
            spec: dict[str, Any] = {"collisionSystems": _systems(category)}
            if mask != _ALL_BITS:
                spec["collideWithSystems"] = _systems(mask)
            self.filters[key] = self.w.top(KHR, "collisionFilters", spec)
        return self.filters[key]

    # -- joints ---------------------------------------------------------------------
    def _joint(self, jid: str, joint: Joint, bodies: tuple[str, str | None]) -> None:
        kind = joint.kind
        if kind == JointKind.SIX_DOF or kind not in _LIMITS:
            self.problems.warn(jid, f"a {kind} joint has no glTF form; not exported")
            return
        if kind == JointKind.HINGE2:
            self.problems.warn(jid, "a hinge2 joint is exported as a universal joint")
        first, second = bodies
        axis = _unit(joint.axis)
        axis2 = _unit(np.asarray(joint.axis2) - axis * (axis @ joint.axis2))
        if not np.any(axis2):
            axis2 = _unit(np.cross(axis, [0.0, 0.0, 1.0] if abs(axis[2]) < 0.9 else
                                  [1.0, 0.0, 0.0]))
        # the frame's axes as the importer reads them: X = axis, Y (here Z) = axis2
        frame = np.eye(4)
        frame[:3, :3] = np.column_stack([axis, np.cross(axis2, axis), axis2])
        frame[:3, 3] = joint.anchor
        limits = _LIMITS[kind](joint)
        description: dict[str, Any] = {"limits": limits}
        drives: list[dict[str, Any]] = []
        linear = kind == JointKind.SLIDER
        if joint.motor_max_force > 0 and kind in _DRIVEN:
            drives.append({
                "type": "linear" if linear else "angular", "mode": "force", "axis": 0,
                "velocityTarget": float(joint.motor_velocity),
                "maxForce": float(joint.motor_max_force), "damping": MOTOR_DAMPING})
        spring = joint.spring
        if spring is not None:  # a position drive: k (target - x) - d v, at most max force
            drives.append({
                "type": "linear" if linear else "angular", "mode": "force", "axis": 0,
                "stiffness": float(spring.stiffness), "damping": float(spring.damping),
                "positionTarget": float(spring.target),
                **({"maxForce": float(spring.max_force)} if math.isfinite(spring.max_force)
                   else {})})
            if len(drives) > 1:
                self.problems.warn(jid, "its motor and its spring are two drives on one axis "
                                        "(colosseum reads both back; other tools may take one)")
        if drives:
            description["drives"] = drives
        index = self.w.top(KHR, "physicsJoints", description)
        reference = joint.reference
        space_b = self._space("jointSpaceB", first, frame,
                              None if reference is None else reference[0])
        space_a = self._space("jointSpaceA" if second is not None else jid, second, frame,
                              None if reference is None or second is None else reference[1])
        self.w.khr(space_a, joint={"connectedNode": space_b, "joint": index})
        if second is not None:
            self.w.doc["nodes"][space_a]["name"] = jid

    def _space(self, name: str, body: str | None, frame: np.ndarray,
               reference: Sequence[float] | None) -> int:
        """An attachment frame under ``body``'s node (at its reference pose, if the joint
        keeps one), or at the root for the world."""
        if body is None:
            local = frame
            parent = None
        else:
            pose = self.poses[body].copy()
            if reference is not None:
                pose[:3, :3] = quat_to_matrix(np.asarray(reference[3:], np.float64))
                pose[:3, 3] = reference[:3]
            local = np.linalg.inv(pose) @ frame
            parent = self.nodes[body]
        return self.w.node(name, to_gltf(local[:3, 3]), parent=parent,
                           rotation=gltf_rotation(matrix_to_quat(local[:3, :3])))


def volume(s: Shape) -> float:
    """A shape's volume (m^3), as the backends weigh it: a mesh by its closed surface."""
    if s.kind == "box":
        return float(np.prod(s.size))
    if s.kind == "sphere":
        return 4 / 3 * np.pi * s.size[0] ** 3
    if s.kind == "cylinder":
        return np.pi * s.size[0] ** 2 * s.size[1]
    if s.kind == "capsule":
        return np.pi * s.size[0] ** 2 * s.size[1] + 4 / 3 * np.pi * s.size[0] ** 3
    if s.vertices is None or s.faces is None:
        return 0.0
    tri = np.asarray(s.vertices)[np.asarray(s.faces)]
    return abs(float(np.einsum("ij,ij->i", tri[:, 0], np.cross(tri[:, 1], tri[:, 2])).sum()))/6


def _at_origin(s: Shape) -> bool:
    return not any(s.offset) and tuple(s.rotation) == (1.0, 0.0, 0.0, 0.0)


def _systems(bits: int) -> list[str]:
    return [f"bit{k}" for k in range(32) if bits >> k & 1]


def _unit(v: Sequence[float]) -> np.ndarray:
    a = np.asarray(v, np.float64)
    n = float(np.linalg.norm(a))
    return a / n if n > 0 else a


def _read_gltf(path: Path) -> tuple[dict[str, Any], list[bytes]]:
    """A .glb's or .gltf's JSON and its buffers' bytes (a .gltf's beside it or data URIs)."""
    data = path.read_bytes()
    if data[:4] == b"glTF":
        (length,) = struct.unpack("<I", data[12:16])
        doc = json.loads(data[20:20 + length])
        rest = data[20 + length:]
        chunk = rest[8:8 + struct.unpack("<I", rest[:4])[0]] if len(rest) >= 8 else b""
        buffers = [chunk] if doc.get("buffers") else []
        for extra in doc.get("buffers", [])[1:]:
            buffers.append(_uri_bytes(path, extra["uri"]))
        return doc, buffers
    doc = json.loads(data)
    return doc, [_uri_bytes(path, b["uri"]) for b in doc.get("buffers", [])]


def _uri_bytes(path: Path, uri: str) -> bytes:
    if uri.startswith("data:"):
        return base64.b64decode(uri.split(",", 1)[1])
    return (path.parent / uri).read_bytes()


def _locked(kind: str, axes: Sequence[int]) -> list[dict[str, Any]]:
    return [{f"{kind}Axes": list(axes), "min": 0.0, "max": 0.0}] if axes else []


def _limit(kind: str, axis: int, joint: Joint) -> list[dict[str, Any]]:
    if joint.low is None and joint.high is None:
        return []
    limit: dict[str, Any] = {f"{kind}Axes": [axis]}
    if joint.low is not None:
        limit["min"] = float(joint.low)
    if joint.high is not None:
        limit["max"] = float(joint.high)
    return [limit]


_LOCK_LINEAR = [{"linearAxes": [0, 1, 2], "max": 0.0}]
_LIMITS = {
    JointKind.FIXED: lambda j: _LOCK_LINEAR + _locked("angular", (0, 1, 2)),
    JointKind.BALL: lambda j: list(_LOCK_LINEAR),
    JointKind.ALIGN: lambda j: _locked("angular", (0, 1, 2)),
    JointKind.HINGE: lambda j: _LOCK_LINEAR + _locked("angular", (1, 2)) + _limit(
        "angular", 0, j),
    JointKind.MOTORIZED_HINGE: lambda j: _LOCK_LINEAR + _locked("angular", (1, 2)) + _limit(
        "angular", 0, j),
    JointKind.SLIDER: lambda j: _locked("linear", (1, 2)) + _locked("angular", (0, 1, 2)) +
    _limit("linear", 0, j),
    JointKind.UNIVERSAL: lambda j: _LOCK_LINEAR + _locked("angular", (2,)) + _limit(
        "angular", 0, j),
    JointKind.HINGE2: lambda j: _LOCK_LINEAR + _locked("angular", (2,)) + _limit(
        "angular", 0, j),
}
_DRIVEN = (JointKind.HINGE, JointKind.MOTORIZED_HINGE, JointKind.SLIDER)
