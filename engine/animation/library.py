"""Rigs and their clips packed into flat arrays, so every avatar's every channel is sampled
by a handful of numpy calls.

A :class:`Rig` is a skinned model's node hierarchy (parents, depth, rest pose) and palette;
the :class:`Library` holds every rig's clips as *tracks* (one animated property of one
node) whose keys sit end to end in one array. Key times are stored twice: as written, and
shifted by a per-track base so that all tracks' keys form one increasing sequence — one
``searchsorted`` then finds the key of every (track, time) query at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.assets.skinned import PATHS, SkinnedModel

#: Track path codes, in the order a pose row stores them.
TRANSLATION, ROTATION, SCALE = 0, 1, 2
#: Interpolation codes.
LINEAR, STEP, CUBIC = 0, 1, 2
_INTERP = {"LINEAR": LINEAR, "STEP": STEP, "CUBICSPLINE": CUBIC}
#: A clip's root is taken as travelling (its horizontal motion becomes the avatar's) when
#: it moves more than this fraction of the model's height per loop.
ROOT_MOTION_FRACTION = 0.05


@dataclass(frozen=True, slots=True)
class ClipInfo:
    """One clip of one rig in the library: its tracks ``[first, stop)``, its length, and
    the horizontal distance its root travels per loop (glTF frame; zero when in place)."""

    rig: int
    name: str
    duration: float
    first: int
    stop: int
    root_node: int
    travel: np.ndarray
    #: ``travel`` in the root's parent frame: what is taken off its translation per loop
    travel_local: np.ndarray

    @property
    def ground_speed(self) -> float:
        """Metres per second (model units) the clip walks at, played at speed 1."""
        return float(np.linalg.norm(self.travel)) / self.duration if self.duration > 0 else 0.0


@dataclass(frozen=True, slots=True)
class Rig:
    """A model's hierarchy as the evaluator needs it."""

    index: int
    model: SkinnedModel
    parents: np.ndarray
    depth: np.ndarray
    #: rest pose rows ``(nodes * 3, 4)``: translation, rotation, scale per node (padded)
    rest: np.ndarray
    clips: dict[str, int]  # clip name -> library clip id

    @property
    def nodes(self) -> int:
        return len(self.parents)

    @property
    def joints(self) -> int:
        return len(self.model.palette_nodes)


def pose_rows(t: np.ndarray, r: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Translation, rotation, scale per node as pose rows ``(n * 3, 4)``."""
    out = np.zeros((len(t), 3, 4))
    out[:, TRANSLATION, :3] = t
    out[:, ROTATION] = r
    out[:, SCALE, :3] = s
    return out.reshape(-1, 4)


class Library:
    """Every rig and clip in use, packed. Grows as models are added; never shrinks (a run
    uses a handful of models)."""

    def __init__(self) -> None:
        self.rigs: list[Rig] = []
        self.clips: list[ClipInfo] = []
        self._by_model: dict[int, int] = {}
        self._track_parts: list[tuple[np.ndarray, ...]] = []
        self._key_parts: list[tuple[np.ndarray, ...]] = []
        self._keys = 0
        self._base = 0.0
        self.version = 0
        self._packed_version = -1
        self._pack()

    def rig_for(self, model: SkinnedModel) -> Rig:
        """The rig of ``model`` (made and its clips packed on first use)."""
        found = self._by_model.get(id(model))
        if found is not None and self.rigs[found].model is model:
            return self.rigs[found]
        index = len(self.rigs)
        parents = model.parents
        depth = np.zeros(len(parents), np.int64)
        for i, p in enumerate(parents):
            depth[i] = 0 if p < 0 else depth[p] + 1
        clips = {clip.name: self._add_clip(index, model, clip) for clip in model.clips}
        rig = Rig(index, model, parents, depth,
                  pose_rows(model.rest_translation, model.rest_rotation, model.rest_scale), clips)
        self.rigs.append(rig)
        self._by_model[id(model)] = index
        self.version += 1
        return rig

    def _add_clip(self, rig: int, model: SkinnedModel, clip: object) -> int:
        from engine.assets.skinned import AnimationClip

        assert isinstance(clip, AnimationClip)
        first = sum(len(p[0]) for p in self._track_parts)
        starts, counts, bases, interps, paths, nodes = [], [], [], [], [], []
        times, searches, values, ins, outs = [], [], [], [], []
        for ch in clip.channels:
            k = len(ch.times)
            width = ch.values.shape[-1]
            starts.append(self._keys)
            counts.append(k)
            bases.append(self._base)
            interps.append(_INTERP[ch.interpolation])
            paths.append(PATHS.index(ch.path))
            nodes.append(ch.node)
            times.append(ch.times)
            searches.append(ch.times + self._base)
            v, vin, vout = np.zeros((k, 4)), np.zeros((k, 4)), np.zeros((k, 4))
            if ch.interpolation == "CUBICSPLINE":
                vin[:, :width], v[:, :width], vout[:, :width] = (ch.values[:, 0], ch.values[:, 1],
                                                                 ch.values[:, 2])
            else:
                v[:, :width] = ch.values
            values.append(v)
            ins.append(vin)
            outs.append(vout)
            self._keys += k
            # the next track's keys all lie after this one's, whatever their times
            self._base = float(searches[-1][-1]) + 1.0 + abs(float(ch.times[0]))
        self._track_parts.append(tuple(np.asarray(a) for a in (
            starts, counts, bases, interps, paths, nodes)))
        self._key_parts.append((np.concatenate(times), np.concatenate(searches),
                                np.concatenate(values), np.concatenate(ins),
                                np.concatenate(outs)))
        root, travel, local = _root_motion(model, clip)
        self.clips.append(ClipInfo(rig, clip.name, float(clip.duration), first,
                                   first + len(clip.channels), root, travel, local))
        return len(self.clips) - 1

    def packed(self) -> Library:
        """Make the flat arrays current (after rigs were added); returns self."""
        if self._packed_version != self.version:
            self._pack()
        return self

    def _pack(self) -> None:
        tracks = list(zip(*self._track_parts, strict=True)) if self._track_parts else [[]] * 6
        keys = list(zip(*self._key_parts, strict=True)) if self._key_parts else [[]] * 5

        def cat(parts: list[np.ndarray] | tuple, dtype: type, shape: tuple[int, ...] = ()
                ) -> np.ndarray:
            return np.concatenate(parts).astype(dtype) if len(parts) else np.zeros(
                (0, *shape), dtype)

        self.track_start = cat(tracks[0], np.int64)
        self.track_count = cat(tracks[1], np.int64)
        self.track_base = cat(tracks[2], np.float64)
        self.track_interp = cat(tracks[3], np.int64)
        self.track_path = cat(tracks[4], np.int64)
        self.track_node = cat(tracks[5], np.int64)
        self.key_time = cat(keys[0], np.float64)
        self.key_search = cat(keys[1], np.float64)
        self.key_value = cat(keys[2], np.float64, (4,))
        self.key_in = cat(keys[3], np.float64, (4,))
        self.key_out = cat(keys[4], np.float64, (4,))
        self.track_first_time = self.key_time[self.track_start] if len(self.track_start) \
            else np.zeros(0)
        last = self.track_start + self.track_count - 1
        self.track_last_time = self.key_time[last] if len(last) else np.zeros(0)
        self.track_lo = self.track_start
        self.track_hi = np.maximum(self.track_start, last - 1)
        self._slerp_constants(last)
        self._packed_version = self.version

    def _slerp_constants(self, last: np.ndarray) -> None:
        """What slerp from each key to the next of its track needs besides the weight, as
        :func:`engine.animation.mixer.fast_slerp` works it out (so results are the same to
        the bit): the angle, one over its sine (0 where the two keys nearly coincide: a
        linear mix is taken there) and the sign that takes the short way. The last key of
        a track pairs with itself."""
        count = len(self.key_value)
        following = np.minimum(np.arange(count) + 1, max(count - 1, 0))
        following[last] = last
        q0, q1 = self.key_value, self.key_value[following]
        dot = np.einsum("ij,ij->i", q0, q1)
        self.key_sign = np.where(dot < 0.0, -1.0, 1.0)
        self.key_theta = np.arccos(np.minimum(dot * self.key_sign, 1.0))
        sin_theta = np.sin(self.key_theta)
        self.key_near = sin_theta < 1e-6
        self.key_inv_sin = np.divide(1.0, sin_theta, out=np.zeros_like(sin_theta),
                                     where=~self.key_near)


def _root_motion(model: SkinnedModel, clip: object) -> tuple[int, np.ndarray, np.ndarray]:
    """The highest node whose translation the clip animates, and the horizontal distance
    (glTF X and Z) it travels from the clip's start to its end: in the model's frame, and
    in its parent's (what is taken off its translation to keep it in place). Zero when it
    stays in place."""
    from engine.animation.sampling import rest_globals, sample_channel
    from engine.assets.skinned import AnimationClip

    assert isinstance(clip, AnimationClip)
    none = (-1, np.zeros(3), np.zeros(3))
    moving = [ch for ch in clip.channels if ch.path == "translation"]
    if not moving or clip.duration <= 0:
        return none
    depth = np.zeros(len(model.parents), np.int64)
    for i, p in enumerate(model.parents):
        depth[i] = 0 if p < 0 else depth[p] + 1
    root = min(moving, key=lambda ch: (depth[ch.node], ch.node))
    parent = int(model.parents[root.node])
    linear = rest_globals(model)[parent, :3, :3] if parent >= 0 else np.eye(3)
    delta = linear @ (sample_channel(root, clip.duration) - sample_channel(root, 0.0))
    travel = np.array([delta[0], 0.0, delta[2]])
    extent = float(np.ptp(np.concatenate([p.vertices for p in model.parts]), axis=0).max())
    if np.linalg.norm(travel) < ROOT_MOTION_FRACTION * extent:
        return none
    return root.node, travel, np.linalg.solve(linear, travel)
