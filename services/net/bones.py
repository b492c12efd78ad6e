"""Avatars' skeletons on the wire: each joint's skinning matrix as one more pose.

A node runs no physics, so it cannot follow the ground, bend legs by IK or walk paths the
way the server's avatars plugin does; it is sent what the server draws instead. Every
joint matrix of an avatar's palette (:class:`engine.animation.Palettes`: the joint's
model-frame matrix times its inverse bind matrix) is a rigid motion for the skeletons
glTF rigs animate (the armature's scale cancels against the inverse bind), so it travels
as a position and a quaternion, a "body" of the pose stream (:mod:`services.net.codec`)
whose id is the avatar's net id and the joint's index with :data:`BONE_FLAG` set. The
codec then sends only what changed, against what the nodes hold, and the node's
:class:`~services.net.follow.Follower` interpolates joints as it does bodies. Bone ids sort
after every body's, so one split separates them.

>>> import numpy as np
>>> ids = bone_ids(np.array([7]), np.array([2]))
>>> [hex(int(i)) for i in ids]
['0x80001c00', '0x80001c01']
>>> owners, joints = split_bone_ids(ids)
>>> owners.tolist(), joints.tolist()
([7, 7], [0, 1])
>>> m = np.zeros((2, 3, 4), np.float32); m[:, :, :3] = np.eye(3); m[1, :, 3] = (1, 2, 3)
>>> poses, stretch = palette_poses(m)
>>> poses[1].tolist(), stretch.tolist()
([1.0, 2.0, 3.0, 1.0, 0.0, 0.0, 0.0], [0.0, 0.0])
>>> bool(np.allclose(palette_matrices(poses), m))
True
"""

from __future__ import annotations

import numpy as np

from engine.rotation import matrices_to_quats, quat_to_matrix

#: Set in every bone id: bodies' net ids stay below it.
BONE_FLAG = 1 << 31
#: Bits of a bone id that hold the joint's index (an avatar has at most 1024 joints).
JOINT_BITS = 10
MAX_JOINTS = 1 << JOINT_BITS
#: Avatars' net ids must fit the bits left (about two million objects).
MAX_AVATAR_NET = 1 << (31 - JOINT_BITS)


def bone_ids(nets: np.ndarray, counts: np.ndarray) -> np.ndarray:
    """The ids of avatars ``nets``' joints (``counts`` each), sorted when ``nets`` are."""
    nets = np.asarray(nets, np.int64)
    counts = np.asarray(counts, np.int64)
    owner = np.repeat(nets, counts)
    starts = np.repeat(np.cumsum(counts) - counts, counts)
    joint = np.arange(int(counts.sum()), dtype=np.int64) - starts
    return (BONE_FLAG | (owner << JOINT_BITS) | joint).astype(np.uint32)


def split_bone_ids(ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(avatar net id, joint index) of each bone id."""
    ids = np.asarray(ids, np.int64) & ~BONE_FLAG
    return ids >> JOINT_BITS, ids & (MAX_JOINTS - 1)


def palette_poses(matrices: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Joint matrices ``(J, 3, 4)`` as poses ``(J, 7)`` (position, quaternion ``w x y z``)
    and how far each joint's most stretched axis is from unit length (a scaled joint,
    which a pose cannot carry: the caller says so)."""
    m = np.asarray(matrices, np.float64)
    linear = m[:, :, :3]
    lengths = np.linalg.norm(linear, axis=1)
    stretch = np.abs(lengths - 1.0).max(axis=1)
    poses = np.empty((len(m), 7))
    poses[:, :3] = m[:, :, 3]
    poses[:, 3:] = matrices_to_quats(linear / np.where(lengths > 0, lengths, 1.0)[:, None, :])
    return poses, stretch


def palette_matrices(poses: np.ndarray) -> np.ndarray:
    """Poses ``(J, 7)`` back as joint matrices ``(J, 3, 4)`` float32, as the renderer
    takes them."""
    poses = np.asarray(poses, np.float64)
    out = np.empty((len(poses), 3, 4), np.float32)
    out[:, :, :3] = quat_to_matrix(poses[:, 3:7])
    out[:, :, 3] = poses[:, :3]
    return out
