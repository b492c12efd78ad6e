"""What an importer found in a model file, format-neutral, and how it becomes scene blocks.

The glTF and Collada importers fill an :class:`ImportedScene` (objects, materials,
joints, cameras, each in the engine's units and axes: metres, Z up, quaternions
``(w, x, y, z)``, scene sizes); :func:`to_db` turns it into a :class:`SceneDB` of
``Material``, ``MaterialPair``, ``Object``, ``Joint`` and ``Camera`` blocks, which the
writer prints as a scene file and the factory builds directly (``Model { Import 1 }``).

Whatever the engine cannot represent is a :class:`ModelDiagnostic` naming the file and
the node, never dropped in silence.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from engine.rotation import matrix_to_quat, quat_to_euler
from engine.scene.db import (
    FLOAT,
    INT,
    STRING,
    STRINGVECTOR,
    STRUCTURE,
    VECTOR,
    Block,
    Entry,
    SceneDB,
    Value,
)
from engine.scene.diagnostics import ERROR, WARNING, Diagnostic, Loc, printable
from engine.scene.schema import (
    ASSET_T,
    ENUM_T,
    NUMBER_OR_VECTOR_T,
    REF_T,
    SCHEMAS,
    STRING_T,
    STRINGVECTOR_T,
    STRUCT_T,
    VEC3_T,
    VECTOR_T,
    Field,
)

Vec3 = tuple[float, float, float]
Quat = tuple[float, float, float, float]

#: KHR and OMI say nothing about combining materials when a file does not; Blender's
#: exporter and OMI write nothing for their default, which is this.
DEFAULT_COMBINE = "average"
#: The engine's friction rule, which KHR cannot name: written in an exported material's
#: extras as its ``frictionCombine``, read back by the importer.
GEOMETRIC_MEAN = "geometricMean"
#: How the engine's backends combine two materials (engine.physics.ode3d, pymunk2d).
ENGINE_FRICTION = "geometric mean"
ENGINE_BOUNCE = "maximum"
#: A body the file gives no mass weighs its shapes' volume at this density (water).
VOLUME_DENSITY = 1000.0


@dataclass(frozen=True, slots=True)
class ModelDiagnostic(Diagnostic):
    """A problem in a model file, told as ``room.glb: warning: node 'Door': ...`` (a model
    has no lines; its nodes have names)."""

    def head(self) -> str:
        if self.line > 0:
            return Diagnostic.head(self)
        return f"{self.path}: {self.severity}: {printable(self.message)}"


class Problems:
    """The diagnostics of one import, each naming the model file and, where there is
    one, the node (or what ``kind`` of thing the name names)."""

    def __init__(self, path: str, kind: str = "node") -> None:
        self.path = path
        self.kind = kind
        self.items: list[Diagnostic] = []
        self._said: set[str] = set()

    def about(self, kind: str) -> Problems:
        """The same diagnostics, naming things of ``kind`` (a Collada rigid_constraint)."""
        other = Problems(self.path, kind)
        other.items, other._said = self.items, self._said
        return other

    def warn(self, node: str | None, message: str) -> None:
        """Something the file declares that the engine approximates or leaves out."""
        self._add(WARNING, node, message)

    def error(self, node: str | None, message: str) -> None:
        """Something broken in the file; that part is skipped, the rest imported."""
        self._add(ERROR, node, message)

    def once(self, key: str, node: str | None, message: str) -> None:
        """A warning told only the first time ``key`` comes up (one per kind of thing)."""
        if key not in self._said:
            self._said.add(key)
            self.warn(node, message)

    def _add(self, severity: str, node: str | None, message: str) -> None:
        text = f"{self.kind} '{node}': {message}" if node is not None else message
        self.items.append(ModelDiagnostic(self.path, 0, 0, severity, text))


@dataclass(slots=True)
class ShapeDecl:
    """One collision shape in its object's frame. ``kind`` is a scene primitive (sizes in
    the scene's terms: box extents, sphere ``(diameter,)``, capsule and cylinder
    ``(diameter, length)`` along local Z) or ``mesh``/``hull``: ``nodes`` of ``file``, or
    its ``mesh`` (in its own space, at ``scale``)."""

    kind: str
    size: tuple[float, ...] = ()
    offset: Vec3 = (0.0, 0.0, 0.0)
    rotation: Quat = (1.0, 0.0, 0.0, 0.0)
    file: str | None = None
    nodes: tuple[str, ...] = ()
    mesh: str | None = None
    scale: Vec3 = (1.0, 1.0, 1.0)
    #: This collider's own collision bits, where they differ from its object's.
    category: int | None = None
    mask: int | None = None


@dataclass(slots=True)
class MaterialDecl:
    """A physics material; ``*_combine`` as the file says (None: not said)."""

    id: str
    friction: float
    bounce: float
    friction_combine: str | None = None
    bounce_combine: str | None = None


@dataclass(slots=True)
class ObjectDecl:
    """One scene Object: a body (``kind`` dynamic, static or kinematic), a trigger, or
    only a visual (``kind`` None). Velocities are world frame, m/s and rad/s."""

    id: str
    node: str
    position: Vec3
    rotation: Quat
    kind: str | None = None
    trigger: bool = False
    mass: float | None = None
    #: kg/m^3, for a mass the file leaves to the shapes' volume (None: the engine's 1 kg).
    density: float | None = None
    velocity: Vec3 = (0.0, 0.0, 0.0)
    angular_velocity: Vec3 = (0.0, 0.0, 0.0)
    gravity: bool = True
    gravity_factor: float = 1.0
    #: The file's centre of mass (object frame, m) and principal moments (kg m^2) with
    #: their axes' turn (None: the shapes').
    center_of_mass: Vec3 | None = None
    inertia: Vec3 | None = None
    inertia_rotation: Quat = (1.0, 0.0, 0.0, 0.0)
    shapes: list[ShapeDecl] = field(default_factory=list)
    material: str | None = None
    category: int | None = None
    mask: int | None = None
    #: The model file and the nodes of it drawn for this object (their own meshes).
    visual: tuple[str, tuple[str, ...]] | None = None
    #: Scene entries the author typed into the node (extras), by the block they go in.
    extras: dict[str, list[Entry]] = field(default_factory=dict)


@dataclass(slots=True)
class JointDecl:
    """A scene Joint: ``type`` a scene joint name, angles in degrees, world frame."""

    id: str
    type: str
    bodies: tuple[str, ...]
    anchor: Vec3
    axis: Vec3 = (0.0, 0.0, 1.0)
    axis2: Vec3 | None = None
    low: float | None = None
    high: float | None = None
    motor_velocity: float = 0.0
    motor_max_force: float = 0.0
    spring: SpringDecl | None = None


@dataclass(slots=True)
class SpringDecl:
    """A joint's spring in the scene's units: stiffness per degree (or per m), damping per
    deg/s (or m/s), target in degrees (or m), max force None: unbounded."""

    stiffness: float
    damping: float
    target: float
    max_force: float | None = None


@dataclass(slots=True)
class CameraDecl:
    id: str
    position: Vec3
    look_at: Vec3
    fov: float


@dataclass(slots=True)
class ImportedScene:
    """Everything one model file declares, ready for :func:`to_db`."""

    source: Path
    format: str
    objects: list[ObjectDecl] = field(default_factory=list)
    materials: list[MaterialDecl] = field(default_factory=list)
    joints: list[JointDecl] = field(default_factory=list)
    cameras: list[CameraDecl] = field(default_factory=list)
    #: World settings the file gives (Collada's gravity and time step), scene units.
    world: dict[str, float | tuple[float, ...]] = field(default_factory=dict)
    #: Scene-level entries from the file's own extras (materials, world settings).
    scene_extras: list[Entry] = field(default_factory=list)
    #: Extensions (or Collada sections) whose data was read.
    read: list[str] = field(default_factory=list)
    #: Scene text typed into the file (extras), by the name its diagnostics carry.
    sources: dict[str, str] = field(default_factory=dict)
    problems: Problems | None = None


# -- numbers as an author would type them ----------------------------------------------
def tidy(x: float) -> float | int:
    """A number at the precision a model file carries (7 significant digits, float32's),
    an integer when it is one: ``0.20000000298023224`` is written ``0.2``."""
    if not math.isfinite(x):
        raise ValueError(f"{x} is not a finite number")
    x = float(x)
    if x.is_integer():  # counts, unit sizes: the most common, and the cheapest
        return int(x) if abs(x) < 1e15 else x
    if abs(x) < 1e-7:  # float32 noise around zero, 0.1 micrometre
        return 0
    r = float(f"{x:.7g}")  # 7 significant digits, correctly rounded (as round() is)
    return int(r) if r.is_integer() and abs(r) < 1e15 else r


def vector(v: Iterable[float]) -> tuple[float, ...]:
    """Plain floats at full precision (what is written is tidied then: :func:`tidy`)."""
    if type(v) is np.ndarray:  # most are: numpy makes the floats itself, five times faster
        return tuple(v.astype(np.float64, copy=False).tolist())
    return tuple(float(x) for x in v)


def quaternion(rotation: np.ndarray) -> Quat:
    """A rotation matrix as ``(w, x, y, z)``, ``w >= 0``, exactly identity when it is one."""
    if rotation is UNTURNED or np.array_equal(rotation, UNTURNED):  # most shapes sit on
        return _IDENTITY                                             # their node, unturned
    return unit_quaternion(matrix_to_quat(rotation))


def unit_quaternion(q: Iterable[float]) -> Quat:
    """A quaternion ``(w, x, y, z)`` as plain floats, ``w >= 0``, exactly identity when it
    is one (float noise aside)."""
    w, x, y, z = (float(c) for c in q)
    if w < 0:
        w, x, y, z = -w, -x, -y, -z
    if abs(x) <= 1e-9 and abs(y) <= 1e-9 and abs(z) <= 1e-9:
        return _IDENTITY
    return (w, x, y, z)


#: The identity rotation, shared (read only): a frame that is known not to turn.
UNTURNED = np.eye(3)
UNTURNED.flags.writeable = False
_IDENTITY: Quat = (1.0, 0.0, 0.0, 0.0)


def unique_ids(names: Sequence[str], taken: Iterable[str] = ()) -> list[str]:
    """IDs for ``names``, each made unique by ``.2``, ``.3`` ... in order of appearance."""
    used = set(taken)
    out = []
    for name in names:
        candidate, k = name, 1
        while candidate in used:
            k += 1
            candidate = f"{name}.{k}"
        used.add(candidate)
        out.append(candidate)
    return out


# -- scene blocks -------------------------------------------------------------------
class _Blocks:
    """Entries with one place (the model file), for a SceneDB nobody parsed."""

    def __init__(self, loc: Loc) -> None:
        self.loc = loc
        self._tidy: dict[float, float | int] = {}  # a model's numbers repeat (sizes, 0, 1)

    def num(self, x: float) -> Value:
        if isinstance(x, int):  # bits and counts, exactly
            return Value(INT, x, self.loc)
        t = self._tidy.get(x)
        if t is None:
            t = self._tidy[x] = tidy(x)
        return Value(INT if isinstance(t, int) else FLOAT, t, self.loc)

    def vec(self, xs: Iterable[float]) -> Value:
        return Value(VECTOR, [self.num(x) for x in xs], self.loc)

    def text(self, s: str) -> Value:
        return Value(STRING, s, self.loc)

    def texts(self, ss: Iterable[str]) -> Value:
        return Value(STRINGVECTOR, [self.text(s) for s in ss], self.loc)

    def block(self, entries: list[Entry]) -> Value:
        return Value(STRUCTURE, Block(entries, self.loc), self.loc)

    def entry(self, key: str, value: Value, comment: str | None = None) -> Entry:
        return Entry(key, value, self.loc, (f"// {comment}",) if comment else ())

    def declared(self, name: str, values: dict[str, Any], comment: str | None = None,
                 key: str | None = None) -> Entry:
        """Block ``name`` with ``values`` (key -> Python value, None left out), each
        written as its declared type says (engine.scene.blocks): a key the block does
        not declare is a writer out of step with the scene format, refused here rather
        than written into a scene that would not load."""
        fields = SCHEMAS[name]
        entries = []
        for k, v in values.items():
            if v is None:
                continue
            if k not in fields:
                raise KeyError(f"block {name!r} declares no key {k!r}")
            entries.append(self.entry(k, self.typed(fields[k], v)))
        return self.entry(key or name, self.block(entries), comment)

    def typed(self, field: Field, v: Any) -> Value:
        """``v`` as the scene value of a key of type ``field.type``."""
        if field.type == STRUCT_T:
            assert field.struct is not None
            return self.declared(field.struct, v).value
        if field.type in (VEC3_T, VECTOR_T) or (
                field.type == NUMBER_OR_VECTOR_T and isinstance(v, tuple | list)):
            return self.vec(v)
        if field.type == STRINGVECTOR_T:
            return self.texts(v)
        if field.type in (STRING_T, ASSET_T, REF_T, ENUM_T):
            return self.text(str(v))
        return self.num(v)


def to_db(scene: ImportedScene, file_ref: str, prefix: str = "",
          header: Sequence[str] = (), loc: Loc | None = None) -> SceneDB:
    """The scene's blocks; ``file_ref`` is how the scene names the model file (relative to
    the scene's folder), ``prefix`` goes before every ID (to import a model twice),
    ``loc`` the place every block says it comes from (default: the model file)."""
    b = _Blocks(loc or Loc(str(scene.source), 0, 0))
    entries: list[Entry] = list(scene.scene_extras)
    for m in scene.materials:
        entries.append(b.declared("Material", {"ID": prefix + m.id, "Friction": m.friction,
                                               "Bounce": m.bounce}))
    for a, c, friction, bounce in material_pairs(scene):
        entries.append(b.declared("MaterialPair", {
            "Material1": a if a == "default" else prefix + a,
            "Material2": c if c == "default" else prefix + c,
            "Friction": friction, "Bounce": bounce},
            comment=f"the file combines these materials' friction and bounce by its own rule "
                    f"(the engine's default: {ENGINE_FRICTION}, {ENGINE_BOUNCE})"))
    for o in scene.objects:
        entries.append(b.entry("Object", b.block(_object(b, o, file_ref, prefix))))
    for j in scene.joints:
        motor = bool(j.motor_max_force)
        entries.append(b.declared("Joint", {
            "ID": prefix + j.id, "Type": j.type, "Bodies": [prefix + x for x in j.bodies],
            "Anchor": j.anchor, "Axis": j.axis, "Axis2": j.axis2, "Low": j.low,
            "High": j.high, "MotorVelocity": j.motor_velocity if motor else None,
            "MotorMaxForce": j.motor_max_force if motor else None,
            "Spring": None if j.spring is None else _spring(j.spring)}))
    if scene.world:
        entries.append(b.declared("World", dict(scene.world)))
    for cam in scene.cameras:
        entries.append(b.declared("Camera", {
            "ID": prefix + cam.id, "Position": cam.position, "LookAt": cam.look_at,
            "Fov": cam.fov}))
    if header and entries:
        first = entries[0]
        entries[0] = Entry(first.key, first.value, first.loc,
                           [*(f"// {h}" for h in header), *first.comments], first.trailing,
                           first.included)
    return SceneDB(Block(entries, b.loc), str(scene.source))


def _object(b: _Blocks, o: ObjectDecl, file_ref: str, prefix: str) -> list[Entry]:
    out = [b.entry("ID", b.text(prefix + o.id)), b.entry("Position", b.vec(o.position))]
    if o.rotation != (1.0, 0.0, 0.0, 0.0):
        out.append(b.entry("Quaternion", b.vec(o.rotation)))
    if o.kind is not None and o.kind != "dynamic":
        out.append(b.entry("Dynamic", b.num(0)) if o.kind == "static" or o.trigger
                   else b.entry("Kinematic", b.num(1)))
    if any(o.velocity):
        out.append(b.entry("Velocity", b.vec(o.velocity)))
    if any(o.angular_velocity):
        out.append(b.entry("AngularVelocity", b.vec(math.degrees(w)
                                                   for w in o.angular_velocity)))
    out = _merged(out, o.extras.get("Object", []))
    if o.visual is not None or o.extras.get("Visual") or o.kind is None:
        visual = []
        if o.visual is not None:
            file, nodes = o.visual
            visual.append(b.entry("Geometry", b.block([
                b.entry("File", b.text(file_ref if file == "" else file)),
                b.entry("Nodes", b.texts(nodes))])))
        elif o.kind is None and not o.extras.get("Visual"):
            visual.append(b.entry("Visible", b.num(0)))  # a sound or script holder
        out.append(b.entry("VisualAttributes", b.block(_merged(visual,
                                                               o.extras.get("Visual", [])))))
    if o.kind is not None:
        phys = []
        if o.trigger:
            phys.append(b.entry("Trigger", b.num(1)))
        if o.mass is not None:
            phys.append(b.entry("Mass", b.num(o.mass)))
        elif o.kind in ("dynamic", "kinematic") and not o.trigger and o.density is not None:
            phys.append(b.entry("Density", b.num(o.density)))
        if o.material is not None:
            phys.append(b.entry("Material", b.text(
                o.material if o.material == "default" else prefix + o.material)))
        if o.category is not None:
            phys.append(b.entry("Category", b.num(o.category)))
        if o.mask is not None:
            phys.append(b.entry("Mask", b.num(o.mask)))
        if not o.gravity:
            phys.append(b.entry("Gravity", b.num(0)))
        elif o.gravity_factor != 1.0:
            phys.append(b.entry("GravityFactor", b.num(o.gravity_factor)))
        if o.center_of_mass is not None:
            phys.append(b.entry("CenterOfMass", b.vec(o.center_of_mass)))
        if o.inertia is not None:
            phys.append(b.entry("Inertia", b.vec(o.inertia)))
            euler = quat_to_euler(o.inertia_rotation)
            if any(abs(a) > 1e-7 for a in euler):
                phys.append(b.entry("InertiaOrientation", b.vec(euler)))
        phys += [b.entry("Geometry", b.block(_shape(b, s, file_ref))) for s in o.shapes]
        out.append(b.entry("PhysicalAttributes", b.block(_merged(phys,
                                                                 o.extras.get("Physical", [])))))
    return out


def _merged(generated: list[Entry], typed: list[Entry]) -> list[Entry]:
    """The importer's entries, then the author's: a key the author typed replaces every
    entry the importer made for it (their ``Geometry`` replaces the file's shapes)."""
    if not typed:
        return generated
    keys = {e.key for e in typed}
    return [e for e in generated if e.key not in keys] + typed


def _spring(s: SpringDecl) -> dict[str, Any]:
    """A joint's Spring block's keys (those at their defaults left out)."""
    return {"Stiffness": s.stiffness, "Damping": s.damping or None,
            "Target": s.target or None, "MaxForce": s.max_force}


def _shape(b: _Blocks, s: ShapeDecl, file_ref: str) -> list[Entry]:
    if s.kind in ("mesh", "hull"):
        out = [b.entry("File", b.text(file_ref if not s.file else s.file)),
               b.entry("Mesh", b.text(s.mesh)) if s.mesh is not None else
               b.entry("Nodes", b.texts(s.nodes)),
               b.entry("ParseMethod", b.text("TriangleMesh" if s.kind == "mesh"
                                             else "ConvexHull"))]
        if any(abs(x - 1.0) > 1e-7 for x in s.scale):
            out.append(b.entry("Scale", b.vec(s.scale)))
    else:
        out = [b.entry("Primitive", b.text(s.kind))]
        if s.kind != "plane":
            out.append(b.entry("Size", b.vec(s.size)))
    if any(abs(x) > 1e-9 for x in s.offset):
        out.append(b.entry("Offset", b.vec(s.offset)))
    if s.rotation != (1.0, 0.0, 0.0, 0.0):
        euler = quat_to_euler(s.rotation)
        if any(abs(a) > 1e-7 for a in euler):
            out.append(b.entry("Orientation", b.vec(euler)))
    if s.category is not None:
        out.append(b.entry("Category", b.num(s.category)))
    if s.mask is not None:
        out.append(b.entry("Mask", b.num(s.mask)))
    return out


# -- material combination --------------------------------------------------------------
def combine(mode_a: str | None, mode_b: str | None, a: float, b: float) -> float:
    """Two materials' values combined as KHR_physics_rigid_bodies and OMI say: average
    wins over minimum, over maximum, over multiply; a material that says no mode takes the
    other's (the conformance scene Materials_01: restitution 0.5 by "minimum" against a
    material that says nothing does not bounce), and when neither says,
    :data:`DEFAULT_COMBINE`; last, the engine's own geometric mean
    (:data:`GEOMETRIC_MEAN`, which our export writes in a material's extras)."""
    modes = {m for m in (mode_a, mode_b) if m} or {DEFAULT_COMBINE}
    if "average" in modes:
        return (a + b) / 2
    if "minimum" in modes:
        return min(a, b)
    if "maximum" in modes:
        return max(a, b)
    if "multiply" in modes:
        return a * b
    return math.sqrt(a * b)


def material_pairs(scene: ImportedScene) -> list[tuple[str, str, float, float]]:
    """``(material1, material2, friction, bounce)`` for every two materials the file's
    objects use whose combination by the file's rule differs from the engine's, so the
    scene says what the file meant."""
    used = {o.material for o in scene.objects if o.kind is not None and not o.trigger}
    declared = {m.id: m for m in scene.materials}
    default = MaterialDecl("default", SCHEMAS["Material"]["Friction"].default,
                           SCHEMAS["Material"]["Bounce"].default)
    pool = [declared.get(name or "default", default) for name in sorted(
        used, key=lambda n: (n is not None, n or ""))]
    out = []
    for i, a in enumerate(pool):
        for c in pool[i:]:
            if not (a.friction >= 0 and c.friction >= 0):  # negative or NaN: the schema
                continue                                   # check tells of the Material
            friction = combine(a.friction_combine, c.friction_combine, a.friction, c.friction)
            bounce = combine(a.bounce_combine, c.bounce_combine, a.bounce, c.bounce)
            engine_friction = math.sqrt(a.friction * c.friction)
            engine_bounce = max(a.bounce, c.bounce)
            if abs(friction - engine_friction) > 1e-9 or abs(bounce - engine_bounce) > 1e-9:
                out.append((a.id, c.id, friction, bounce))
    return out
