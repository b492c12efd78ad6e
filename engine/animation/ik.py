"""Two-bone inverse kinematics on posed skeletons, batched over many chains.

A chain is three nodes ``a`` (hip, shoulder), ``b`` (knee, elbow) and ``c`` (ankle, wrist).
:func:`solve` bends ``b`` so that ``c`` can be as far from ``a`` as the target is, swings
the chain about ``a`` so ``c`` lands on the target, and optionally turns ``c`` to a wanted
orientation (a foot flat on a slope, a hand as a tracker holds it). It works on the
model-frame matrices the mixer made, moving each node's whole subtree, so everything hung
below (toes, fingers, a held box) follows.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from engine.rotation import axis_angle_matrices, from_to

_EPS = 1e-9


@dataclass(frozen=True, slots=True)
class Chains:
    """``n`` chains: the rows of their nodes, and the rows of each node's subtree with the
    chain each belongs to (concatenated)."""

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    sub_a: np.ndarray
    sub_a_chain: np.ndarray
    sub_b: np.ndarray
    sub_b_chain: np.ndarray
    sub_c: np.ndarray
    sub_c_chain: np.ndarray

    def __len__(self) -> int:
        return len(self.a)


def subtree(parents: np.ndarray, root: int) -> np.ndarray:
    """``root`` and every node below it (parents come before children)."""
    inside = np.zeros(len(parents), bool)
    inside[root] = True
    for i in range(root + 1, len(parents)):
        if parents[i] >= 0 and inside[parents[i]]:
            inside[i] = True
    return np.flatnonzero(inside)


def make_chains(items: list[tuple[int, np.ndarray, int, int, int]]) -> Chains:
    """Chains from ``(first row, parents, a, b, c)``: a skeleton laid out from ``first row``
    with these parents, and the three node indices within it."""
    a, b, c = [], [], []
    subs: dict[str, tuple[list[np.ndarray], list[np.ndarray]]] = {k: ([], []) for k in "abc"}
    for i, (row, parents, na, nb, nc) in enumerate(items):
        a.append(row + na)
        b.append(row + nb)
        c.append(row + nc)
        for name, node in (("a", na), ("b", nb), ("c", nc)):
            rows = subtree(parents, node) + row
            subs[name][0].append(rows)
            subs[name][1].append(np.full(len(rows), i))

    def cat(parts: list[np.ndarray]) -> np.ndarray:
        return np.concatenate(parts).astype(np.int64) if parts else np.zeros(0, np.int64)

    return Chains(np.array(a, np.int64), np.array(b, np.int64), np.array(c, np.int64),
                  cat(subs["a"][0]), cat(subs["a"][1]), cat(subs["b"][0]), cat(subs["b"][1]),
                  cat(subs["c"][0]), cat(subs["c"][1]))


def turn(world: np.ndarray, rows: np.ndarray, chain: np.ndarray, rotation: np.ndarray,
         pivot: np.ndarray) -> None:
    """Rotate the matrices at ``rows`` (each of chain ``chain[i]``) by that chain's
    ``rotation`` about its world ``pivot``, in place."""
    r = rotation[chain]
    p = pivot[chain]
    moved = world[rows]
    moved[:, :3, :3] = r @ moved[:, :3, :3]
    moved[:, :3, 3] = np.einsum("nij,nj->ni", r, moved[:, :3, 3] - p) + p
    world[rows] = moved


def solve(world: np.ndarray, chains: Chains, target: np.ndarray,
          end_rotation: np.ndarray | None = None) -> None:
    """Bend and swing each chain so its end ``c`` reaches ``target`` ``(n, 3)`` (as near
    as the bones' lengths allow), in place; ``end_rotation`` ``(n, 3, 3)`` is then the
    orientation given to ``c`` (None: it keeps the one it had, relative to the world)."""
    if not len(chains):
        return
    pa, pb, pc = (world[chains.a, :3, 3], world[chains.b, :3, 3], world[chains.c, :3, 3])
    kept = world[chains.c, :3, :3].copy() if end_rotation is None else end_rotation
    l1 = np.linalg.norm(pb - pa, axis=1)
    l2 = np.linalg.norm(pc - pb, axis=1)
    reach = np.linalg.norm(target - pa, axis=1)
    d = np.clip(reach, np.abs(l1 - l2) + 1e-6, l1 + l2 - 1e-6)
    u, v = pc - pb, pa - pb
    denom = np.maximum(l1 * l2, _EPS)
    now = np.arccos(np.clip(np.einsum("ij,ij->i", u, v) / denom, -1.0, 1.0))
    want = np.arccos(np.clip((l1 * l1 + l2 * l2 - d * d) / (2.0 * denom), -1.0, 1.0))
    axis = np.cross(u, v)
    norm = np.linalg.norm(axis, axis=1, keepdims=True)
    # a straight limb has no bend plane: bend about the knee's own x axis
    fallback = world[chains.b, :3, 0]
    axis = np.where(norm > 1e-6 * denom[:, None], axis / np.maximum(norm, _EPS), fallback)
    axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), _EPS)
    knee = axis_angle_matrices(axis, now - want)
    turn(world, chains.sub_b, chains.sub_b_chain, knee, pb)
    end = world[chains.c, :3, 3]
    swing = from_to(end - pa, target - pa)
    turn(world, chains.sub_a, chains.sub_a_chain, swing, pa)
    current = world[chains.c, :3, :3]
    fix = kept @ np.linalg.inv(current)
    turn(world, chains.sub_c, chains.sub_c_chain, fix, world[chains.c, :3, 3].copy())
