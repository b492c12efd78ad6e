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

from collections import ChainMap
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import engine.scene.blocks as blocks
import engine.scene.schema as sc
from components import (
    Joint,
    MaterialProps,
    Name,
)
from components.blocks import Body
from components.display import binding_problem as display_binding_problem
from components.script import SavedScript, ScriptHandler, ScriptTimer
from engine.anomalies import AnomalySpec
from engine.assets import AssetError, Assets
from engine.experiments.design import Design
from engine.measures import MeasureSpec
from engine.memory import paused_gc
from engine.physics.backend import (
    MAX_DENSITY,
    MAX_MASS,
    BackendName,
    MaterialPair,
    SleepState,
    WorldSettings,
)
from engine.realtime import TIME_STEP
from engine.rotation import view_problem
from engine.scene.db import (
    STRUCTURE,
    VECTOR,
    Block,
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
from engine.scene.objects import ObjectBuilder
from engine.scene.postpass import PostPassSpec
from engine.scene.reader import Index as _Index
from engine.scene.reader import Reader as _Reader
from engine.scene.shaders import ShaderProgramSpec, ShaderStateSpec

if TYPE_CHECKING:
    from engine.app import Engine


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
    #: (VertexShader or FragmentShader, ID) -> its file, which a program names.
    shader_files: dict[tuple[str, str], str] = field(default_factory=dict)
    #: The materials that set a Density (their objects' masses come from it).
    dense_materials: set[str] = field(default_factory=set)
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
    #: Scene-wide settings a plugin's block makes, by block name (``Session``).
    settings: dict[str, Any] = field(default_factory=dict)


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


class _Builder(ObjectBuilder):
    """Builds a SceneSpec: the Objects (their own parts: engine.scene.objects), then every
    block and key on the registry, in its place and order."""

    def __init__(self, folder: Path, report: Reporter, assets: Assets):
        self.folder = folder
        self.report = report
        self.assets = assets
        self.problems: list[Diagnostic] = []
        self.skipped: set[str] = set()  # IDs of objects left out for a failed asset
        self.materials: dict[str, MaterialProps] = {"default": MaterialProps()}
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
        spec = self.spec = SceneSpec(materials=self.materials)
        root = _Index(db.root)
        self.script_states = self.saved_scripts(root)
        self.root, self.owned, self.claimed = root, {}, {}
        self.gathered, self.finishing = {}, {}
        self.declared_entities(root, spec, entity=False, first=True)  # materials, world
        if self.extent is None:  # a spawned snippet's is the running world's
            self.extent = spec.world.extent
        spec.world.extent = self.extent
        for i, blk in enumerate(root.blocks("Object")):
            spec.entities.append(self.object(blk, i))
        spec.sleep = self.sleep
        self.declared_entities(root, spec, entity=False)
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


    # -- objects -----------------------------------------------------------
    def object(self, blk: Block, index: int) -> EntitySpec:
        """The object's components (its own, then those of the keys and blocks features
        declare on it), or a skipped spec when a model it needs failed."""
        r = _Reader(blk, "Object")
        oid = r("ID") or f"object{index}"
        try:
            comps, has_body = self.object_parts(r, oid)
            context = _Context(self, r, blk.loc, oid, "Object", has_body, r, comps)
            for name, declared in blocks.keys_of("Object"):  # Script, Graspable, User ...
                comps += declared.build(r(name), context)
            comps += self.declared_blocks(r, "Object", oid, has_body, comps)
        except AssetError as exc:
            self.problem(exc, f"object '{oid}' is left out")
            self.skipped.add(oid)
            return EntitySpec(oid, [], blk.loc, skipped=True)
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

    def declared_entities(self, root: _Index, spec: SceneSpec, entity: bool = True,
                          first: bool = False) -> None:
        """Top-level declared blocks: an entity each, named by its ID (one its build
        leaves out keeps its place, skipped); with ``entity`` False, those that make none
        (joints, scene-wide settings); with ``first``, those built before the objects. A
        scene's setting not written is built from its defaults."""
        for block in blocks.BLOCKS.values():
            if "Scene" not in block.inside or (block.entity, block.first) != (entity, first):
                continue
            written = root.blocks(block.written_as)
            if block.once:  # written again: the last one replaces it (told by the check)
                written = written[-1:]
            if block.setting and not written:
                written = [Block(loc=root.loc)]
            for i, blk in enumerate(written):
                bid = _Reader(blk, block.name).get("ID") or block.unnamed or \
                    f"{block.name.lower()}{i}"
                made = self.declared(block, blk, bid, "Scene", False)
                if not entity:  # its build handed what it made to the context (or to
                    continue  # its finish step)
                skipped = made is None or (not made and block.hook is not None)
                parts = [] if skipped and block.hook is not None else [Name(bid), *(made or [])]
                spec.entities.append(EntitySpec(bid, parts, blk.loc, skipped=skipped))


    def scene_entities(self, root: _Index, spec: SceneSpec) -> None:
        """The top-level keys features declared (each a ``Script``: an entity, script0 ...)
        and then the top-level declared blocks that are entities."""
        for name, declared in blocks.keys_of("Scene"):
            for i, e in enumerate(root.get_all(name)):
                eid = f"{name.lower()}{i}"
                context = _Context(self, _Reader(Block([e], e.loc), "Scene"), e.loc, eid,
                                   "Scene", False)
                made = declared.build(e.value.py(), context)
                spec.entities.append(EntitySpec(eid, [Name(eid), *made], e.loc))
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
        from engine.physics.commands import SetSleepState  # a running engine has it loaded

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
