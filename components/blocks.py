"""How a feature declares its scene block beside its component, as plain data.

A :class:`BlockDeclaration` names the block, where it may stand (``"Scene"``: the top
level, an entity of its own; ``"Object"``: on an object; or inside another block), its
keys (:class:`Key`: type, default, unit, range, example) and two plain functions: *build*
(the checked values -> the components) and *save* (a live component -> the values a
saved state writes back); a block whose parts only make sense together (several
``Input`` blocks are one input setup) also gives a *finish* step, run once the whole
scene is built, with every part its blocks made. The scene format
(:mod:`engine.scene.blocks`) turns every declaration into its schema, its checks,
``colosseum keys`` and KEYS.md, building and ``--save-state``; the declaration lives in
the component's own module, which is why this vocabulary sits in the components layer:
declaring a block imports nothing of the engine.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, Protocol

#: The key types a declaration may use (the names engine.scene.schema gives them).
KINDS = ("int", "float", "bool", "string", "asset", "vec3", "vector", "stringvector",
         "struct", "enum", "ref", "number_or_vector", "any")


@dataclass(frozen=True, slots=True)
class Key:
    """One key of a block: its scene name, type, default and meaning.

    ``unit`` is written before the meaning (``"m/s, the rim's top speed"``; alone where
    the unit says it all); ``low`` and
    ``high`` bound a number (told at its line, as ``check`` tells every mistake);
    ``example`` is the value text ``colosseum keys`` shows where the default says too
    little. ``lengths``, ``allowed``, ``ref`` and ``struct`` are the schema's: how many
    numbers a vector holds, an enum's choices, the kind a reference names, the block a
    structure opens. A ``repeat`` key (not a structure) reaches *build* as the tuple of
    every value written, in order.
    """

    name: str
    kind: str
    default: Any = None
    doc: str = ""
    unit: str = ""
    example: str | None = None
    low: float | None = None
    high: float | None = None
    required: bool = False
    repeat: bool = False
    lengths: tuple[int, ...] = ()
    allowed: tuple[str, ...] = ()
    ref: str | None = None
    struct: str | None = None

    @property
    def meaning(self) -> str:
        """The documented meaning, its unit first."""
        if not self.unit:
            return self.doc
        return f"{self.unit}, {self.doc}" if self.doc else self.unit


@dataclass(frozen=True, slots=True)
class Body:
    """What a block may know of an object it names by ID (a joint's bodies): its pose
    (position, quaternion) as the scene places it, whether it has a body and whether
    that body is static, and whether this scene (or snippet) makes it (else it is one of
    the running world's)."""

    pose: tuple[tuple[float, ...], tuple[float, ...]]
    physical: bool
    static: bool
    here: bool


class BuildContext(Protocol):
    """What a block's *build* function may ask of the scene being built."""

    #: The ID of the object the block stands in (or, at the top level, the block's own).
    owner: str
    #: Where the block stands: ``"Scene"``, ``"Object"`` or the block it is inside.
    place: str
    #: Whether the object it stands in has a body (PhysicalAttributes, or neither block).
    has_body: bool

    def error(self, key: str | None, message: str, item: int | None = None) -> None:
        """An error at ``key``'s line (None: the block's own line; ``item``: at that value
        of a vector, or of a list written as ``key``); the scene fails."""

    def given(self, key: str) -> bool:
        """Whether the author wrote ``key`` (not only its default)."""

    def warning(self, key: str | None, message: str) -> None:
        """A warning at ``key``'s line (None: the block's own line)."""

    def beside(self, key: str) -> tuple[Mapping[str, Any], BuildContext] | None:
        """The block ``key`` written beside this one in the same object (its values and a
        context telling at its lines); None where there is none."""

    def component(self, kind: type) -> Any:
        """The object's component of type ``kind`` made so far (its body: Physical), or
        None; a block may adjust it."""

    def check_mass(self, key: str) -> None:
        """Tell a mass or density at ``key`` that is not positive, or past what any body
        may have."""

    def input_name(self, key: str, kind: str, who: str) -> None:
        """``key`` names an input ``kind`` ("tracker" or "glove"): once the scene's Input
        is read, a name it does not declare is told (an error where it declares some, a
        warning where the name must come from a device); ``who`` starts the message."""

    def model_file(self, key: str) -> str | None:
        """``key``'s model file if it can be read; else None, told as a problem (the object
        keeps its own look)."""

    def inner(self, key: str) -> list[tuple[Mapping[str, Any], BuildContext]]:
        """The blocks written inside this one as ``key``: each one's values (defaults
        filled in) and a context telling at its lines."""

    def link(self, component: Any, field: str, target: str) -> None:
        """Set ``component.field`` to the entity of object ``target`` once the scene's
        entities exist (a reference by ID; nothing is set if that object is left out)."""

    def made(self, kind: type) -> bool:
        """Whether an entity made before this block has a component of type ``kind``."""

    def suggest(self, name: str, choices: Any) -> str:
        """`` (did you mean 'X'?)`` for the closest of ``choices``; empty if none is."""

    def problem(self, key: str | None, message: str, warning: bool = False,
                item: int | None = None) -> None:
        """An error (or ``warning``) at ``key``'s line (at its ``item``-th value, where
        given) that leaves out only what it says: listed with the scene's problems, the
        run goes on (as for an asset that failed)."""

    def within_world(self, key: str, points: bool = False) -> None:
        """Tell a point at ``key`` (its first three numbers: x y z; with ``points``, every
        three numbers) outside the world."""

    def orientation(self) -> tuple[float, ...]:
        """The block's exact ``Quaternion`` where one is written, else its ``Orientation``
        (Euler degrees), as a unit quaternion."""

    def quaternion(self, key: str) -> tuple[float, ...]:
        """``key`` as a unit quaternion; all zeros is told (and the identity taken)."""

    def skinned_model(self, key: str, outcome: str) -> Any | None:
        """``key``'s skinned model (engine.assets.skinned) if it can be read; else None,
        and ``outcome`` (what is left out) told as a problem."""

    def saved(self, block: str, owner: str) -> tuple[Mapping[str, Any], BuildContext] | None:
        """The top-level ``block`` (a saved state's, such as AvatarState) whose Owner is
        ``owner``, taken: its values and a context telling at its lines; None if none."""

    def claim(self, kind: str, name: str) -> str | None:
        """Claim the scene-wide ``name`` of ``kind`` (an anomaly's ID) for this block:
        where it was claimed first (``path:line:col``), or None if this is the first."""

    def scene(self, setting: str) -> Any:
        """The scene-wide ``setting`` (a SceneSpec field, such as the list ``anomalies``)
        a block that makes no entity fills."""

    def settle(self, setting: str, value: Any) -> None:
        """Set the scene-wide ``setting`` (a SceneSpec field, such as ``input``) to
        ``value``: a finish step's result."""

    def gathered(self, name: str) -> list[Any]:
        """The scene-wide list ``name`` that blocks add to while the scene is built and a
        finish step reads (``input_name`` adds to ``"input names"``: (who, kind, name, the
        context and key telling at its line))."""

    def variables(self) -> set[str]:
        """The names of the scene's own variables (lower-case keys at its top)."""

    def folder(self) -> str:
        """The content folder the scene's files are relative to."""

    def where(self, key: str | None) -> str:
        """``key``'s place (its block's where it is not written) as ``path:line``."""

    def saved_script(self, owner: str) -> Any:
        """The saved state (SavedScript) ``owner``'s script resumes from, taken; or None."""

    def body(self, name: str) -> Body | None:
        """Object ``name`` as made so far (None: no such object; see :meth:`left_out`)."""

    def view_problem(self, forward: tuple[float, ...]) -> str | None:
        """What is wrong with a view along ``forward`` (None: nothing): engine.rotation's
        check, lent here because a component module cannot import it."""

    def left_out(self, name: str) -> bool:
        """Whether object ``name`` was left out (an asset it needs failed, told)."""

    def join(self, joint: Any, bodies: tuple[str, str | None], skipped: bool = False) -> None:
        """Make ``joint`` (a Joint) between the objects ``bodies`` names, once they exist;
        ``skipped`` keeps its place (a body was left out)."""

    def sound_file(self, key: str, outcome: str) -> str | None:
        """``key``'s sound file if it can be played; else None, and ``outcome`` (what is
        left out) told as a problem at its line."""


#: values (every key, defaults filled in), context -> the components; None leaves the
#: block out (a top-level one keeps its place as a skipped entity).
Build = Callable[[Mapping[str, Any], BuildContext], "list[Any] | None"]
#: a live component -> the keys a saved state sets on its block (values as Python data).
Save = Callable[[Any], dict[str, Any]]
#: every part the blocks of one kind made (in file order; empty where none is written), a
#: scene-wide context -> nothing (it settles what they make together: ctx.settle).
Finish = Callable[[list[Any], BuildContext], None]


@dataclass(frozen=True, slots=True)
class BlockDeclaration:
    """A scene block a feature declares (see the module's docstring).

    ``doc`` is what the block is (its key's meaning where it stands; a mapping, place ->
    text, where it means something else in each place); ``repeat`` whether
    an object (or its parent block) may hold several (at the top level every block
    repeats, unless ``once``: a second is warned about and replaces the first; a
    ``setting`` is once too); ``saves`` the component type whose live values ``save``
    writes back.

    ``key`` is the key it is written as where it stands, where that differs from its name:
    a block's name is its schema's, one for the whole format (``InputDevice``), while
    inside ``Input`` it is written ``Device``. ``finish`` runs once the scene is built,
    written or not (see :data:`Finish`).
    """

    name: str
    keys: tuple[Key, ...]
    build: Build
    doc: str | Mapping[str, str] = ""
    inside: tuple[str, ...] = ("Object",)
    repeat: bool = False
    saves: type | None = None
    save: Save | None = None
    unnamed: str = ""
    #: A top-level block that makes no entity of its own: its build hands what it makes
    #: to the context (a joint, a scene-wide setting), or returns the parts its finish
    #: step puts together.
    entity: bool = True
    key: str = ""
    #: Written at most once at the top level (a Session log, an Experiment).
    once: bool = False
    #: A top-level block is given an ``ID`` key (its entity's name) unless it has one;
    #: False: it has none (a scene-wide setting nothing refers to, such as ``Input``).
    named: bool = True
    finish: Finish | None = None
    #: Built before the scene's objects, which name what it makes (a material) or are
    #: checked against it (the world's extent); the rest are built after them.
    first: bool = False
    #: A scene's setting (World): written at most once, and built from its defaults, at
    #: the top of the file, where the scene does not write it.
    setting: bool = False

    @property
    def written_as(self) -> str:
        """The key it is written as (its ``key``, else its name)."""
        return self.key or self.name


#: Every declaration made so far, by block name (engine.scene.blocks registers each).
DECLARED: dict[str, BlockDeclaration] = {}
_LISTENERS: list[Callable[[BlockDeclaration], None]] = []


def declare(block: BlockDeclaration) -> BlockDeclaration:
    """Declare ``block`` (a component module does so when it is imported)."""
    for listener in _LISTENERS:  # one refused (a name taken) is not declared
        listener(block)
    DECLARED[block.name] = block
    return block


def on_declare(listener: Callable[[BlockDeclaration], None]) -> None:
    """Call ``listener`` with every declaration, those made already first."""
    _LISTENERS.append(listener)
    for block in list(DECLARED.values()):
        listener(block)


#: value (the key's, its default where not written), context -> the components.
KeyBuild = Callable[[Any, BuildContext], "list[Any]"]


@dataclass(frozen=True, slots=True)
class KeyDeclaration:
    """A key a feature adds to a block it does not own: ``Script`` on an ``Object`` (and at
    the top level, where each one is an entity of its own), ``Graspable``, ``User``.
    *build* gets the key's value (its default where not written) and the context of the
    block it stands in, and returns the components it makes there (often none)."""

    key: Key
    build: KeyBuild
    inside: tuple[str, ...] = ("Object",)


#: Every key declaration made so far, by (place, key).
DECLARED_KEYS: dict[tuple[str, str], KeyDeclaration] = {}
_KEY_LISTENERS: list[Callable[[KeyDeclaration], None]] = []


def declare_key(declared: KeyDeclaration) -> KeyDeclaration:
    """Declare a key (a component module does so when it is imported)."""
    for listener in _KEY_LISTENERS:
        listener(declared)
    for place in declared.inside:
        DECLARED_KEYS[(place, declared.key.name)] = declared
    return declared


def on_declare_key(listener: Callable[[KeyDeclaration], None]) -> None:
    """Call ``listener`` with every key declaration, those made already first."""
    _KEY_LISTENERS.append(listener)
    for declared in list({id(d): d for d in DECLARED_KEYS.values()}.values()):
        listener(declared)

