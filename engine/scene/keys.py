"""The scene key reference, generated from the schema: every key of every block with its
type, default, meaning and an example. ``colosseum keys [BLOCK]`` prints it; docs/KEYS.md
is :func:`reference_markdown` (a test keeps the page equal to it).

>>> print(block_text("Uniform"))
Uniform  (inside PostPass: a uniform's value)
  ID     STRING, required                 uniform name in the GLSL source
         e.g. ID "DiffuseColor"
  Value  FLOAT or VECTOR (1-4), required  a number, or up to 4 numbers (vec2..vec4)
         e.g. Value [0 0.25 1]
"""

from __future__ import annotations

import difflib
from typing import Any

import engine.scene.schema as sc
from engine.scene.blocks import EXAMPLES, from_content

_TYPES = {
    sc.INT_T: "INT", sc.FLOAT_T: "FLOAT", sc.BOOL_T: "INT 0/1", sc.STRING_T: "STRING",
    sc.ASSET_T: "STRING file name", sc.VEC3_T: "VECTOR [x y z]", sc.VECTOR_T: "VECTOR",
    sc.STRINGVECTOR_T: "STRINGVECTOR", sc.STRUCT_T: "STRUCTURE", sc.ENUM_T: "STRING",
    sc.REF_T: "STRING ID", sc.NUMBER_OR_VECTOR_T: "FLOAT or VECTOR (1-4)", sc.ANY_T: "anything",
}

#: Examples where the type and default say too little (block, key) -> value text.
_EXAMPLES: dict[tuple[str, str], str] = {
    ("Scene", "Content"): '"../content/demo"',
    ("Object", "ID"): '"crate1"', ("Object", "Size"): "[1 1 1]",
    ("Object", "Quaternion"): "[1 0 0 0]",
    ("Object", "VelocitySamples"): "[0 0 0.01 0 0 0]", ("Object", "IdleSteps"): "5",
    ("Visual", "Texture"): '"textures/wood.png"', ("Visual", "ShaderState"): '"toon"',
    ("Visual", "Color"): "[0.72 0.52 0.3]",
    ("Physical", "Mass"): "2", ("Physical", "Density"): "700", ("Physical", "Material"): '"wood"',
    ("Physical", "CenterOfMass"): "[0 0 -0.3]", ("Physical", "Inertia"): "[0.2 0.2 0.05]",
    ("Physical", "InertiaOrientation"): "[0 0 45]",
    ("Spring", "Stiffness"): "0.5", ("Spring", "Damping"): "0.05", ("Spring", "Target"): "10",
    ("Spring", "MaxForce"): "20",
    ("Geometry", "File"): '"models/rock.obj"', ("Geometry", "Size"): "[0.6]",
    ("Geometry", "ParseMethod"): '"ConvexHull"',
    ("Uniform", "ID"): '"DiffuseColor"', ("Uniform", "Value"): "[0 0.25 1]",
    ("ScriptState", "Owner"): '"ball"', ("ScriptState", "Globals"): '"{score = 3}"',
    ("ScriptState", "Locals"): '"{bounces = 2}"',
    ("ScriptTimer", "Function"): '"kick"', ("ScriptTimer", "Due"): "0.5",
    ("ScriptTimer", "Period"): "0.25",
    ("ScriptHandler", "Event"): '"door"', ("ScriptHandler", "Function"): '"opened"',
    ("AvatarState", "Owner"): '"guide"', ("AvatarState", "Path"): "[0 0 0  4 0 0  4 4 0]",
    ("AvatarState", "Waypoint"): "1", ("AvatarState", "Ground"): "0.2",
    ("AvatarState", "GroundAt"): "[1.5 0]", ("AvatarState", "StepOffset"): "-0.04",
    ("AvatarState", "CapsulePosition"): "[1.5 0 0.2]",
    ("AvatarState", "CapsuleQuaternion"): "[1 0 0 0]",
    ("AnimationGroup", "Phase"): "0.25", ("AnimationGroup", "Current"): "1",
    ("AnimationLayer", "Clip"): '"Walk"', ("AnimationLayer", "Weight"): "0.6",
    ("AnimationLayer", "FadeFrom"): "0.2", ("AnimationLayer", "FadeTo"): "1",
    ("AnimationLayer", "FadeTime"): "0.1", ("AnimationLayer", "FadeLength"): "0.25",
    ("AnimationRequest", "Clips"): '["Walk" "Run"]', ("AnimationRequest", "Weights"): "[1 0]",
    ("AnimationRequest", "Fade"): "0.3", ("AnimationRequest", "Speed"): "1.2",
    ("AnimationRequest", "Loop"): "0",
    ("HeldState", "Object"): '"crate"', ("HeldState", "Bone"): '"hand.R"',
    ("HeldState", "Last"): "[0.4 0.2 1.1]",
    ("BoneDrive", "Bone"): '"hand.L"', ("BoneDrive", "Position"): "[0.3 0.4 1.2]",
    ("BoneDrive", "Quaternion"): "[1 0 0 0]",
}


def _number(x: Any) -> str:
    return f"{x:g}" if isinstance(x, float) else str(x)


def _value(value: Any) -> str:
    if isinstance(value, tuple):
        return "[" + " ".join(_value(x) for x in value) + "]"
    if isinstance(value, str):
        return f'"{value}"'
    return _number(value)


def type_text(field: sc.Field) -> str:
    """The key's type as an author writes it, with its choices or target."""
    text = _TYPES[field.type]
    if field.type == sc.ENUM_T:
        text += ": " + " | ".join(f'"{a}"' for a in field.allowed)
    elif field.type == sc.REF_T and field.ref:
        text += f" of {'an' if field.ref[0] in 'AEIOU' else 'a'} {field.ref}"
    elif field.type == sc.STRUCT_T and field.struct:
        text += f" {{ {field.struct} keys }}"
    elif field.lengths:
        text += f" ({', '.join(map(str, field.lengths))} numbers)"
    if field.repeat:
        text += ", repeatable"
    if field.required:
        text += ", required"
    return text


def default_text(field: sc.Field) -> str:
    return "" if field.default is None else _value(field.default)


def example(block: str, key: str, field: sc.Field) -> str:
    """A line of scene text using the key."""
    given = _EXAMPLES.get((block, key), EXAMPLES.get((block, key)))
    if given is not None:
        return f"{key} {given}"
    if field.type == sc.STRUCT_T:
        return f"{key} {{ ... }}"
    if field.type == sc.ANY_T:
        return f"{key} {{ gain 2 Labels [\"a\" \"b\"] }}"
    if field.type == sc.ENUM_T and field.default is None:
        return f'{key} "{field.allowed[0]}"'
    if field.default is not None:
        return f"{key} {_value(field.default)}"
    if field.type == sc.VECTOR_T:  # as many numbers as it takes
        return f"{key} {_value((0.0,) * (field.lengths[0] if field.lengths else 3))}"
    if field.type == sc.STRINGVECTOR_T:
        return f'{key} ["a" "b"]'
    typical = {sc.INT_T: 1, sc.FLOAT_T: 1.0, sc.BOOL_T: 1, sc.VEC3_T: (0.0, 0.0, 1.0)}
    return f"{key} {_value(typical.get(field.type, 'name'))}"


def _parents() -> dict[str, tuple[str, str]]:
    """Block -> (the block holding it, the key) where it first appears."""
    found: dict[str, tuple[str, str]] = {}
    for block, fields in sc.SCHEMAS.items():
        for key, field in fields.items():
            if field.struct and field.struct not in found:
                found[field.struct] = (block, key)
    return found


def about(block: str) -> str:
    if block == "Scene":
        return "the top level of a scene file"
    parent, key = _parents()[block]
    doc = sc.SCHEMAS[parent][key].doc
    where = "at the top level" if parent == "Scene" else f"inside {parent}"
    return f"{where}{' as ' + key if key != block else ''}: {doc}"


def blocks(content: bool = False) -> list[str]:
    """Every block; with ``content``, those content folders declared too."""
    return [b for b in sc.SCHEMAS if content or not from_content(b)]


def find_block(name: str) -> str | None:
    """The schema block an author means by ``name`` (a block or the key that opens it)."""
    by_lower = {b.lower(): b for b in sc.SCHEMAS}
    for fields in sc.SCHEMAS.values():
        for key, field in fields.items():
            if field.struct:
                by_lower.setdefault(key.lower(), field.struct)
    return by_lower.get(name.lower())


def suggest(name: str) -> str:
    close = difflib.get_close_matches(name, blocks(), n=1)
    return f"; did you mean {close[0]!r}?" if close else ""


def block_text(block: str) -> str:
    """One block's keys for a terminal: key, type, default and meaning, then an example."""
    fields = sc.SCHEMAS[block]
    rows = []
    for key, field in fields.items():
        kind = type_text(field)
        default = default_text(field)
        if default:
            kind += f", default {default}"
        rows.append((key, kind, field.doc, example(block, key, field)))
    kw = max(len(r[0]) for r in rows)
    tw = max(len(r[1]) for r in rows)
    lines = [f"{block}  ({about(block)})"]
    for key, kind, doc, ex in rows:
        lines.append(f"  {key:<{kw}}  {kind:<{tw}}  {doc}".rstrip())
        lines.append(f"  {'':<{kw}}  e.g. {ex}")
    return "\n".join(lines)


def reference_markdown() -> str:
    """docs/KEYS.md: every block, every key."""
    out = ["# Scene keys", "",
           "<!-- generated from engine/scene/schema.py and the blocks features declare "
           "(engine.scene.blocks) by `python -m tools.docs`; "
           "tests/scene/test_keys_reference.py keeps it equal -->", "",
           "Every key a scene file may hold, block by block: its type, its default (a key "
           "left out takes it), what it means and an example. Units: metres, kilograms, "
           "seconds, degrees; Z is up. Keys starting with a lower-case letter are your own "
           "variables. `colosseum keys BLOCK` prints one block in a terminal.", ""]
    out += ["Blocks: " + ", ".join(f"[{b}](#{b.lower()})" for b in blocks()), ""]
    for block in blocks():
        fields = {k: f for k, f in sc.SCHEMAS[block].items()
                  if not (f.struct and from_content(f.struct))}
        out += [f"## {block}", "", about(block)[0].upper() + about(block)[1:] + ".", "",
                "| key | type | default | meaning | example |", "|---|---|---|---|---|"]
        for key, field in fields.items():
            kind = type_text(field).replace("|", "\\|")
            if field.struct:
                kind = kind.replace(f"{{ {field.struct} keys }}",
                                    f"{{ [{field.struct}](#{field.struct.lower()}) }}")
            default = default_text(field)
            shown = f"`{default}`" if default else ""
            out.append(f"| `{key}` | {kind} | {shown} | {field.doc} "
                       f"| `{example(block, key, field)}` |")
        out.append("")
    return "\n".join(out)
