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

from components import Transform
from engine.events import ContactBegan, ContactEnded, Contacts
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


def _moved(now: tuple[float, ...] | None, then: tuple[float, ...] | None) -> bool:
    if now is None or then is None:
        return now is not then
    return max(abs(x - y) for x, y in zip(now, then, strict=True)) > MOVED


class ContactEventsSystem(System):
    """Emits ContactBegan / ContactEnded from the frame's Contacts batch."""

    phase = Phase.POST_PHYSICS
    reads = (Transform,)

    def __init__(self) -> None:
        self.touching = np.zeros(0, np.int64)  # sorted pair keys touching last frame
        self._frame_keys: list[np.ndarray] = []
        self._frame_impulse: list[np.ndarray] = []
        #: entity -> its pose (x y z qw qx qy qz) when last seen touching something
        self._seen_at: dict[int, tuple[float, ...]] = {}

    def setup(self, engine: Engine) -> None:
        engine.events.subscribe(Contacts, self._collect)

    def _collect(self, event: Contacts) -> None:
        batch = event.batch
        self._frame_keys.append(pair_keys(batch["a"], batch["b"]))
        self._frame_impulse.append(batch["impulse"])

    def _pose(self, engine: Engine, entity: int) -> tuple[float, ...] | None:
        """Where a body is now; None for the world or a deleted body."""
        if entity < 0 or not engine.world.entity_exists(entity):
            return None
        t = engine.world.try_component(entity, Transform)
        return None if t is None else (*t.position.tolist(), *t.orientation.tolist())

    def run(self, engine: Engine, dt: float) -> None:
        if self._frame_keys:
            keys = np.concatenate(self._frame_keys)
            impulses = np.concatenate(self._frame_impulse)
            self._frame_keys, self._frame_impulse = [], []
            now, inverse = np.unique(keys, return_inverse=True)
            totals = np.bincount(inverse.reshape(-1), weights=impulses, minlength=len(now))
        elif not len(self.touching):
            return
        else:
            now, totals = np.zeros(0, np.int64), np.zeros(0)
        began = ~np.isin(now, self.touching, assume_unique=True)
        missing = self.touching[~np.isin(self.touching, now, assume_unique=True)]
        kept = []
        for key in missing.tolist():
            a, b = split(key)
            poses = [(e, self._pose(engine, e)) for e in (a, b) if e >= 0]
            if any(e >= 0 and not engine.world.entity_exists(e) for e in (a, b)):
                continue  # deleted: its contacts end without an event
            if all(not _moved(pose, self._seen_at.get(e)) for e, pose in poses):
                kept.append(key)  # nothing moved: asleep on each other, still touching
            else:
                engine.events.emit(ContactEnded(a, b))
        for key, impulse in zip(now[began].tolist(), totals[began].tolist(), strict=True):
            a, b = split(key)
            engine.events.emit(ContactBegan(a, b, impulse))
        for key in now.tolist():
            for entity in split(key):
                pose = self._pose(engine, entity)
                if pose is not None:
                    self._seen_at[entity] = pose
        self.touching = np.union1d(now, np.asarray(kept, np.int64))
        if len(self._seen_at) > 4 * len(self.touching) + 64:  # forget bodies long apart
            alive = {e for key in self.touching.tolist() for e in split(key)}
            self._seen_at = {e: p for e, p in self._seen_at.items() if e in alive}
