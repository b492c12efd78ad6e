"""Validation: a parsed SceneDB against the schema, every problem in one pass.

Reports unknown keys (with "did you mean", including wrong case), type errors
that say what was expected, missing required keys, duplicate IDs, references to
IDs that do not exist (with suggestions) and asset files that are not there
(naming the path looked for, relative to the scene file's folder).
"""

from __future__ import annotations

from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path

import engine.scene.blocks as blocks
import engine.scene.schema as sc
from engine.assets.generated import is_generated
from engine.confine import Confinement
from engine.scene.db import (
    FLOAT,
    INCLUDE,
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
from engine.scene.diagnostics import Loc, Reporter, quoted, suggest
from engine.scene.hints import block_name, unknown_key_hint
from engine.scene.paths import NOT_FOUND, file_problem, shown

#: Size lengths each primitive accepts (see the schema module doc).
SIZE_LENGTHS = {"sphere": (1,), "box": (1, 3), "capsule": (2,), "cylinder": (2,)}
SIZE_FORMS = {"sphere": "[diameter]", "box": "[x y z] or [side]",
              "capsule": "[diameter length]", "cylinder": "[diameter length]"}


@dataclass
class _Ctx:
    report: Reporter
    ids: dict[str, dict[str, Loc]] = field(default_factory=lambda: {k: {} for k in sc.ID_KINDS})
    refs: list[tuple[str, Value]] = field(default_factory=list)
    #: IDs declared elsewhere, by kind (looked up, never copied: the running world's
    #: objects, for a snippet a script spawns, may be many)
    known: Mapping[str, Collection[str]] = field(default_factory=dict)
    #: Where an ID declared elsewhere is told as first declared (the file's start).
    elsewhere: Loc | None = None
    assets: list[Value] = field(default_factory=list)
    targets: list[Value] = field(default_factory=list)


def validate(db: SceneDB, content_dir: Path | None, report: Reporter,
             known: Mapping[str, Collection[str]] | None = None,
             allow: Iterable[Path] = ()) -> None:
    """Check ``db`` against the schema; problems go to ``report``.

    ``known`` names IDs declared elsewhere (the running scene, for a snippet a
    script spawns), by kind, so references to them resolve and declaring one again is a
    duplicate; it is only asked whether it holds a name (and listed for a "did you mean"
    when one is unknown), so a live view of a large world costs nothing per object.
    Asset files must lie in ``content_dir`` or one of ``allow`` (:mod:`engine.confine`).
    """
    ctx = _Ctx(report, known=known or {}, elsewhere=db.root.loc)
    _block(db.root, "Scene", ctx, db.root.loc, None)
    _resolve(ctx)
    if content_dir is not None:
        confine = Confinement.of(content_dir, allow)
        told: dict[str, str | None] = {}  # a file's problem, looked at once however often
        for v in ctx.assets:              # it is named (an imported model: every object)
            if is_generated(v.data):  # made by the asset service, not read
                continue
            if v.data not in told:
                told[v.data] = _asset_problem(content_dir, v.data, confine)
            message = told[v.data]
            if message is not None:
                report.error(v.loc, message)


def _asset_problem(content_dir: Path, name: str, confine: Confinement) -> str | None:
    """Why the file ``name`` (relative to ``content_dir``) cannot be used, or None."""
    target = content_dir / name
    problem = confine.problem(target)
    if problem is not None:  # refused before it is looked at
        return f'cannot use file "{quoted(name)}": {problem}'
    problem = file_problem(target)
    if problem == NOT_FOUND:
        return f'file not found: "{quoted(name)}" (looked for {shown(target)})'
    if problem is not None:
        return f'cannot use file "{quoted(name)}": {problem}'
    return None


def _block(block: Block, name: str, ctx: _Ctx, where: Loc, size: Value | None) -> None:
    checks = _CHECKS[name]
    seen: dict[str, Entry] = {}
    for e in block:
        key = e.key
        check = checks.get(key)
        if check is None:
            if key == INCLUDE:
                continue
            fields = sc.SCHEMAS[name]
            lower = key.lower()
            if key[0].islower() and not any(k.lower() == lower for k in fields):
                continue  # the author's variable
            hint = unknown_key_hint(key, name, e.value) if ctx.report.accepts(e.loc) else ""
            ctx.report.error(e.loc, f"unknown key '{quoted(key)}' in {block_name(name)}{hint}")
            continue
        f, kinds, lengths = check
        if key in seen and not f.repeat:
            ctx.report.warning(e.loc, f"'{key}' given again; this one replaces line "
                                      f"{seen[key].loc.line}")
        seen[key] = e
        v = e.value
        if f.type == _STRUCT_T and v.kind == STRUCTURE:  # the common cases, without a call
            _block(v.data, f.struct, ctx, e.loc, size)
            continue
        quick = v.kind in kinds and (not lengths or len(v.data) in lengths)
        if key == "Size" and name == "Object" and (quick or _type_ok(v, f, name)):
            size = v
        if not quick:
            _value(e, f, name, ctx, size)
    for k in _REQUIRED[name]:
        if k not in seen:
            ctx.report.error(where, f"{name} is missing required key '{k}'")
    if "ID" in seen and name in _ID_KINDS:
        idv = seen["ID"].value
        key = str(idv.data)
        first = ctx.ids[name].get(key)
        if first is None and key in ctx.known.get(name, ()):  # declared elsewhere: there
            first = ctx.elsewhere
        if first is not None:
            ctx.report.error(idv.loc, f"duplicate {name} ID '{quoted(key)}' (first declared at "
                                      f"{first.path}:{first.line}:{first.col})")
        else:
            ctx.ids[name][key] = idv.loc
    if name == "Geometry":
        _geometry(seen, ctx, where, size)


def _geometry(seen: dict[str, Entry], ctx: _Ctx, where: Loc, size: Value | None) -> None:
    prim = seen.get("Primitive")
    if prim is not None and "File" in seen:
        ctx.report.error(prim.loc, "Geometry has both Primitive and File; give one")
    if prim is None and "File" not in seen and "ParseMethod" not in seen:
        ctx.report.error(where, "Geometry needs a Primitive or a File")
    size = seen["Size"].value if "Size" in seen else size
    if prim is None or prim.value.kind != STRING or size is None or size.kind != VECTOR:
        return
    kind = prim.value.data
    if kind in SIZE_LENGTHS and len(size.data) not in SIZE_LENGTHS[kind]:
        ctx.report.error(size.loc, f"Size of a {kind} is {SIZE_FORMS[kind]}, got "
                                   f"{len(size.data)} number{'s' if len(size.data) != 1 else ''}")
    for item in size.data:
        if item.data <= 0:
            ctx.report.error(item.loc, f"Size must be positive, got {item.data}")


def _describe(v: Value) -> str:
    if v.kind == VECTOR:
        return f"VECTOR of {len(v.data)} number{'s' if len(v.data) != 1 else ''}"
    if v.kind == STRINGVECTOR:
        return f"STRINGVECTOR of {len(v.data)} string{'s' if len(v.data) != 1 else ''}"
    if v.kind == STRING:
        return f'STRING "{v.data}"' if len(v.data) < 30 else "STRING"
    if v.kind == STRUCTURE:
        return "STRUCTURE"
    return f"{v.kind} {v.data!r}"


def _counts(lengths: tuple[int, ...]) -> str:
    if not lengths:
        return "any number of"
    words = [str(n) for n in lengths]
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]


_EXPECTED = {
    sc.INT_T: "INT",
    sc.FLOAT_T: "a number (INT or FLOAT)",
    sc.BOOL_T: "0 or 1",
    sc.STRING_T: "STRING",
    sc.ASSET_T: "STRING (a file name)",
    sc.VEC3_T: "VECTOR of 3 numbers",
    sc.STRUCT_T: "STRUCTURE { ... }",
    sc.NUMBER_OR_VECTOR_T: "a number or a VECTOR",
}


def _expected(f: sc.Field) -> str:
    t = f.type
    if t == sc.VECTOR_T:
        return f"VECTOR of {_counts(f.lengths)} numbers"
    if t == sc.STRINGVECTOR_T:
        return f"STRINGVECTOR of {_counts(f.lengths)} strings"
    if t == sc.ENUM_T:
        return "STRING, one of " + ", ".join(f'"{a}"' for a in f.allowed)
    if t == sc.REF_T:
        return f"STRING naming a {f.ref}"
    return _EXPECTED.get(t, t)


#: Required keys of each schema, in schema order.
_REQUIRED = {name: [k for k, f in fields.items() if f.required]
             for name, fields in sc.SCHEMAS.items()}
_STRUCT_T = sc.STRUCT_T
_ALL_KINDS = frozenset((INT, FLOAT, STRING, VECTOR, STRINGVECTOR, STRUCTURE))


def _quick(owner: str, key: str, f: sc.Field) -> tuple[frozenset[str], tuple[int, ...]]:
    """Value kinds (and vector lengths, if limited) that pass ``f`` with nothing to record.

    Other values go through :func:`_value`, which checks and records them in full.
    """
    t = f.type
    if t == sc.FLOAT_T:
        return frozenset((INT, FLOAT)), ()
    if t == sc.INT_T:
        return frozenset((INT,)), ()
    if t == sc.STRING_T and not (owner == "Controller" and key == "Target"):
        return frozenset((STRING,)), ()
    if t == sc.VEC3_T:
        return frozenset((VECTOR,)), (3,)
    if t == sc.VECTOR_T:
        return frozenset((VECTOR,)), f.lengths
    if t == sc.ANY_T:
        return _ALL_KINDS, ()
    return frozenset(), ()


#: Per schema, key -> (field, kinds and lengths that pass without a call: see _quick).
_CHECKS = {name: {k: (f, *_quick(name, k, f)) for k, f in fields.items()}
           for name, fields in sc.SCHEMAS.items()}
_ID_KINDS = frozenset(sc.ID_KINDS)


def _refresh(name: str) -> None:
    """A block registered (engine.scene.blocks): its checks and the parent's anew."""
    fields = sc.SCHEMAS[name]
    _REQUIRED[name] = [k for k, f in fields.items() if f.required]
    _CHECKS[name] = {k: (f, *_quick(name, k, f)) for k, f in fields.items()}


blocks.on_register(_refresh)
#: Field types whose check is only the value's kind.
_KINDS = {sc.FLOAT_T: (INT, FLOAT), sc.STRUCT_T: (STRUCTURE,),
          sc.NUMBER_OR_VECTOR_T: (INT, FLOAT, VECTOR)}


def _type_ok(v: Value, f: sc.Field, owner: str) -> bool:
    t, k = f.type, v.kind
    kinds = _KINDS.get(t)
    if kinds is not None:
        return k in kinds
    if t == sc.ANY_T:
        return True
    if t == sc.INT_T:
        return k == INT or (k == FLOAT and float(v.data).is_integer())
    if t == sc.FLOAT_T:
        return k in (INT, FLOAT)
    if t == sc.BOOL_T:
        return k in (INT, FLOAT) and v.data in (0, 1)
    if t in (sc.STRING_T, sc.ASSET_T, sc.ENUM_T):
        return k == STRING or (owner == "Material" and f is sc.SCHEMAS[owner]["ID"] and k == INT)
    if t == sc.REF_T:
        return k == STRING or (f.ref == "Material" and k == INT)
    if t == sc.VEC3_T:
        return k == VECTOR and len(v.data) == 3
    if t == sc.VECTOR_T:
        return k == VECTOR and (not f.lengths or len(v.data) in f.lengths)
    if t == sc.STRINGVECTOR_T:
        return (k == STRINGVECTOR or (k == VECTOR and not v.data)) and (
            not f.lengths or len(v.data) in f.lengths)
    if t == sc.STRUCT_T:
        return k == STRUCTURE
    if t == sc.NUMBER_OR_VECTOR_T:
        return k in (INT, FLOAT, VECTOR)
    return False


def _value(e: Entry, f: sc.Field, owner: str, ctx: _Ctx, size: Value | None) -> None:
    v = e.value
    if not _type_ok(v, f, owner):
        ctx.report.error(v.loc, f"'{e.key}' expects {_expected(f)}, got {_describe(v)}")
        return
    if f.type == sc.STRUCT_T:
        _block(v.data, f.struct, ctx, e.loc, size)
    elif f.type == sc.ENUM_T and v.data not in f.allowed:
        ctx.report.error(v.loc, f"unknown {e.key} \"{quoted(v.data)}\""
                                f"{suggest(v.data, f.allowed)}; expected one of "
                                f"{', '.join(f.allowed)}")
    elif f.type == sc.REF_T:
        ctx.refs.append((f.ref, v))
    elif f.type == sc.STRINGVECTOR_T and f.ref:
        ctx.refs.extend((f.ref, item) for item in v.data)
    elif f.type == sc.ASSET_T:
        ctx.assets.append(v)
    elif owner == "Controller" and e.key == "Target":
        ctx.targets.append(v)


_TARGET_KINDS = {"motor": "Joint", "force": "Object", "kinematic": "Object"}


def _resolve(ctx: _Ctx) -> None:
    for kind, v in ctx.refs:
        name = str(v.data)
        if _declared(ctx, kind, name):
            continue
        if kind == "Material" and (v.kind == INT or name == "default"):
            if v.kind == INT:
                ctx.report.warning(v.loc, f"Material {quoted(name)} is not declared; default "
                                          "material properties are used")
            continue
        hint = suggest(name, _names(ctx, kind)) if ctx.report.accepts(v.loc) else ""
        ctx.report.error(v.loc, f"unknown {kind} '{quoted(name)}'{hint}")
    for v in ctx.targets:
        prefix, _, name = v.data.partition(":")
        kind = _TARGET_KINDS.get(prefix)
        if kind is None:
            ctx.report.error(v.loc, f"controller target \"{quoted(v.data)}\" must start with "
                                    "motor:, force: or kinematic:")
        elif not _declared(ctx, kind, name):
            hint = suggest(name, _names(ctx, kind)) if ctx.report.accepts(v.loc) else ""
            ctx.report.error(v.loc, f"unknown {kind} '{quoted(name)}' in controller target{hint}")


def _declared(ctx: _Ctx, kind: str, name: str) -> bool:
    return name in ctx.ids[kind] or name in ctx.known.get(kind, ())


def _names(ctx: _Ctx, kind: str) -> list[str]:
    """Every ID of ``kind`` (for a suggestion, when a reference is unknown)."""
    return [*ctx.ids[kind], *ctx.known.get(kind, ())]
