"""What to say about an unknown key: meaning first, then place, then spelling.

Authors bring names from the paper's listings and from other engines (``Radius``,
``Scale``, ``Colour``, ``Rotation``, ``Restitution``...), and put real keys in the
wrong block (``Mass`` on an Object instead of in its PhysicalAttributes). A
spelling match alone misses both; :func:`unknown_key_hint` tries, in order: a key
of this block the name means, a block below this one that has the key, another
declaration that has it, and only then the closest spelling.
"""

from __future__ import annotations

from functools import cache

import engine.scene.schema as sc
from engine.scene.db import FLOAT, INT, Value
from engine.scene.diagnostics import suggest

_SIZE_NOTE = "a sphere's Size is its diameter, a box's [x y z], a capsule's [diameter length]"
_EULER = "Euler angles in degrees [rx ry rz]"

#: Lower-cased names from elsewhere -> the keys they may mean, each with a note; the
#: first key this block (or a block below it) has is the hint.
ALIASES: dict[str, tuple[tuple[str, str], ...]] = {
    "radius": (("Size", _SIZE_NOTE),),
    "diameter": (("Size", _SIZE_NOTE),),
    "extents": (("Size", _SIZE_NOTE),),
    "dimensions": (("Size", _SIZE_NOTE),),
    "halfextents": (("Size", "Size is full extents, twice the half extents"),),
    "scale": (("Size", "an Object's Size sizes its primitives; a model's Scale goes in its "
                       "Geometry"),),
    "colour": (("Color", "RGB or RGBA, 0..1"),),
    "rgb": (("Color", "RGB or RGBA, 0..1"),),
    "diffuse": (("Color", "RGB or RGBA, 0..1"),),
    "rotation": (("Orientation", _EULER), ("Quaternion", "[w x y z]")),
    "rot": (("Orientation", _EULER),),
    "euler": (("Orientation", _EULER),),
    "eulerangles": (("Orientation", _EULER),),
    "angles": (("Orientation", _EULER),),
    "heading": (("Orientation", _EULER),),
    "quat": (("Quaternion", "[w x y z]"),),
    "translation": (("Position", "metres [x y z]"),),
    "location": (("Position", "metres [x y z]"),),
    "pos": (("Position", "metres [x y z]"),),
    "origin": (("Position", "metres [x y z]"),),
    "center": (("Position", "metres [x y z]"),),
    "centre": (("Position", "metres [x y z]"),),
    "linearvelocity": (("Velocity", "m/s [vx vy vz]"),),
    "vel": (("Velocity", "m/s [vx vy vz]"),),
    "angularvel": (("AngularVelocity", "degrees per second [wx wy wz]"),),
    "restitution": (("Bounce", "restitution, 0..1"),),
    "bounciness": (("Bounce", "restitution, 0..1"),),
    "elasticity": (("Bounce", "restitution, 0..1"),),
    "static": (("Dynamic", "Dynamic 0 makes a body static"),),
    "isstatic": (("Dynamic", "Dynamic 0 makes a body static"),),
    "weight": (("Mass", "kilograms"),),
    "damping": (("LinearDamping", "and AngularDamping"),),
    "mesh": (("File", "a model file, loaded with trimesh"),),
    "model": (("File", "a model file, loaded with trimesh"),),
    "filename": (("File", "relative to the scene file's folder"),),
    "shape": (("Primitive", "sphere, box, capsule, cylinder or plane"),),
    "dt": (("TimeStep", "seconds per dynamics step"),),
    "deltatime": (("TimeStep", "seconds per dynamics step"),),
    "fixedtimestep": (("TimeStep", "seconds per dynamics step"),),
    "volume": (("Gain", "1 is the file's own loudness"),),
    "fieldofview": (("Fov", "vertical, degrees"),),
    "target": (("LookAt", "the point the camera looks at"),),
    "name": (("ID", "the name other declarations refer to"),),
    "visual": (("VisualAttributes", "how the object looks"),),
    "graphics": (("VisualAttributes", "how the object looks"),),
    "physics": (("PhysicalAttributes", "mass, material and collision geometry"),),
    "physical": (("PhysicalAttributes", "mass, material and collision geometry"),),
    "rigidbody": (("PhysicalAttributes", "mass, material and collision geometry"),),
}


@cache
def _key_of_struct() -> dict[str, str]:
    """Schema name -> the key that opens it (``Visual`` -> ``VisualAttributes``)."""
    out: dict[str, str] = {}
    for fields in sc.SCHEMAS.values():
        for key, f in fields.items():
            if f.type == sc.STRUCT_T and f.struct:
                out.setdefault(f.struct, key)
    return out


@cache
def _below(block: str, key: str) -> str | None:
    """Where under ``block`` (up to two levels) ``key`` is a key, as the author writes it
    (``VisualAttributes { Geometry {``); None if nowhere."""
    for k, f in sc.SCHEMAS[block].items():
        if f.type == sc.STRUCT_T and f.struct and key in sc.SCHEMAS[f.struct]:
            return f"{k} {{ ... }}"
    for k, f in sc.SCHEMAS[block].items():
        if f.type != sc.STRUCT_T or not f.struct:
            continue
        for k2, f2 in sc.SCHEMAS[f.struct].items():
            if f2.type == sc.STRUCT_T and f2.struct and key in sc.SCHEMAS[f2.struct]:
                return f"{k} {{ {k2} {{ ... }} }}"
    return None


@cache
def _owners(key: str) -> tuple[str, ...]:
    """The declarations (as written) that have ``key``."""
    opens = _key_of_struct()
    return tuple(opens.get(name, name) for name, fields in sc.SCHEMAS.items()
                 if key in fields and name != "Scene")


def _note(note: str, key: str, value: Value | None) -> str:
    """``note``, with the diameter worked out when a radius is given as a number."""
    if key.lower() == "radius" and value is not None and value.kind in (INT, FLOAT):
        return f"a sphere's Size is its diameter: Size [{2 * value.data:g}] for Radius " \
               f"{value.data:g}"
    return note


def unknown_key_hint(key: str, block: str, value: Value | None = None) -> str:
    """`` (...)`` to follow "unknown key 'KEY' in BLOCK", or empty when nothing fits."""
    fields = sc.SCHEMAS[block]
    aliases = ALIASES.get(key.lower(), ())
    for target, note in aliases:
        if target in fields and target != key:
            return f" (did you mean '{target}'? {_note(note, key, value)})"
    where = _below(block, key)
    if where is not None:
        return f" ('{key}' goes in {where})"
    for target, note in aliases:
        where = _below(block, target)
        if where is not None:
            return f" (did you mean '{target}' in {where}? {_note(note, key, value)})"
    spelling = suggest(key, fields)
    if spelling:
        return spelling
    here = block_name(block)
    owners = _owners(key)
    if owners:
        return f" ('{key}' is a key of {' and '.join(owners[:3])}, not of {here})"
    for target, note in aliases:
        owners = _owners(target)
        if owners:
            return (f" (did you mean '{target}'? {_note(note, key, value)}; it is a key of "
                    f"{' and '.join(owners[:3])}, not of {here})")
    return ""


def block_name(block: str) -> str:
    """A schema's name as the author writes it (``Visual`` is ``VisualAttributes``)."""
    return _key_of_struct().get(block, block)
