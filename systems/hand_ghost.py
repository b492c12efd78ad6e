"""The ghost finger: where a physical finger is blocked, the tracked one is drawn see-through.

The paper's real/virtual discrepancy rule (section 5.4) shows a hand pulled away from its
tracker see-through and on top of everything, so the person sees both where their hand
is and where the virtual one was stopped. A fingered hand does the same per finger: a
finger whose physical tip is farther than :data:`GHOST_AFTER` from its tracked tip
(``HandState.finger_deviation``, filled by the hands plugin) is drawn a second time as
the tracker has it — each bone a capsule between two consecutive tracked joints, as thick
as their radii — in the hand's colour at the see-through alpha, as an overlay (never
hidden behind the object that stops it).

The ghost's bodies are Visual-only entities (no physics, never saved in a state), made
the first time one of a hand's fingers is blocked and moved every frame in RENDER,
before the renderer reads the poses. They show the hand's input hand through its
``Frame`` object, as ``hand:joint`` reads it (:mod:`services.input.hand_query`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from components import Hand, HandState, Shape, Transform, Visual
from engine.system import Phase, System
from services.input import InputState
from services.input.events import FINGERS, HAND_JOINTS, HandJoints
from services.input.hand_query import tracked_hand
from systems.hand_fingers import joint_arrays

if TYPE_CHECKING:
    from engine.app import Engine

#: A finger is drawn as a ghost when its tip is farther than this (m) from the tracked one.
GHOST_AFTER = 0.01
#: A ghost bone's capsule is remade when the tracked bone's length or thickness changed by
#: more than this (m): a tracker's bone lengths wobble by less.
RESIZE_AFTER = 0.001
#: The ghost's colour where the hand has no look of its own.
GHOST_COLOR = (0.8, 0.8, 0.8)


def _bones() -> tuple[tuple[int, int, int], ...]:
    """(finger index, joint a, joint b) of every bone, metacarpal to tip, thumb first."""
    out = []
    for f, name in enumerate(FINGERS):
        first = HAND_JOINTS.index(f"{name}_metacarpal")
        last = HAND_JOINTS.index(f"{name}_tip")
        out += [(f, j, j + 1) for j in range(first, last)]
    return tuple(out)


BONES = _bones()
_FINGER = np.array([b[0] for b in BONES])
_A = np.array([b[1] for b in BONES])
_B = np.array([b[2] for b in BONES])
#: Each bone from the 26 joints by one product: its far joint less its near one (along),
#: and their mean (its centre, its radius).
_ALONG = np.zeros((len(BONES), len(HAND_JOINTS)))
_ALONG[np.arange(len(BONES)), _B], _ALONG[np.arange(len(BONES)), _A] = 1.0, -1.0
_MEAN = np.abs(_ALONG) / 2.0
#: A direction v's (x, y, z) as (v_z, -v_y, v_x, 0): with 1 added to w, the quaternion
#: of +Z turned onto v, unnormalised.
_HALF_WAY = np.array([[0.0, 0.0, 1.0, 0.0], [0.0, -1.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]])


@dataclass(slots=True, eq=False)
class _Ghost:
    """One hand's ghost: an entity per bone (:data:`BONES` order) and its capsule's size."""

    bones: list[int]
    sizes: np.ndarray  # (bones, 2): radius, length
    shown: bool = False  # whether any of its bones is visible
    #: which bones were shown, in which colour, when their looks were last set
    looks: tuple[np.ndarray, tuple[float, ...]] | None = None


def blocked_fingers(state: HandState, after: float = GHOST_AFTER) -> np.ndarray:
    """Which fingers (thumb to little) are blocked: their tip deviation beyond ``after``."""
    deviation = np.zeros(len(FINGERS))
    given = np.asarray(state.finger_deviation[:len(FINGERS)], dtype=float)
    deviation[:len(given)] = given
    return deviation > after


def bone_capsules(joints: HandJoints) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each bone's capsule: centre (n, 3), orientation (n, 4) and size (n, 2: radius,
    length between the joints' centres, the caps reaching round them)."""
    p = joint_arrays(joints)[0]
    along = _ALONG @ p
    sizes = np.empty((len(BONES), 2))
    sizes[:, 1] = np.sqrt(np.einsum("ij,ij->i", along, along))
    quats = _up_to(along / np.maximum(sizes[:, 1:], 1e-12))
    sizes[:, 0] = np.maximum(_MEAN @ joints.radii, 1e-4)
    return _MEAN @ p, quats, sizes


def _up_to(v: np.ndarray) -> np.ndarray:
    """The smallest turns (n, 4) of +Z onto unit directions ``v``, as quaternions built
    straight from the half-way vector (every frame, for every bone: no matrices); a bone
    along -Z (or of no length) turns about X."""
    q = v @ _HALF_WAY
    q[:, 0] += 1.0
    norm = np.sqrt(np.einsum("ij,ij->i", q, q))
    if norm.min() < 1e-6:  # rare: along -Z
        flipped = norm < 1e-6
        q[flipped] = (0.0, 1.0, 0.0, 0.0)
        norm[flipped] = 1.0
    return q / norm[:, None]


class GhostFingerSystem(System):
    """RENDER, before the renderer: each fingered hand's blocked fingers drawn as ghosts."""

    phase = Phase.RENDER
    before = ("RenderSystem",)
    reads = (Hand, HandState, Visual, Transform)
    writes = (Visual, Transform)

    def __init__(self, alpha: float, threshold: float = GHOST_AFTER) -> None:
        self.alpha = alpha
        self.threshold = threshold
        self.ghosts: dict[int, _Ghost] = {}

    def run(self, engine: Engine, dt: float) -> None:
        world = engine.world
        for hand in [h for h in self.ghosts if not world.entity_exists(h)]:
            for bone in self.ghosts.pop(hand).bones:
                engine.despawn(bone)
        inputs = engine.try_resource(InputState)
        for entity, (_, state) in world.get_components(Hand, HandState):
            ghost = self.ghosts.get(entity)
            if ghost is None and not any(d > self.threshold for d in state.finger_deviation):
                continue  # a palm-only hand, or no finger blocked (in plain Python: the
                # common case, every frame)
            blocked = blocked_fingers(state, self.threshold)
            if ghost is None and not blocked.any():
                continue
            joints = None if inputs is None or not state.tracked else \
                tracked_hand(world, entity, inputs)
            if joints is None:
                blocked[:] = False
                if ghost is None:
                    continue
            look = world.try_component(entity, Visual)
            rgb = GHOST_COLOR if look is None else tuple(look.color[:3])
            self._show(engine, entity, joints, blocked[_FINGER], (*rgb, self.alpha))

    def _show(self, engine: Engine, hand: int, joints: HandJoints | None, shown: np.ndarray,
              color: tuple[float, ...]) -> None:
        """Move, resize, colour and show or hide one hand's ghost bones."""
        world = engine.world
        ghost = self.ghosts.get(hand)
        if joints is None:
            assert ghost is not None
            for bone in ghost.bones:
                world.component_for_entity(bone, Visual).visible = False
            ghost.shown, ghost.looks = False, None
            return
        if ghost is not None and not ghost.shown and not shown.any():
            return  # hidden and staying so: nothing to move (most frames of most hands)
        centres, quats, sizes = bone_capsules(joints)
        if ghost is None:
            ghost = self.ghosts[hand] = _Ghost([engine.spawn(
                Transform(centres[i], quats[i]), _look(sizes[i], color, False))
                for i in range(len(BONES))], sizes.copy())
        resized = np.abs(sizes - ghost.sizes).max(axis=1) > RESIZE_AFTER
        poses = world.poses
        rows = poses.rows(ghost.bones)  # every bone moved in one go (hidden ones too)
        if (rows < 0).any():
            raise LookupError(f"hand {hand}: a ghost bone lost its Transform")
        poses.position[rows] = centres
        poses.orientation[rows] = quats
        ghost.shown = bool(shown.any())
        if ghost.looks is not None and not resized.any() and ghost.looks[1] == color and \
                np.array_equal(ghost.looks[0], shown):
            return  # the same bones shown, alike: only moved
        ghost.looks = (shown.copy(), color)
        for i, bone in enumerate(ghost.bones):
            visual = world.component_for_entity(bone, Visual)
            if not shown[i] and not visual.visible:
                continue  # hidden and staying so: sized when shown
            if resized[i]:  # a new Visual: the renderer builds its capsule again
                ghost.sizes[i] = sizes[i]
                world.add_component(bone, _look(sizes[i], color, bool(shown[i])))
            elif visual.visible != shown[i] or tuple(visual.color) != color:
                visual.visible, visual.color = bool(shown[i]), color  # type: ignore[assignment]


def _look(size: np.ndarray, color: tuple[float, ...], visible: bool) -> Visual:
    return Visual(shapes=[Shape("capsule", (float(size[0]), float(size[1])))],
                  color=color, visible=visible, overlay=True,  # type: ignore[arg-type]
                  shadower=False, shadowed=False)
