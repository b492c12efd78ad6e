"""content/hands replays its recorded session: touch, grasp, two hands, the crate, the
drawer and the table rule all happen as the session means them to."""

from __future__ import annotations

import math

import numpy as np

from components import HandState, Transform
from engine import EngineConfig, Phase, system
from engine.content import REPO_ROOT
from engine.rotation import local_axis
from engine.scene import check, instantiate, load_spec
from services.input.replay import InputReplayer
from systems import create_engine

CONTENT = REPO_ROOT / "content" / "hands"


def test_the_hands_content_checks_clean():
    assert [d for d in check(CONTENT) if d.is_error] == []


def test_the_recorded_session_replays_what_it_shows():
    spec = load_spec(CONTENT / "main.scene")
    config = EngineConfig(content_dir=CONTENT, fast=True, dt=spec.time_step)
    seen: list[dict] = []
    with create_engine(config) as engine:
        engine.add_system(InputReplayer(CONTENT / "demo.input"))
        ids = instantiate(engine, spec)

        @system(Phase.POST_PHYSICS, reads=(Transform, HandState))
        def note(e, dt):
            w = e.world
            pose = {name: w.component_for_entity(ids[name], Transform) for name in
                    ("cup1", "plank", "crate", "drawer", "right hand")}
            seen.append({"t": e.time, **{k: t.position.copy() for k, t in pose.items()},
                         "plank tilt": math.degrees(math.asin(min(1.0, abs(
                             local_axis(pose["plank"].orientation, 0)[2])))),
                         "right": w.component_for_entity(ids["right hand"], HandState).mode,
                         "collides": w.component_for_entity(ids["right hand"],
                                                            HandState).colliding})

        engine.add_system(note)
        engine.run(seconds=24.0)

    def during(t0: float, t1: float, key: str) -> list:
        return [s[key] for s in seen if t0 <= s["t"] < t1]

    cup = np.array(during(3.0, 4.4, "cup1"))
    assert cup[:, 2].max() - cup[0, 2] > 0.2  # carried up by the right hand
    assert "grasp" in during(3.0, 4.4, "right")
    plank = np.array(during(7.6, 8.4, "plank"))
    assert plank[:, 2].min() > 0.75 + 0.25 and max(during(7.6, 8.4, "plank tilt")) < 3.0
    crate = np.array(during(10.8, 12.4, "crate"))
    assert crate[:, 2].max() < 0.26  # 490 N: one hand's 300 N does not lift it
    crate = np.array(during(15.5, 16.8, "crate"))
    assert crate[:, 2].min() > 0.25 + 0.15  # two hands do
    assert during(21.0, 21.2, "drawer")[0][1] < 0.05  # pulled out 20 cm and more
    # pushed into the table: it stops on the top, then lets go of it and passes through
    assert not all(during(18.5, 19.5, "collides"))
    assert np.array(during(20.0, 21.0, "right hand"))[:, 2].max() < 0.75 - 0.4
    assert np.array(during(23.0, 24.0, "right hand"))[:, 2].min() > 0.9
