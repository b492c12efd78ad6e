"""Factory: SceneDB -> entity specs -> entities. The only place descriptions become entities.

:func:`build_specs` is pure: it reads a validated SceneDB (defaults filled from
the schema) and returns a :class:`SceneSpec` — per object the list of component
instances, plus joints (bodies named by object ID), materials, material pairs,
shaders, world settings. A mistake in the description raises :class:`SceneError`
before anything exists, so a bad file never half-loads a world. An asset that
cannot be used (a model, texture or sound file that is unreadable, a hull that
cannot be built) is not a mistake in the text: its object (or just its sound, or
texture) is left out, marked ``skipped``, with a diagnostic in
:attr:`SceneSpec.problems`, and the run goes on. Files are read through one
:class:`engine.assets.Assets` cache, which the renderer and the sound system share.
:func:`instantiate` then creates the entities and resolves object IDs to entity
ids; a spec is consumed by instantiating it once.
"""

from __future__ import annotations

import math
from collections import ChainMap
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

import engine.scene.blocks as blocks
import engine.scene.random_state as random_state
import engine.scene.schema as sc
from components import (
    Graspable,
    Joint,
    MaterialProps,
    Name,
    Physical,
    Script,
    Shape,
    Transform,
    Trigger,
    UserOwned,
    Visual,
)
from components.blocks import Body
from components.display import binding_problem as display_binding_problem
from components.hand import HAND_SIZE, PALM_SIZE
from components.script import SavedScript, ScriptHandler, ScriptTimer
from engine.anomalies import AnomalySpec
from engine.assets import AssetError, Assets, nodes_name
from engine.assets.geometry import convex_hull
from engine.experiments.design import Design
from engine.measures import MeasureSpec
from engine.memory import paused_gc
from engine.physics.backend import (
    MAX_DENSITY,
    MAX_EXTENT,
    MAX_MASS,
    MAX_SPEED,
    WORLD_EXTENT,
    WORLD_RANGES,
    BackendName,
    MaterialPair,
    SleepState,
    WorldSettings,
    metres,
)
from engine.physics.commands import SetSleepState
from engine.realtime import STEP_RANGE, STEP_WARNING, TIME_STEP
from engine.rotation import UNIT_ROUNDING, euler_to_quat, rotate, view_problem
from engine.scene.db import (
    INCLUDE,
    STRINGVECTOR,
    STRUCTURE,
    VECTOR,
    Block,
    Entry,
    SceneDB,
    Value,
)
from engine.scene.diagnostics import (
    ERROR,
    WARNING,
    Diagnostic,
    Loc,
    Reporter,
    suggest,
)
from engine.scene.inputs import InputSpec
from engine.scene.postpass import PostPassSpec

if TYPE_CHECKING:
    from engine.app import Engine

#: A virtual hand's body when the author gives none: a palm-sized box (m) of 0.45 kg.
#: Shared defaults (tuples: immutable, so every shape and pose may hold the same one).
_ORIGIN = (0.0, 0.0, 0.0)
_IDENTITY = (1.0, 0.0, 0.0, 0.0)
DEFAULT_SIZES = {"sphere": (1.0,), "box": (1.0, 1.0, 1.0), "capsule": (0.5, 1.0),
                 "cylinder": (0.5, 1.0), "plane": ()}


@dataclass(slots=True)
class EntitySpec:
    """An entity's components; ``skipped`` (no components) when an asset it needs failed:
    kept in its place so a saved state still matches the file's blocks to entities."""

    id: str
    components: list[Any]
    loc: Loc
    skipped: bool = False


@dataclass(slots=True)
class JointSpec:
    """A joint and the IDs of its bodies; ``skipped`` when one of them was."""

    id: str
    joint: Joint
    bodies: tuple[str, str | None]
    loc: Loc
    skipped: bool = False


@dataclass(slots=True)
class ShaderStateSpec:
    program: str
    uniforms: dict[str, float | tuple[float, ...]]


@dataclass(slots=True)
class ShaderProgramSpec:
    vertex: str | None  # file path of the vertex shader
    fragment: str | None
    enabled: bool


def binding_problem(action: str, profile: str, path: str) -> str | None:
    """What is wrong with a headset's ``Bind`` (None: nothing): the scene's check, and
    the OpenXR display's (services.xr.bindings.Rebinding)."""
    return display_binding_problem(action, profile, path, suggest)


@dataclass(frozen=True, slots=True)
class Link:
    """A reference by ID a declared block made (components.blocks.BuildContext.link): once
    the entities exist, ``component`` of ``entity``'s gets ``field`` = ``target``'s."""

    entity: str
    component: type
    field: str
    target: str


@dataclass(slots=True)
class SceneSpec:
    """Everything a scene file declares, ready to instantiate."""

    entities: list[EntitySpec] = field(default_factory=list)
    joints: list[JointSpec] = field(default_factory=list)
    materials: dict[str, MaterialProps] = field(default_factory=dict)
    material_pairs: list[MaterialPair] = field(default_factory=list)
    shader_programs: dict[str, ShaderProgramSpec] = field(default_factory=dict)
    shader_states: dict[str, ShaderStateSpec] = field(default_factory=dict)
    world: WorldSettings = field(default_factory=WorldSettings)
    time_step: float = TIME_STEP
    backend: str = BackendName.ODE
    time: float = 0.0
    #: The scene's random generator when a saved state was written (see random_state).
    random_state: dict[str, object] | None = None
    #: References by ID that declared blocks made, set once the entities exist.
    links: list[Link] = field(default_factory=list)
    #: Object ID -> sleep-rule state a saved state carries (see :class:`SleepState`).
    sleep: dict[str, SleepState] = field(default_factory=dict)
    content_dir: Path | None = None
    db: SceneDB | None = None
    #: Assets that could not be used, each at the line that named it (what was skipped).
    problems: list[Diagnostic] = field(default_factory=list)
    #: The files this spec read; instantiate makes it the engine's Assets resource.
    assets: Assets | None = None
    #: The ``Input`` and ``Output`` blocks (devices, calibration, published values).
    input: InputSpec = field(default_factory=InputSpec)
    #: The ``Measure`` blocks: values the run reports at its end.
    measures: list[MeasureSpec] = field(default_factory=list)
    #: The visual anomalies declared (``DoubleVision``, ``Hemianopia``, ...).
    anomalies: list[AnomalySpec] = field(default_factory=list)
    #: The ``Experiment`` block: the study's design (engine.experiments), if any.
    experiment: Design | None = None
    #: The ``PostPass`` blocks, in order.
    post_passes: list[PostPassSpec] = field(default_factory=list)


@dataclass(slots=True)
class SpawnRecord:
    """What one script call made at run time, kept so a saved state writes it too.

    ``spawn(text)``: the snippet's SceneDB, the folder its asset names are relative to,
    and the entity its i-th ``Object`` block (``objects[i]``), i-th ``Joint`` block
    (``joints[i]``) and i-th ``Avatar`` block (``avatars[i]``) became. ``createJoint``:
    ``db`` None and ``joints`` its one joint entity, whose Joint component holds all a
    ``Joint`` block needs.
    """

    db: SceneDB | None
    content_dir: Path | None
    objects: list[int]
    joints: list[int]
    avatars: list[int] = field(default_factory=list)


@dataclass(slots=True)
class SceneIds:
    """Resource left by :func:`instantiate`: object ID <-> entity id, and the spec.

    :attr:`spawned` lists, oldest first, what scripts made since (see
    :class:`SpawnRecord`; recorded on the main thread by the scripting API), so
    ``write_state`` can write it. A record is dropped, snippet and all, as soon as the
    last entity it made is gone (:meth:`released`), so a script that spawns and deletes
    forever holds nothing of what it deleted.
    """

    entities: dict[str, int]
    joints: dict[str, int]
    spec: SceneSpec
    #: record number -> record, oldest first
    _records: dict[int, SpawnRecord] = field(default_factory=dict)
    #: record number -> how many entities it made are still alive
    _alive: dict[int, int] = field(default_factory=dict)
    #: entity -> the number of the record that made it
    _made_by: dict[int, int] = field(default_factory=dict)
    _count: int = 0

    @property
    def spawned(self) -> list[SpawnRecord]:
        return list(self._records.values())

    def record(self, made: SpawnRecord, exists: Callable[[int], bool]) -> None:
        """Keep ``made`` while an entity it made (``exists``) is alive."""
        alive = [e for e in (*made.objects, *made.joints, *made.avatars)
                 if e >= 0 and exists(e)]
        if not alive:
            return
        number = self._count
        self._count += 1
        self._records[number] = made
        self._alive[number] = len(alive)
        for entity in alive:
            self._made_by[entity] = number

    def released(self, entity: int) -> None:
        """``entity`` left the world; the record that made it goes with its last one."""
        number = self._made_by.pop(entity, None)
        if number is None:
            return
        self._alive[number] -= 1
        if not self._alive[number]:
            del self._alive[number], self._records[number]


_DEFAULTS = {name: {k: f.default for k, f in fields.items()}
             for name, fields in sc.SCHEMAS.items()}
blocks.on_register(lambda name: _DEFAULTS.__setitem__(
    name, {k: f.default for k, f in sc.SCHEMAS[name].items()}))



class _Reader(dict):
    """A block's values as plain Python with the schema's defaults filled in.

    ``r("Key")`` is the value (or default); ``r.has("Key")`` whether the author wrote it.
    """

    __slots__ = ("entries", "block", "has", "value", "block_name")
    __call__ = dict.__getitem__

    def __init__(self, block: Block | None, schema: str):
        dict.__init__(self, _DEFAULTS[schema])
        self.block_name = schema
        entries = [] if block is None else block.entries
        last = self._read(entries)
        if INCLUDE in last:  # read again with the included files' entries spliced in
            entries = list(block)  # type: ignore[arg-type]
            self.clear()
            self.update(_DEFAULTS[schema])
            last = self._read(entries)
        self.entries = entries
        self.block = block
        #: Whether the author wrote ``key``; the Value written (or None).
        self.has: Callable[[str], bool] = last.__contains__
        self.value: Callable[[str], Value | None] = last.get

    def _read(self, entries: list[Entry]) -> dict[str, Value]:
        """Set each key's plain value (the last one written wins); returns the Values."""
        last: dict[str, Value] = {}
        for e in entries:
            v = last[e.key] = e.value
            self[e.key] = tuple([x.data for x in v.data]) if v.kind in _VECTORS else v.data
        return last

    def blocks(self, key: str) -> list[Block]:
        return [e.value.data for e in self.entries
                if e.key == key and e.value.kind == STRUCTURE]


_VECTORS = (VECTOR, STRINGVECTOR)


def _fingered(hand: Value) -> bool:
    """Whether a ``Hand`` block asks for fingers (its palm is then smaller than a hand)."""
    return any(e.key == "Fingers" and bool(e.value.data) for e in hand.data.entries)


class _Index:
    """The root block's entries grouped by key in one pass (10,000 objects, a dozen keys)."""

    def __init__(self, root: Block):
        self.groups: dict[str, list[Entry]] = {}
        for e in root:
            self.groups.setdefault(e.key, []).append(e)

    def get_all(self, key: str) -> list[Entry]:
        return self.groups.get(key, [])

    def blocks(self, key: str) -> list[Block]:
        return [e.value.data for e in self.get_all(key) if e.value.kind == STRUCTURE]

    def value(self, key: str) -> Value | None:
        found = self.get_all(key)
        return found[-1].value if found else None


def _floats(t: Any) -> tuple[float, ...]:
    return tuple(map(float, t))


def _uniforms(r: _Reader) -> dict[str, float | tuple[float, ...]]:
    """A block's ``Uniform`` entries: name -> number or numbers."""
    uniforms: dict[str, float | tuple[float, ...]] = {}
    for u in r.blocks("Uniform"):
        ur = _Reader(u, "Uniform")
        val = ur("Value")
        uniforms[ur("ID")] = _floats(val) if isinstance(val, tuple) else float(val)
    return uniforms


Pose = tuple[tuple[float, ...], tuple[float, ...]]


def build_specs(db: SceneDB, content_dir: str | Path | None = None,
                materials: dict[str, MaterialProps] | None = None,
                bodies: Mapping[str, Pose] | None = None,
                assets: Assets | None = None, extent: float | None = None) -> SceneSpec:
    """SceneDB -> SceneSpec. Raises SceneError (with places) for mistakes in the text;
    assets that cannot be used skip their object and are listed in ``spec.problems``.

    ``materials`` and ``bodies`` (object ID -> position, orientation) exist elsewhere
    (the running scene, when a script spawns a snippet) and may be used by ID here;
    ``assets`` is the running scene's cache (a new one when None); ``extent`` the running
    world's (default: the file's ``World { Extent }``), which positions must lie in.
    """
    folder = Path(content_dir) if content_dir is not None else Path(db.path).parent
    b = _Builder(folder, Reporter(sources=dict(db.sources)), assets or Assets(folder))
    b.extent = extent
    if materials:
        b.materials.update(materials)
    if bodies is not None:  # the snippet's own objects come first; the world's looked up
        b.poses = ChainMap(b.own_poses, bodies)  # type: ignore[arg-type]
    with paused_gc():
        spec = b.build(db)
    b.report.raise_if_errors()
    spec.db = db
    spec.content_dir = folder
    spec.problems = Reporter(b.problems).diagnostics
    spec.assets = b.assets
    return spec


class _Context:
    """What a declared block's build function may ask (components.blocks.BuildContext):
    its block's values, the object it stands in (``outer``, its components ``made``)."""

    __slots__ = ("builder", "reader", "loc", "owner", "place", "has_body", "outer", "parts")

    def __init__(self, builder: _Builder, reader: _Reader, loc: Loc, owner: str, place: str,
                 has_body: bool, outer: _Reader | None = None,
                 parts: list[Any] | None = None) -> None:
        self.builder, self.reader, self.loc = builder, reader, loc
        self.owner, self.place, self.has_body = owner, place, has_body
        self.outer, self.parts = outer, parts if parts is not None else []

    def at(self, reader: _Reader, loc: Loc) -> _Context:
        """The same object's context for another block (told at its lines)."""
        return _Context(self.builder, reader, loc, self.owner, self.place, self.has_body,
                        self.outer, self.parts)

    def _loc(self, key: str | None) -> Loc:
        written = None if key is None else self.reader.value(key)
        return self.loc if written is None else written.loc

    def error(self, key: str | None, message: str, item: int | None = None) -> None:
        written = None if key is None or item is None else self.reader.value(key)
        where = self._loc(key) if written is None else written.data[item].loc
        self.builder.report.error(where, message)

    def warning(self, key: str | None, message: str) -> None:
        self.builder.report.warning(self._loc(key), message)

    def given(self, key: str) -> bool:
        return self.reader.has(key)

    def inner(self, key: str) -> list[tuple[Mapping[str, Any], _Context]]:
        struct = sc.SCHEMAS[self.reader.block_name][key].struct
        assert struct is not None, f"{key} opens no block"
        return [(r, self.at(r, b.loc)) for b in self.reader.blocks(key)
                for r in [_Reader(b, struct)]]

    def beside(self, key: str) -> tuple[Mapping[str, Any], _Context] | None:
        written = None if self.outer is None else self.outer.value(key)
        if written is None or written.kind != STRUCTURE:
            return None
        struct = sc.SCHEMAS[self.outer.block_name][key].struct  # type: ignore[union-attr]
        r = _Reader(written.data, struct or key)
        return r, self.at(r, written.loc)

    def component(self, kind: type) -> Any:
        return next((c for c in self.parts if isinstance(c, kind)), None)

    def check_mass(self, key: str) -> None:
        written = self.reader.value(key)
        if written is not None:
            self.builder.limited(written, key, MAX_MASS if key == "Mass" else MAX_DENSITY,
                                 "kg" if key == "Mass" else "kg/m³")

    def input_name(self, key: str, kind: str, who: str) -> None:
        if self.reader(key):
            self.gathered("input names").append((who, kind, self.reader(key), self, key))

    def model_file(self, key: str) -> str | None:
        return self.builder.model(self.reader, key)

    def link(self, component: Any, field: str, target: str) -> None:
        self.builder.spec.links.append(Link(self.owner, type(component), field, target))

    def made(self, kind: type) -> bool:
        return any(isinstance(c, kind) for e in self.builder.spec.entities
                   for c in e.components)

    def suggest(self, name: str, choices: Any) -> str:
        return suggest(name, choices)

    def sound_file(self, key: str, outcome: str) -> str | None:
        return self.builder.sound_file(self.reader, key, outcome)

    def problem(self, key: str | None, message: str, warning: bool = False,
                item: int | None = None) -> None:
        written = None if key is None or item is None else self.reader.value(key)
        where = self._loc(key) if written is None else written.data[item].loc
        self.builder.told(where, message, WARNING if warning else ERROR)

    def within_world(self, key: str, points: bool = False) -> None:
        value = self.reader.value(key)
        if not points or value is None:
            self.builder.inside(value, key)
            return
        items = value.data
        for k in range(0, len(items) - 2, 3):  # each point x y z within the world
            self.builder.inside(Value(VECTOR, items[k:k + 3], items[k].loc), f"{key} point")

    def orientation(self) -> tuple[float, ...]:
        return self.builder.orientation(self.reader)

    def quaternion(self, key: str) -> tuple[float, ...]:
        return self.builder.quaternion(self.reader, key)

    def skinned_model(self, key: str, outcome: str) -> Any | None:
        b = self.builder
        try:
            return b.assets.skinned(self.reader(key), self._loc(key), b.folder)
        except AssetError as exc:
            b.problem(exc, outcome)
            return None

    def saved(self, block: str, owner: str) -> tuple[Mapping[str, Any], _Context] | None:
        found = self.builder.saved_blocks(block).pop(owner, None)
        if found is None:
            return None
        r = _Reader(found, block)
        return r, self.at(r, found.loc)

    def saved_script(self, owner: str) -> Any:
        return self.builder.script_states.pop(owner, None)

    def claim(self, kind: str, name: str) -> str | None:
        first = self.builder.claimed.setdefault((kind, name), self.loc)
        return None if first is self.loc else f"{first.path}:{first.line}:{first.col}"

    def scene(self, setting: str) -> Any:
        return getattr(self.builder.spec, setting)

    def settle(self, setting: str, value: Any) -> None:
        setattr(self.builder.spec, setting, value)

    def gathered(self, name: str) -> list[Any]:
        return self.builder.gathered.setdefault(name, [])

    def variables(self) -> set[str]:
        root = self.builder.root
        return set() if root is None else {k for k in root.groups if k[:1].islower()}

    def folder(self) -> str:
        return str(self.builder.folder)

    def where(self, key: str | None) -> str:
        where = self._loc(key)
        return f"{where.path}:{where.line}"

    def body(self, name: str) -> Body | None:
        b = self.builder
        pose = b.poses.get(name)
        if pose is None:
            return None
        return Body(pose, name in b.physical_ids, name in b.static_ids, name in b.own_poses)

    def view_problem(self, forward: tuple[float, ...]) -> str | None:
        return view_problem(forward)

    def left_out(self, name: str) -> bool:
        return name in self.builder.skipped

    def join(self, joint: Joint, bodies: tuple[str, str | None], skipped: bool = False
             ) -> None:
        self.builder.spec.joints.append(JointSpec(self.owner, joint, bodies, self.loc,
                                                  skipped))


class _Builder:
    def __init__(self, folder: Path, report: Reporter, assets: Assets):
        self.folder = folder
        self.report = report
        self.assets = assets
        self.problems: list[Diagnostic] = []
        self.skipped: set[str] = set()  # IDs of objects left out for a failed asset
        self.materials: dict[str, MaterialProps] = {"default": MaterialProps()}
        self.dense_materials: set[str] = set()
        #: Object ID -> pose (position, quaternion), the file's own ...
        self.own_poses: dict[str, Pose] = {}
        #: ... and, for a spawned snippet, the running world's bodies after them
        self.poses: Mapping[str, Pose] = self.own_poses
        self.physical_ids: set[str] = set()
        self.static_ids: set[str] = set()  # bodies that never move (a joint sees no body)
        self.sleep: dict[str, SleepState] = {}
        #: Scene-wide lists blocks fill while the scene is built (the trackers a hand
        #: names) and the parts each block kind with a finish step made, for that step.
        self.gathered: dict[str, list[Any]] = {}
        self.finishing: dict[str, list[Any]] = {}
        #: Owner -> the saved state its script resumes from, and the block that said so.
        self.script_states: dict[str, SavedScript] = {}
        self.script_blocks: dict[str, Block] = {}
        #: Points of the file must lie within +-extent (m) on every axis.
        self.extent: float | None = None
        #: What is built so far (declared blocks' links and headset check read it).
        self.spec = SceneSpec()
        #: Saved-state block kind -> owner ID -> the block it resumes from (taken).
        self.owned: dict[str, dict[str, Block]] = {}
        self.root: _Index | None = None
        #: (kind, name) -> where a block claimed that scene-wide name first.
        self.claimed: dict[tuple[str, str], Loc] = {}

    def build(self, db: SceneDB) -> SceneSpec:
        spec = self.spec = SceneSpec()
        root = _Index(db.root)
        if self.extent is None:
            self.extent = self.world_extent(root)
        self.script_states = self.saved_scripts(root)
        self.root, self.owned, self.claimed = root, {}, {}
        self.gathered, self.finishing = {}, {}
        for blk in root.blocks("Material"):
            r = _Reader(blk, "Material")
            name = str(r("ID"))
            density = r.value("Density")
            if density is not None:
                self.limited(density, "Density", MAX_DENSITY, "kg/m³")
            self.materials[name] = MaterialProps(
                name=name, friction=float(r("Friction")), bounce=float(r("Bounce")),
                bounce_velocity=float(r("BounceVelocity")), softness=float(r("Softness")),
                density=float(r("Density")),
                contact_sound=self.sound_file(r, "ContactSound", "the material stays silent"))
            if r.has("Density"):
                self.dense_materials.add(name)
        spec.materials = self.materials
        for i, blk in enumerate(root.blocks("Object")):
            spec.entities.append(self.object(blk, i))
        spec.sleep = self.sleep
        self.declared_entities(root, spec, entity=False)
        self.shaders(root, spec)
        self.world(root, spec)
        self.scene_entities(root, spec)
        self.finish(db.root.loc)
        self.unclaimed_script_states()
        return spec

    def finish(self, loc: Loc) -> None:
        """Each block kind's finish step, once every block is built, with the parts its
        blocks made (Input's: every Input block's devices and trackers as one spec)."""
        for block in list(blocks.BLOCKS.values()):
            if block.finish is not None:
                ctx = _Context(self, _Reader(None, block.name), loc, block.name, "Scene",
                               False)
                block.finish(self.finishing.get(block.name, []), ctx)

    def saved_blocks(self, kind: str) -> dict[str, Block]:
        """Owner ID -> the top-level ``kind`` block (a saved state's) about it."""
        if kind not in self.owned:
            blks = [] if self.root is None else self.root.blocks(kind)
            self.owned[kind] = {str(_Reader(b, kind)("Owner")): b for b in blks}
        return self.owned[kind]

    # -- assets --------------------------------------------------------------
    def problem(self, error: AssetError, outcome: str) -> None:
        """Tell of an asset that failed, at its scene line, and what was left out."""
        self.assets.mark_told(error)
        where = error.where or Loc(str(self.folder), 0, 0)
        self.problems.append(Diagnostic(where.path, where.line, where.col, ERROR,
                                        f"{error.message}; {outcome}"))

    def sound_file(self, r: _Reader, key: str, outcome: str) -> str | None:
        """``r(key)``, a sound file, if it can be played; else None, told as a problem."""
        file = r(key)
        if file is not None:
            try:
                self.assets.sound(file, r.value(key).loc, self.folder)
            except AssetError as exc:
                self.problem(exc, outcome)
                return None
        return file

    # -- objects -----------------------------------------------------------
    def object(self, blk: Block, index: int) -> EntitySpec:
        """The object's components, or a skipped spec when a model it needs failed."""
        r = _Reader(blk, "Object")
        oid = r("ID") or f"object{index}"
        try:
            return self.object_components(r, oid, blk)
        except AssetError as exc:
            self.problem(exc, f"object '{oid}' is left out")
            self.skipped.add(oid)
            return EntitySpec(oid, [], blk.loc, skipped=True)

    def quaternion(self, r: _Reader, key: str) -> tuple[float, ...]:
        """``r(key)`` as a unit quaternion (one already unit kept bit-exact, as a saved
        state wrote it); all zeros is an error."""
        quat = _floats(r(key))
        norm = math.sqrt(sum(q * q for q in quat))
        if norm == 0.0:
            self.report.error(r.value(key).loc, f"{key} must not be all zeros")
            return _IDENTITY
        return quat if abs(norm - 1.0) <= UNIT_ROUNDING else tuple(q / norm for q in quat)

    def orientation(self, r: _Reader) -> tuple[float, ...]:
        """The exact ``Quaternion`` where one is written, else ``Orientation`` (degrees)."""
        return self.quaternion(r, "Quaternion") if r.has("Quaternion") else euler_to_quat(
            r("Orientation"))

    def object_components(self, r: _Reader, oid: str, blk: Block) -> EntitySpec:
        self.inside(r.value("Position"), "Position")
        self.fits(r.value("Size"))
        for key in ("Velocity", "AngularVelocity", "Spin"):
            self.slow_enough(r, key)
        position = _floats(r("Position"))
        quat = self.orientation(r)
        angular = tuple(_floats(r("Spin"))) if r.has("Spin") else tuple(
            map(math.radians, r("AngularVelocity"))) if r.has("AngularVelocity") else _ORIGIN
        comps: list[Any] = [Name(oid), Transform(position, quat, r("Velocity"), angular)]
        size = r("Size")
        hand_blk = r.value("Hand")
        if hand_blk is not None and size is None:  # a hand's body is a hand-sized box
            size = PALM_SIZE if _fingered(hand_blk) else HAND_SIZE
        vis_blk, phys_blk = r.value("VisualAttributes"), r.value("PhysicalAttributes")
        bare = vis_blk is None and phys_blk is None
        vis = _Reader(vis_blk.data if vis_blk else None, "Visual")
        phys = _Reader(phys_blk.data if phys_blk else None, "Physical")
        visual_shapes, model, scale = self.visual_geometry(vis, size)
        if vis_blk is not None or bare:
            if not visual_shapes and model is None:
                visual_shapes = self.physical_shapes(phys, size, (), None, (1.0,) * 3,
                                                     position, quat)[0]
            comps.append(Visual(
                shapes=visual_shapes, model=model, scale=scale,
                color=_color(vis("Color")), texture=self.texture(vis),
                shader_state=vis("ShaderState"), shadower=bool(vis("Shadower")),
                shadowed=bool(vis("Shadowed")), visible=bool(vis("Visible"))))
        if phys_blk is not None or bare:
            body = self.physical(r, phys, size, visual_shapes, model, scale, position, quat)
            comps.append(body)
            if phys("Trigger"):
                comps.append(Trigger(mask=int(phys("Mask"))))
            self.physical_ids.add(oid)
            if body.kind == "static":
                self.static_ids.add(oid)
            if any(map(r.has, ("Asleep", "SleepVelocity", "SleepTimer", "SleepReference",
                               "RestSteps", "RestSlid", "RestForce", "RestPreloaded"))):
                self.sleep[oid] = self.sleep_spec(r)
        self.own_poses[oid] = (position, quat)
        if r.has("Script"):
            comps.append(Script(file=r("Script"), saved=self.script_states.pop(oid, None)))
        if not r("Graspable"):
            comps.append(Graspable(False))
        if r.has("User"):
            comps.append(UserOwned(r("User")))
        comps += self.declared_blocks(r, "Object", oid, phys_blk is not None or bare, comps)
        return EntitySpec(oid, comps, blk.loc)

    def declared_blocks(self, r: _Reader | _Index, place: str, owner: str,
                        has_body: bool, parts: list[Any] | None = None) -> list[Any]:
        """The components of the blocks features declared for ``place`` (engine.scene.
        blocks: the engine's own and a content folder's), on the entity of ``owner``
        (whose components so far are ``parts``)."""
        made: list[Any] = []
        outer = r if isinstance(r, _Reader) and place == "Object" else None
        for block in blocks.BLOCKS.values():
            if place in block.inside:
                for blk in r.blocks(block.written_as):
                    made += self.declared(block, blk, owner, place, has_body, outer,
                                          parts) or []
        return made

    def declared(self, block: blocks.BlockType, blk: Block, owner: str, place: str,
                 has_body: bool, outer: _Reader | None = None,
                 parts: list[Any] | None = None) -> list[Any] | None:
        """One declared block's components, and those of the blocks declared inside it;
        None (told at the line) when a value is out of its key's range or its build
        leaves it out. A repeated key's value is every value written (in order)."""
        r = _Reader(blk, block.name)
        fields = sc.SCHEMAS[block.name]
        values = {k: r(k) if not fields[k].repeat or fields[k].type == sc.STRUCT_T else
                  tuple(e.value.py() for e in r.entries if e.key == k) for k in block.keys}
        problems = block.problems(values)
        for k, message in problems:
            self.report.error(r.value(k).loc, f"{block.name}: {message}")
        if problems:
            return None
        if block.hook is None:
            made: list[Any] | None = [block.build(values)]
        else:
            made = block.hook(values, _Context(self, r, blk.loc, owner, place, has_body,
                                               outer, parts))
        if made is None:
            return None
        made = made + self.declared_blocks(r, block.name, owner, has_body, parts)
        if block.finish is not None:  # its finish step gets every block's parts
            self.finishing.setdefault(block.name, []).extend(made)
        return made

    def declared_entities(self, root: _Index, spec: SceneSpec, entity: bool = True) -> None:
        """Top-level declared blocks: an entity each, named by its ID (one its build
        leaves out keeps its place, skipped); with ``entity`` False, those that make none
        (joints, scene-wide settings), before the world's settings are read."""
        for block in blocks.BLOCKS.values():
            if "Scene" not in block.inside or block.entity != entity:
                continue
            written = root.blocks(block.written_as)
            for i, blk in enumerate(written[-1:] if block.once else written):
                bid = _Reader(blk, block.name).get("ID") or block.unnamed or \
                    f"{block.name.lower()}{i}"
                made = self.declared(block, blk, bid, "Scene", False)
                if not entity:  # its build handed what it made to the context (or to
                    continue  # its finish step)
                skipped = made is None or (not made and block.hook is not None)
                parts = [] if skipped and block.hook is not None else [Name(bid), *(made or [])]
                spec.entities.append(EntitySpec(bid, parts, blk.loc, skipped=skipped))

    def visual_geometry(self, vis: _Reader, size: Any
                        ) -> tuple[list[Shape], str | None, tuple[float, float, float]]:
        """Primitives and the model drawn (loaded now, so a bad one skips the object and
        the renderer finds it in the cache)."""
        shapes: list[Shape] = []
        model, scale = None, (1.0, 1.0, 1.0)
        for g in vis.blocks("Geometry"):
            gr = _Reader(g, "Geometry")
            if gr.has("File"):
                if model is None:
                    model, scale = _model_name(gr), _floats(gr("Scale"))
                    self.assets.model(model, gr.value("File").loc, self.folder)
            elif gr.has("Primitive") and gr("Primitive") != "plane":
                shapes.append(_primitive(gr, size))
        return shapes, model, scale

    def limited(self, value: Value, key: str, most: float, unit: str) -> None:
        """Report a Mass or Density not positive, or past what any body may have."""
        if not (value.data > 0 and math.isfinite(value.data)):
            self.report.error(value.loc, f"{key} must be positive, got {value.data:g}")
        elif value.data > most:
            self.report.error(value.loc, f"{key} {value.data:g} {unit} is past the most a "
                                         f"body may have ({most:g} {unit})")

    def physical(self, r: _Reader, phys: _Reader, size: Any, visual_shapes: list[Shape],
                 model: str | None, scale: tuple[float, ...], position: tuple[float, ...],
                 quat: tuple[float, ...]) -> Physical:
        shapes, has_plane = self.physical_shapes(phys, size, visual_shapes, model, scale,
                                                 position, quat)
        for key, most, unit in (("Mass", MAX_MASS, "kg"), ("Density", MAX_DENSITY, "kg/m³")):
            value = phys.value(key)
            if value is not None:
                self.limited(value, key, most, unit)
        mat_name = str(phys("Material"))
        material = self.materials.get(mat_name) or MaterialProps(name=mat_name)
        if phys.has("Density"):
            material = MaterialProps(**{**_fields(material), "density": float(phys("Density"))})
        if phys.has("Mass"):
            mass: float | None = float(phys("Mass"))
        elif phys.has("Density") or mat_name in self.dense_materials:
            mass = None
        else:
            mass = 1.0
        kind = "dynamic"
        if has_plane or not r("Dynamic"):
            kind = "static"
        elif r("Kinematic"):
            kind = "kinematic"
        if phys("Trigger"):  # detects what its Mask names; nothing collides with it
            return Physical(kind="kinematic" if r("Kinematic") else "static", mass=mass,
                            shapes=shapes, material=material, category=0, mask=0)
        return Physical(kind=kind, mass=mass, shapes=shapes, material=material,
                        linear_damping=float(phys("LinearDamping")),
                        angular_damping=float(phys("AngularDamping")),
                        can_sleep=bool(phys("CanSleep")), category=int(phys("Category")),
                        mask=int(phys("Mask")), gravity=bool(phys("Gravity")),
                        gravity_factor=self.gravity_factor(phys),
                        **self.mass_frame(phys))

    def gravity_factor(self, phys: _Reader) -> float:
        """``GravityFactor``, finite and not too large (told at its number, else 1)."""
        factor = float(phys("GravityFactor"))
        if not math.isfinite(factor) or abs(factor) > 1e3:
            self.report.error(phys.value("GravityFactor").loc, f"GravityFactor must be a "
                              f"finite number from -1000 to 1000, got {factor:g}")
            return 1.0
        return factor

    def mass_frame(self, phys: _Reader) -> dict[str, Any]:
        """``CenterOfMass``, ``Inertia`` and ``InertiaOrientation`` as Physical fields; a
        centre not finite or a moment negative or not finite is told at its number and
        left to the shapes. A moment of 0 is infinite: the body never turns about that
        axis (as KHR_physics_rigid_bodies says)."""
        out: dict[str, Any] = {}
        for key, ok, need in (("CenterOfMass", math.isfinite, "finite numbers of metres"),
                              ("Inertia", lambda x: 0 <= x < math.inf,
                               "moments of kg*m^2, 0 or more (0: infinite)")):
            value = phys.value(key)
            if value is None or value.kind != VECTOR:
                continue
            bad = next((item for item in value.data if not ok(item.data)), None)
            if bad is not None:
                self.report.error(bad.loc, f"{key} must be {need}, got {bad.data:g}")
                continue
            out["center_of_mass" if key == "CenterOfMass" else "inertia"] = _floats(phys(key))
        if "inertia" in out:
            out["inertia_rotation"] = euler_to_quat(phys("InertiaOrientation"))
        elif phys.has("InertiaOrientation") and not phys.has("Inertia"):
            self.told(phys.value("InertiaOrientation").loc, "InertiaOrientation turns the "
                      "axes of Inertia's moments; without Inertia it does nothing", WARNING)
        self.inside(phys.value("CenterOfMass"), "CenterOfMass")
        return out

    def physical_shapes(self, phys: _Reader, size: Any, visual_shapes: Any, model: str | None,
                        scale: tuple[float, ...], position: tuple[float, ...],
                        quat: tuple[float, ...]) -> tuple[list[Shape], bool]:
        shapes: list[Shape] = []
        has_plane = False
        for g in phys.blocks("Geometry"):
            gr = _Reader(g, "Geometry")
            self.fits(gr.value("Size"))
            self.inside(gr.value("Offset"), "Offset")
            if gr.has("File") or gr.has("ParseMethod"):
                file_v = gr.value("File")
                file, fscale = (_model_name(gr), _floats(gr("Scale"))) if file_v else (model,
                                                                                     scale)
                loc = file_v.loc if file_v else g.loc
                if file is None:
                    self.report.error(loc, "ParseMethod needs a model: give File here or in "
                                           "VisualAttributes Geometry")
                    continue
                shape = self.mesh_shape(file, fscale, gr("ParseMethod") or "ConvexHull", loc)
                shape.offset = _floats(gr("Offset"))
                shape.rotation = euler_to_quat(gr("Orientation"))
                shapes.append(_own_bits(shape, gr))
            elif gr("Primitive") == "plane":
                has_plane = True
                normal = rotate(quat, (0.0, 0.0, 1.0))
                d = sum(n * p for n, p in zip(normal, position, strict=True))
                shapes.append(Shape("plane", (*normal, d)))
            else:
                shapes.append(_own_bits(_primitive(gr, size), gr))
        if not shapes:
            if visual_shapes:
                shapes = [_copy_shape(s) for s in visual_shapes]
            elif model is not None:
                shapes = [self.mesh_shape(model, scale, "Box", phys.block.loc if phys.block
                                          else Loc("", 0, 0))]
            else:
                shapes = [_primitive(_Reader(None, "Geometry"), size)]
        return shapes, has_plane

    def model(self, r: _Reader, key: str) -> str | None:
        """``r(key)``, a model file, if it can be read; else None, told as a problem."""
        file = r(key)
        if file is not None:
            try:
                self.assets.model(file, r.value(key).loc, self.folder)
            except AssetError as exc:
                self.problem(exc, "the object keeps its own look")
                return None
        return file

    def texture(self, vis: _Reader) -> str | None:
        """The Visual's texture file; one that cannot be read is told here (the renderer
        draws a checker in its place, so the author sees which surface lost it)."""
        file = vis("Texture")
        if file is not None:
            try:
                self.assets.image(file, vis.value("Texture").loc, self.folder)
            except AssetError as exc:
                self.problem(exc, "drawn with a checker instead")
        return file

    def mesh_shape(self, file: str, scale: tuple[float, ...], method: str, loc: Loc) -> Shape:
        """A physics shape from a model at ``scale`` (made once per file, scale and method;
        each body gets its own Shape). Raises AssetError for a model or hull that fails."""
        model = self.assets.model(file, loc, self.folder)
        path = self.assets.resolve(file, self.folder)
        action = ("build a convex hull of model" if method == "ConvexHull"
                  else "make a physics shape of model")
        made = self.assets.derived(("shape", path, scale, method), action, file, path,
                                   lambda: _model_shape(model.triangles(), scale, method), loc)
        return _copy_shape(made)

    def told(self, loc: Loc, message: str, severity: str = ERROR) -> None:
        """A problem with a model's content (not the text): told, the run goes on."""
        self.problems.append(Diagnostic(loc.path, loc.line, loc.col, severity, message))

    def sleep_spec(self, r: _Reader) -> SleepState:
        """An object's saved sleep-rule state, so a loaded state falls asleep on time."""
        if not r("SleepTimer") >= 0:
            self.report.error(r.value("SleepTimer").loc, "SleepTimer must not be negative")
        if r.has("SleepTimer") and not r.has("SleepReference"):
            self.report.error(r.value("SleepTimer").loc, "SleepTimer needs the "
                              "SleepReference its quiet stretch began with")

        def velocity(key: str) -> np.ndarray | None:
            if not r.has(key):
                return None
            v = np.array(r(key), np.float64)
            v[3:] = np.radians(v[3:])  # written in deg/s, like AngularVelocity
            return v

        steps = int(r("RestSteps"))
        if not 0 <= steps <= 2:
            self.report.error(r.value("RestSteps").loc, "RestSteps must be 0, 1 or 2")
        force = r("RestForce")
        return SleepState(bool(r("Asleep")), velocity("SleepVelocity"),
                          max(float(r("SleepTimer")), 0.0), velocity("SleepReference"),
                          min(max(steps, 0), 2), bool(r("RestSlid")),
                          None if force is None else np.array(_floats(force)),
                          bool(r("RestPreloaded")))

    # -- shaders, world, scene-level entities ---------------------------------
    def shaders(self, root: _Index, spec: SceneSpec) -> None:
        files = {}
        for key in ("VertexShader", "FragmentShader"):
            files[key] = {str(_Reader(b, key)("ID")): _Reader(b, key)("File")
                          for b in root.blocks(key)}
        for b in root.blocks("ShaderProgram"):
            r = _Reader(b, "ShaderProgram")
            spec.shader_programs[r("ID")] = ShaderProgramSpec(
                files["VertexShader"].get(r("VertexShader")),
                files["FragmentShader"].get(r("FragmentShader")), bool(r("Enable")))
        for b in root.blocks("ShaderState"):
            r = _Reader(b, "ShaderState")
            spec.shader_states[r("ID")] = ShaderStateSpec(r("ShaderProgram"), _uniforms(r))

    def world_extent(self, root: _Index) -> float:
        """The file's World Extent (m), checked; the default where it is refused."""
        blk = root.value("World")
        w = _Reader(blk.data if blk else None, "World")
        extent = w("Extent")
        if not (0 < extent <= MAX_EXTENT):
            self.report.error(w.value("Extent").loc, f"Extent must be a positive number of "
                              f"metres up to {MAX_EXTENT:g}, got {extent:g}")
            return WORLD_EXTENT
        return float(extent)

    def inside(self, value: Value | None, what: str) -> None:
        """Report a point the file wrote (a VECTOR whose first three numbers are x y z)
        outside the world, at the number that is."""
        if value is None or value.kind != VECTOR:
            return
        extent = self.extent or WORLD_EXTENT
        for axis, item in zip("xyz", value.data, strict=False):
            if abs(item.data) > extent:
                self.report.error(item.loc, f"{what} {axis} = {item.data:g} is outside the "
                                  f"world ({metres(extent)}; World {{ Extent }} sets it)")
                return

    def fits(self, size: Value | None) -> None:
        """Report a Size the file wrote that is not positive or larger than the world (a
        body's bounding box must stay in ODE's range)."""
        if size is None or size.kind != VECTOR:
            return
        extent = self.extent or WORLD_EXTENT
        for item in size.data:
            if not item.data > 0:
                self.report.error(item.loc, f"Size must be positive, got {item.data:g}")
                return
            if item.data > extent:
                self.report.error(item.loc, f"Size {item.data:g} m is larger than the world "
                                            f"({metres(extent)}; World {{ Extent }} sets it)")
                return

    def slow_enough(self, r: _Reader, key: str) -> None:
        """Report a velocity the file wrote that no backend can take."""
        value = r.value(key)
        if value is None or value.kind != VECTOR:
            return
        numbers = [item.data for item in value.data]
        speed = math.hypot(*(map(math.radians, numbers) if key == "AngularVelocity"
                             else numbers))
        if speed > MAX_SPEED:
            unit = "rad/s" if key == "AngularVelocity" else "m/s"
            self.report.error(value.loc, f"{key} is {speed:g} {unit}, over the limit of "
                                         f"{MAX_SPEED:g} {unit}")

    def world(self, root: _Index, spec: SceneSpec) -> None:
        blk = root.value("World")
        w = _Reader(blk.data if blk else None, "World")
        self.time_step(w)
        pairs = spec.material_pairs  # the MaterialPair blocks (engine.physics.backend)
        checked = self.world_numbers(w)
        spec.world = WorldSettings(gravity=_floats(w("Gravity")),
                                   auto_sleep=bool(w("AutoSleep")),
                                   material_pairs=pairs, solver_seed=w("SolverSeed"),
                                   extent=self.extent or WORLD_EXTENT, **checked)
        spec.time_step = float(w("TimeStep"))
        spec.backend = w("Dynamics")
        spec.time = float(w("Time"))
        if w("RandomState") is not None:
            try:
                spec.random_state = random_state.parse(str(w("RandomState")))
            except ValueError as exc:
                self.report.error(w.value("RandomState").loc, str(exc))

    def world_numbers(self, w: _Reader) -> dict[str, Any]:
        """The World block's bounded settings, each checked against its one range
        (:data:`WORLD_RANGES`); a refused one reported at its key and left at its default."""
        defaults = WorldSettings()
        checked: dict[str, Any] = {}
        for key, name in _WORLD_KEYS.items():
            value, allowed = w(key), WORLD_RANGES[name]
            if name == "sleep_angular":  # the file's is in deg/s
                value = math.radians(value)
            if value not in allowed:
                shown = math.degrees(value) if name == "sleep_angular" else value
                self.report.error(w.value(key).loc, f"{key} must be {allowed.text()}, got "
                                                    f"{shown:g}")
                value = getattr(defaults, name)
            checked[name] = type(getattr(defaults, name))(value)
        return checked

    def time_step(self, w: _Reader) -> None:
        """TimeStep within :data:`STEP_RANGE` (an error), up to :data:`STEP_WARNING` (else
        a warning: the step is suspicious)."""
        step, where = w("TimeStep"), w.value("TimeStep")
        low, high = STEP_RANGE
        if not (low < step <= high):
            self.report.error(where.loc, f"TimeStep must be more than {low:g} s and at most "
                                         f"{high:g} s, got {step:g}")
        elif step > STEP_WARNING:
            self.problems.append(Diagnostic(
                where.loc.path, where.loc.line, where.loc.col, WARNING,
                f"TimeStep {step:g} s is long: contacts and joints lose accuracy past "
                f"{STEP_WARNING:g} s ({TIME_STEP:g} is the default)"))

    def scene_entities(self, root: _Index, spec: SceneSpec) -> None:
        for i, e in enumerate(root.get_all("Script")):
            sid = f"script{i}"
            script = Script(file=e.value.data, saved=self.script_states.pop(sid, None))
            spec.entities.append(EntitySpec(sid, [Name(sid), script], e.loc))
        self.declared_entities(root, spec)

    def unclaimed_script_states(self) -> None:
        """Warn of each ScriptState no script took (after every script's owner is built)."""
        for owner, block in self.script_blocks.items():
            if owner in self.script_states:  # its owner runs no script (or was left out)
                self.problems.append(Diagnostic(
                    block.loc.path, block.loc.line, block.loc.col, WARNING,
                    f"ScriptState for {owner!r}, which runs no script here; ignored"))

    def saved_scripts(self, root: _Index) -> dict[str, SavedScript]:
        """Owner -> the saved state its script resumes from (a loaded saved state)."""
        states: dict[str, SavedScript] = {}
        for blk in root.blocks("ScriptState"):
            r = _Reader(blk, "ScriptState")
            timers = tuple(ScriptTimer(str(t("Function")), float(t("Due")), float(t("Period")))
                           for t in (_Reader(b, "ScriptTimer") for b in r.blocks("Timer")))
            handlers = tuple(ScriptHandler(str(h("Event")), str(h("Function")))
                             for h in (_Reader(b, "ScriptHandler") for b in r.blocks("Handler")))
            owner = str(r("Owner"))
            states[owner] = SavedScript(str(r("Globals")), str(r("Locals")), timers, handlers)
            self.script_blocks[owner] = blk
        return states


#: The World block's bounded keys and the WorldSettings field each sets.
_WORLD_KEYS = {"ERP": "erp", "CFM": "cfm", "Iterations": "iterations",
               "MaxContacts": "max_contacts", "WarmStart": "warm_start",
               "ContactSoftness": "contact_softness", "ExactRows": "exact_rows",
               "SleepTime": "sleep_time", "SleepLinear": "sleep_linear",
               "SleepAngular": "sleep_angular"}


def _opt(v: Any) -> float | None:
    return None if v is None else float(v)


def _fields(m: MaterialProps) -> dict[str, Any]:
    return {k: getattr(m, k) for k in m.__slots__}


def _color(c: tuple[float, ...]) -> tuple[float, float, float, float]:
    c = _floats(c)
    return c if len(c) == 4 else (*c, 1.0)


def _copy_shape(s: Shape) -> Shape:
    return Shape(s.kind, s.size, s.offset, s.rotation, s.vertices, s.faces)


def _model_shape(triangles: tuple[np.ndarray, np.ndarray], scale: tuple[float, ...],
                 method: str) -> Shape:
    """A model's triangles at ``scale`` as the ParseMethod's shape: the mesh itself, its
    convex hull, or the box or sphere around it (centred on the bounds' centre)."""
    vertices = triangles[0] * np.asarray(scale, np.float64)
    if method == "TriangleMesh":
        return Shape("mesh", (), vertices=vertices, faces=triangles[1].astype(np.int32))
    if method == "ConvexHull":
        hull_vertices, hull_faces = convex_hull(vertices)
        return Shape("hull", (), vertices=hull_vertices, faces=hull_faces.astype(np.int32))
    lo, hi = vertices.min(axis=0), vertices.max(axis=0)
    center = tuple(float(c) for c in (lo + hi) / 2)
    if method == "Box":
        return Shape("box", tuple(float(e) for e in hi - lo), offset=center)
    radius = float(np.linalg.norm(vertices - (lo + hi) / 2, axis=1).max())
    return Shape("sphere", (radius,), offset=center)


def _model_name(gr: _Reader) -> str:
    """A Geometry's model: its File, or only the File's ``Nodes`` or ``Mesh``."""
    if gr.has("Nodes"):
        return nodes_name(gr("File"), gr("Nodes"))
    return nodes_name(gr("File"), [gr("Mesh")], mesh=True) if gr.has("Mesh") else gr("File")


def _own_bits(shape: Shape, gr: _Reader) -> Shape:
    """``shape`` with the Geometry block's own ``Category``/``Mask``, where it gives them."""
    if gr.has("Category"):
        shape.category = int(gr("Category"))
    if gr.has("Mask"):
        shape.mask = int(gr("Mask"))
    return shape


def _primitive(gr: _Reader, size: Any) -> Shape:
    """A primitive Shape from the format's sizes (diameters) to the component's (radii)."""
    kind = gr("Primitive") or "box"
    given = gr("Size") if gr.has("Size") else size
    s = _floats(given) if given is not None else DEFAULT_SIZES[kind]
    if kind == "sphere":
        dims: tuple[float, ...] = (s[0] / 2,)
    elif kind == "box":
        dims = s if len(s) == 3 else (s[0],) * 3
    else:
        dims = (s[0] / 2, s[1] if len(s) > 1 else s[0])
    offset = _floats(gr("Offset")) if gr.has("Offset") else _ORIGIN
    rotation = euler_to_quat(gr("Orientation")) if gr.has("Orientation") else _IDENTITY
    return Shape(kind, dims, offset, rotation)


def instantiate(engine: Engine, spec: SceneSpec, as_scene: bool = True) -> dict[str, int]:
    """Create the spec's entities and joints; returns object ID -> entity id.

    With ``as_scene`` (loading a scene file) it also leaves :class:`SceneIds` and the
    scene's WorldSettings as engine resources and sets the clock to the scene's Time;
    objects spawned at run time (from Lua snippets) pass ``as_scene=False`` and leave
    the loaded scene's resources alone.
    """
    made = [es for es in spec.entities if not es.skipped]
    with paused_gc():
        entities = engine.spawn_many([es.components for es in made])
    ids = dict(zip([es.id for es in made], entities, strict=True))
    for link in spec.links:
        if link.entity in ids and link.target in ids:
            setattr(engine.world.component_for_entity(ids[link.entity], link.component),
                    link.field, ids[link.target])
    joints: dict[str, int] = {}
    for js in spec.joints:
        if js.skipped:
            continue
        a, b = js.bodies
        js.joint.body_a = ids[a]
        js.joint.body_b = None if b is None else ids[b]
        joints[js.id] = engine.spawn(Name(js.id), js.joint)
    if spec.sleep:  # after the bodies and their joints (whose motors wake them) are made
        sleep = [SetSleepState(ids[oid], state) for oid, state in spec.sleep.items()]
        engine.defer(lambda: [engine.physics.push(command) for command in sleep])
    if as_scene:
        scene_ids = SceneIds(ids, joints, spec)
        engine.insert_resource(scene_ids)
        # every entity a script makes is named: its record goes with the last of them
        engine.world.on_remove(Name, lambda entity, _name: scene_ids.released(entity))
        if spec.assets is not None:  # render, sound and spawns use the files it read
            assets = engine.try_resource(Assets)
            if assets is None:
                engine.insert_resource(spec.assets)
            elif assets is not spec.assets:
                assets.adopt(spec.assets)
                spec.assets = assets
        engine.insert_resource(spec.world)
        # a saved state continues at the time it was saved, its generator where it stood
        engine.time = engine.physics.time = spec.time
        if spec.random_state is not None:
            engine.rng.bit_generator.state = spec.random_state
    return ids
