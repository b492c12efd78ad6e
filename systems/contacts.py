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


def _poses(bodies: BodyState, entities: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The pose rows (x y z qw qx qy qz) of ``entities`` in a physics state, and which are
    there; the world (-1) is there, at a pose of zeros."""
    world = entities < 0
    poses = np.zeros((len(entities), 7))
    if not len(bodies.keys):
        return poses, world
    order = np.argsort(bodies.keys, kind="stable")
    sorted_keys = bodies.keys[order]
    at = np.minimum(np.searchsorted(sorted_keys, entities), len(sorted_keys) - 1)
    found = world | (sorted_keys[at] == entities)
    hit = found & ~world
    poses[hit] = bodies.table[order[at[hit]], :7]
    return poses, found


def _pair_poses(bodies: BodyState, keys: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The poses of each pair's two bodies ``(K, 2, 7)``, and whether both are there."""
    a = keys >> 32
    low = keys & _LOW
    b = np.where(low >= 1 << 31, low - (1 << 32), low)
    poses, found = _poses(bodies, np.concatenate([a, b]))
    n = len(keys)
    return np.stack([poses[:n], poses[n:]], axis=1), found[:n] & found[n:]


class ContactEventsSystem(System):
    """Emits ContactBegan / ContactEnded from the frame's Contacts batch."""

    phase = Phase.POST_PHYSICS

    def __init__(self) -> None:
        self.touching = np.zeros(0, np.int64)  # sorted pair keys touching last frame
        self._frame_keys: list[np.ndarray] = []
        self._frame_impulse: list[np.ndarray] = []
        #: the physics state of the last frame, where pairs touching then were seen
        self._previous: Snapshot | None = None
        #: pairs no longer reported but still touching (asleep), sorted, and the poses of
        #: their two bodies ``(K, 2, 7)`` where they were last seen touching
        self._kept = np.zeros(0, np.int64)
        self._kept_poses = np.zeros((0, 2, 7))

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
        self._kept, self._kept_poses = self._still_touching(engine, missing, snapshot)
        for key, impulse in zip(now[began].tolist(), totals[began].tolist(), strict=True):
            a, b = split(key)
            engine.events.emit(ContactBegan(a, b, impulse))
        self._previous = snapshot
        self.touching = np.union1d(now, self._kept)

    def _still_touching(self, engine: Engine, missing: np.ndarray, snapshot: Snapshot
                        ) -> tuple[np.ndarray, np.ndarray]:
        """Of the pairs touching last frame and not reported now, those whose bodies have
        not moved since they were last seen touching (asleep on each other), with those
        poses; the others have ended (told, unless a body was deleted). All pairs at
        once: a few hundred crumbs asleep on a floor cost 3 ms a frame one by one."""
        if not len(missing):
            return missing, np.zeros((0, 2, 7))
        then = np.zeros((len(missing), 2, 7))
        seen = np.zeros(len(missing), bool)
        at = np.minimum(np.searchsorted(self._kept, missing), max(len(self._kept) - 1, 0))
        kept = (self._kept[at] == missing) if len(self._kept) else seen.copy()
        then[kept], seen[kept] = self._kept_poses[at[kept]], True
        if self._previous is not None and (~kept).any():
            then[~kept], seen[~kept] = _pair_poses(self._previous.bodies, missing[~kept])
        now, found = _pair_poses(snapshot.bodies, missing)
        still = seen & found & (np.abs(now - then).max(axis=(1, 2)) <= MOVED)
        exists = engine.world.entity_exists
        for key in missing[~still].tolist():
            a, b = split(key)
            if exists(a) and (b < 0 or exists(b)):  # a deleted body's contacts end untold
                engine.events.emit(ContactEnded(a, b))
        return missing[still], then[still]
