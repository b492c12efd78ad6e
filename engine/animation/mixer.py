"""Every avatar's animation state and its evaluation, batched over all avatars.

An avatar plays *layers* (a clip at a time, speed and weight); layers started together by
one ``play``, ``queue`` or ``blend`` form a *group* that shares one phase, so a blend of a
walk and a run keeps their feet in step whatever their lengths (each clip is stretched to
the weighted mean length). Each frame :meth:`Mixer.advance` moves every phase and fade
with a few numpy calls and reports the groups that reached their end; :meth:`Mixer.evaluate`
samples every layer's every channel, blends the layers of each avatar (translation and
scale linearly, rotation by slerp, the layers folded in one by one with weight
``w_k / (w_rest + w_1 + ... + w_k)``, where ``w_rest = max(0, 1 - sum w)`` keeps the rest
pose), and composes the hierarchies into model-frame matrices.

Per-layer numbers live in arrays (the only copy); Python objects hold what changes rarely
(which clip, which group), so a script can start and blend clips without a per-frame cost.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from components.avatar_saved import SavedGroup, SavedLayer, SavedRequest
from engine.animation import _compose
from engine.animation.library import CUBIC, ROTATION, STEP, Library, Rig
from engine.animation.sampling import hermite
from engine.rotation import quat_normalize


class AnimationError(ValueError):
    """A request an avatar cannot follow (an unknown clip, a bad weight); says what exists."""


@dataclass(frozen=True, slots=True)
class ClipSettings:
    """How a clip plays unless a call says otherwise; ``ground_speed`` (model units per
    second at speed 1) replaces the speed measured from its root motion."""

    speed: float = 1.0
    loop: bool = True
    ground_speed: float | None = None


@dataclass(frozen=True, slots=True)
class Request:
    """A queued start: clips with their weights, how long to fade in, speed and looping."""

    weights: tuple[tuple[str, float], ...]
    fade: float
    speed: float | None
    loop: bool | None


@dataclass(frozen=True, slots=True)
class AnimationEnded:
    """A clip played to its end (a looping one only when something was queued after it);
    an event on the engine's bus, and ``onAnimationEnd`` in Lua."""

    avatar: int
    clip: str


@dataclass(slots=True)
class Palettes:
    """Every avatar's joint matrices this frame, as the renderer takes them: ``matrices``
    ``(J, 3, 4)`` float32 (the top rows of each 4x4), ``offsets`` entity -> first row.
    The avatars plugin publishes it as an engine resource; ``version`` counts frames."""

    matrices: np.ndarray = field(default_factory=lambda: np.zeros((0, 3, 4), np.float32))
    offsets: dict[int, int] = field(default_factory=dict)
    version: int = 0


@dataclass(slots=True)
class Animator:
    """One avatar's animation: its rig, clip settings, current group and queue."""

    key: int
    rig: Rig
    settings: dict[str, ClipSettings] = field(default_factory=dict)
    default_fade: float = 0.0
    group: int = -1  # the group started last (-1: none)
    queue: deque[Request] = field(default_factory=deque)
    row: int = 0  # first row of its nodes in the pose arrays (set by the mixer)

    def clip_id(self, name: str) -> int:
        found = self.rig.clips.get(name)
        if found is None:
            names = ", ".join(self.rig.clips) or "none"
            raise AnimationError(f"model {self.rig.model.path.name!r} has no clip {name!r} "
                                 f"(its clips: {names})")
        return found


class _Table:
    """Rows of numbers with free-list reuse (layers, groups)."""

    def __init__(self, columns: dict[str, type]) -> None:
        self._columns = columns
        self.size = 0
        for name, dtype in columns.items():
            setattr(self, name, np.zeros(16, dtype))
        self.used = np.zeros(16, bool)
        self._free: list[int] = []

    def add(self, **values: float | int | bool) -> int:
        if self._free:
            row = self._free.pop()
        else:
            row = self.size
            self.size += 1
            if row >= len(self.used):
                for name in (*self._columns, "used"):
                    old = getattr(self, name)
                    setattr(self, name, np.concatenate([old, np.zeros_like(old)]))
        for name in self._columns:
            getattr(self, name)[row] = values.get(name, 0)
        self.used[row] = True
        return row

    def remove(self, row: int) -> None:
        self.used[row] = False
        self._free.append(row)


#: A phase this close to 1 is the end: a rate like 1/1.5 s summed frame by frame must not
#: end a clip one frame late for the last bit of rounding.
PHASE_EPSILON = 1e-9

_LAYER_COLUMNS = {"avatar": np.int64, "clip": np.int64, "group": np.int64, "order": np.int64,
                  "speed": np.float64, "duration": np.float64, "weight": np.float64,
                  "weight_from": np.float64, "weight_to": np.float64,
                  "fade_elapsed": np.float64, "fade_length": np.float64}
_GROUP_COLUMNS = {"avatar": np.int64, "order": np.int64, "phase": np.float64, "loop": bool,
                  "ended": bool}


class Mixer:
    """All avatars' layers, advanced and evaluated together (main thread)."""

    def __init__(self, library: Library | None = None) -> None:
        self.library = library or Library()
        self.animators: dict[int, Animator] = {}
        self.layers = _Table(_LAYER_COLUMNS)
        self.groups = _Table(_GROUP_COLUMNS)
        self._names: dict[int, str] = {}  # layer row -> clip name
        self._order = 0
        self._dirty = True
        self._plan: _Plan | None = None

    # -- avatars ----------------------------------------------------------------------
    def add(self, key: int, rig: Rig, settings: dict[str, ClipSettings] | None = None,
            fade: float = 0.0) -> Animator:
        """Start animating avatar ``key`` (in its rest pose until a clip is played)."""
        self.remove(key)
        animator = Animator(key, rig, dict(settings or {}), max(0.0, float(fade)))
        self.animators[key] = animator
        self._dirty = True
        return animator

    def remove(self, key: int) -> None:
        animator = self.animators.pop(key, None)
        if animator is None:
            return
        for row in self._rows_of(key):
            self._drop_layer(row)
        for g in np.flatnonzero(self.groups.used[:self.groups.size]
                                & (self.groups.avatar[:self.groups.size] == key)):
            self.groups.remove(int(g))
        self._dirty = True

    def __contains__(self, key: int) -> bool:
        return key in self.animators

    # -- control ----------------------------------------------------------------------
    def play(self, key: int, clip: str, fade: float | None = None, speed: float | None = None,
             loop: bool | None = None) -> None:
        """Play ``clip`` now, crossfading from what played over ``fade`` seconds; the
        queue is cleared."""
        self.animators[key].queue.clear()
        self.blend(key, {clip: 1.0}, fade, speed, loop)

    def blend(self, key: int, weights: dict[str, float], fade: float | None = None,
              speed: float | None = None, loop: bool | None = None) -> None:
        """Play clips at once with these weights, in step. If exactly these clips play
        already, only their weights move to the new ones (over ``fade``)."""
        animator = self.animators[key]
        checked = self._checked(animator, weights, fade, speed)
        fade_s = animator.default_fade if fade is None else float(fade)
        current = self._group_layers(animator.group)
        if current and {self._names[r] for r in current} == set(checked) and not \
                self.groups.ended[animator.group]:
            t = self.layers
            for row in current:
                self._fade(row, checked[self._names[row]], fade_s)
                if speed is not None:
                    t.speed[row] = float(speed)
            if loop is not None:
                self.groups.loop[animator.group] = bool(loop)
            return
        self._start(animator, Request(tuple(checked.items()), fade_s, speed, loop))

    def queue(self, key: int, clip: str | dict[str, float], fade: float | None = None,
              speed: float | None = None, loop: bool | None = None) -> None:
        """Start ``clip`` (or a blend) when what plays now reaches its end; a looping clip
        ends at the end of its current loop."""
        animator = self.animators[key]
        weights = {clip: 1.0} if isinstance(clip, str) else clip
        checked = self._checked(animator, weights, fade, speed)
        request = Request(tuple(checked.items()),
                          animator.default_fade if fade is None else float(fade), speed, loop)
        g = animator.group
        if g < 0 or self.groups.ended[g]:
            self._start(animator, request)
            return
        animator.queue.append(request)
        self.groups.loop[g] = False  # the current clip ends at the end of this loop

    def stop(self, key: int, fade: float | None = None) -> None:
        """Fade everything out (back to the rest pose) and clear the queue."""
        animator = self.animators[key]
        animator.queue.clear()
        fade_s = animator.default_fade if fade is None else float(fade)
        animator.group = -1
        for row in self._rows_of(key):
            self._fade(row, 0.0, fade_s)

    def playing(self, key: int) -> list[tuple[str, float, float]]:
        """(clip, time in seconds, weight) of every layer of avatar ``key``."""
        t = self.layers
        out = []
        for row in sorted(self._rows_of(key), key=lambda r: t.order[r]):
            g = t.group[row]
            out.append((self._names[row], float(self.groups.phase[g] * t.duration[row]),
                        float(t.weight[row])))
        return out

    def ground_speeds(self) -> dict[int, float]:
        """How fast (model units per second) each avatar's blend of clips walks: the
        weighted mean of its clips' ground speeds times their playback rates (weights
        summing to less than 1 walk slower, as the rest pose stands still)."""
        plan = self._current_plan()
        rows = plan.layer_rows
        animators = list(self.animators.values())
        if not len(rows):
            return {a.key: 0.0 for a in animators}
        t = self.layers
        w = t.weight[rows]
        speed = np.bincount(plan.layer_avatar, w * t.speed[rows] * plan.layer_ground_speed,
                            len(animators))
        total = np.maximum(np.bincount(plan.layer_avatar, w, len(animators)), 1.0)
        return {a.key: float(v) for a, v in zip(animators, speed / total, strict=True)}

    # -- internals of control -----------------------------------------------------------
    def _checked(self, animator: Animator, weights: dict[str, float], fade: float | None,
                 speed: float | None) -> dict[str, float]:
        if not weights:
            raise AnimationError("no clip given")
        out = {}
        # in the model's order, whatever the caller's (a Lua table has none that repeats):
        # layers are slerped in turn, which depends on their order
        for name, w in sorted(weights.items(), key=lambda item: animator.clip_id(str(item[0]))):
            if not isinstance(w, int | float) or isinstance(w, bool) or not 0.0 <= w < 1e6:
                raise AnimationError(f"weight of {name!r} must be a number >= 0, got {w!r}")
            out[str(name)] = float(w)
        for what, value in (("fade", fade), ("speed", speed)):
            if value is not None and not (isinstance(value, int | float)  # a boolean is no
                                          and not isinstance(value, bool)  # number here
                                          and 0.0 <= value < 1e6):
                raise AnimationError(f"{what} must be a number >= 0, got {value!r}")
        return out

    def _start(self, animator: Animator, request: Request) -> None:
        """Fade out every layer of the avatar and start the request's clips in a new group."""
        animator.group = -1
        for row in self._rows_of(animator.key):
            self._fade(row, 0.0, request.fade)
        first = request.weights[0][0]
        setting = animator.settings.get(first, ClipSettings())
        loop = setting.loop if request.loop is None else request.loop
        if animator.queue:
            loop = False
        g = animator.group = self._add_group(animator, 0.0, loop)
        for name, w in request.weights:
            speed = animator.settings.get(name, ClipSettings()).speed \
                if request.speed is None else request.speed
            row = self._add_layer(animator, g, name, speed)
            self._fade(row, w, request.fade, start=0.0)

    def _add_group(self, animator: Animator, phase: float, loop: bool, ended: bool = False
                   ) -> int:
        self._dirty = True
        self._order += 1
        return self.groups.add(avatar=animator.key, order=self._order, phase=phase, loop=loop,
                               ended=ended)

    def _add_layer(self, animator: Animator, group: int, name: str, speed: float,
                   **weights: float) -> int:
        """A layer playing clip ``name`` in ``group`` (started after every other layer)."""
        clip = animator.clip_id(name)
        row = self.layers.add(avatar=animator.key, clip=clip, group=group, order=self._order,
                              speed=speed, duration=self.library.clips[clip].duration,
                              **weights)
        self._order += 1
        self._names[row] = name
        self._dirty = True
        return row

    # -- saved states ---------------------------------------------------------------------
    def capture(self, key: int) -> tuple[tuple[SavedGroup, ...], tuple[SavedRequest, ...]]:
        """Avatar ``key``'s groups (oldest first, each layer's weight and fade) and queue:
        everything :meth:`restore` needs to continue its animation exactly."""
        animator = self.animators[key]
        t, g = self.layers, self.groups
        layers: dict[int, list[SavedLayer]] = {}
        for row in sorted(self._rows_of(key), key=lambda r: t.order[r]):
            layers.setdefault(int(t.group[row]), []).append(SavedLayer(
                self._names[row], float(t.speed[row]), float(t.weight[row]),
                float(t.weight_from[row]), float(t.weight_to[row]),
                float(t.fade_elapsed[row]), float(t.fade_length[row])))
        groups = tuple(SavedGroup(tuple(rows), float(g.phase[x]), bool(g.loop[x]),
                                  bool(g.ended[x]), x == animator.group)
                       for x, rows in layers.items())
        queue = tuple(SavedRequest(r.weights, r.fade, r.speed, r.loop) for r in animator.queue)
        return groups, queue

    def restore(self, key: int, groups: tuple[SavedGroup, ...],
                queue: tuple[SavedRequest, ...]) -> None:
        """Put avatar ``key`` (just added) where :meth:`capture` found one; raises
        AnimationError for a clip its model lacks (nothing restored then)."""
        animator = self.animators[key]
        for name in [layer.clip for group in groups for layer in group.layers] + [
                name for request in queue for name, _ in request.weights]:
            animator.clip_id(name)
        for saved in groups:
            g = self._add_group(animator, saved.phase, saved.loop, saved.ended)
            if saved.current:
                animator.group = g
            for layer in saved.layers:
                self._add_layer(animator, g, layer.clip, layer.speed, weight=layer.weight,
                                weight_from=layer.fade_from, weight_to=layer.fade_to,
                                fade_elapsed=layer.fade_time, fade_length=layer.fade_length)
        animator.queue.extend(Request(r.weights, r.fade, r.speed, r.loop) for r in queue)
        if animator.group < 0 and animator.queue:  # nothing current (a clip left out): on
            self._start(animator, animator.queue.popleft())

    def _fade(self, row: int, target: float, length: float, start: float | None = None) -> None:
        t = self.layers
        if start is not None:
            t.weight[row] = start
        if length <= 0.0:
            t.weight[row] = target
        t.weight_from[row] = t.weight[row]
        t.weight_to[row] = target
        t.fade_elapsed[row] = 0.0
        t.fade_length[row] = max(0.0, length)
        if target == 0.0 and length <= 0.0 and not self._current(row):
            self._drop_layer(row)
            self._dirty = True

    def _current(self, row: int) -> bool:
        """Whether layer ``row`` belongs to what its avatar plays now (a clip blended at
        weight 0 stays, in step, ready to be weighted up)."""
        owner = self.animators.get(int(self.layers.avatar[row]))
        return owner is not None and owner.group == int(self.layers.group[row])

    def _drop_layer(self, row: int) -> None:
        if self.layers.used[row]:
            g = int(self.layers.group[row])
            self.layers.remove(row)
            self._names.pop(row, None)
            if not self._group_layers(g) and self.groups.used[g]:
                owner = self.animators.get(int(self.groups.avatar[g]))
                if owner is None or owner.group != g:
                    self.groups.remove(g)

    def _rows_of(self, key: int) -> list[int]:
        t = self.layers
        n = t.size
        return np.flatnonzero(t.used[:n] & (t.avatar[:n] == key)).tolist()

    def _group_layers(self, g: int) -> list[int]:
        if g < 0:
            return []
        t = self.layers
        n = t.size
        return np.flatnonzero(t.used[:n] & (t.group[:n] == g)).tolist()

    # -- per frame ----------------------------------------------------------------------
    def advance(self, dt: float) -> list[AnimationEnded]:
        """Move every fade and phase on by ``dt``; start queued clips of groups that ended.
        Returns the clips that reached their end this frame."""
        plan = self._current_plan()
        rows = plan.layer_rows
        ended: list[AnimationEnded] = []
        if len(rows):
            t, g = self.layers, self.groups
            t.fade_elapsed[rows] += dt
            length = t.fade_length[rows]
            k = np.where(length > 0, np.minimum(t.fade_elapsed[rows] / np.where(
                length > 0, length, 1.0), 1.0), 1.0)
            w = t.weight_from[rows] + (t.weight_to[rows] - t.weight_from[rows]) * k
            t.weight[rows] = w
            faded_out = rows[(t.weight_to[rows] == 0.0) & (k >= 1.0)]  # before ends re-fade
            groups = t.group[rows]
            dur = t.duration[rows]
            rate = np.where(dur > 0, t.speed[rows] / np.where(dur > 0, dur, 1.0), 0.0)
            size = g.size
            num = np.bincount(groups, w * rate, size)
            den = np.bincount(groups, w, size)
            plain = np.bincount(groups, rate, size) / np.maximum(np.bincount(groups, None, size),
                                                                  1)
            group_rate = np.where(den > 1e-12, num / np.where(den > 1e-12, den, 1.0), plain)
            live = plan.group_rows
            moving = live[~g.ended[live]]
            phase = g.phase[moving] + dt * group_rate[moving]
            loop = g.loop[moving]
            phase[loop] %= 1.0
            done = ~loop & (phase >= 1.0 - PHASE_EPSILON)
            g.phase[moving] = np.minimum(phase, 1.0)
            # by avatar (in the order they were made), then oldest first: the order a saved
            # state's clips end in too
            finished = moving[done]
            for group in finished[np.lexsort((g.order[finished], g.avatar[finished]))].tolist():
                g.ended[group] = True
                ended.extend(self._ended(group))
            for row in faded_out.tolist():
                if self.layers.used[row] and not self._current(row):
                    self._drop_layer(row)
                    self._dirty = True
        return ended

    def _ended(self, group: int) -> list[AnimationEnded]:
        key = int(self.groups.avatar[group])
        names = [self._names[r] for r in sorted(self._group_layers(group),
                                                key=lambda r: self.layers.order[r])]
        animator = self.animators.get(key)
        if animator is not None and animator.group == group and animator.queue:
            self._start(animator, animator.queue.popleft())
        return [AnimationEnded(key, name) for name in names]

    def _current_plan(self) -> _Plan:
        if self._dirty or self._plan is None or self._plan.library_version != \
                self.library.version:
            self._plan = _Plan(self)
            self._dirty = False
        return self._plan

    def evaluate(self) -> tuple[np.ndarray, _Plan]:
        """Every avatar's nodes in the model frame ``(rows, 4, 4)`` (each animator's
        nodes from ``animator.row``) and the plan that laid them out (its ``palettes``
        turns them into joint matrices)."""
        plan = self._current_plan()
        return plan.evaluate(self), plan


class _Plan:
    """Index arrays for one layout of layers and avatars (rebuilt when it changes).

    Only the rows some layer animates are sampled and blended (each avatar's *animated
    rows*: node and path pairs its clips have tracks for); every other row keeps the rest
    pose. Hierarchies are composed over the nodes sorted by depth, each depth one slice.
    """

    def __init__(self, mixer: Mixer) -> None:
        lib = mixer.library.packed()
        self.library_version = mixer.library.version
        t = mixer.layers
        n = t.size
        used = np.flatnonzero(t.used[:n])
        animators = list(mixer.animators.values())
        index = {a.key: i for i, a in enumerate(animators)}
        used = used[np.isin(t.avatar[used], list(index))] if len(used) else used
        # layers by avatar (in the animators' order), then by when they started
        owner = np.array([index[int(a)] for a in t.avatar[used]], np.int64)
        sort = np.lexsort((t.order[used], owner)) if len(used) else np.zeros(0, np.int64)
        self.layer_rows = used[sort]
        self.layer_avatar = layer_avatar = owner[sort]
        self.group_rows = np.unique(t.group[self.layer_rows])
        self._avatars(animators)
        clips = [mixer.library.clips[int(c)] for c in t.clip[self.layer_rows]]
        ground = []
        for a, clip, row in zip(layer_avatar, clips, self.layer_rows, strict=True):
            setting = animators[a].settings.get(mixer._names[int(row)])
            given = None if setting is None else setting.ground_speed
            ground.append(clip.ground_speed if given is None else given)
        self.layer_ground_speed = np.array(ground, np.float64)
        # every track of every layer's clip; each avatar's animated rows
        tracks = [np.arange(c.first, c.stop) for c in clips]
        q_track = np.concatenate(tracks) if tracks else np.zeros(0, np.int64)
        q_layer = np.repeat(np.arange(len(clips)), [len(x) for x in tracks]).astype(np.int64)
        q_row = lib.track_node[q_track] * 3 + lib.track_path[q_track]  # within its rig
        animated = [np.unique(q_row[layer_avatar[q_layer] == a]) for a in range(len(animators))]
        sizes = np.array([len(x) for x in animated], np.int64)
        avatar_start = np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
        self.sparse_rest = np.concatenate(
            [a.rig.rest[rows] for a, rows in zip(animators, animated, strict=True)]) \
            if animators else np.zeros((0, 4))
        self.sparse_full = np.concatenate(
            [a.row * 3 + rows for a, rows in zip(animators, animated, strict=True)]) \
            if animators else np.zeros(0, np.int64)
        layer_size = sizes[layer_avatar]
        self.layer_start = np.concatenate([[0], np.cumsum(layer_size)[:-1]]).astype(np.int64)
        self.layer_rest = np.concatenate([self.sparse_rest[avatar_start[a]:avatar_start[a] + m]
                                          for a, m in zip(layer_avatar, layer_size,
                                                          strict=True)]) \
            if len(layer_avatar) else np.zeros((0, 4))

        def slot(layer: np.ndarray, row: np.ndarray) -> np.ndarray:
            """Where (layer, rig row) sits in the layers' sparse pose array."""
            a = layer_avatar[layer]
            return self.layer_start[layer] + np.array(
                [np.searchsorted(animated[x], r) for x, r in zip(a, row, strict=True)],
                np.int64).reshape(-1)

        self._queries(lib, q_track, q_layer, slot(q_layer, q_row))
        # root motion taken off, per layer whose clip travels
        moving = np.array([i for i, c in enumerate(clips) if np.any(c.travel_local)], np.int64)
        self.rm_layer = moving
        self.rm_dst = slot(moving, np.array([clips[i].root_node * 3 for i in moving], np.int64))
        self.rm_local = np.array([clips[i].travel_local for i in moving]).reshape(-1, 3)
        self.rm_duration = np.array([clips[i].duration for i in moving], np.float64)
        self._rounds(len(animators), layer_size, avatar_start, animated)

    def _queries(self, lib: Any, q_track: np.ndarray, q_layer: np.ndarray,
                 q_dst: np.ndarray) -> None:
        """The sampling queries (a track of a layer's clip, and where its value goes),
        grouped by how they are interpolated (lerp, slerp, cubic): each group a slice, so
        its rows are views, not copies."""
        path, interp = lib.track_path[q_track], lib.track_interp[q_track]
        plain = interp != CUBIC
        groups = (plain & (path != ROTATION), plain & (path == ROTATION), ~plain)
        by_kind = np.concatenate([np.flatnonzero(g) for g in groups])
        q_track, q_layer, q_dst = q_track[by_kind], q_layer[by_kind], q_dst[by_kind]
        path, interp = path[by_kind], interp[by_kind]
        bounds = np.cumsum([0] + [int(g.sum()) for g in groups])
        self.q_lin, self.q_rot, self.q_cubic = (
            slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:], strict=True))
        self.q_layer = q_layer
        self.q_first = lib.track_first_time[q_track]
        self.q_last = lib.track_last_time[q_track]
        self.q_base = lib.track_base[q_track]
        self.q_lo = lib.track_lo[q_track]
        self.q_hi = lib.track_hi[q_track]
        self.q_end = lib.track_start[q_track] + lib.track_count[q_track] - 1
        self.q_dst = q_dst
        self.q_step = np.flatnonzero(interp == STEP)
        self.q_cubic_rot = path[self.q_cubic] == ROTATION

    def _rounds(self, avatars: int, layer_size: np.ndarray, avatar_start: np.ndarray,
                animated: list[np.ndarray]) -> None:
        """Blending rounds: the k-th layer of every avatar with at least k, its animated
        rows (translations and scales lerped, rotations slerped)."""
        layer_avatar = self.layer_avatar
        counts = np.bincount(layer_avatar, minlength=avatars)
        self.first_layer = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
        layer_seq = np.arange(len(layer_avatar)) - self.first_layer[layer_avatar]
        self.rounds = []
        for k in range(int(counts.max()) if len(counts) else 0):
            layers = np.flatnonzero(layer_seq == k)
            m = layer_size[layers]
            offsets = np.concatenate([np.arange(x) for x in m]).astype(np.int64)
            which = np.repeat(layers, m)
            dst = np.repeat(avatar_start[layer_avatar[layers]], m) + offsets
            src = self.layer_start[which] + offsets
            rot = np.concatenate([animated[layer_avatar[x]] % 3 == ROTATION for x in layers])
            self.rounds.append((dst, src, dst[~rot], src[~rot], which[~rot], dst[rot],
                                src[rot], which[rot], layers))

    def _avatars(self, animators: list[Animator]) -> None:
        """Each avatar's nodes as a block (``animator.row``), their rest pose, the depth
        order the hierarchy is composed in, and where the palettes come from."""
        row = 0
        rest, parents, depth, palette_rows, ibms = [], [], [], [], []
        self.palette_offsets: dict[int, int] = {}
        joints = 0
        for a in animators:
            a.row = row
            rig = a.rig
            rest.append(rig.rest)
            parents.append(np.where(rig.parents >= 0, rig.parents + row, -1))
            depth.append(rig.depth)
            palette_rows.append(rig.model.palette_nodes + row)
            ibms.append(rig.model.inverse_bind)
            self.palette_offsets[a.key] = joints
            joints += rig.joints
            row += rig.nodes
        self.rows = row
        self.avatar_rest = np.concatenate(rest) if rest else np.zeros((0, 4))
        self.parent = (np.concatenate(parents) if parents else np.zeros(0)).astype(np.int64)
        level = np.concatenate(depth) if depth else np.zeros(0, np.int64)
        self.order = np.argsort(level, kind="stable").astype(np.int64)  # parents first
        self.palette_rows = (np.concatenate(palette_rows) if palette_rows else np.zeros(
            0)).astype(np.int64)
        self.inverse_bind = np.ascontiguousarray(
            np.concatenate(ibms) if ibms else np.zeros((0, 4, 4)), np.float64)

    def evaluate(self, mixer: Mixer) -> np.ndarray:
        """Every node's model-frame matrix: the layers sampled at their times, blended
        per avatar onto its rest pose, composed down the hierarchy."""
        t = mixer.layers
        rows = self.layer_rows
        layer_time = mixer.groups.phase[t.group[rows]] * t.duration[rows]
        pose = self.layer_rest.copy()
        if len(self.q_layer):
            pose[self.q_dst] = self._sample(mixer.library, layer_time)
        if len(self.rm_layer):
            frac = layer_time[self.rm_layer] / self.rm_duration
            pose[self.rm_dst, :3] -= frac[:, None] * self.rm_local
        sparse = self.sparse_rest.copy()
        if len(rows):
            self._blend(t.weight[rows], len(mixer.animators), pose, sparse)
        full = self.avatar_rest.copy()
        full[self.sparse_full] = sparse
        return self._hierarchy(full)

    def _sample(self, lib: Any, layer_time: np.ndarray) -> np.ndarray:
        """Each query's value at its layer's time: lerp, slerp (angles worked out when the
        library was packed) or cubic Hermite between the keys around it."""
        tq = np.clip(layer_time[self.q_layer], self.q_first, self.q_last)
        i = np.searchsorted(lib.key_search, self.q_base + tq, side="right") - 1
        i = np.clip(i, self.q_lo, self.q_hi)
        i1 = np.minimum(i + 1, self.q_end)
        k0, k1 = lib.key_time[i], lib.key_time[i1]
        span = k1 - k0
        alpha = np.clip(np.divide(tq - k0, span, out=np.zeros_like(span), where=span > 0),
                        0.0, 1.0)
        alpha[self.q_step] = np.floor(alpha[self.q_step])
        v0, v1 = lib.key_value[i], lib.key_value[i1]
        out = np.empty_like(v0)
        lin = self.q_lin
        out[lin] = v0[lin] + alpha[lin, None] * (v1[lin] - v0[lin])
        rot = self.q_rot
        if rot.stop > rot.start:
            k, a = i[rot], alpha[rot]
            theta, inv, near = lib.key_theta[k], lib.key_inv_sin[k], lib.key_near[k]
            w0 = np.where(near, 1.0 - a, np.sin((1.0 - a) * theta) * inv)
            w1 = np.where(near, a, np.sin(a * theta) * inv) * lib.key_sign[k]
            # unit keys (as the reader leaves them) slerp to unit quaternions
            out[rot] = w0[:, None] * v0[rot] + w1[:, None] * v1[rot]
        c = self.q_cubic
        if c.stop > c.start:
            s = span[c, None]
            value = hermite(v0[c], lib.key_out[i[c]] * s, v1[c], lib.key_in[i1[c]] * s,
                            alpha[c])
            value[self.q_cubic_rot] = quat_normalize(value[self.q_cubic_rot])
            out[c] = value
        return out

    def _blend(self, w: np.ndarray, avatars: int, pose: np.ndarray,
               sparse: np.ndarray) -> None:
        """Blend each avatar's layers (weights ``w``) onto its rest pose in ``sparse``,
        animated rows only, round by round."""
        running = np.maximum(0.0, 1.0 - np.bincount(self.layer_avatar, w, avatars))
        for dst, src, ts_dst, ts_src, ts_which, r_dst, r_src, r_which, layers in self.rounds:
            owners = self.layer_avatar[layers]
            running[owners] += w[layers]
            f_layer = np.divide(w[layers], running[owners], out=np.zeros(len(layers)),
                                where=running[owners] > 0)
            if np.all(f_layer == 1.0):  # the usual first round: nothing to mix with
                sparse[dst] = pose[src]
                continue
            factor = np.zeros(len(w))
            factor[layers] = f_layer
            sparse[ts_dst] += factor[ts_which][:, None] * (pose[ts_src] - sparse[ts_dst])
            sparse[r_dst] = fast_slerp(sparse[r_dst], pose[r_src], factor[r_which])

    def _hierarchy(self, pose: np.ndarray) -> np.ndarray:
        """Model-frame matrices of every node, composed down the tree (parents first)."""
        world = np.empty((self.rows, 4, 4))
        _compose.compose(np.ascontiguousarray(pose.reshape(-1, 12)), self.parent, self.order,
                         world)
        return world

    def palettes(self, world: np.ndarray) -> np.ndarray:
        """Every avatar's joint matrices ``(J, 4, 4)``, in ``palette_offsets`` order."""
        out = np.empty((len(self.palette_rows), 4, 4))
        _compose.palettes(world, self.palette_rows, self.inverse_bind, out)
        return out


def fast_slerp(q0: np.ndarray, q1: np.ndarray, t: np.ndarray) -> np.ndarray:
    """:func:`engine.rotation.slerp` for rows ``(n, 4)`` and weights ``(n,)``, the short
    way, in fewer numpy passes (the evaluator's inner loop); equal to it to rounding."""
    dot = np.einsum("ij,ij->i", q0, q1)
    sign = np.where(dot < 0.0, -1.0, 1.0)
    dot = np.minimum(dot * sign, 1.0)
    theta = np.arccos(dot)
    sin_theta = np.sin(theta)
    near = sin_theta < 1e-6
    inv = np.divide(1.0, sin_theta, out=np.zeros_like(sin_theta), where=~near)
    w0 = np.where(near, 1.0 - t, np.sin((1.0 - t) * theta) * inv)
    w1 = np.where(near, t, np.sin(t * theta) * inv) * sign
    out = w0[:, None] * q0 + w1[:, None] * q1
    return out / np.sqrt(np.einsum("ij,ij->i", out, out))[:, None]
