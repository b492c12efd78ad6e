"""Scene keys typed into a model's nodes: the paper's comment-field workflow (section 4.4).

In Blender an object's custom properties are written to its glTF node as ``extras``; in
Collada a node's ``<extra>``. Either way the author types our scene keys:

* one property per key, ``Mass = 2``, ``Material = "wood"``, ``Sound = "knock.wav"``,
  ``Script = "door.lua"`` (a string for a key that takes a number or a block is scene
  text: ``Position = "[0 0 2]"``, ``PhysicalAttributes = "{ Mass 2 }"``);
* or the whole comment field in one property named ``colosseum``: ``Mass 2
  Material "wood"``.

The text is read by the scene parser, so a mistake is told like any other, at its
line and column, in a file named after the model and the node: ``room.glb node 'Door'
extras:1:1: error: unknown key 'Mas' ... (did you mean 'Mass'?)``; that node's extras
are then left out and the rest imported. Each key goes where the schema keeps it:
``PhysicalAttributes`` (Mass, Material, Geometry, ...), ``VisualAttributes`` (Color,
Texture, ...), or the Object itself (Sound, Script, Position, ...). A property whose
name is no scene key is told and left out.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from typing import Any

import engine.scene.blocks  # noqa: F401  (every block in the schema, before it is read below)
from engine.interchange.model import ImportedScene, ObjectDecl, Problems
from engine.scene import schema as sc
from engine.scene.db import INCLUDE, STRING, STRUCTURE, Block, Entry, Value
from engine.scene.diagnostics import ERROR, Diagnostic, SceneError, suggest
from engine.scene.parser import Limits, parse_text
from engine.scene.writer import quote

#: The property holding a whole comment field of scene text.
TEXT_PROPERTY = "colosseum"
#: Extras are a few lines; a property past this is refused, not parsed.
EXTRAS_LIMITS = Limits(max_bytes=256 * 1024, max_tokens=100_000, max_nesting=16, max_files=1)

_PHYSICAL = frozenset(sc.SCHEMAS["Physical"])
_VISUAL = frozenset(sc.SCHEMAS["Visual"]) - {"Geometry"}  # a Geometry is physical
_OBJECT = frozenset(sc.SCHEMAS["Object"]) - {"ID", "VisualAttributes", "PhysicalAttributes"}
_SCENE = frozenset(sc.SCHEMAS["Scene"])
_TEXT_TYPES = (sc.STRING_T, sc.ASSET_T, sc.ENUM_T, sc.REF_T)


@dataclass(slots=True)
class Extras:
    """A node's (or the file's) extras as scene entries, by the block they belong in
    (``Object``, ``Physical``, ``Visual``, or ``Scene`` for the file's own)."""

    entries: dict[str, list[Entry]] = field(default_factory=dict)
    #: The scene text read, by the name its diagnostics carry (for their source lines).
    sources: dict[str, str] = field(default_factory=dict)
    problems: list[Diagnostic] = field(default_factory=list)
    #: What the properties say that is no scene key (told once, then left out).
    ignored: list[str] = field(default_factory=list)

    @property
    def physical(self) -> bool:
        """Whether the author made the node a body (a physical key in its extras)."""
        return bool(self.entries.get("Physical"))


def read_extras(extras: Any, label: str, scene_level: bool = False) -> Extras:
    """The scene entries in ``extras`` (a JSON value), parsed as scene text named
    ``label`` (``room.glb node 'Door' extras``); ``scene_level`` for the file's own
    extras, whose keys are top-level blocks (Material, World, ...)."""
    out = Extras()
    if not isinstance(extras, dict) or not extras:
        return out
    lines = []
    for name, value in extras.items():
        if name == TEXT_PROPERTY and isinstance(value, str):
            lines.append(value)
            continue
        known = _SCENE if scene_level else _PHYSICAL | _VISUAL | _OBJECT | {"Geometry"}
        if name not in known:
            hint = suggest(name, known) if name[:1].isupper() else ""
            out.ignored.append(f"'{name}'{hint}")
            continue
        try:
            lines.append(f"{name} {_text(name, value, scene_level)}")
        except ValueError as exc:
            out.ignored.append(f"'{name}' ({exc})")
    if not lines:
        return out
    text = "\n".join(lines) + "\n"
    out.sources[label] = text
    try:
        db = parse_text(text, label, limits=EXTRAS_LIMITS)
    except SceneError as exc:
        out.problems.extend(exc.diagnostics)
        return out
    out.problems.extend(db.warnings)
    known = _SCENE if scene_level else _PHYSICAL | _VISUAL | _OBJECT | {
        "Geometry", "PhysicalAttributes", "VisualAttributes"}
    for e in db.root.entries:
        if e.key == INCLUDE:
            out.ignored.append("'Include' (extras cannot include files)")
        elif e.key not in known and not e.key[:1].islower():
            out.problems.append(Diagnostic(e.loc.path, e.loc.line, e.loc.col, ERROR,
                                           f"unknown key '{e.key}'{suggest(e.key, known)}; "
                                           f"left out"))
        elif e.key[:1].islower():
            continue  # the author's variable, used by the lines after it
        elif scene_level:
            out.entries.setdefault("Scene", []).append(e)
        elif e.key in ("PhysicalAttributes", "VisualAttributes") and e.value.kind == STRUCTURE:
            where = "Physical" if e.key == "PhysicalAttributes" else "Visual"
            out.entries.setdefault(where, []).extend(e.value.data.entries)
        else:
            where = ("Physical" if e.key in _PHYSICAL else "Visual" if e.key in _VISUAL
                     else "Object")
            out.entries.setdefault(where, []).append(_sound_block(e))
    return out


def attach(extras: Extras, obj: ObjectDecl | None, node: str | None, scene: ImportedScene,
           problems: Problems) -> None:
    """Put a node's extras into the object it belongs to, their text into the scene's
    sources (for the diagnostics' source lines); told if they cannot be read or are no
    scene keys."""
    scene.sources.update(extras.sources)
    problems.items.extend(extras.problems)
    if extras.problems and not extras.entries:
        problems.error(node, "its extras are left out (see the errors above)")
    if extras.ignored:
        problems.warn(node, f"extras {', '.join(extras.ignored)} are no scene keys; left out")
    if obj is not None:
        for where, entries in extras.entries.items():
            obj.extras.setdefault(where, []).extend(entries)


def _field(name: str) -> sc.Field | None:
    for schema in ("Physical", "Visual", "Object", "Scene"):
        found = sc.SCHEMAS[schema].get(name)
        if found is not None:
            return found
    return None


def _text(name: str, value: Any, scene_level: bool) -> str:
    """A property's value as scene text for key ``name``."""
    f = _field(name)
    if isinstance(value, str):
        takes_text = f is not None and (f.type in _TEXT_TYPES or f.type == sc.STRINGVECTOR_T
                                        or (name == "Sound" and not scene_level))
        if takes_text and not value.lstrip().startswith(("[", "{", '"')):
            return quote(value)
        return value
    return _json_text(value)


def _json_text(value: Any) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, int | float):
        if not math.isfinite(value):
            raise ValueError(f"{value} is not a finite number")
        return repr(value)
    if isinstance(value, str):
        return quote(value)
    if isinstance(value, list):
        return "[" + " ".join(_json_text(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + " ".join(f"{k} {_json_text(v)}" for k, v in value.items()) + " }"
    raise ValueError(f"a {type(value).__name__} ({json.dumps(value)[:40]}) is no scene value")


def _sound_block(e: Entry) -> Entry:
    """``Sound "knock.wav"`` (as typed in a comment field) is ``Sound { File "knock.wav" }``."""
    if e.key != "Sound" or e.value.kind != STRING:
        return e
    file_entry = Entry("File", e.value, e.value.loc)
    return Entry("Sound", Value(STRUCTURE, Block([file_entry], e.loc), e.loc), e.loc,
                 e.comments, e.trailing)
