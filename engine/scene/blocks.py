"""Scene blocks a feature declares for itself, a content folder's own systems included.

A block is declared next to the component it builds: a plain dataclass whose fields
are the block's keys (``water_level`` is the key ``WaterLevel``), typed, with defaults,
meanings, units and ranges given by :func:`key`::

    @scene_block("Buoyancy", doc="floats in a pool of water")
    @dataclass
    class Buoyancy:
        density: float = key(1000.0, "kg/m³, the liquid's density", low=0.0)
        level: float = key(0.0, "m, the surface's height (z)")

From then on ``Object { ... Buoyancy { Density 800 } }`` builds that component on the
object; ``colosseum check`` tells a wrong key or value at its line, with a did-you-mean;
``colosseum keys Buoyancy`` documents it; ``--save-state`` writes the component's values
back. A content folder declares its blocks in ``systems/*.py``, which is imported before
its scene is read. ``inside=("Scene",)`` makes a top-level block (``ID`` names its
entity) instead.

The engine's own blocks are declared the same way, as data beside their component
(:class:`components.blocks.BlockDeclaration`: typed keys with units, ranges and examples,
a *build* function from the checked values to components, a *save* function back), and
registered here when the components are imported; they may also stand inside another
block. Either kind is one :class:`BlockType`, which the schema check, the factory, the
key reference (``colosseum keys``, docs/KEYS.md) and ``--save-state`` go through.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple, TypeVar, get_type_hints

import components  # noqa: F401  (every component module declares its block on import)
import engine.scene.schema as sc
from components.blocks import (
    DECLARED,
    BlockDeclaration,
    Build,
    Finish,
    KeyDeclaration,
    Save,
    on_declare,
    on_declare_key,
)

T = TypeVar("T")
#: Where a content folder's block may stand: inside an ``Object``, or at the top of a
#: scene (the engine's own may also stand inside another block).
PLACES = ("Object", "Scene")
#: Python types of a component's fields -> the scene's types.
_TYPES: dict[Any, str] = {float: sc.FLOAT_T, int: sc.INT_T, bool: sc.BOOL_T,
                          str: sc.STRING_T}
_NAME = re.compile(r"^[A-Z][A-Za-z0-9]*$")


class BlockError(ValueError):
    """A block declared wrongly (by its author: a programming error, told at import)."""


@dataclass(frozen=True, slots=True)
class KeyInfo:
    """What :func:`key` adds to a dataclass field: meaning, and a range where one holds."""

    doc: str
    low: float | None = None
    high: float | None = None


class BlockKey(NamedTuple):
    """A block key's dataclass field, its meaning and range, and its Python type."""

    field: str
    info: KeyInfo
    hint: Any


@dataclass(frozen=True, slots=True)
class BlockType:
    """A registered block: its schema name, where it stands, the component it builds.

    A content folder's block builds its one dataclass field by field; an engine block
    (declared with :class:`components.blocks.BlockDeclaration`) has its own ``hook``
    (values, context -> components) and ``saver`` (component -> keys), and ``component``
    is the type its saver writes back (None: nothing is written back)."""

    name: str
    component: type | None
    inside: tuple[str, ...]
    doc: str
    #: scene key -> its field
    keys: Mapping[str, BlockKey]
    hook: Build | None = None
    saver: Save | None = None
    #: The module that declared it (a content folder's are left out of the engine's docs).
    module: str = ""
    #: The ID of a top-level one written without one ("": its name and place, sound0).
    unnamed: str = ""
    #: Whether a top-level one is an entity (False: its build hands its work to the
    #: context, as a Joint does).
    entity: bool = True
    #: The key it is written as ("": its name; ``Device`` for ``InputDevice``).
    key: str = ""
    #: Run once the scene is built, with every part its blocks made (components.blocks).
    finish: Finish | None = None
    #: A top-level one the scene holds once: only the last written is built.
    once: bool = False
    #: Built before the scene's objects (see components.blocks.BlockDeclaration).
    first: bool = False
    #: A scene's one setting (World): built from its defaults where it is not written.
    setting: bool = False

    @property
    def written_as(self) -> str:
        """The key an author writes it as, where it stands."""
        return self.key or self.name

    def build(self, values: Mapping[str, Any]) -> Any:
        """The component from checked values (scene keys)."""
        assert self.component is not None
        return self.component(**{key.field: _python(values[k], key.hint)
                                 for k, key in self.keys.items() if k in values})

    def save(self, component: Any) -> dict[str, Any]:
        """The component's values as scene keys (what a saved state writes)."""
        if self.saver is not None:
            return self.saver(component)
        return {k: getattr(component, key.field) for k, key in self.keys.items()}

    def problems(self, values: Mapping[str, Any]) -> list[tuple[str, str]]:
        """(key, message) for every value outside its key's range."""
        out = []
        for k, (_, info, _) in self.keys.items():
            value = values.get(k)
            if not isinstance(value, int | float) or isinstance(value, bool):
                continue
            if info.low is not None and value < info.low:
                out.append((k, f"{k} must be at least {info.low:g}, got {value:g}"))
            elif info.high is not None and value > info.high:
                out.append((k, f"{k} must be at most {info.high:g}, got {value:g}"))
        return out


#: Every registered block, by name.
BLOCKS: dict[str, BlockType] = {}
#: Called with a block's name when it is registered (caches of the schema refresh).
_LISTENERS: list[Callable[[str], None]] = []


def key(default: Any, doc: str, low: float | None = None, high: float | None = None) -> Any:
    """A block key as a dataclass field: its default, meaning (with its unit first, as
    ``"kg/m³, the liquid's density"``) and range."""
    if isinstance(default, list):
        default = tuple(default)
    return dataclasses.field(default=default, metadata={"colosseum": KeyInfo(doc, low, high)})


def key_name(field: str) -> str:
    """A field's scene key: ``water_level`` -> ``WaterLevel``."""
    return "".join(part[:1].upper() + part[1:] for part in field.split("_"))


def scene_block(name: str, inside: tuple[str, ...] = ("Object",), doc: str = ""
                ) -> Callable[[type[T]], type[T]]:
    """Declare the dataclass below as block ``name`` (see the module's docstring)."""
    def declare(component: type[T]) -> type[T]:
        register(name, component, inside, doc or (component.__doc__ or "").strip())
        return component
    return declare


def register(name: str, component: type, inside: tuple[str, ...] = ("Object",),
             doc: str = "") -> BlockType:
    """Register ``component`` (a dataclass) as block ``name``; again with the same
    component (a module imported anew) replaces it, a name taken otherwise is refused."""
    if not _NAME.match(name):
        raise BlockError(f"block {name!r}: a block's name is a word in CamelCase")
    if not dataclasses.is_dataclass(component):
        raise BlockError(f"block {name!r}: {component!r} is not a dataclass")
    if not inside or any(p not in PLACES for p in inside):
        raise BlockError(f"block {name!r}: inside must name some of {', '.join(PLACES)}")
    known = BLOCKS.get(name)
    if (known is None and name in sc.SCHEMAS) or (known is not None and (
            known.component is None or known.hook is not None
            or known.component.__qualname__ != component.__qualname__)):
        raise BlockError(f"block {name!r} exists already; choose another name")
    fields, keys = _schema(name, component)
    block = BlockType(name, component, tuple(inside), doc or name, keys,
                      module=component.__module__)
    _enter(block, fields, {place: block.doc for place in inside}, repeat=False)
    return block


def _enter(block: BlockType, fields: dict[str, sc.Field], docs: Mapping[str, str],
           repeat: bool) -> None:
    """Make ``block`` known: its schema, a key in each place it stands (repeatable at the
    top level unless ``once``), the listeners."""
    BLOCKS[block.name] = block
    sc.SCHEMAS[block.name] = fields
    for place in block.inside:
        sc.SCHEMAS[place][block.written_as] = sc.Field(
            sc.STRUCT_T, None, docs[place], struct=block.name,
            repeat=repeat or (place == "Scene" and not block.once))
    for listener in _LISTENERS:
        for changed in (block.name, *block.inside):
            listener(changed)


def register_declared(declared: BlockDeclaration) -> BlockType:
    """Register an engine block declared beside its component (components.blocks)."""
    name = declared.name
    if not _NAME.match(name):
        raise BlockError(f"block {name!r}: a block's name is a word in CamelCase")
    places = [p for p in declared.inside if p not in sc.SCHEMAS]
    if not declared.inside or places:
        raise BlockError(f"block {name!r}: it cannot stand inside {places or 'nothing'}: "
                         "a place is Scene, Object or a block known already")
    known = BLOCKS.get(name)
    if (known is None and name in sc.SCHEMAS) or (
            known is not None and known.module != declared.build.__module__):
        raise BlockError(f"block {name!r} exists already; choose another name")
    written = declared.written_as
    taken = [p for p in declared.inside
             if written in sc.SCHEMAS[p] and sc.SCHEMAS[p][written].struct != name]
    if taken:
        raise BlockError(f"block {name!r}: {taken[0]} has a key {written!r} "
                         "already; choose another key")
    fields: dict[str, sc.Field] = {}
    keys: dict[str, BlockKey] = {}
    for k in declared.keys:
        if k.kind not in _KINDS:
            raise BlockError(f"block {name!r}: key {k.name!r} has no type {k.kind!r}")
        fields[k.name] = sc.Field(_KINDS[k.kind], k.default, k.meaning, k.repeat, k.required,
                                  k.allowed, k.ref, k.struct, k.lengths)
        keys[k.name] = BlockKey(k.name, KeyInfo(k.meaning, k.low, k.high), None)
        if k.example is not None:
            EXAMPLES[(name, k.name)] = k.example
    if "Scene" in declared.inside and declared.named and "ID" not in fields:  # its name
        fields["ID"] = sc.Field(sc.STRING_T, "", f"name of this {name}")
    doc = declared.doc
    docs = {p: doc if isinstance(doc, str) else doc[p] for p in declared.inside}
    block = BlockType(name, declared.saves, tuple(declared.inside), docs[declared.inside[0]],
                      keys, declared.build, declared.save, declared.build.__module__,
                      declared.unnamed, declared.entity, declared.key, declared.finish,
                      declared.once or declared.setting, declared.first, declared.setting)
    _enter(block, fields, docs, declared.repeat)
    return block


#: (place, key) -> a key a feature declared on a block it does not own (Script, User).
KEYS: dict[tuple[str, str], KeyDeclaration] = {}


def register_key(declared: KeyDeclaration) -> None:
    """Register a key declared on another block (components.blocks.KeyDeclaration)."""
    k = declared.key
    for place in declared.inside:
        known = KEYS.get((place, k.name))
        if place not in sc.SCHEMAS or (known is None and k.name in sc.SCHEMAS[place]) or (
                known is not None and known.build.__module__ != declared.build.__module__):
            raise BlockError(f"key {k.name!r}: {place} has it already, or is no block")
        if k.kind not in _KINDS:
            raise BlockError(f"key {k.name!r} has no type {k.kind!r}")
        sc.SCHEMAS[place][k.name] = sc.Field(_KINDS[k.kind], k.default, k.meaning, k.repeat,
                                             k.required, k.allowed, k.ref, k.struct, k.lengths)
        KEYS[(place, k.name)] = declared
        if k.example is not None:
            EXAMPLES[(place, k.name)] = k.example
        for listener in _LISTENERS:
            listener(place)


def unregister_key(place: str, name: str) -> None:
    """Take key ``name`` off block ``place`` again (a test's own key)."""
    from components.blocks import DECLARED_KEYS

    if KEYS.pop((place, name), None) is not None:
        DECLARED_KEYS.pop((place, name), None)
        sc.SCHEMAS[place].pop(name, None)
        for listener in _LISTENERS:
            listener(place)


def keys_of(place: str) -> list[tuple[str, KeyDeclaration]]:
    """The keys features declared on block ``place``, in the order they were declared."""
    return [(name, declared) for (at, name), declared in KEYS.items() if at == place]


#: A declaration's key types -> the schema's (the same names).
_KINDS = {t: t for t in (sc.INT_T, sc.FLOAT_T, sc.BOOL_T, sc.STRING_T, sc.ASSET_T, sc.VEC3_T,
                         sc.VECTOR_T, sc.STRINGVECTOR_T, sc.STRUCT_T, sc.ENUM_T, sc.REF_T,
                         sc.NUMBER_OR_VECTOR_T, sc.ANY_T)}
#: (block, key) -> the example value text a declaration gives (colosseum keys shows it).
EXAMPLES: dict[tuple[str, str], str] = {}


def _schema(name: str, component: type) -> tuple[dict[str, sc.Field], dict[str, BlockKey]]:
    hints = get_type_hints(component)
    fields: dict[str, sc.Field] = {}
    keys: dict[str, BlockKey] = {}
    for f in dataclasses.fields(component):
        info = f.metadata.get("colosseum") or KeyInfo("")
        kind = _scene_type(name, f.name, hints.get(f.name), f.default)
        default = None if f.default is dataclasses.MISSING else f.default
        if isinstance(default, bool):  # the scene writes flags as 0 and 1
            default = int(default)
        scene_key = key_name(f.name)
        fields[scene_key] = sc.Field(kind, default, info.doc, lengths=(
            (len(default),) if kind == sc.VECTOR_T and default is not None else ()))
        keys[scene_key] = BlockKey(f.name, info, hints.get(f.name))
    if "ID" not in fields:
        fields["ID"] = sc.Field(sc.STRING_T, "", f"name of this {name}")
    return fields, keys


def _scene_type(block: str, field: str, hint: Any, default: Any) -> str:
    if hint in _TYPES:
        return _TYPES[hint]
    if isinstance(default, tuple) and all(isinstance(x, int | float) for x in default):
        return sc.VEC3_T if len(default) == 3 else sc.VECTOR_T
    raise BlockError(f"block {block!r}: field {field!r} must be a float, int, bool, str or "
                     "a tuple of numbers with a default")


def _python(value: Any, hint: Any) -> Any:
    """A checked scene value as a field's Python value (its type ``hint``; vectors as
    tuples of floats)."""
    if isinstance(value, list | tuple):
        return tuple(float(x) for x in value)
    if hint is float and isinstance(value, int) and not isinstance(value, bool):
        return float(value)
    if hint is bool:
        return bool(value)
    return value


def unregister(name: str) -> None:
    """Take block ``name`` out again (a test's own block)."""
    block = BLOCKS.pop(name, None)
    DECLARED.pop(name, None)
    if block is None:
        return
    sc.SCHEMAS.pop(name, None)
    for place in block.inside:
        if place in sc.SCHEMAS:
            sc.SCHEMAS[place].pop(block.written_as, None)
            for listener in _LISTENERS:
                listener(place)


def from_content(name: str) -> bool:
    """Whether block ``name`` was declared by a content folder's systems (not the
    engine's own, so the engine's reference pages leave it out)."""
    from engine.content import CONTENT_MODULES

    block = BLOCKS.get(name)
    return block is not None and block.module.startswith(CONTENT_MODULES)


def on_register(listener: Callable[[str], None]) -> None:
    """Call ``listener(name)`` for each schema entry a registration adds or changes."""
    _LISTENERS.append(listener)


def of_component(component: Any) -> BlockType | None:
    """The block that builds components of this one's type (None: no such block)."""
    for block in BLOCKS.values():
        if type(component) is block.component:
            return block
    return None


def builtin(block: BlockType) -> bool:
    """Whether ``block`` is one of the engine's own (declared beside its component)."""
    return block.hook is not None


#: The engine's modules that declare blocks outside components, in the order their blocks
#: are registered after the components' own (the schema, ``colosseum keys`` and KEYS.md list
#: them so, whichever of them a program happened to import first).
ENGINE_BLOCKS = ("engine.physics.backend", "engine.measures", "engine.scene.anomalies",
                 "engine.scene.postpass", "engine.scene.world", "engine.scene.shaders",
                 "engine.scene.inputs", "engine.experiments.scene")


def _rank(declared: BlockDeclaration) -> int:
    """Where a declaration made before this module was imported is registered."""
    module = declared.build.__module__
    if module.startswith("components."):
        return 0
    return ENGINE_BLOCKS.index(module) + 1 if module in ENGINE_BLOCKS else len(ENGINE_BLOCKS) + 1


def _register_declared_so_far() -> None:
    """Register every declaration made so far, in :func:`_rank`'s order, then each one
    made from now on (a content folder's) as it is made."""
    ordered = sorted(DECLARED.values(), key=_rank)  # stable: a module's own order is kept
    DECLARED.clear()
    DECLARED.update((d.name, d) for d in ordered)
    on_declare(register_declared)


import engine.physics.backend  # noqa: E402, F401, I001  (the engine's blocks declared
import engine.measures  # noqa: E402, F401, I001  outside components: ENGINE_BLOCKS)
import engine.scene.anomalies  # noqa: E402, F401, I001
import engine.scene.postpass  # noqa: E402, F401, I001
import engine.scene.inputs  # noqa: E402, F401, I001
import engine.experiments.scene  # noqa: E402, F401, I001
import engine.scene.world  # noqa: E402, F401, I001
import engine.scene.shaders  # noqa: E402, F401, I001
_register_declared_so_far()
on_declare_key(register_key)
