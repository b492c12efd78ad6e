"""Save a running simulation as a scene file (the paper's "state at time t").

The loaded SceneDB is written self-contained (includes inlined, expressions
frozen to their values) with each object's current pose and velocities (and,
where the backend keeps one, its auto-sleep state), the joints' motor settings,
the solver's random state and the simulated time. Orientation is written exactly
as ``Quaternion`` (and, for people, as ``Orientation`` degrees), floats with
full precision, so loading the file continues the motion.

A joint keeps the ``Anchor`` and axes it was made with, plus the poses its bodies
had then (``ReferencePose1``/``ReferencePose2``): loading makes it as if the bodies
stood there, so it holds them exactly as before, however far they have moved.
"""

from __future__ import annotations

import math
import os
from pathlib import Path
from typing import TYPE_CHECKING

from components import Joint, Transform
from engine.physics.backend import SleepState, SupportsSleepState
from engine.scene import schema as sc
from engine.scene.db import FLOAT, INT, STRING, STRUCTURE, VECTOR, Block, Entry, Value
from engine.scene.diagnostics import Loc
from engine.scene.factory import SceneIds
from engine.scene.parser import parse_text
from engine.scene.rotation import exact_degrees, quat_to_euler
from engine.scene.writer import write

if TYPE_CHECKING:
    from engine.app import Engine

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
        if f.type == sc.ASSET_T and e.value.kind == STRING:
            e.value.data = Path(os.path.relpath(src / e.value.data, dst)).as_posix()
        elif f.type == sc.STRUCT_T and e.value.kind == STRUCTURE:
            _rebase_assets(e.value.data, f.struct, src, dst)


def _sleep_keys(block: Block, state: SleepState | None) -> None:
    """Write a body's auto-sleep state (``None``: fresh, or a backend that keeps none)."""
    for key in ("Asleep", "IdleSteps", "VelocitySamples"):
        _drop(block, key)
    if state is None:
        return
    if state.asleep:
        _set(block, "Asleep", Value(INT, 1, _HERE))
    if state.idle_steps:
        _set(block, "IdleSteps", Value(INT, int(state.idle_steps), _HERE))
    if len(state.samples):
        _set(block, "VelocitySamples", _vec(
            x if k < 3 else exact_degrees(x)
            for row in state.samples.tolist() for k, x in enumerate(row)))


def write_state(engine: Engine, out_path: str | os.PathLike | None = None) -> str:
    """Scene text of the running simulation; needs a scene loaded with ``instantiate``.

    With ``out_path`` (where the text will be saved), model, sound, script and
    shader file names are rewritten relative to that file's folder.
    """
    ids: SceneIds = engine.resource(SceneIds)
    spec = ids.spec
    assert spec.db is not None, "write_state needs a spec built from a SceneDB"
    db = parse_text(write(spec.db, literal=True, flatten=True), spec.db.path)
    if out_path is not None and spec.content_dir is not None:
        _rebase_assets(db.root, "Scene", spec.content_dir.resolve(),
                       Path(out_path).resolve().parent)
    world = engine.world
    root = db.root
    # the solver's random state and each body's auto-sleep state, where the backend has them
    seed, sleep = engine.physics.request(lambda backend: (
        getattr(backend, "solver_seed", None),
        backend.sleep_states() if isinstance(backend, SupportsSleepState) else None)
    ).result(5.0)
    objects = [e for e in root.entries if e.key == "Object"]
    for index, entry in enumerate(objects):
        eid = ids.entities.get(spec.entities[index].id)
        t = None if eid is None else world.try_component(eid, Transform) \
            if world.entity_exists(eid) else None
        if t is None:
            root.entries.remove(entry)
            continue
        blk = entry.value.data
        q = [float(x) for x in t.orientation]
        _set(blk, "Position", _vec(t.position))
        _set(blk, "Orientation", _vec(quat_to_euler(q)))
        _set(blk, "Quaternion", _vec(q))
        _set(blk, "Velocity", _vec(t.linear_velocity))
        _set(blk, "AngularVelocity", _vec(exact_degrees(float(w)) for w in t.angular_velocity))
        _sleep_keys(blk, None if sleep is None else sleep.get(eid))
    joints = [e for e in root.entries if e.key == "Joint"]
    for js, entry in zip(spec.joints, joints, strict=False):
        jid = ids.joints.get(js.id)
        joint = None if jid is None or not world.entity_exists(jid) else \
            world.try_component(jid, Joint)
        if joint is None or joint.broken:
            root.entries.remove(entry)
            continue
        conv = (lambda x: x) if joint.kind == "slider" else math.degrees
        blk = entry.value.data
        # as made at first: the anchor and axes then, and where its bodies were then
        _set(blk, "Anchor", _vec(joint.anchor))
        _set(blk, "Axis", _vec(joint.axis))
        _set(blk, "Axis2", _vec(joint.axis2))
        if joint.reference is not None:
            pose_a, pose_b = joint.reference
            _set(blk, "ReferencePose1", _vec(pose_a))
            if pose_b is not None:
                _set(blk, "ReferencePose2", _vec(pose_b))
        _set(blk, "MotorVelocity", Value(FLOAT, conv(joint.motor_velocity), _HERE))
        _set(blk, "MotorMaxForce", Value(FLOAT, float(joint.motor_max_force), _HERE))
    world_entry = next((e for e in root.entries if e.key == "World"), None)
    if world_entry is None or world_entry.value.kind != STRUCTURE:
        world_entry = Entry("World", Value(STRUCTURE, Block(), _HERE), _HERE)
        root.entries.append(world_entry)
    _set(world_entry.value.data, "Time", Value(FLOAT, float(engine.time), _HERE))
    if seed is not None:  # the solver shuffles constraints with it
        _set(world_entry.value.data, "SolverSeed", Value(INT, int(seed), _HERE))
    header = f"// state of {spec.db.path} at t = {spec.time + engine.time!r} s"
    return header + "\n" + write(db, literal=True)
