"""Scene text of an object made in Python (``engine.spawn(Name(..), Transform(..),
Visual(..))``), from its components: what a network node needs to show it.

A script's ``spawn`` keeps the text it was made from; a Python system's entity has only
components, so a server writes them back as an ``Object`` block: its ID, pose and
velocities, the user it stands for, how it looks (primitives, a model file, colour,
texture, shader state, shadows, visibility) and its sound. The body is not written:
nodes run no physics. What the format cannot say — a visual made of vertex arrays, a
plane or an overlay — raises :class:`Unwritable` with the reason, so the caller can name
the object.

>>> from components import Name, Shape, Transform, Visual
>>> block = object_block("crate", Transform((0, 0, 1)), Visual([Shape("box", (1, 2, 3))]))
>>> from engine.scene.writer import write
>>> print(write(block, literal=True).strip().splitlines()[0])
ID "crate"
"""

from __future__ import annotations

from components import Shape, Sound, Transform, UserOwned, Visual
from engine.assets.service import split_nodes
from engine.rotation import quat_to_euler
from engine.scene.blocks import BLOCKS
from engine.scene.db import FLOAT, INT, STRING, STRINGVECTOR, STRUCTURE, VECTOR, Block, Entry, Value
from engine.scene.diagnostics import Loc

_HERE = Loc("<python object>", 0, 0)
#: Primitive kinds a Geometry block can draw.
_PRIMITIVES = ("sphere", "box", "capsule", "cylinder")


class Unwritable(ValueError):
    """An object whose components the scene format cannot express (the text says why)."""


def _number(x: float) -> Value:
    return Value(FLOAT, float(x), _HERE)


def _vec(values: object) -> Value:
    return Value(VECTOR, [_number(x) for x in values], _HERE)  # type: ignore[attr-defined]


def _string(text: str) -> Value:
    return Value(STRING, text, _HERE)


def _flag(on: bool) -> Value:
    return Value(INT, int(bool(on)), _HERE)


def _struct(entries: list[tuple[str, Value]]) -> Value:
    return Value(STRUCTURE, Block([Entry(k, v, _HERE) for k, v in entries]), _HERE)


def _geometry(shape: Shape) -> Value:
    if shape.kind not in _PRIMITIVES or shape.vertices is not None:
        raise Unwritable(f"a {shape.kind} visual shape (a Geometry block draws "
                         f"{', '.join(_PRIMITIVES)} or a model file)")
    size = shape.size
    diameters = (2 * size[0],) if shape.kind == "sphere" else tuple(size) \
        if shape.kind == "box" else (2 * size[0], size[1])
    entries = [("Primitive", _string(shape.kind)), ("Size", _vec(diameters))]
    if any(shape.offset):
        entries.append(("Offset", _vec(shape.offset)))
    if tuple(shape.rotation) != (1.0, 0.0, 0.0, 0.0):
        entries.append(("Orientation", _vec(quat_to_euler(shape.rotation))))
    return _struct(entries)


def _model(name: str, scale: tuple[float, float, float]) -> Value:
    file, nodes, mesh = split_nodes(name)
    entries = [("File", _string(file)), ("Scale", _vec(scale))]
    if nodes is not None:
        names = Value(STRINGVECTOR, [_string(n) for n in nodes], _HERE)
        entries.append(("Mesh", _string(nodes[0])) if mesh else ("Nodes", names))
    return _struct(entries)


def _visual(visual: Visual) -> Value:
    if visual.overlay:
        raise Unwritable("an overlay visual (only hands draw so)")
    entries = [("Geometry", _geometry(s)) for s in visual.shapes]
    if visual.model is not None:
        entries.append(("Geometry", _model(visual.model, visual.scale)))
    entries += [("Color", _vec(visual.color)), ("Shadower", _flag(visual.shadower)),
                ("Shadowed", _flag(visual.shadowed)), ("Visible", _flag(visual.visible))]
    if visual.texture is not None:
        entries.append(("Texture", _string(visual.texture)))
    if visual.shader_state is not None:
        entries.append(("ShaderState", _string(visual.shader_state)))
    return _struct(entries)


def _sound(sound: Sound) -> Value:
    """The Sound block, as its declaration writes it back (components.sound)."""
    return _struct([(k, _plain(v)) for k, v in BLOCKS["Sound"].save(sound).items()])


def _plain(value: object) -> Value:
    """A declaration's saved value (a flag, a whole number, a number, text) as scene text."""
    if isinstance(value, bool):
        return _flag(value)
    if isinstance(value, int):
        return Value(INT, value, _HERE)
    if isinstance(value, str):
        return _string(value)
    return _number(value)  # type: ignore[arg-type]


def object_block(name: str, transform: Transform, visual: Visual | None = None,
                 sound: Sound | None = None, user: UserOwned | None = None) -> Block:
    """The ``Object`` block (its body) of an entity with these components; one without a
    Visual is written invisible (a bare block would get a default look). Raises
    :class:`Unwritable`."""
    t = transform
    entries: list[tuple[str, Value]] = [
        ("ID", _string(name)), ("Position", _vec(t.position)),
        ("Quaternion", _vec(t.orientation)), ("Velocity", _vec(t.linear_velocity))]
    if user is not None:
        entries.append(("User", _string(user.user)))
    entries.append(("VisualAttributes", _visual(visual) if visual is not None
                    else _struct([("Visible", _flag(False))])))
    if sound is not None:
        entries.append(("Sound", _sound(sound)))
    return Block([Entry(k, v, _HERE) for k, v in entries])
