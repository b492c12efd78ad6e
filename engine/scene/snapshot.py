"""Save a running simulation as a scene file (the paper's "state at time t").

The loaded SceneDB is written self-contained (includes inlined, expressions
frozen to their values) with each object's current pose and velocities (and,
where the backend keeps one, its auto-sleep state), the joints' motor settings,
the solver's random state, the scene's random generator, the simulated time and each
running script's state (see :mod:`services.scripting.persist`). Orientation is written exactly
as ``Quaternion`` (and, for people, as ``Orientation`` degrees), floats with
full precision, so loading the file continues the motion.

A joint keeps the ``Anchor`` and axes it was made with, plus the poses its bodies
had then (``ReferencePose1``/``ReferencePose2``): loading makes it as if the bodies
stood there, so it holds them exactly as before, however far they have moved.

What scripts made at run time (``spawn(text)`` snippets and ``createJoint``, recorded
in :attr:`SceneIds.spawned`) follows the file's own objects and joints, oldest first,
written the same way; what was deleted since (or a broken joint) is left out. IDs
stay unique: a taken one gets ``~2``, ``~3``, ... (``ball``, ``ball~2``) and the joints
naming that object are written to match.

An avatar's block gets its root pose; an ``AvatarState`` says what it was doing (its
clips, fades and queue, its path, ground following, held objects, driven bones and its
capsule's pose; see :class:`components.avatar_saved.SavedAvatar`), so it continues instead of
starting as its block says.

Each visual anomaly's block (engine.anomalies) says whether it is on and its severity as
the run left them, so anomalies switched or set by a script or an input stay so.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

import engine.scene.blocks as blocks
import engine.scene.random_state as random_state
import engine.scene.schema as sc
from components import HandState, Joint, Name, Transform
from components.avatar_saved import SavedAvatar
from components.exact import exact_degrees, exact_preimage
from components.joint import LINEAR_KINDS, SCENE_JOINT_TYPES, Spring
from engine.anomalies import ANOMALIES, Anomalies
from engine.assets.generated import is_generated
from engine.physics.backend import (
    BodyState,
    SleepState,
    SupportsExactState,
    SupportsSleepState,
)
from engine.rotation import quat_to_euler
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
from engine.scene.diagnostics import Loc
from engine.scene.factory import SceneIds, SpawnRecord
from engine.scene.parser import parse_text
from engine.scene.writer import write
from engine.services import AvatarStates, ScriptStates

if TYPE_CHECKING:
    from engine.app import Engine
    from engine.world import World

_HERE = Loc("<state>", 0, 0)


def _vec(values: object) -> Value:
    return Value(VECTOR, [Value(FLOAT, float(x), _HERE) for x in values], _HERE)


def _drop(block: Block, key: str) -> None:
    block.entries[:] = [e for e in block.entries if e.key != key]


def _set(block: Block, key: str, value: Value) -> None:
    """Replace the last ``key`` in ``block`` (dropping earlier repeats) or append it."""
    found = [e for e in block.entries if e.key == key]
    for e in found[:-1]:
        block.entries.remove(e)
    if found:
        found[-1].value = value
    else:
        block.entries.append(Entry(key, value, _HERE))


def _rebase_assets(block: Block, schema: str, src: Path, dst: Path) -> None:
    """Rewrite asset file names so they still resolve from a file saved in ``dst``."""
    fields = sc.SCHEMAS[schema]
    for e in block.entries:
        f = fields.get(e.key)
        if f is None:
            continue
        if f.type == sc.ASSET_T and e.value.kind == STRING and not is_generated(e.value.data):
            e.value.data = Path(os.path.relpath(src / e.value.data, dst)).as_posix()
        elif f.type == sc.STRUCT_T and e.value.kind == STRUCTURE:
            _rebase_assets(e.value.data, f.struct, src, dst)


def _sleep_keys(block: Block, state: SleepState | None) -> None:
    """Write a body's sleep-rule state and resting standing (``None``: fresh, or a backend
    that keeps none)."""
    for key in ("Asleep", "SleepVelocity", "SleepTimer", "SleepReference", "RestSteps",
                "RestSlid", "RestForce", "RestPreloaded"):
        _drop(block, key)
    if state is None:
        return
    if state.rest_steps:
        _set(block, "RestSteps", Value(INT, int(state.rest_steps), _HERE))
    if state.rest_slid:
        _set(block, "RestSlid", Value(INT, 1, _HERE))
    if state.rest_preloaded:
        _set(block, "RestPreloaded", Value(INT, 1, _HERE))
    if state.rest_force is not None:
        _set(block, "RestForce", _vec(state.rest_force.tolist()))
    if state.asleep:
        _set(block, "Asleep", Value(INT, 1, _HERE))
    for key, v in (("SleepVelocity", state.smoothed), ("SleepReference", state.reference)):
        if v is not None:
            _set(block, key, _vec(x if k < 3 else exact_degrees(x)
                                  for k, x in enumerate(v.tolist())))
    if state.reference is not None:
        _set(block, "SleepTimer", Value(FLOAT, float(state.timer), _HERE))


def _literal(db: SceneDB, src: Path | None, dst: Path | None) -> Block:
    """A self-contained copy of ``db``'s root (includes inlined, expressions frozen),
    its asset names rebased from folder ``src`` to ``dst`` when both are known."""
    root = parse_text(write(db, literal=True, flatten=True), db.path).root
    if src is not None and dst is not None:
        _rebase_assets(root, "Scene", src.resolve(), dst)
    return root


def _transform(world: World, entity: int | None) -> Transform | None:
    if entity is None or not world.entity_exists(entity):
        return None
    return world.try_component(entity, Transform)


def _write_pose(blk: Block, t: Transform) -> None:
    """Where an object or avatar stands: exactly (``Quaternion``) and for people."""
    q = [float(x) for x in t.orientation]
    _set(blk, "Position", _vec(t.position))
    _set(blk, "Orientation", _vec(quat_to_euler(q)))
    _set(blk, "Quaternion", _vec(q))


@dataclass(frozen=True, slots=True)
class _Row:
    """A body's state as its backend would have it put back (SupportsExactState)."""

    position: np.ndarray
    orientation: np.ndarray
    linear_velocity: np.ndarray
    angular_velocity: np.ndarray


def _rows(state: BodyState) -> dict[int, _Row]:
    """Body key (its entity) -> its exact row."""
    t = state.table
    return {int(k): _Row(t[i, :3], t[i, 3:7], t[i, 7:10], t[i, 10:13])
            for i, k in enumerate(state.keys.tolist())}


def _write_body(blk: Block, t: Transform | _Row, sleep: SleepState | None) -> None:
    """An object's pose, velocities and auto-sleep state now."""
    _write_pose(blk, t)
    _set(blk, "Velocity", _vec(t.linear_velocity))
    spin = [float(w) for w in t.angular_velocity]
    degrees = [exact_degrees(w) for w in spin]
    _set(blk, "AngularVelocity", _vec(degrees))
    _drop(blk, "Spin")
    if any(math.radians(d) != w for d, w in zip(degrees, spin, strict=True)):
        _set(blk, "Spin", _vec(spin))  # no degrees give it back to the bit
    _sleep_keys(blk, sleep)


def _write_joint(blk: Block, joint: Joint) -> None:
    """A joint's block as its declaration saves it (components.joint.save_joint)."""
    for key, value in blocks.BLOCKS["Joint"].save(joint).items():
        _set(blk, key, _literal_value(value))


def _live_joint(world: World, entity: int | None, names: dict[int, str]) -> Joint | None:
    """The joint at ``entity`` if it still holds bodies that are written (else None)."""
    if entity is None or entity < 0 or not world.entity_exists(entity):
        return None
    joint = world.try_component(entity, Joint)
    if joint is None or joint.broken or joint.body_a not in names or (
            joint.body_b is not None and joint.body_b not in names):
        return None
    return joint


def _definition(material: Block) -> tuple:
    """What a Material block says, but for its ID (to tell a redeclaration from a new one)."""
    return tuple((e.key, repr(e.value.py())) for e in material.entries if e.key != "ID")


def _unique(name: str, taken: set[str]) -> str:
    """``name``, or ``name~2``, ``name~3``, ... whichever is free first; now taken."""
    found, n = name, 2
    while found in taken:
        found, n = f"{name}~{n}", n + 1
    taken.add(found)
    return found


_TYPE_NAMES = {kind: name for name, kind in SCENE_JOINT_TYPES.items()}


def _string(text: str) -> Value:
    return Value(STRING, text, _HERE)


def _block(key: str, entries: list[tuple[str, Value]]) -> Entry:
    return Entry(key, Value(STRUCTURE, Block([Entry(k, v, _HERE) for k, v in entries]),
                            _HERE), _HERE)


class _Spawns:
    """Writes what scripts made (:class:`SpawnRecord`) after the file's own entries."""

    def __init__(self, world: World, root: Block, names: dict[int, str], taken: set[str],
                 sleep: dict[int, SleepState] | None, dst: Path | None,
                 exact: dict[int, _Row]):
        self.world, self.root, self.names, self.taken = world, root, names, taken
        self.sleep, self.dst, self.exact = sleep, dst, exact
        #: avatar entity -> the ID its spawned Avatar block is written with
        self.avatars: dict[int, str] = {}
        #: material ID written -> its definition (see _definition)
        self.materials = {str(b.get("ID")): _definition(b) for b in root.blocks("Material")}

    def name(self, entity: int, fallback: str) -> str:
        named = self.world.try_component(entity, Name)
        return _unique(named.id if named is not None and named.id else fallback, self.taken)

    def bodies(self, joint: Joint) -> Value:
        ids = [self.names[joint.body_a]] + ([] if joint.body_b is None
                                            else [self.names[joint.body_b]])
        return Value(STRINGVECTOR, [_string(i) for i in ids], _HERE)

    def snippet(self, rec: SpawnRecord) -> None:
        """A ``spawn(text)``: its objects, joints and avatars still there, and the materials
        it declared. One whose ID is written already with another definition is written
        as ``wood~2`` (and its objects refer to that); an identical one is not repeated.
        An avatar's holds are left to its AvatarState (its objects may be renamed)."""
        assert rec.db is not None
        root = _literal(rec.db, rec.content_dir, self.dst)
        out: list[Entry] = []
        renamed: dict[str, str] = {}
        for entry in root.get_all("Material"):  # the snippet's own, used by its objects
            mid = str(entry.value.data.get("ID"))
            definition = _definition(entry.value.data)
            same = next((name for name, d in self.materials.items() if d == definition and (
                name == mid or name.startswith(mid + "~"))), None)
            if same is not None:
                renamed[mid] = same
                continue
            renamed[mid] = name = _unique(mid, set(self.materials))
            self.materials[name] = definition
            _set(entry.value.data, "ID", _string(name))
            out.append(entry)
        for entry, entity in zip(root.get_all("Object"), rec.objects, strict=True):
            t = _transform(self.world, entity)
            if t is None:
                continue
            blk = entry.value.data
            physical = blk.get("PhysicalAttributes")
            material = None if not isinstance(physical, Block) else physical.value("Material")
            if material is not None and material.kind == STRING and material.data in renamed:
                _set(physical, "Material", _string(renamed[material.data]))
            self.names[entity] = oid = self.name(entity, "object")
            _set(blk, "ID", _string(oid))
            _write_body(blk, self.exact.get(entity, t),
                        None if self.sleep is None else self.sleep.get(entity))
            out.append(entry)
        for entry, entity in zip(root.get_all("Joint"), rec.joints, strict=True):
            joint = _live_joint(self.world, entity, self.names)
            if joint is None:
                continue
            blk = entry.value.data
            _set(blk, "ID", _string(self.name(entity, "joint")))
            _set(blk, "Bodies", self.bodies(joint))
            _write_joint(blk, joint)
            out.append(entry)
        for entry, entity in zip(root.get_all("Avatar"), rec.avatars, strict=True):
            t = _transform(self.world, entity)
            if t is None:
                continue
            blk = entry.value.data
            self.avatars[entity] = aid = self.name(entity, "avatar")
            _set(blk, "ID", _string(aid))
            _write_pose(blk, t)
            _drop(blk, "Hold")
            out.append(entry)
        self.root.entries.extend(out)

    def joint(self, entity: int) -> None:
        """A ``createJoint``: a Joint block from its component (limits in file units)."""
        joint = _live_joint(self.world, entity, self.names)
        if joint is None:
            return
        conv = (lambda x: x) if joint.kind in LINEAR_KINDS else exact_degrees
        entries = [("ID", _string(self.name(entity, "joint"))),
                   ("Type", _string(_TYPE_NAMES[joint.kind])), ("Bodies", self.bodies(joint))]
        for key, limit in (("Low", joint.low), ("High", joint.high)):
            if limit is not None:
                entries.append((key, Value(FLOAT, conv(float(limit)), _HERE)))
        if joint.spring is not None:
            entries.append(("Spring", _spring_block(joint.kind, joint.spring)))
        entry = _block("Joint", entries)
        _write_joint(entry.value.data, joint)
        self.root.entries.append(entry)


def _spring_block(kind: str, spring: Spring) -> Value:
    """A spawned joint's spring as a Spring block, in file units (per degree and degrees
    for a hinge) that read back to the same values (see :func:`exact_preimage`)."""
    per = 1.0 if kind in LINEAR_KINDS else math.degrees(1.0)
    entries = [(key, Value(FLOAT, exact_preimage(lambda f: f * per, v, v / per), _HERE))
               for key, v in (("Stiffness", spring.stiffness), ("Damping", spring.damping))]
    target = spring.target if kind in LINEAR_KINDS else exact_degrees(spring.target)
    entries.append(("Target", Value(FLOAT, target, _HERE)))
    if math.isfinite(spring.max_force):
        entries.append(("MaxForce", Value(FLOAT, spring.max_force, _HERE)))
    return _block("Spring", entries).value


def _drop_follows(root: Block, written: set[str]) -> None:
    """A camera following an object that is not written (deleted, or left out for a bad
    asset) follows nothing, so the saved file refers to no missing object."""
    for entry in root.entries:
        if entry.key != "Camera" or entry.value.kind != STRUCTURE:
            continue
        blk = entry.value.data
        follow = blk.value("Follow")
        if follow is not None and follow.data not in written:
            blk.entries = [e for e in blk.entries if e.key != "Follow"]


def _script_states(engine: Engine, ids: SceneIds, root: Block, names: dict[int, str]) -> None:
    """A ``ScriptState`` for each running script of a written object or of the scene, so
    the saved file resumes its scripts (see :mod:`services.scripting.persist`)."""
    scripts = engine.try_resource(ScriptStates)
    if scripts is None:
        return
    scene_ids = {entity: sid for sid, entity in ids.entities.items()}
    for entity, saved in scripts.saved_scripts(names.get).items():
        owner = names.get(entity)
        if owner is None and not engine.world.has_component(entity, Transform):
            owner = scene_ids.get(entity)  # a scene script (script0, ...)
        if owner is None:
            continue
        entries: list[tuple[str, Value]] = [("Owner", _string(owner))]
        for key, text in (("Globals", saved.globals), ("Locals", saved.locals)):
            if text != "{}":
                entries.append((key, _string(text)))
        block = _block("ScriptState", entries)
        for timer in saved.timers:
            block.value.data.entries.append(_block("Timer", [
                ("Function", _string(timer.function)),
                ("Due", Value(FLOAT, float(timer.due), _HERE)),
                ("Period", Value(FLOAT, float(timer.period), _HERE))]))
        for handler in saved.handlers:
            block.value.data.entries.append(_block("Handler", [
                ("Event", _string(handler.event)), ("Function", _string(handler.function))]))
        root.entries.append(block)


def _number(x: float) -> Value:
    return Value(FLOAT, float(x), _HERE)


def _flag(on: bool) -> Value:
    return Value(INT, int(bool(on)), _HERE)


def _avatars(world: World, ids: SceneIds, root: Block, objects: set[str]) -> dict[int, str]:
    """Each avatar block with its root pose now (those deleted or left out are left out);
    returns avatar entity -> ID. Authored holds of objects no longer written are dropped,
    so the file names no missing object."""
    written: dict[int, str] = {}
    for index, entry in enumerate([e for e in root.entries if e.key == "Avatar"]):
        blk = entry.value.data
        aid = str(blk.get("ID") or f"avatar{index}")  # the factory's name by place
        eid = ids.entities.get(aid)
        t = _transform(world, eid)
        if eid is None or t is None:
            root.entries.remove(entry)
            continue
        written[eid] = aid
        if blk.value("ID") is None:
            _set(blk, "ID", _string(aid))
        _write_pose(blk, t)
        blk.entries = [e for e in blk.entries if e.key != "Hold" or e.value.kind != STRUCTURE
                       or e.value.data.get("Object") in objects]
    return written


def _avatar_state(owner: str, saved: SavedAvatar) -> Entry:
    """An ``AvatarState`` block: what ``saved`` holds, every number exact."""
    entries: list[tuple[str, Value]] = [("Owner", _string(owner))]
    if saved.path:
        entries.append(("Path", _vec(x for p in saved.path for x in p)))
    entries += [("PathLoop", _flag(saved.path_loop)),
                ("Waypoint", Value(INT, int(saved.waypoint), _HERE))]
    if saved.ground is not None:
        entries.append(("Ground", _number(saved.ground)))
    if saved.ground_at is not None:
        entries.append(("GroundAt", _vec(saved.ground_at)))
    entries.append(("StepOffset", _number(saved.step_offset)))
    if saved.capsule is not None:
        entries += [("CapsulePosition", _vec(saved.capsule[0])),
                    ("CapsuleQuaternion", _vec(saved.capsule[1]))]
    block = _block("AvatarState", entries)
    inner = block.value.data.entries
    for group in saved.groups:
        g = _block("Group", [("Phase", _number(group.phase)), ("Loop", _flag(group.loop)),
                            ("Ended", _flag(group.ended)), ("Current", _flag(group.current))])
        g.value.data.entries += [_block("Layer", [
            ("Clip", _string(layer.clip)), ("Speed", _number(layer.speed)),
            ("Weight", _number(layer.weight)), ("FadeFrom", _number(layer.fade_from)),
            ("FadeTo", _number(layer.fade_to)), ("FadeTime", _number(layer.fade_time)),
            ("FadeLength", _number(layer.fade_length))]) for layer in group.layers]
        inner.append(g)
    for request in saved.queue:
        fields = [("Clips", Value(STRINGVECTOR, [_string(c) for c, _ in request.weights],
                                  _HERE)),
                  ("Weights", _vec(w for _, w in request.weights)),
                  ("Fade", _number(request.fade))]
        if request.speed is not None:
            fields.append(("Speed", _number(request.speed)))
        if request.loop is not None:
            fields.append(("Loop", _flag(request.loop)))
        inner.append(_block("Queued", fields))
    for held in saved.holds:
        fields = [("Object", _string(str(held.hold.target))), ("Bone", _string(held.hold.bone)),
                  ("Offset", _vec(held.hold.offset)), ("Quaternion", _vec(held.hold.rotation))]
        if held.last is not None:
            fields.append(("Last", _vec(held.last)))
        inner.append(_block("Hold", fields))
    inner += [_block("Drive", [("Bone", _string(d.bone)), ("Position", _vec(d.position)),
                               ("Quaternion", _vec(d.orientation))]) for d in saved.drives]
    return block


def _avatar_states(engine: Engine, root: Block, avatars: dict[int, str],
                   objects: dict[int, str]) -> None:
    """An ``AvatarState`` for each written avatar the avatars plugin animates."""
    states = engine.try_resource(AvatarStates)
    if states is None:
        return
    for entity, saved in states.saved_avatars(objects.get).items():
        if entity in avatars:
            root.entries.append(_avatar_state(avatars[entity], saved))


def _holding(world: World, hands: dict[int, Block], names: dict[int, str]) -> None:
    """Each hand's ``Holding``: what it holds now (by the IDs written), held again on load."""
    for eid, blk in hands.items():
        entry = blk.value("Hand")
        if entry is None or entry.kind != STRUCTURE:
            continue
        held = [names[e] for e in world.component_for_entity(eid, HandState).held
                if e in names]
        _drop(entry.data, "Holding")
        if held:
            _set(entry.data, "Holding", Value(STRINGVECTOR, [_string(n) for n in held],
                                              _HERE))


def _anomalies(engine: Engine, root: Block) -> None:
    """Each visual anomaly as the run left it: switched and set (one a script declared gets
    a block of its own; a ramp in progress is saved as where it is going)."""
    anomalies = engine.try_resource(Anomalies)
    if anomalies is None:
        return
    blocks: dict[str, Block] = {}
    for kind in ANOMALIES.values():
        for entry in root.entries:
            if entry.key == kind.block and entry.value.kind == STRUCTURE:
                written = entry.value.data.value("ID")
                blocks[str(written.data) if written is not None and written.data
                       else kind.name] = entry.value.data
    for state in anomalies.states.values():
        block = blocks.get(state.id)
        if block is None:
            entry = _block(state.kind.block, [("ID", _string(state.id))])
            root.entries.append(entry)
            block = entry.value.data
        _set(block, "Enabled", Value(INT, int(state.enabled), _HERE))
        _set(block, "Onset", _number(state.onset))
        _set(block, "Eye", _string(state.eye))
        for key, value in state.values.items():
            _set(block, key, _string(value) if isinstance(value, str) else
                 _vec(value) if isinstance(value, tuple) else _number(value))


def _taken(ids: SceneIds) -> set[str]:
    """IDs of the file's own entries (those without one are written with the one they
    were given by their place, so loading the saved file keeps every name)."""
    return {es.id for es in ids.spec.entities} | {js.id for js in ids.spec.joints}


def _declared(world: World, entity: int, blk: Block, own: str | None = None) -> None:
    """The components of declared blocks (engine.scene.blocks) as they are now: an engine
    block's save sets its keys on the block written, wherever it stands (the entity's own
    top-level block ``own``, or inside another; the rest stay as the author wrote them);
    a content folder's block is written whole."""
    for component in world.components_for_entity(entity):
        block = blocks.of_component(component)
        if block is None:
            continue
        entries = [(k, _literal_value(v)) for k, v in block.save(component).items()]
        written = blk if block.name == own else (
            _written(blk, block.name) if blocks.builtin(block) else None)
        if written is not None:
            for k, v in entries:
                _set(written, k, v)
        else:
            _set(blk, block.name, _block(block.name, entries).value)


def _written(blk: Block, name: str) -> Block | None:
    """Block ``name`` as written in ``blk``, or in a declared block inside it."""
    entry = blk.value(name)
    if entry is not None and entry.kind == STRUCTURE:
        return entry.data
    for e in blk.entries:
        if e.key in blocks.BLOCKS and e.value.kind == STRUCTURE:
            found = _written(e.value.data, name)
            if found is not None:
                return found
    return None


def _declared_entities(world: World, ids: SceneIds, root: Block) -> None:
    """Top-level declared blocks (an entity each, named by ID or place) as they are now."""
    for name, block in blocks.BLOCKS.items():
        if "Scene" not in block.inside or not block.entity:  # a Joint is written above
            continue
        written = [e for e in root.entries if e.key == name and e.value.kind == STRUCTURE]
        for i, entry in enumerate(written):
            given = entry.value.data.value("ID")
            bid = str(given.data) if given is not None and given.data else f"{name.lower()}{i}"
            eid = ids.entities.get(bid)
            if eid is not None and world.entity_exists(eid):
                _declared(world, eid, entry.value.data, name)


def _literal_value(value: Any) -> Value:
    """A Python value as scene text: a number, a flag, text or a vector."""
    if isinstance(value, bool):
        return _flag(value)
    if isinstance(value, int):
        return Value(INT, value, _HERE)
    if isinstance(value, float):
        return _number(value)
    if isinstance(value, str):
        return _string(value)
    return _vec(value)


def write_state(engine: Engine, out_path: str | os.PathLike | None = None,
                names: dict[int, str] | None = None) -> str:
    """Scene text of the running simulation; needs a scene loaded with ``instantiate``.

    Model, sound, script and shader file names are relative to the content folder (as
    its ``main.scene`` names them). With ``out_path`` (where the text will be saved) the
    file also says where that folder is, relative to it (``Content``), so it runs from
    anywhere as long as the two keep their places. ``names``, when given, receives the
    object or avatar ID each written entity got (a network server tells its nodes which
    is which).
    Without local physics (a network node) the solver's and sleep states are left out.
    """
    ids: SceneIds = engine.resource(SceneIds)
    spec = ids.spec
    assert spec.db is not None, "write_state needs a spec built from a SceneDB"
    dst = None if spec.content_dir is None else spec.content_dir.resolve()
    root = _literal(spec.db, spec.content_dir, dst)
    _drop(root, "Content")
    if out_path is not None and dst is not None:
        here = Path(out_path).resolve().parent
        root.entries.insert(0, Entry("Content", _string(
            Path(os.path.relpath(dst, here)).as_posix()), _HERE))
    world = engine.world
    seed, sleep, exact = _physics_state(engine)
    names = {} if names is None else names  # entity -> the object ID written for it
    hands = _objects(world, ids, root, names, sleep, exact)
    _joints(world, ids, root, names)
    avatars = _avatars(world, ids, root, set(names.values()))  # before spawned ones come
    spawns = _Spawns(world, root, names, _taken(ids), sleep, dst, exact)
    for rec in ids.spawned:
        if rec.db is None:
            spawns.joint(rec.joints[0])
        else:
            spawns.snippet(rec)
    avatars.update(spawns.avatars)
    _declared_entities(world, ids, root)
    _drop_follows(root, set(names.values()))
    _holding(world, hands, names)
    _avatar_states(engine, root, avatars, names)
    _script_states(engine, ids, root, names | avatars)
    _anomalies(engine, root)
    names.update(avatars)  # the caller's map names avatars too
    _world_clock(engine, root, seed)
    return _header(spec.db.path, engine.time, dst) + write(root, literal=True)


def _physics_state(engine: Engine) -> tuple[int | None, dict[int, SleepState] | None,
                                             dict[int, _Row]]:
    """The solver's random state, each body's auto-sleep state and its exact state, where
    the backend has them (none without local physics: a node, or physics stopped)."""
    from engine.physics.driver import PhysicsUnavailable  # reading a scene needs no driver

    try:
        return engine.physics.request(lambda backend: (
            getattr(backend, "solver_seed", None),
            backend.sleep_states() if isinstance(backend, SupportsSleepState) else None,
            _rows(backend.exact_state()) if isinstance(backend, SupportsExactState) else {})
        ).result(5.0)
    except PhysicsUnavailable:  # poses only
        return None, None, {}


def _objects(world: World, ids: SceneIds, root: Block, names: dict[int, str],
             sleep: dict[int, SleepState] | None, exact: dict[int, _Row]) -> dict[int, Block]:
    """The file's objects as they are now (one gone is left out), each named in ``names``
    and its declared blocks saved; the hands' written blocks, by entity."""
    spec, hands = ids.spec, {}
    objects = [e for e in root.entries if e.key == "Object"]
    for index, entry in enumerate(objects):
        eid = ids.entities.get(spec.entities[index].id)
        t = _transform(world, eid)
        if eid is None or t is None:
            root.entries.remove(entry)
            continue
        names[eid] = oid = spec.entities[index].id
        blk = entry.value.data
        if blk.value("ID") is None:  # its name by place would move as others are left out
            _set(blk, "ID", _string(oid))
        _write_body(blk, exact.get(eid, t), None if sleep is None else sleep.get(eid))
        if world.has_component(eid, HandState):
            hands[eid] = blk
        _declared(world, eid, blk)
    return hands


def _joints(world: World, ids: SceneIds, root: Block, names: dict[int, str]) -> None:
    """The file's joints that still hold written bodies, as their declaration saves them."""
    joints = [e for e in root.entries if e.key == "Joint"]
    for js, entry in zip(ids.spec.joints, joints, strict=False):
        joint = _live_joint(world, ids.joints.get(js.id), names)
        if joint is None:
            root.entries.remove(entry)
            continue
        if entry.value.data.value("ID") is None:
            _set(entry.value.data, "ID", _string(js.id))
        _write_joint(entry.value.data, joint)


def _world_clock(engine: Engine, root: Block, seed: int | None) -> None:
    """The World block's time, the solver's random state and the scene's generator (what
    spawned text's randInterval draws from), so the saved state continues the run."""
    entry = next((e for e in root.entries if e.key == "World"), None)
    if entry is None or entry.value.kind != STRUCTURE:
        entry = Entry("World", Value(STRUCTURE, Block(), _HERE), _HERE)
        root.entries.append(entry)
    _set(entry.value.data, "Time", Value(FLOAT, float(engine.time), _HERE))
    if seed is not None:  # the solver shuffles constraints with it
        _set(entry.value.data, "SolverSeed", Value(INT, int(seed), _HERE))
    generator = random_state.text(engine.rng)
    if generator is not None:
        _set(entry.value.data, "RandomState", _string(generator))


def _header(source: str, time: float, content: Path | None) -> str:
    """Where the state came from and when (for people: 12 significant digits; the exact
    time is World's ``Time``), and what its file names are relative to."""
    folder = "" if content is None else f" (saved from {content})"
    return (f"// state of {source} at t = {time:.12g} s\n"
            f"// file names are relative to the content folder{folder}\n")
