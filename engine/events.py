"""The event bus: collision, input, timer and custom events.

Events are queued as they are emitted and delivered, in order, when the
scheduler calls :meth:`EventBus.dispatch` between phases, so a handler never
runs in the middle of another system. Contacts arrive as one :class:`Contacts`
batch per frame (a numpy array), never as one Python object per contact.
"""

from __future__ import annotations

import logging
from collections import defaultdict
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

log = logging.getLogger("colosseum.events")

E = TypeVar("E")
Handler = Callable[[Any], None]


@dataclass(frozen=True, slots=True)
class Contacts:
    """All contacts of the physics steps since the last frame (CONTACT_DTYPE array)."""

    batch: np.ndarray


@dataclass(frozen=True, slots=True)
class ContactBegan:
    """Two bodies touch that did not touch the frame before (``b`` is -1 for static world
    geometry); ``impulse`` is what they exchanged this frame (N·s, summed over contacts and
    steps)."""

    a: int
    b: int
    impulse: float


@dataclass(frozen=True, slots=True)
class ContactEnded:
    """Two bodies that touched no longer do (bodies asleep on each other still touch; a
    deleted body's contacts end without one)."""

    a: int
    b: int


@dataclass(frozen=True, slots=True)
class HandTouched:
    """A virtual hand began touching an object it could grasp."""

    hand: int
    object: int


@dataclass(frozen=True, slots=True)
class HandGrasped:
    """A virtual hand took hold of an object (the glove's button, or a script)."""

    hand: int
    object: int


@dataclass(frozen=True, slots=True)
class HandReleased:
    """A virtual hand let go of an object (button up, a script, a lost tracker, a break)."""

    hand: int
    object: int


@dataclass(frozen=True, slots=True)
class KeyEvent:
    """A key went down or up; names are lower case ("space", "up", "f1", "a").

    Also the input layer's typed ``Key`` event (``services.input.Key``): ``device`` is where
    it came from, ``timestamp`` when (``time.monotonic()`` seconds, 0 when unknown).
    """

    key: str
    pressed: bool
    device: str = "keyboard"
    timestamp: float = 0.0


@dataclass(frozen=True, slots=True)
class TimerEvent:
    name: str


@dataclass(frozen=True, slots=True)
class CustomEvent:
    name: str
    data: Any = None


@dataclass(frozen=True, slots=True)
class Spawned:
    """An entity was created from a description (factory or script)."""

    entity: int


@dataclass(frozen=True, slots=True)
class Despawned:
    entity: int


@dataclass(frozen=True, slots=True)
class AnomalySwitched:
    """A visual anomaly (engine.anomalies) was switched on or off, or its severity set:
    ``anomaly`` its ID, ``kind`` what it is, ``enabled`` whether it is on now, ``onset`` the
    seconds its effect takes to grow or fade, ``severity`` its parameters as (scene key,
    value) pairs, ``source`` who did it ("scene", "lua:scripts/x.lua:12", "input:key:f2",
    "python")."""

    anomaly: str
    kind: str
    enabled: bool
    onset: float
    severity: tuple[tuple[str, Any], ...]
    source: str


@dataclass(frozen=True, slots=True)
class BodyFault:
    """The dynamics backend found a body or joint in a non-finite state and reset it."""

    key: int
    message: str


class EventBus:
    """Typed publish/subscribe with queued delivery."""

    def __init__(self) -> None:
        self._handlers: dict[type, list[Handler]] = defaultdict(list)
        self._queue: list[Any] = []
        self._frame: dict[type, list[Any]] = defaultdict(list)

    def subscribe(self, event_type: type[E], handler: Callable[[E], None]) -> None:
        self._handlers[event_type].append(handler)

    def unsubscribe(self, event_type: type[E], handler: Callable[[E], None]) -> None:
        handlers = self._handlers.get(event_type, [])
        if handler in handlers:
            handlers.remove(handler)

    def emit(self, event: Any) -> None:
        """Queue an event; it is delivered at the next dispatch."""
        self._queue.append(event)

    def dispatch(self) -> None:
        """Deliver every queued event (and those emitted while delivering)."""
        while self._queue:
            queue, self._queue = self._queue, []
            for event in queue:
                self._frame[type(event)].append(event)
                for handler in tuple(self._handlers.get(type(event), ())):
                    handler(event)

    def frame(self, event_type: type[E]) -> list[E]:
        """Events of this type delivered during the current frame."""
        return self._frame.get(event_type, [])

    def end_frame(self) -> None:
        self._frame.clear()
