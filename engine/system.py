"""Systems, phases and plugins: how behaviour is attached to the engine.

A system declares the phase it runs in, the component types it reads and writes
(checked in debug mode: ``EngineConfig.debug``, on in the test suite) and, where
it matters, which systems of its phase it runs before or after. A plugin is any
object with a ``name`` and ``build(engine)`` that adds systems and resources;
content folders add their own from ``systems/*.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import IntEnum, StrEnum
from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

if TYPE_CHECKING:
    from engine.app import Engine


#: In ``reads``/``writes``: every component type (a system whose behaviour comes from
#: content, like Lua scripts, that may find, spawn and change objects of any kind).
ANY_COMPONENT: type = object


class PluginName(StrEnum):
    """Every plugin's name, the one list: what ``requestPlugin`` asks for, what a service
    names as its owner, what a plugin calls itself (``systems.PLUGINS`` maps each to its
    module; the paper's aliases are there too)."""

    PHYSICS = "physics"
    SCRIPTING = "scripting"
    CONTROLLERS = "controllers"
    RENDER = "render"
    SOUND = "sound"
    INPUT = "input"
    AVATARS = "avatars"
    TRIGGERS = "triggers"
    HANDS = "hands"
    MEASURES = "measures"
    WHEELCHAIR = "wheelchair"
    SESSION = "session"
    ANOMALIES = "anomalies"
    #: The headset display (OpenXR): assembled by --xr or a scene's Display { Kind "openxr" }.
    XR = "xr"
    #: Runs an experiment's trials: assembled by ``colosseum experiment run``.
    EXPERIMENT = "experiment"
    #: Assembled by ``colosseum serve`` and ``join``, not requested by content.
    NET_SERVER = "net-server"
    NET_NODE = "net-node"
    #: The first plugin of every default engine: it registers the others by name.
    REGISTRY = "registry"


class Phase(IntEnum):
    """Phases of one frame, in the order they run.

    INPUT drains devices; SCRIPT runs scripts; PRE_PHYSICS turns this frame's input into
    actuation (controllers, hand drives) so it reaches this frame's step; FIXED steps the
    dynamics; POST_PHYSICS reacts to contacts; RENDER draws.
    """

    INPUT = 0
    SCRIPT = 1
    PRE_PHYSICS = 2
    FIXED = 3
    POST_PHYSICS = 4
    RENDER = 5


class System:
    """Base class for systems. Override :meth:`run`; the rest is optional."""

    phase: ClassVar[Phase] = Phase.SCRIPT
    reads: ClassVar[tuple[type, ...]] = ()
    writes: ClassVar[tuple[type, ...]] = ()
    #: Names of systems of the same phase this one runs before / after.
    before: ClassVar[tuple[str, ...]] = ()
    after: ClassVar[tuple[str, ...]] = ()

    @property
    def name(self) -> str:
        return type(self).__name__

    def setup(self, engine: Engine) -> None:
        """Called once, on the main thread, before the first frame."""

    def run(self, engine: Engine, dt: float) -> None:
        raise NotImplementedError

    def shutdown(self, engine: Engine) -> None:
        """Called once when the engine closes, also after an error."""


class FunctionSystem(System):
    """A plain function ``f(engine, dt)`` registered as a system."""

    def __init__(self, fn: Callable[[Engine, float], None], phase: Phase,
                 reads: tuple[type, ...], writes: tuple[type, ...],
                 before: tuple[str, ...] = (), after: tuple[str, ...] = ()) -> None:
        self.fn = fn
        self.phase = phase  # type: ignore[misc]
        self.reads = reads  # type: ignore[misc]
        self.writes = writes  # type: ignore[misc]
        self.before = before  # type: ignore[misc]
        self.after = after  # type: ignore[misc]

    @property
    def name(self) -> str:
        return getattr(self.fn, "__qualname__", repr(self.fn))

    def run(self, engine: Engine, dt: float) -> None:
        self.fn(engine, dt)


def system(phase: Phase = Phase.SCRIPT, reads: tuple[type, ...] = (),
           writes: tuple[type, ...] = (), before: tuple[str, ...] = (),
           after: tuple[str, ...] = ()) -> Callable[[Callable[[Engine, float], None]],
                                                    FunctionSystem]:
    """Decorator: turn ``def f(engine, dt)`` into a system.

    ``before``/``after`` name systems of the same phase (class names, or a function's
    qualified name) this one must run before or after.

    >>> from components import Transform
    >>> @system(Phase.SCRIPT, reads=(Transform,))
    ... def report(engine, dt):
    ...     pass
    >>> report.phase.name, report.reads
    ('SCRIPT', (<class 'components.transform.Transform'>,))
    """

    def wrap(fn: Callable[[Engine, float], None]) -> FunctionSystem:
        return FunctionSystem(fn, phase, reads, writes, before, after)

    return wrap


def order_systems(systems: list[System]) -> list[System]:
    """``systems`` (one phase's, in the order added) reordered so every ``before``/``after``
    holds; otherwise the order added is kept. Names that match no system are ignored
    (the system they name may come from a plugin that is not loaded).

    >>> a, b = system()(lambda e, dt: None), system(before=("first",))(lambda e, dt: None)
    >>> def first(e, dt): pass
    >>> [s.name for s in order_systems([a, system()(first), b])][1:]
    ['<lambda>', 'first']
    """
    names = {s.name for s in systems}
    index = {id(s): i for i, s in enumerate(systems)}
    after: dict[int, set[int]] = {id(s): set() for s in systems}
    for s in systems:
        for other in systems:
            if other.name in s.after or s.name in other.before:
                after[id(s)].add(id(other))
    ordered: list[System] = []
    placed: set[int] = set()
    while len(ordered) < len(systems):
        ready = [s for s in systems if id(s) not in placed and after[id(s)] <= placed]
        if not ready:
            stuck = sorted(s.name for s in systems if id(s) not in placed)
            raise ValueError(f"systems {', '.join(stuck)} order each other in a cycle "
                             f"(before/after among {sorted(names)})")
        first = min(ready, key=lambda s: index[id(s)])
        ordered.append(first)
        placed.add(id(first))
    return ordered


@runtime_checkable
class Plugin(Protocol):
    name: str

    def build(self, engine: Engine) -> None: ...


class UndeclaredAccess(RuntimeError):
    """Debug mode: a system touched component types missing from its ``reads``/``writes``."""

    def __init__(self, system: System, types: list[str]) -> None:
        reads = ", ".join(t.__name__ for t in system.reads) or "nothing"
        writes = ", ".join(t.__name__ for t in system.writes) or "nothing"
        super().__init__(f"{system.name} touched {', '.join(types)} without declaring it "
                         f"(it declares reads: {reads}; writes: {writes}); add it to the "
                         "system's reads (queries) or writes (components added, removed or "
                         "changed)")


class SystemFailure(RuntimeError):
    """A system raised; carries the system's name so the report names it."""

    def __init__(self, system_name: str, original: BaseException) -> None:
        super().__init__(f"system {system_name!r} raised {type(original).__name__}: {original}")
        self.system_name = system_name
        self.original = original

