"""The entity store: the one module that imports esper.

esper 3 keeps its databases in module globals and switches between them with
``switch_world``; :class:`World` gives each engine a private, uniquely named
esper world and switches to it before every call, so two engines in one process
never see each other's entities. Only the main thread may use a World.

Transforms added to a world are adopted by its :class:`PoseTable`: their arrays
become views into contiguous numpy tables, so the dynamics system writes every
pose with one vectorised assignment instead of a Python loop over bodies. An
adopted Transform stays bound: assigning a field (``t.position = (1, 2, 3)``)
writes into its row rather than detaching it, so the engine sees every write.
"""

from __future__ import annotations

import itertools
from collections import defaultdict
from collections.abc import Callable, Iterable, Iterator
from typing import Any, TypeVar, overload

import esper
import numpy as np

from components import Transform

C = TypeVar("C")
C1 = TypeVar("C1")
C2 = TypeVar("C2")
C3 = TypeVar("C3")

ComponentHook = Callable[[int, Any], None]

_world_names = itertools.count()


def row_index(rows: np.ndarray) -> slice | np.ndarray:
    """The cheapest index for ``rows``: a slice where they are one increasing run.

    Bodies spawned together sit in consecutive rows, and a backend that keeps its
    bodies in key order hands them over in that order; a slice then copies a
    whole table in one block instead of gathering row by row.

    >>> row_index(np.array([4, 5, 6]))
    slice(4, 7, None)
    >>> row_index(np.array([4, 6]))
    array([4, 6])
    """
    n = len(rows)
    if n and rows[-1] - rows[0] == n - 1 and (n == 1 or bool(np.all(np.diff(rows) == 1))):
        return slice(int(rows[0]), int(rows[-1]) + 1)
    return rows


class AdoptedTransform(Transform):
    """A Transform whose arrays are rows of a pose table (see :class:`PoseTable`).

    Assigning a field copies into the row, so ``t.position = new`` moves the entity
    like ``t.position[:] = new`` does instead of silently detaching it from the table.

    >>> table = PoseTable()
    >>> t = Transform()
    >>> table.adopt(1, t)
    >>> t.position = (1.0, 2.0, 3.0)
    >>> table.position[table.row_of[1]].tolist()
    [1.0, 2.0, 3.0]
    """

    __slots__ = ()

    def __setattr__(self, name: str, value: Any) -> None:
        getattr(self, name)[...] = value


_set = object.__setattr__


def _kind(component: Any) -> type:
    """The type a component is filed under (an adopted Transform is still a Transform)."""
    kind = type(component)
    return Transform if kind is AdoptedTransform else kind


class PoseTable:
    """Contiguous storage for every adopted Transform, one row per entity.

    One (capacity, 13) ``table`` holds each row's ``x y z  qw qx qy qz  vx vy vz  wx wy
    wz``, the layout of a state read (``BodyState.table``), which it takes in one
    copy; ``position``, ``orientation``, ``linear_velocity`` and ``angular_velocity``
    are its column views. Rows are recycled through a free list; growth doubles
    capacity and re-points the adopted Transforms at the new table (amortised O(1)
    per entity).
    """

    def __init__(self, capacity: int = 64) -> None:
        self._use(np.zeros((capacity, 13)))
        self.orientation[:, 0] = 1.0
        self._owner: list[Transform | None] = [None] * capacity
        self._free: list[int] = list(range(capacity - 1, -1, -1))
        self.row_of: dict[int, int] = {}
        self._entity_at = np.full(capacity, -1, np.int64)  # row -> its entity (-1: free)
        #: Bumped whenever rows are assigned or released; caches keyed on it stay valid.
        self.version = 0
        self._index: tuple[int, np.ndarray, np.ndarray] | None = None  # for rows()

    @property
    def capacity(self) -> int:
        return len(self._owner)

    def adopt(self, entity: int, transform: Transform) -> None:
        self.adopt_many([entity], [transform])

    def adopt_many(self, entities: list[int], transforms: list[Transform]) -> None:
        """Adopt many Transforms: one numpy assignment per field; rows as if one by one."""
        n = len(transforms)
        if not n:
            return
        rows: list[int] = []
        while len(rows) < n:  # the rows one adopt() after another would take
            if not self._free:
                self._grow()
            take = min(n - len(rows), len(self._free))
            rows += self._free[:-take - 1:-1]
            del self._free[-take:]
        index = np.asarray(rows, dtype=np.intp)
        for name in ("position", "orientation", "linear_velocity", "angular_velocity"):
            getattr(self, name)[index] = [getattr(t, name) for t in transforms]
        owner, row_of, bind = self._owner, self.row_of, self._bind
        for entity, row, t in zip(entities, rows, transforms, strict=True):
            bind(row, t)
            owner[row] = t
            row_of[entity] = row
        self._entity_at[index] = entities
        self.version += 1

    def release(self, entity: int) -> None:
        row = self.row_of.pop(entity, None)
        if row is None:
            return
        transform = self._owner[row]
        if transform is not None:  # detach: keep the values, drop the views
            _set(transform, "__class__", Transform)
            transform.position = transform.position.copy()
            transform.orientation = transform.orientation.copy()
            transform.linear_velocity = transform.linear_velocity.copy()
            transform.angular_velocity = transform.angular_velocity.copy()
        self._owner[row] = None
        self._free.append(row)
        self._entity_at[row] = -1
        self.version += 1

    def rows(self, entities: Iterable[int]) -> np.ndarray:
        """Row indices of ``entities``; -1 where an entity has no Transform.

        A sorted search over the rows' entities, the sort made once per :attr:`version`
        and shared by every caller: a plan of 5,000 bodies is made again whenever one
        comes or goes, and a dict lookup per entity in Python cost milliseconds a frame.
        """
        keys = np.asarray(entities if isinstance(entities, np.ndarray) else
                          np.fromiter(entities, np.int64), np.int64)
        index = self._index
        if index is None or index[0] != self.version:
            order = np.argsort(self._entity_at, kind="stable")
            index = self._index = (self.version, self._entity_at[order], order)
        _, ordered, order = index
        if not len(ordered):
            return np.full(keys.shape, -1, np.int64)
        at = np.minimum(np.searchsorted(ordered, keys), len(ordered) - 1)
        return np.where((ordered[at] == keys) & (keys >= 0), order[at], -1)

    def _bind(self, row: int, transform: Transform) -> None:
        _set(transform, "position", self.position[row])
        _set(transform, "orientation", self.orientation[row])
        _set(transform, "linear_velocity", self.linear_velocity[row])
        _set(transform, "angular_velocity", self.angular_velocity[row])
        _set(transform, "__class__", AdoptedTransform)

    def _use(self, table: np.ndarray) -> None:
        self.table = table
        self.position = table[:, 0:3]
        self.orientation = table[:, 3:7]
        self.linear_velocity = table[:, 7:10]
        self.angular_velocity = table[:, 10:13]

    def _grow(self) -> None:
        old = self.capacity
        new = old * 2
        grown = np.zeros((new, 13))
        grown[:old] = self.table
        self._use(grown)
        self.orientation[old:, 0] = 1.0
        self._owner.extend([None] * (new - old))
        self._free.extend(range(new - 1, old - 1, -1))
        self._entity_at = np.concatenate([self._entity_at, np.full(new - old, -1, np.int64)])
        for row, transform in enumerate(self._owner[:old]):
            if transform is not None:
                self._bind(row, transform)


class AccessAudit:
    """Which component types the running system touches (the engine's debug mode).

    Reads are every query; writes are components added or removed. Hooks run for
    whoever registered them, so their accesses are not counted against the system
    that triggered them. What a system does to a component it got (``t.position[0] =
    1``) cannot be seen here; the engine compares the pose table before and after
    (Transforms), for other components declaring ``writes`` stays the author's word.
    """

    __slots__ = ("read", "written", "paused")

    def __init__(self) -> None:
        self.read: set[type] = set()
        self.written: set[type] = set()
        self.paused = 0

    def reads(self, *kinds: type) -> None:
        if not self.paused:
            self.read.update(kinds)

    def writes(self, *kinds: type) -> None:
        if not self.paused:
            self.written.update(kinds)


class World:
    """A private esper world plus a pose table and component add/remove hooks."""

    def __init__(self) -> None:
        self.name = f"colosseum-{next(_world_names)}"
        #: Set by the engine's debug mode while a system runs (see :class:`AccessAudit`).
        self.audit: AccessAudit | None = None
        self.poses = PoseTable()
        self._on_add: dict[type, list[ComponentHook]] = defaultdict(list)
        self._on_remove: dict[type, list[ComponentHook]] = defaultdict(list)
        self._enter()

    def _enter(self) -> None:
        if esper.current_world != self.name:
            esper.switch_world(self.name)

    # -- hooks -------------------------------------------------------------
    def on_add(self, component_type: type, hook: ComponentHook) -> None:
        """Call ``hook(entity, component)`` whenever a component of this type is added."""
        self._on_add[component_type].append(hook)

    def on_remove(self, component_type: type, hook: ComponentHook) -> None:
        self._on_remove[component_type].append(hook)

    def _added(self, entity: int, component: Any) -> None:
        if isinstance(component, Transform):
            self.poses.adopt(entity, component)
        self._run_hooks(self._on_add.get(_kind(component), ()), entity, component)

    def _removing(self, entity: int, component: Any) -> None:
        self._run_hooks(self._on_remove.get(_kind(component), ()), entity, component)
        if isinstance(component, Transform):
            self.poses.release(entity)

    def _run_hooks(self, hooks: Iterable[ComponentHook], entity: int, component: Any) -> None:
        audit = self.audit
        if audit is not None:
            audit.paused += 1
        try:
            for hook in hooks:
                hook(entity, component)
        finally:
            if audit is not None:
                audit.paused -= 1

    # -- entities ----------------------------------------------------------
    def create_entity(self, *components: Any) -> int:
        self._enter()
        if self.audit is not None:
            self.audit.writes(*map(_kind, components))
        entity = esper.create_entity(*components)
        for component in components:
            self._added(entity, component)
        return entity

    def create_entities(self, component_lists: Iterable[Iterable[Any]]) -> list[int]:
        """Create many entities; same result as :meth:`create_entity` on each, but cheaper.

        Their Transforms are adopted in one batch, then add hooks run entity by entity
        in order (so a hook sees every entity of the batch already created).
        """
        self._enter()
        create = esper.create_entity
        entities: list[int] = []
        made: list[tuple[int, tuple[Any, ...]]] = []
        posed: list[int] = []
        transforms: list[Transform] = []
        audit = self.audit
        for components in component_lists:
            components = tuple(components)
            if audit is not None:
                audit.writes(*map(_kind, components))
            entity = create(*components)
            entities.append(entity)
            made.append((entity, components))
            for component in components:
                if isinstance(component, Transform):
                    posed.append(entity)
                    transforms.append(component)
        self.poses.adopt_many(posed, transforms)
        hooks = self._on_add
        if hooks:
            for entity, components in made:
                for component in components:
                    self._run_hooks(hooks.get(_kind(component), ()), entity, component)
        return entities

    def delete_entity(self, entity: int) -> None:
        """Delete now (the engine defers this to the end of a frame; see Engine.despawn)."""
        self._enter()
        if not esper.entity_exists(entity):
            return
        for component in esper.components_for_entity(entity):
            self._removing(entity, component)
        esper.delete_entity(entity, immediate=True)

    def entity_exists(self, entity: int) -> bool:
        self._enter()
        return esper.entity_exists(entity)

    def add_component(self, entity: int, component: Any) -> None:
        self._enter()
        kind = _kind(component)
        if self.audit is not None:
            self.audit.writes(kind)
        old = esper.try_component(entity, kind)
        if old is not None:
            self._removing(entity, old)
        esper.add_component(entity, component, type_alias=kind)
        self._added(entity, component)

    def remove_component(self, entity: int, component_type: type[C]) -> C | None:
        self._enter()
        if self.audit is not None:
            self.audit.writes(component_type)
        component = esper.try_component(entity, component_type)
        if component is None:
            return None
        self._removing(entity, component)
        esper.remove_component(entity, component_type)
        return component

    def clear(self) -> None:
        for entity in list(self.entities()):
            self.delete_entity(entity)

    def close(self) -> None:
        self.clear()
        if esper.current_world == self.name:
            esper.switch_world("default")
        if self.name in esper.list_worlds():
            esper.delete_world(self.name)

    # -- queries -----------------------------------------------------------
    def entities(self) -> Iterator[int]:
        self._enter()
        return iter(list(esper.get_entities()))

    def __len__(self) -> int:
        self._enter()
        return sum(1 for _ in esper.get_entities())

    def component_for_entity(self, entity: int, component_type: type[C]) -> C:
        self._enter()
        if self.audit is not None:
            self.audit.reads(component_type)
        return esper.component_for_entity(entity, component_type)

    def try_component(self, entity: int, component_type: type[C]) -> C | None:
        self._enter()
        if self.audit is not None:
            self.audit.reads(component_type)
        return esper.try_component(entity, component_type)

    def has_component(self, entity: int, component_type: type) -> bool:
        self._enter()
        if self.audit is not None:
            self.audit.reads(component_type)
        return esper.has_component(entity, component_type)

    def components_for_entity(self, entity: int) -> tuple[Any, ...]:
        self._enter()
        found = esper.components_for_entity(entity)
        if self.audit is not None:
            self.audit.reads(*map(_kind, found))
        return found

    def get_component(self, component_type: type[C]) -> list[tuple[int, C]]:
        self._enter()
        if self.audit is not None:
            self.audit.reads(component_type)
        return esper.get_component(component_type)

    @overload
    def get_components(self, c1: type[C1]) -> list[tuple[int, tuple[C1]]]: ...
    @overload
    def get_components(self, c1: type[C1], c2: type[C2]) -> list[tuple[int, tuple[C1, C2]]]: ...
    @overload
    def get_components(
        self, c1: type[C1], c2: type[C2], c3: type[C3]
    ) -> list[tuple[int, tuple[C1, C2, C3]]]: ...
    def get_components(self, *component_types: type) -> list[tuple[int, tuple[Any, ...]]]:
        self._enter()
        if self.audit is not None:
            self.audit.reads(*component_types)
        return esper.get_components(*component_types)
