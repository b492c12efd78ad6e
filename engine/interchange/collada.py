"""Collada physics: ``<physics_scene>`` with the ``<physics_model>``s it instantiates,
read into an :class:`~engine.interchange.model.ImportedScene` (paper section 7: one file
for rendering and simulation).

* ``<instance_rigid_body body target>``: the rigid body ``body`` moves node ``target``;
  it is an Object there, drawn with the node's geometry (and its children's, down to the
  next body), its ``<shape>``s (box, sphere, capsule, cylinder, tapered ones, plane,
  ``<instance_geometry>`` of a ``<mesh>`` or ``<convex_mesh>``) placed by their own
  ``<translate>``/``<rotate>``; ``<dynamic>false`` makes it static. As Blender's 2006
  exporter writes it, a body may be named instead of given a sid, an instance may name
  no body when its model holds one, and a box may have ``<half_extends>``. The instance's
  ``<velocity>``, ``<angular_velocity>`` (degrees per second), ``<dynamic>`` and
  ``<mass>`` win over the body's.
* ``<physics_material>``: dynamic friction and restitution (static friction told).
* ``<mass_frame>`` and ``<inertia>``: the body's centre of mass and principal moments.
* ``<rigid_constraint>``: the frames of ``<ref_attachment>`` and ``<attachment>`` in
  their bodies (one left out, as Bullet's converter does, is the world where the other
  starts), ``<limits>`` (``<swing_cone_and_twist>`` degrees, ``<linear>``) per axis:
  min = max locks it, an infinite or inverted range frees it; ``<spring>`` (angular on a
  hinge, linear on a slider) is the joint's Spring.
* ``<physics_scene>``'s gravity and time step become the scene's World.
* A node's ``<extra><technique profile="colosseum">`` holds scene keys as text, like
  glTF extras (:mod:`engine.interchange.extras`).

Nodes with geometry and no body are drawn as static scenery objects. Axes and units
follow the file's ``<up_axis>`` and ``<unit>``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from xml.etree.ElementTree import Element

import numpy as np

from engine.assets.dae import ColladaDocument
from engine.assets.gltf import Frame, decompose
from engine.interchange.extras import TEXT_PROPERTY, Extras, attach, read_extras
from engine.interchange.joints import (
    FREE,
    LOCKED,
    Dof,
    Frames,
    WorkingJoint,
    working_joint,
)
from engine.interchange.model import (
    ImportedScene,
    JointDecl,
    MaterialDecl,
    ObjectDecl,
    Problems,
    ShapeDecl,
    quaternion,
    tidy,
    unique_ids,
    vector,
)
from engine.rotation import axis_angle_matrices, from_to

#: Past this a limit is no limit (exporters write FLT_MAX for a free axis).
_UNBOUNDED = 1e30
#: The Z axis, the one a plane's normal and a cylinder's length point along, as one row.
_UP = np.array([[0.0, 0.0, 1.0]])


@dataclass(slots=True)
class _Body:
    """A rigid body instance: its element, the instance's overrides, its target node."""

    sid: str
    element: Element
    instance: Element
    node: int


class _Importer:
    def __init__(self, doc: ColladaDocument, problems: Problems) -> None:
        self.doc = doc
        self.problems = problems
        tag = doc.xml.tag
        self.ns = tag[:tag.index("}") + 1] if tag.startswith("{") else ""
        self.scene = ImportedScene(doc.path, "Collada", problems=problems)
        self.materials: dict[str, str] = {}  # physics_material id -> MaterialDecl id
        self.bodies: dict[int, _Body] = {}  # target node -> body
        self.by_sid: dict[tuple[int, str], int] = {}  # (model instance, body sid) -> node
        self.owner: dict[int, ObjectDecl] = {}
        self.frames: dict[int, np.ndarray] = {}  # id(object) -> its unscaled 4x4 (Z up)
        self.object_node: dict[int, int] = {}

    # -- XML -----------------------------------------------------------------------
    def find(self, el: Element | None, path: str) -> Element | None:
        if el is None:
            return None
        return el.find("/".join(self.ns + p for p in path.split("/")))

    def findall(self, el: Element | None, path: str) -> list[Element]:
        if el is None:
            return []
        return el.findall("/".join(self.ns + p for p in path.split("/")))

    def floats(self, el: Element | None, path: str = "", count: int | None = None,
               what: str = "", node: str | None = None) -> list[float] | None:
        """The numbers in ``el/path`` (None when absent or unreadable, told)."""
        target = self.find(el, path) if path else el
        if target is None or target.text is None:
            return None
        try:
            values = [float(x) for x in target.text.split()]
        except ValueError:
            self.problems.error(node, f"<{path or what}> holds something that is not a "
                                      f"number; left out")
            return None
        if count is not None and len(values) < count:
            self.problems.error(node, f"<{path or what}> has {len(values)} numbers, not "
                                      f"{count}; left out")
            return None
        if any(math.isnan(v) for v in values):
            self.problems.error(node, f"<{path or what}> holds NaN; left out")
            return None
        return values

    def transform(self, el: Element, node: str | None) -> np.ndarray:
        """The 4x4 of ``el``'s ``<translate>``/``<rotate>`` children, in order (file
        units and axes)."""
        m = np.eye(4)
        for child in el:
            tag = child.tag[len(self.ns):]
            if tag == "translate":
                t = self.floats(child, count=3, what="translate", node=node)
                if t is not None:
                    step = np.eye(4)
                    step[:3, 3] = t[:3]
                    m = m @ step
            elif tag == "rotate":
                r = self.floats(child, count=4, what="rotate", node=node)
                if r is not None and any(r[:3]):
                    step = np.eye(4)
                    axis = np.array(r[:3]) / math.hypot(*r[:3])
                    step[:3, :3] = axis_angle_matrices(axis[None], np.radians(r[3:4]))[0]
                    m = m @ step
        return m

    # -- top level ---------------------------------------------------------------------
    def run(self) -> ImportedScene:
        for i, reason in sorted(self.doc.bad_nodes.items()):
            if not reason.startswith("its ancestor"):
                self.problems.error(self.doc.name(i), f"{reason}; it and its children are "
                                                      f"left out")
        self._materials()
        joints = self._physics_scenes()
        if self.bodies or joints:
            self.scene.read.append("physics_scene")
        self._objects()
        for instance, constraint in joints:
            decl = self._joint(instance, constraint)
            if decl is not None:
                self.scene.joints.append(decl)
        ids = unique_ids([o.id for o in self.scene.objects])
        for o, new in zip(self.scene.objects, ids, strict=True):
            o.id = new
        for decl, new in zip(self.scene.joints, unique_ids([j.id for j in self.scene.joints],
                                                           ids), strict=True):
            decl.id = new
        return self.scene

    def _materials(self) -> None:
        for m in self.findall(self.doc.xml, "library_physics_materials/physics_material"):
            key = m.get("id") or m.get("name") or f"material{len(self.materials)}"
            self.materials[key] = self._material(m, key)

    def _material(self, m: Element, key: str) -> str:
        tc = self.find(m, "technique_common")
        dynamic = (self.floats(tc, "dynamic_friction") or [0.5])[0]
        static = (self.floats(tc, "static_friction") or [dynamic])[0]
        bounce = (self.floats(tc, "restitution") or [0.0])[0]
        if abs(static - dynamic) > 1e-6:
            self.problems.warn(None, f"physics material {key}: static friction {tidy(static)} "
                                     f"differs from dynamic friction {tidy(dynamic)}; contacts "
                                     f"here have one Coulomb coefficient, the dynamic one")
        name = m.get("name") or key
        self.scene.materials.append(MaterialDecl(name, dynamic, bounce))
        return name

    def _physics_scenes(self) -> list[tuple[int, Element]]:
        library = {s.get("id"): s for s in
                   self.findall(self.doc.xml, "library_physics_scenes/physics_scene")}
        chosen = [library.get((i.get("url") or "").lstrip("#")) for i in
                  self.findall(self.doc.xml, "scene/instance_physics_scene")]
        scenes = [s for s in chosen if s is not None] or list(library.values())
        models = {m.get("id"): m for m in
                  self.findall(self.doc.xml, "library_physics_models/physics_model")}
        joints: list[tuple[int, Element]] = []
        for scene in scenes:
            self._world(scene)
            for instance in self.findall(scene, "instance_physics_model"):
                model = models.get((instance.get("url") or "").lstrip("#"))
                if model is None:
                    self.problems.error(None, f"an instance_physics_model names "
                                              f"{instance.get('url')!r}, which the file does not "
                                              f"declare; left out")
                    continue
                if instance.get("parent"):
                    self.problems.warn(None, f"physics model {model.get('id')!r} is placed by "
                                             f"its bodies' nodes; its parent "
                                             f"{instance.get('parent')!r} is not applied")
                key = id(instance)
                for ibody in self.findall(instance, "instance_rigid_body"):
                    self._body(key, model, ibody)
                seen: dict[str, int] = {}
                for iconstraint in self.findall(instance, "instance_rigid_constraint"):
                    sid = iconstraint.get("constraint", "")
                    same = [c for c in self.findall(model, "rigid_constraint")
                            if c.get("sid") == sid]
                    nth = seen[sid] = seen.get(sid, -1) + 1
                    if len(same) > 1:  # Bullet's converter names every one alike
                        self.problems.once(f"sid-{sid}", None, f"{len(same)} rigid_constraints "
                                           f"share sid {sid!r}; their instances are taken "
                                           f"in order")
                    found = same[min(nth, len(same) - 1)] if same else None
                    if found is None:
                        self.problems.error(None, f"instance_rigid_constraint names {sid!r}, "
                                                  f"which its physics model does not declare; "
                                                  f"left out")
                    else:
                        joints.append((key, found))
        return joints

    def _world(self, scene: Element) -> None:
        tc = self.find(scene, "technique_common")
        gravity = self.floats(tc, "gravity", 3)
        if gravity is not None:
            self.scene.world["Gravity"] = tuple(self.doc.axes @ np.array(gravity[:3]) *
                                                self.doc.meter)
        step = self.floats(tc, "time_step", 1)
        if step is not None and step[0] > 0:
            self.scene.world["TimeStep"] = step[0]

    def _body(self, key: int, model: Element, instance: Element) -> None:
        sid, target = instance.get("body", ""), instance.get("target", "")
        bodies = self.findall(model, "rigid_body")
        element = next((b for b in bodies if b.get("sid") == sid), None)
        if element is None and sid:  # Blender's 2006 exporter names bodies, gives no sid
            element = next((b for b in bodies if b.get("name") == sid), None)
        if element is None and not sid and len(bodies) == 1:
            element = bodies[0]  # ... and names no body when its model holds one
            sid = element.get("sid") or element.get("name") or ""
        node = self.doc.node_index(target)
        if element is None:
            self.problems.error(None, f"instance_rigid_body names body {sid!r}, which its "
                                      f"physics model does not declare; left out")
        elif node is None:
            self.problems.error(None, f"rigid body {sid!r} moves node {target!r}, which the "
                                      f"visual scene does not have; left out")
        elif node in self.doc.bad_nodes:
            pass  # told with the node
        elif node in self.bodies:
            self.problems.error(self.doc.name(node), f"two rigid bodies move it; the second "
                                                     f"({sid!r}) is left out")
        else:
            self.bodies[node] = _Body(sid, element, instance, node)
            self.by_sid[key, sid] = node

    # -- objects -------------------------------------------------------------------
    def _objects(self) -> None:
        import collada

        for i, node in enumerate(self.doc.nodes):
            if i in self.doc.bad_nodes:
                continue
            parent = self.doc.parents[i]
            above = self.owner.get(parent) if parent >= 0 else None
            has_geometry = any(isinstance(c, collada.scene.GeometryNode) for c in node.children)
            extras = self._extras(i)
            made = None
            if i in self.bodies:
                made = self._rigid_body(i)
            elif extras.physical and above is None:
                made = self._new_object(i, "dynamic")
            elif above is None and (has_geometry or extras.entries):
                made = self._new_object(i, None)
            obj = made or above
            attach(extras, obj, self.doc.name(i), self.scene, self.problems)
            self._missing_geometry(i)
            if obj is None:
                continue
            self.owner[i] = obj
            if has_geometry:
                ref = self.doc.node_ref(i)
                first = self.doc.node_ref(self.object_node[id(obj)])
                if obj.visual is None:
                    obj.visual = ("", (first,) if first == ref else (first, ref))
                else:
                    obj.visual = ("", (*obj.visual[1], ref))

    def _missing_geometry(self, i: int) -> None:
        """Tell each ``<instance_geometry>`` of node ``i`` naming a geometry the file does
        not have (pycollada leaves it out, so the node is drawn without it)."""
        xml = getattr(self.doc.nodes[i], "xmlnode", None)
        for el in self.findall(xml, "instance_geometry"):
            url = (el.get("url") or "").lstrip("#")
            if url not in self._geometry_ids:
                self.problems.error(self.doc.name(i), f"its <instance_geometry> names "
                                                      f"geometry {url!r}, which the file "
                                                      f"does not have; it is not drawn")

    @cached_property
    def _geometry_ids(self) -> set[str]:
        return {g.get("id") or "" for g in self.findall(self.doc.xml,
                                                        "library_geometries/geometry")}

    def _extras(self, i: int) -> Extras:
        xml = getattr(self.doc.nodes[i], "xmlnode", None)
        text = None
        for technique in self.findall(xml, "extra/technique"):
            if technique.get("profile") == TEXT_PROPERTY:
                text = "".join(technique.itertext())
        return read_extras({TEXT_PROPERTY: text} if text else None,
                           f"{self.doc.path.name} node '{self.doc.name(i)}' extras")

    def _new_object(self, i: int, kind: str | None) -> ObjectDecl:
        f = decompose(self.doc.to_z_up(self.doc.world[i]))
        name = self.doc.name(i)
        if f.sheared:
            self.problems.warn(name, "its parents' non-uniform scale shears it; its shapes "
                                     "and mesh are the nearest unsheared ones")
        obj = ObjectDecl(name, name, vector(f.translation), quaternion(f.rotation), kind)
        self.scene.objects.append(obj)
        self.frames[id(obj)] = f.unscaled()
        self.object_node[id(obj)] = i
        return obj

    def _rigid_body(self, i: int) -> ObjectDecl:
        body = self.bodies[i]
        name = self.doc.name(i)
        tc = self.find(body.element, "technique_common")
        over = self.find(body.instance, "technique_common")
        dynamic = _bool(self.find(over, "dynamic"), _bool(self.find(tc, "dynamic"), True))
        obj = self._new_object(i, "dynamic" if dynamic else "static")
        mass = (self.floats(over, "mass") or self.floats(tc, "mass") or [None])[0]
        if dynamic and mass is not None:
            if mass > 0:
                obj.mass = mass
            else:
                self.problems.warn(name, f"its mass {mass} is not positive; the mass comes "
                                         f"from its shapes")
        if dynamic:
            self._mass_frame(obj, i, over, tc, name)
        for key, attr, scale in (("velocity", "velocity", self.doc.meter),
                                 ("angular_velocity", "angular_velocity", math.pi / 180)):
            v = self.floats(over, key, 3, node=name)
            if v is not None and dynamic:
                setattr(obj, attr, vector(self.doc.axes @ np.array(v[:3]) * scale))
        material = self._material_of(tc, name)
        if material is not None:
            obj.material = material
        base = np.linalg.inv(self.frames[id(obj)])
        for shape in self.findall(tc, "shape"):
            self._shape(obj, shape, base, name)
        if not obj.shapes and not any(e.key == "Geometry" for e in obj.extras.get(
                "Physical", [])):
            if dynamic:
                self.problems.warn(name, "a rigid body without shapes: it gets a small sphere "
                                         "that collides with nothing")
                obj.shapes.append(ShapeDecl("sphere", (0.1,)))
                obj.category, obj.mask = 0, 0
            else:  # its plane went to an object of its own: what stays is drawn only
                obj.kind = None
        return obj

    def _mass_frame(self, obj: ObjectDecl, i: int, over: Element | None,
                    tc: Element | None, name: str) -> None:
        """``<mass_frame>`` (the centre of mass and the principal axes, in the body's frame)
        and ``<inertia>`` (the principal moments along them, kg in the file's unit
        squared), the instance's winning over the body's; Bullet's converter writes
        ``<inertia>`` for every body, its mass frame left out: one of its shapes."""
        frame = self.find(over, "mass_frame")
        frame = frame if frame is not None else self.find(tc, "mass_frame")
        moments = self.floats(over, "inertia", 3, node=name) or self.floats(
            tc, "inertia", 3, node=name)
        turn = np.eye(3)
        if frame is not None:
            rel = decompose(np.linalg.inv(self.frames[id(obj)]) @ self.doc.to_z_up(
                self.doc.world[i] @ self.transform(frame, name)))
            if np.any(np.abs(rel.translation) > 1e-12):
                obj.center_of_mass = vector(rel.translation)
            turn = rel.rotation
        if moments is None or not any(moments[:3]):
            return
        if min(moments[:3]) <= 0:
            self.problems.error(name, f"its <inertia> {[tidy(x) for x in moments[:3]]} is not "
                                      f"3 positive moments; left out (the shapes' inertia is "
                                      f"used)")
            return
        obj.inertia = vector(np.abs(self.doc.axes) @ np.array(moments[:3]) *
                             self.doc.meter ** 2)
        obj.inertia_rotation = quaternion(turn)

    def _material_of(self, el: Element | None, name: str) -> str | None:
        instance = self.find(el, "instance_physics_material")
        if instance is not None:
            key = (instance.get("url") or "").lstrip("#")
            if key not in self.materials:
                self.problems.error(name, f"it names physics material {key!r}, which the file "
                                          f"does not declare; the default material is used")
                return None
            return self.materials[key]
        inline = self.find(el, "physics_material")
        if inline is not None:
            key = inline.get("id") or f"{name}.material"
            self.materials[key] = self._material(inline, key)
            return self.materials[key]
        return None

    def _shape(self, obj: ObjectDecl, shape: Element, base: np.ndarray, name: str) -> None:
        material = self._material_of(shape, name)
        if material is not None and obj.material not in (None, material):
            self.problems.warn(name, f"a body has one material here: '{obj.id}' keeps "
                                     f"'{obj.material}'")
        elif material is not None:
            obj.material = material
        rel = decompose(base @ self.doc.to_z_up(self.doc.world[self.object_node[id(obj)]] @
                                                self.transform(shape, name)))
        m = self.doc.meter
        kinds = ("box", "sphere", "cylinder", "capsule", "tapered_cylinder", "tapered_capsule",
                 "plane", "instance_geometry")
        found = next(((k, self.find(shape, k)) for k in kinds if self.find(shape, k)
                      is not None), None)
        if found is None:
            self.problems.error(name, "a <shape> without a geometry it knows; left out")
            return
        kind, el = found
        offset, rotation = vector(rel.translation), rel.rotation
        try:
            if kind == "box":
                half = self.floats(el, "half_extents" if self.find(el, "half_extents")
                                   is not None else "half_extends", 3, node=name)
                if half is None:
                    return
                size = np.abs(self.doc.axes @ np.array(half[:3])) * 2 * m
                decl = ShapeDecl("box", vector(size), offset, quaternion(rotation))
            elif kind == "sphere":
                radius = self.floats(el, "radius", 1, node=name)
                if radius is None:
                    return
                decl = ShapeDecl("sphere", (2 * radius[0] * m,), offset, quaternion(rotation))
            elif kind == "plane":
                self._plane(obj, el, rel, name)
                return
            elif kind == "instance_geometry":
                decl = self._geometry(el, rel, name)
                if decl is None:
                    return
            else:
                decl = self._round(kind, el, rel, name)
                if decl is None:
                    return
        except ValueError as exc:
            self.problems.error(name, f"{exc}; its shape is left out")
            return
        if decl.size and min(decl.size) <= 0:
            self.problems.error(name, f"its {kind} shape has zero size; left out")
            return
        obj.shapes.append(decl)

    def _round(self, kind: str, el: Element, rel: Frame, name: str) -> ShapeDecl | None:
        """A cylinder or capsule (tapered ones too) along the file's local Y."""
        height = self.floats(el, "height", 1, node=name)
        radii: list[float] = []
        for key in ("radius", "radius1", "radius2"):
            radii += self.floats(el, key, node=name) or []
        if height is None or not radii:
            self.problems.error(name, f"a <{kind}> without height or radius; left out")
            return None
        if max(radii) - min(radii) > 1e-6:
            self.problems.warn(name, f"a <{kind}> of radii {[tidy(r) for r in radii]} is round, "
                                     f"of the largest radius, here")
        base = "capsule" if "capsule" in kind else "cylinder"
        m = self.doc.meter
        along_y = from_to(_UP, (self.doc.axes @ np.array([0.0, 1.0, 0.0]))[None])[0]
        return ShapeDecl(base, (2 * max(radii) * m, height[0] * m), vector(rel.translation),
                         quaternion(rel.rotation @ along_y))

    def _geometry(self, el: Element, rel: Frame, name: str) -> ShapeDecl | None:
        url = (el.get("url") or "").lstrip("#")
        geometry = next((g for g in self.findall(self.doc.xml, "library_geometries/geometry")
                         if g.get("id") == url), None)
        if geometry is None:
            self.problems.error(name, f"its shape names geometry {url!r}, which the file does "
                                      f"not have; left out")
            return None
        convex = self.find(geometry, "convex_mesh")
        kind, ref = "mesh", url
        if convex is not None:
            kind = "hull"
            ref = (convex.get("convex_hull_of") or f"#{url}").lstrip("#")
        try:
            self.doc.mesh_model(ref)
        except ValueError as exc:
            self.problems.error(name, f"its shape's geometry cannot be read: {exc}; left out")
            return None
        return ShapeDecl(kind, (), vector(rel.translation), quaternion(rel.rotation), "", mesh=ref)

    def _plane(self, obj: ObjectDecl, el: Element, rel: Frame, name: str) -> None:
        equation = self.floats(el, "equation", 4, node=name)
        if equation is None:
            return
        if obj.kind != "static":
            self.problems.error(name, "a plane shape cannot move; left out")
            return
        normal_file = np.array(equation[:3])
        length = float(np.linalg.norm(normal_file))
        if length == 0:
            self.problems.error(name, "its plane's normal is zero; left out")
            return
        point_file = -equation[3] * normal_file / length ** 2
        body = self.frames[id(obj)]
        normal = body[:3, :3] @ rel.rotation @ (self.doc.axes @ normal_file / length)
        point = body @ np.append(rel.translation + rel.rotation @ (
            self.doc.axes @ point_file * self.doc.meter), 1.0)
        local = np.linalg.inv(body) @ point
        if np.allclose(body[:3, 2], normal, atol=1e-9) and abs(local[2]) < 1e-9:
            obj.shapes.append(ShapeDecl("plane"))  # the body's own XY plane, as here
            return
        plane = ObjectDecl(f"{obj.id}.plane", name, vector(point[:3]),
                           quaternion(from_to(_UP, normal[None])[0]), "static",
                           shapes=[ShapeDecl("plane")], material=obj.material)
        self.scene.objects.append(plane)

    # -- joints ------------------------------------------------------------------------
    def _joint(self, instance: int, constraint: Element) -> JointDecl | None:
        name = constraint.get("name") or constraint.get("sid") or "constraint"
        problems = self.problems.about("rigid_constraint")
        tc = self.find(constraint, "technique_common")
        enabled = self.find(tc, "enabled")
        if enabled is not None and not _bool(enabled, True):
            problems.warn(name, "a disabled rigid_constraint; left out")
            return None
        sides = []
        found = {key: self.find(constraint, key) for key in ("ref_attachment", "attachment")}
        if not any(el is not None for el in found.values()):
            problems.error(name, "a rigid_constraint with neither <ref_attachment> nor "
                                 "<attachment>; left out")
            return None
        for key, el in found.items():
            if el is None:  # Bullet's converter writes a body held to the world so
                problems.warn(name, f"a rigid_constraint without <{key}>: that side is the "
                                    f"world, where the other side starts")
                sides.append(None)
                continue
            sid = (el.get("rigid_body") or "").lstrip("#")
            node = self.by_sid.get((instance, sid)) if sid else None
            if sid and node is None:
                problems.error(name, f"its <{key}> names rigid body {sid!r}, which its "
                                          f"physics model does not have; left out")
                return None
            owner = self.owner.get(node) if node is not None else None
            world = self.doc.world[node] if node is not None else np.eye(4)
            frame = decompose(self.doc.to_z_up(world @ self.transform(el, name)))
            moving = owner.id if owner is not None and owner.kind == "dynamic" else None
            sides.append((moving, frame))
        given = next(side for side in sides if side is not None)
        (ref_body, ref_frame), (att_body, att_frame) = (
            side if side is not None else (None, given[1]) for side in sides)
        if ref_body is None and att_body is None:
            problems.warn(name, "its rigid_constraint connects nothing that moves; left out")
            return None
        if _bool(self.find(tc, "interpenetrate"), False) is False and self.find(
                tc, "interpenetrate") is not None:
            problems.once("interpenetrate", name, "jointed bodies never collide here "
                                                       "(interpenetrate false is not represented)")
        frames = Frames(ref_frame.rotation @ self.doc.axes, ref_frame.translation,
                        att_frame.rotation @ self.doc.axes, att_frame.translation)
        made = working_joint(name, self._dofs(tc, name), frames, ref_body, att_body,
                             problems)
        if made is None:
            return None
        self._springs(tc, made, name, problems)
        return made.decl(name)

    def _springs(self, tc: Element | None, joint: WorkingJoint, name: str,
                 problems: Problems) -> None:
        """``<spring>``: its ``<angular>`` part (stiffness per degree, target in degrees, as
        Collada counts angles) on a hinge's free axis, its ``<linear>`` part (per file
        unit) on a slider's; a part the joint has no free axis for is told."""
        for kind in ("angular", "linear"):
            el = self.find(tc, f"spring/{kind}")
            if el is None:
                continue
            stiffness, damping, target = ((self.floats(el, key, 1, node=name) or [0.0])[0]
                                          for key in ("stiffness", "damping", "target_value"))
            if min(stiffness, damping) < 0:
                problems.error(name, f"its {kind} spring has a negative stiffness or damping; "
                                     f"left out")
                continue
            if stiffness == 0 and damping == 0:
                continue  # a spring that pulls with nothing: none
            angular = kind == "angular"
            if joint.type not in (("Hinge", "MotorizedHinge") if angular else ("Slider",)):
                problems.warn(name, f"its {kind} spring (stiffness {tidy(stiffness)}) is not "
                                    f"represented: springs here act on a hinge's or slider's "
                                    f"free axis, and this joint is a {joint.type}")
                continue
            per = math.degrees(1.0) if angular else 1.0 / self.doc.meter
            joint.pull(stiffness * per, damping * per,
                       math.radians(target) if angular else target * self.doc.meter, None)

    def _dofs(self, tc: Element | None, name: str) -> list[Dof]:
        dofs: list[Dof] = []
        for path, scale in (("limits/linear", self.doc.meter),
                            ("limits/swing_cone_and_twist", math.pi / 180)):
            low = self.floats(self.find(tc, path), "min", 3, node=name) or [0.0] * 3
            high = self.floats(self.find(tc, path), "max", 3, node=name) or [0.0] * 3
            for lo, hi in zip(low[:3], high[:3], strict=True):
                if lo == hi:
                    dofs.append(LOCKED)
                elif lo > hi or (abs(lo) >= _UNBOUNDED and abs(hi) >= _UNBOUNDED):
                    dofs.append(FREE)
                else:
                    dofs.append(("limited", lo * scale if abs(lo) < _UNBOUNDED else -math.inf,
                                 hi * scale if abs(hi) < _UNBOUNDED else math.inf))
        return dofs


def import_collada(doc: ColladaDocument, problems: Problems) -> ImportedScene:
    """Everything ``doc``'s physics scenes declare, and its scenery, as declarations."""
    return _Importer(doc, problems).run()


def _bool(el: Element | None, default: bool) -> bool:
    if el is None or el.text is None:
        return default
    return el.text.strip().lower() in ("true", "1")
