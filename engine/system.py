"""Systems, phases and plugins: how behaviour is attached to the engine.

A system declares the phase it runs in and the component types it reads and
writes (documentation today, the basis for checks and parallel schedules
tomorrow). A plugin is any object with a ``name`` and ``build(engine)`` that
adds systems and resources; content folders add their own from ``systems/*.py``.
"""

from __future__ import annotations

from collections.abc import Callable
from enum import IntEnum
from typing import TYPE_CHECKING, ClassVar, Protocol, runtime_checkable

if TYPE_CHECKING:
    from engine.app import Engine


class Phase(IntEnum):
    """Phases of one frame, in the order they run."""

    INPUT = 0
    SCRIPT = 1
    FIXED = 2
    POST_PHYSICS = 3
    RENDER = 4


class System:
    """Base class for systems. Override :meth:`run`; the rest is optional."""

    phase: ClassVar[Phase] = Phase.SCRIPT
    reads: ClassVar[tuple[type, ...]] = ()
    writes: ClassVar[tuple[type, ...]] = ()

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
                 reads: tuple[type, ...], writes: tuple[type, ...]) -> None:
        self.fn = fn
        self.phase = phase  # type: ignore[misc]
        self.reads = reads  # type: ignore[misc]
        self.writes = writes  # type: ignore[misc]

    @property
    def name(self) -> str:
        return getattr(self.fn, "__qualname__", repr(self.fn))

    def run(self, engine: Engine, dt: float) -> None:
        self.fn(engine, dt)


def system(phase: Phase = Phase.SCRIPT, reads: tuple[type, ...] = (),
           writes: tuple[type, ...] = ()) -> Callable[[Callable[[Engine, float], None]],
                                                      FunctionSystem]:
    """Decorator: turn ``def f(engine, dt)`` into a system.

    >>> from components import Transform
    >>> @system(Phase.SCRIPT, reads=(Transform,))
    ... def report(engine, dt):
    ...     pass
    >>> report.phase.name, report.reads
    ('SCRIPT', (<class 'components.transform.Transform'>,))
    """

    def wrap(fn: Callable[[Engine, float], None]) -> FunctionSystem:
        return FunctionSystem(fn, phase, reads, writes)

    return wrap


@runtime_checkable
class Plugin(Protocol):
    name: str

    def build(self, engine: Engine) -> None: ...


class SystemFailure(RuntimeError):
    """A system raised; carries the system's name so the report names it."""

    def __init__(self, system_name: str, original: BaseException) -> None:
        super().__init__(f"system {system_name!r} raised {type(original).__name__}: {original}")
        self.system_name = system_name
        self.original = original

