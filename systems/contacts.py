"""Contact begin and end: which pairs of bodies started or stopped touching this frame.

The physics system hands over every step's contacts as one :class:`Contacts` batch per
frame, as long as bodies touch (scripts' ``onCollision``, every frame). This system keeps
the set of touching pairs and emits :class:`ContactBegan` for a pair that touches now and
did not the frame before, :class:`ContactEnded` for one that touched and no longer does.
Sleeping bodies are not collided (ODE and pymunk stop reporting their contacts), so a pair
missing from a frame has ended only once one of its bodies has moved from where it was
last seen touching (by :data:`MOVED` m, or turned as much): a stack that falls asleep
keeps touching, and a pair that drifts apart ends when the gap is that wide. In threaded
mode a frame sees the contacts of the physics steps since the last one; a frame with no
new step changes nothing.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from engine.events import ContactBegan, ContactEnded, Contacts
from engine.physics.backend import BodyState
from engine.physics.driver import Snapshot
from engine.system import Phase, System

if TYPE_CHECKING:
    from engine.app import Engine

#: How far (m, and quaternion components) a body of a pair no longer reported must have
#: moved since it was last seen touching for the pair to have ended.
MOVED = 1e-3

#: A pair as one int64: the larger entity id in the high half, the other (or -1, the
#: world) in the low half, so (a, b) and (b, a) are the same pair.
_LOW = np.int64(0xFFFFFFFF)


def pair_keys(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """One key per contact's pair, the same for either order; -1 (world) sorts low."""
    a, b = a.astype(np.int64), b.astype(np.int64)
    high, low = np.maximum(a, b), np.minimum(a, b)
    return (high << 32) | (low & _LOW)


def split(key: int) -> tuple[int, int]:
    """(a, b) of a pair key: b is -1 for the world."""
    a, low = key >> 32, key & 0xFFFFFFFF
    return a, (low - (1 << 32) if low >= 1 << 31 else low)


def _pose(bodies: BodyState, entity: int) -> np.ndarray | None:
    """The pose row (x y z qw qx qy qz) of ``entity`` in a physics state, if it is there."""
    rows = np.flatnonzero(bodies.keys == entity)
    return bodies.table[rows[0], :7] if len(rows) else None


def _moved(then: Snapshot, now: Snapshot, entities: tuple[int, ...]) -> bool:
    """Whether any of ``entities`` (bodies; -1 is the world) moved by MOVED between the
    two physics states."""
    for entity in entities:
        if entity < 0:
            continue
        before, after = _pose(then.bodies, entity), _pose(now.bodies, entity)
        if before is None or after is None or np.abs(after - before).max() > MOVED:
            return True
    return False


class ContactEventsSystem(System):
    """Emits ContactBegan / ContactEnded from the frame's Contacts batch."""

    phase = Phase.POST_PHYSICS

    def __init__(self) -> None:
        self.touching = np.zeros(0, np.int64)  # sorted pair keys touching last frame
        self._frame_keys: list[np.ndarray] = []
        self._frame_impulse: list[np.ndarray] = []
        #: the physics state of the last frame, where pairs touching then were seen
        self._previous: Snapshot | None = None
        #: pairs no longer reported but still touching (asleep): the state last seen in
        self._kept: dict[int, Snapshot] = {}

    def setup(self, engine: Engine) -> None:
        engine.events.subscribe(Contacts, self._collect)

    def _collect(self, event: Contacts) -> None:
        batch = event.batch
        self._frame_keys.append(pair_keys(batch["a"], batch["b"]))
        self._frame_impulse.append(batch["impulse"])

    def run(self, engine: Engine, dt: float) -> None:
        snapshot = engine.physics.snapshot
        if self._frame_keys:
            keys = np.concatenate(self._frame_keys)
            impulses = np.concatenate(self._frame_impulse)
            self._frame_keys, self._frame_impulse = [], []
            now, inverse = np.unique(keys, return_inverse=True)
            totals = np.bincount(inverse.reshape(-1), weights=impulses, minlength=len(now))
        elif not len(self.touching):
            self._previous = snapshot
            return
        else:
            now, totals = np.zeros(0, np.int64), np.zeros(0)
        began = ~np.isin(now, self.touching, assume_unique=True)
        missing = self.touching[~np.isin(self.touching, now, assume_unique=True)]
        kept: dict[int, Snapshot] = {}
        exists = engine.world.entity_exists
        for key in missing.tolist():
            a, b = split(key)
            if not exists(a) or (b >= 0 and not exists(b)):
                continue  # deleted: its contacts end without an event
            then = self._kept.get(key, self._previous)
            if then is not None and not _moved(then, snapshot, (a, b)):
                kept[key] = then  # nothing moved: asleep on each other, still touching
            else:
                engine.events.emit(ContactEnded(a, b))
        for key, impulse in zip(now[began].tolist(), totals[began].tolist(), strict=True):
            a, b = split(key)
            engine.events.emit(ContactBegan(a, b, impulse))
        self._kept = kept
        self._previous = snapshot
        self.touching = np.union1d(now, np.fromiter(kept, np.int64, len(kept)))
