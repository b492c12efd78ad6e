"""Keyframe interpolation and transforms: the reference a test can read line by line, and
the batched forms the evaluator runs over every avatar at once.

glTF's rules: before the first key a channel holds its first value, after the last its last;
LINEAR interpolates translations and scales linearly and rotations by slerp; STEP holds a
key until the next; CUBICSPLINE is a Hermite spline whose tangents are scaled by the key
interval (rotations normalised afterwards).
"""

from __future__ import annotations

import numpy as np

from engine.assets.skinned import Channel, SkinnedModel
from engine.rotation import compose, quat_normalize, slerp


def sample_channel(channel: Channel, t: float) -> np.ndarray:
    """One channel's value at time ``t`` (the plain reference)."""
    times = channel.times
    cubic = channel.interpolation == "CUBICSPLINE"
    values = channel.values[:, 1] if cubic else channel.values
    if t <= times[0] or len(times) == 1:
        return values[0].copy()
    if t >= times[-1]:
        return values[-1].copy()
    i = int(np.searchsorted(times, t, side="right")) - 1
    span = times[i + 1] - times[i]
    s = (t - times[i]) / span
    if channel.interpolation == "STEP":
        return values[i].copy()
    if cubic:
        out = hermite(values[i], channel.values[i, 2] * span, values[i + 1],
                      channel.values[i + 1, 0] * span, np.float64(s))
        return quat_normalize(out) if channel.path == "rotation" else out
    if channel.path == "rotation":
        return slerp(values[i], values[i + 1], s)
    return values[i] + s * (values[i + 1] - values[i])


def hermite(p0: np.ndarray, m0: np.ndarray, p1: np.ndarray, m1: np.ndarray, s: np.ndarray
            ) -> np.ndarray:
    """Cubic Hermite spline between ``p0`` and ``p1`` with (interval-scaled) tangents."""
    s = np.asarray(s, np.float64)
    if s.ndim:
        s = s[..., None]
    s2, s3 = s * s, s * s * s
    return ((2 * s3 - 3 * s2 + 1) * p0 + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * p1
            + (s3 - s2) * m1)


def global_matrices(parents: np.ndarray, local: np.ndarray) -> np.ndarray:
    """Each node's transform in the model frame from local ones (parents come first)."""
    out = np.empty_like(local)
    for i, p in enumerate(parents):
        out[i] = local[i] if p < 0 else out[p] @ local[i]
    return out


def rest_globals(model: SkinnedModel) -> np.ndarray:
    """The model's nodes in their rest pose, model frame ``(nodes, 4, 4)``."""
    return global_matrices(model.parents, compose(
        model.rest_translation, model.rest_rotation, model.rest_scale))


def clip_pose(model: SkinnedModel, clip_name: str | None, t: float
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every node's local translation, rotation, scale with one clip at time ``t``
    (reference: channel by channel; nodes the clip does not animate keep their rest)."""
    tr, rot, sc = (model.rest_translation.copy(), model.rest_rotation.copy(),
                   model.rest_scale.copy())
    clip = None if clip_name is None else model.clip(clip_name)
    for ch in () if clip is None else clip.channels:
        target = {"translation": tr, "rotation": rot, "scale": sc}[ch.path]
        target[ch.node] = sample_channel(ch, t)
    return tr, rot, sc


def joint_matrices(model: SkinnedModel, local: np.ndarray) -> np.ndarray:
    """The palette ``(joints, 4, 4)``: each joint's global transform times its inverse
    bind matrix (what moves a bind-pose vertex to its posed place)."""
    return global_matrices(model.parents, local)[model.palette_nodes] @ model.inverse_bind
