"""The ghost finger drawn by the EGL renderer: a blocked finger's tracked bones show, see-through
and on top, and only while it is blocked."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from render_helpers import pixel_at

from components import Hand, HandState, Shape, Transform, Visual
from engine.app import Engine, EngineConfig
from engine.rotation import quat_to_matrix
from engine.scene.factory import instantiate
from engine.scene.loader import spec_from_text
from services.input import InputState
from services.input.events import HAND_JOINTS
from services.input.hand_pose import GESTURES, pose_hand
from systems.hand_ghost import BONES, GHOST_AFTER, GhostFingerSystem, bone_capsules
from systems.input import InputPlugin
from systems.render import RenderOptions, RenderPlugin, RenderSystem

W, H = 240, 180
ALPHA = 0.45
WRIST = (-0.09, 0.0, 1.0)
CAMERA = 'Camera { Position [0 -0.35 1.3] LookAt [0 0 1.0] }\n'


def _bone_middle(joints, finger: str) -> tuple[float, float, float]:
    """The middle of a finger's proximal bone (its longest)."""
    a = np.array(joints.positions[HAND_JOINTS.index(f"{finger}_proximal")])
    b = np.array(joints.positions[HAND_JOINTS.index(f"{finger}_proximal") + 1])
    return tuple((a + b) / 2)


@pytest.fixture
def scene(tmp_path: Path):
    opts = RenderOptions(backend="headless", size=(W, H))
    with Engine(EngineConfig(backend="ballistic", fast=True, content_dir=tmp_path),
                plugins=[RenderPlugin(opts), InputPlugin()]) as engine:
        instantiate(engine, spec_from_text(CAMERA, tmp_path))
        ghost = GhostFingerSystem(ALPHA)
        engine.add_system(ghost)
        hand = engine.spawn(Transform(WRIST), Hand(tracker="hand_r", fingers=True),
                            HandState(tracked=True, finger_deviation=(0.0,) * 5))
        # a dark wall the fingers are behind, as an object that stops them would be
        engine.spawn(Transform((0.0, -0.12, 1.0)),
                     Visual(shapes=[Shape("box", (0.6, 0.02, 0.6))], color=(0.1, 0.1, 0.5, 1.0)))
        engine.run(frames=1)
        joints = pose_hand("hand_r", WRIST, (1.0, 0.0, 0.0, 0.0), GESTURES["open"])
        engine.resource(InputState).hands["hand_r"] = joints
        yield engine, hand, joints, ghost


def _frame(engine: Engine, joints) -> dict[str, np.ndarray]:
    engine.run(frames=1)
    renderer = engine.resource(RenderSystem).renderer
    image = renderer.read_pixels()[..., :3]
    return {f: pixel_at(renderer, image, _bone_middle(joints, f))
            for f in ("index", "middle", "little")}


def test_a_blocked_finger_shows_its_ghost_over_what_blocks_it(scene):
    engine, hand, joints, ghost = scene
    state = engine.world.component_for_entity(hand, HandState)
    before = _frame(engine, joints)
    wall = before["index"]
    assert np.allclose(before["middle"], wall, atol=2) and wall[2] > wall[0] + 20
    assert ghost.ghosts == {}  # nothing made until a finger is blocked

    state.finger_deviation = (0.0, 0.03, 0.0, 0.0, 0.0)  # the index stopped 3 cm short
    shown = _frame(engine, joints)
    grey = np.array([0.8, 0.8, 0.8]) * 255
    # drawn over the wall, see-through: ALPHA of the lit grey over the wall behind (at
    # most white's share; an opaque ghost would be grey through and through)
    assert shown["index"][0] > wall[0] + 0.25 * grey[0]
    assert shown["index"][0] <= ALPHA * 255 + (1 - ALPHA) * wall[0] + 2
    assert shown["index"][2] >= (1 - ALPHA) * wall[2] - 2  # the wall shows through
    assert np.allclose(shown["middle"], wall, atol=2)  # a free finger has none
    assert np.allclose(shown["little"], wall, atol=2)

    state.finger_deviation = (0.0, 0.0, GHOST_AFTER * 1.5, 0.0, 0.0)  # now the middle
    moved = _frame(engine, joints)
    assert np.allclose(moved["index"], wall, atol=2)
    assert moved["middle"][0] > wall[0] + 0.25 * grey[0]

    state.finger_deviation = (0.0, 0.0, GHOST_AFTER * 0.9, 0.0, 0.0)  # within: no ghost
    assert np.allclose(_frame(engine, joints)["middle"], wall, atol=2)


def test_the_ghost_follows_the_tracked_joints_and_hides_while_untracked(scene):
    engine, hand, joints, ghost = scene
    state = engine.world.component_for_entity(hand, HandState)
    state.finger_deviation = (0.0, 0.05, 0.0, 0.0, 0.0)
    engine.run(frames=1)
    (made,) = ghost.ghosts.values()
    assert len(made.bones) == len(BONES) == 19
    # each bone a capsule from joint to joint, as thick as the joints
    centres, _, sizes = bone_capsules(joints)
    for i, bone in enumerate(made.bones):
        t = engine.world.component_for_entity(bone, Transform)
        np.testing.assert_allclose(t.position, centres[i], atol=1e-12)
        axis = np.array([0.0, 0.0, 1.0])
        a, b = (np.array(joints.positions[j]) for j in BONES[i][1:])
        np.testing.assert_allclose(quat_to_matrix(t.orientation) @ axis * sizes[i][1],
                                   b - a, atol=1e-9)
    bent = pose_hand("hand_r", WRIST, (1.0, 0.0, 0.0, 0.0), GESTURES["fist"])
    engine.resource(InputState).hands["hand_r"] = bent
    index_tip = made.bones[[i for i, b in enumerate(BONES) if b[2] ==
                            HAND_JOINTS.index("index_tip")][0]]
    engine.run(frames=1)
    t = engine.world.component_for_entity(index_tip, Transform)
    tip, distal = (np.array(bent.positions[HAND_JOINTS.index(n)])
                   for n in ("index_tip", "index_distal"))
    np.testing.assert_allclose(t.position, (tip + distal) / 2, atol=1e-12)
    state.tracked = False  # a lost hand has no tracked finger to show
    engine.run(frames=1)
    assert not any(engine.world.component_for_entity(b, Visual).visible for b in made.bones)
    engine.despawn(hand)  # the ghost goes with its hand
    engine.run(frames=2)
    assert ghost.ghosts == {} and not any(engine.world.entity_exists(b) for b in made.bones)
