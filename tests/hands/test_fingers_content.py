"""content/hands/fingers.scene replays its recorded 26-joint session: each object is
grasped by contact (no button) and lifted, the long box by both hands."""

from __future__ import annotations

from components import HandState, Transform
from engine import EngineConfig, Phase, system
from engine.content import REPO_ROOT
from engine.scene import check, instantiate, load_spec
from services.input.replay import InputReplayer
from systems import create_engine

CONTENT = REPO_ROOT / "content" / "hands"
OBJECTS = ("cup", "mug", "pen", "ball", "long box")


def test_the_fingered_scene_checks_clean():
    assert [d for d in check(CONTENT / "fingers.scene") if d.is_error] == []


def test_the_fingered_session_grasps_and_lifts_each_object():
    spec = load_spec(CONTENT / "fingers.scene")
    config = EngineConfig(content_dir=CONTENT, fast=True, dt=spec.time_step)
    held: dict[str, set[str]] = {o: set() for o in OBJECTS}
    start: dict[str, float] = {}
    highest: dict[str, float] = {}
    with create_engine(config) as engine:
        engine.add_system(InputReplayer(CONTENT / "fingers.input"))
        ids = instantiate(engine, spec)
        names = {ids[o]: o for o in OBJECTS}
        names[ids["mug handle"]] = "mug"  # the mug is held by its handle

        @system(Phase.POST_PHYSICS, reads=(Transform, HandState))
        def note(e, dt):
            w = e.world
            for hand in ("right hand", "left hand"):
                for obj in w.component_for_entity(ids[hand], HandState).held:
                    if obj in names:
                        held[names[obj]].add(hand)
            for o in OBJECTS:
                z = float(w.component_for_entity(ids[o], Transform).position[2])
                start.setdefault(o, z)
                highest[o] = max(highest.get(o, z), z)

        engine.add_system(note)
        engine.run(seconds=24.5)
    assert held == {"cup": {"right hand"}, "mug": {"right hand"}, "pen": {"right hand"},
                    "ball": {"right hand"}, "long box": {"right hand", "left hand"}}
    for o in OBJECTS:
        assert highest[o] - start[o] > 0.1, (o, highest[o] - start[o])  # lifted (15 cm)
