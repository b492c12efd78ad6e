"""The fingered hand (``Hand { Fingers 1 }``) against physics: its fingertips follow the
tracked ones, what the thumb and a finger press from opposite sides is held and let go
when the grip opens, and the goals of ``colosseum bench hands`` hold with margins."""

from __future__ import annotations

import logging
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from app.bench import fingers as bench
from app.bench.hand_grips import pinch
from components import Hand, HandState, Physical, Transform
from components.hand import HAND_SIZE, PALM_SIZE
from engine.events import Contacts, HandGrasped, HandReleased
from engine.scene import spec_from_text
from systems.hand_fingers import opposed
from systems.hands import Hands

ROOT = Path(__file__).resolve().parents[2]


def _press(point: tuple[float, ...], push: tuple[float, ...], force: float
           ) -> tuple[np.ndarray, np.ndarray, float]:
    d = np.asarray(push, dtype=float)
    return np.asarray(point, dtype=float), d / np.linalg.norm(d), force


def test_presses_that_oppose_inside_the_friction_cone_grip_and_others_do_not():
    thumb = _press((-0.03, 0, 0), (1, 0, 0), 2.0)  # pushes the object toward +x
    index = _press((0.03, 0, 0), (-1, 0, 0), 2.0)
    assert opposed({"thumb": thumb, "index": index}) == ("thumb", "index")
    # 30 degrees off the line between them: inside a cone of mu 0.8 (38.7 degrees)
    tilted = _press((0.03, 0, 0), (-np.cos(0.52), np.sin(0.52), 0), 2.0)
    assert opposed({"thumb": thumb, "index": tilted}) == ("thumb", "index")
    # 50 degrees off: outside it; pushing the same way: no grip; too light: no grip
    wide = _press((0.03, 0, 0), (-np.cos(0.87), np.sin(0.87), 0), 2.0)
    assert opposed({"thumb": thumb, "index": wide}) == ()
    assert opposed({"thumb": thumb, "index": _press((0.03, 0, 0), (1, 0, 0), 2.0)}) == ()
    assert opposed({"thumb": thumb, "index": _press((0.03, 0, 0), (-1, 0, 0), 0.1)}) == ()
    # no thumb, no grip (two fingers side by side do not pinch); the palm opposes too
    assert opposed({"index": index, "middle": thumb}) == ()
    assert opposed({"thumb": thumb, "palm": index}) == ("thumb", "palm")


def test_the_scene_key_fingers_makes_a_fingered_hand_with_a_palm_sized_body(tmp_path: Path):
    spec = spec_from_text('Object { ID "h" Hand { Tracker "right" Fingers 1 } }\n'
                          'Object { ID "p" Hand { Tracker "hand_r" } }\n', tmp_path)
    hands = {o.id: o for o in spec.entities}
    fingered = next(c for c in hands["h"].components if isinstance(c, Hand))
    palm = next(c for c in hands["p"].components if isinstance(c, Hand))
    assert fingered.fingers and not palm.fingers  # palm only stays the default
    sizes = {oid: next(c for c in hands[oid].components if isinstance(c, Physical))
             .shapes[0].size for oid in ("h", "p")}
    assert tuple(sizes["h"]) == PALM_SIZE and tuple(sizes["p"]) == HAND_SIZE


def test_colosseum_keys_hand_documents_fingers():
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    result = subprocess.run([sys.executable, "-m", "app.cli", "keys", "Hand"], cwd=ROOT,
                            capture_output=True, text=True, env=env, timeout=120)
    assert result.returncode == 0, result.stderr
    assert "Fingers" in result.stdout and "phalanges" in result.stdout


def test_fingertips_follow_the_tracked_tips_at_half_a_metre_per_second(tmp_path: Path):
    row = bench.fingertips(tmp_path, 1.5)
    # goal 3 mm; 1.52 mm measured with the hand in the air solved at the world's 20
    # iterations (contact_iterations: 40 only where it touches something), 0.98 at 40
    assert row["error_rms_mm"] <= 2.0
    assert row["palm_rms_mm"] <= 1.5


def test_a_hand_s_own_bones_never_touch_each_other_in_a_fist(tmp_path: Path):
    from services.input.hand_pose import GESTURES, pose_hand

    own: list[int] = []
    count: list[int] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        parts = {ids["hand_r"], *bench.bones_of(e, ids["hand_r"])}
        count.append(len(parts))
        for c in e.events.frame(Contacts):
            a, b = c.batch["a"].tolist(), c.batch["b"].tolist()
            own.extend(1 for x, y in zip(a, b, strict=True) if x in parts and y in parts)

    def fist(t: float) -> Any:
        curls = {f: min(t, 1.0) for f in GESTURES["fist"]}
        return pose_hand("right", (0, 0, 1), (1, 0, 0, 0), curls, timestamp=t)

    bench.run(bench.hand("hand_r", "right"), tmp_path, {"right": fist}, 1.5, note, settle=0)
    assert max(count) == 16 and not own  # the palm and 15 phalanges, no contact among them


def test_a_pinched_ball_is_held_lifted_and_let_go_when_the_grip_opens(tmp_path: Path):
    width = 0.06
    centre = np.array([0.0, 0.0, bench.TOP + width / 2])
    feed = bench.grasping("right", centre, width, (0.0, 1.0, 0.0), bench.lift(), open_at=2.2)
    events: list[tuple[str, float, Any]] = []
    spots: list[tuple[float, np.ndarray, np.ndarray, tuple[str, ...]]] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        if not spots:  # the bus's handlers (what onGrasp and onRelease are told from)
            e.events.subscribe(HandGrasped, lambda ev: events.append(("grasp", e.time, ev)))
            e.events.subscribe(HandReleased, lambda ev: events.append(("release", e.time,
                                                                        ev)))
        ball = e.world.component_for_entity(ids["ball"], Transform)
        state = e.world.component_for_entity(ids["hand_r"], HandState)
        spots.append((e.time, ball.position.copy(), ball.linear_velocity.copy(), state.grip))

    bench.run(bench.TABLE + bench.ball("ball", width, centre) + bench.hand("hand_r", "right"),
              tmp_path, {"right": feed}, 3.2, note, settle=0.0)
    kinds = [k for k, _, _ in events]
    assert kinds == ["grasp", "release"]  # once each: no flicker at the grip's edge
    grasped, released = events[0][1], events[1][1]
    assert 0.3 < grasped < 0.8 and 2.2 < released < 2.5  # by contact, by opening
    held = [s for s in spots if grasped < s[0] < released]
    assert all(s[3] == ("thumb", "index") for s in held)
    lifted = max(s[1][2] for s in held)
    assert lifted > centre[2] + 0.12  # lifted with the hand (15 cm)
    assert spots[-1][1][2] < centre[2] + 0.01  # let go: it fell back to the table


def test_releasing_gives_the_object_the_hand_s_velocity_and_nothing_more(tmp_path: Path):
    """The hand lets go while carrying the ball sideways at 0.3 m/s: the ball leaves at
    the hand's velocity, not flung by the fingers that opened round it."""
    width = 0.06
    centre = np.array([0.0, 0.0, bench.TOP + width / 2])

    def carry(t: float) -> np.ndarray:
        return bench.lift()(t) + np.array([0.3 * max(t - 1.8, 0.0), 0.0, 0.0])

    feed = bench.grasping("right", centre, width, (0.0, 1.0, 0.0), carry, open_at=2.1)
    seen: list[tuple[float, np.ndarray, tuple[int, ...]]] = []

    def note(e: Any, ids: dict[str, int]) -> None:
        ball = e.world.component_for_entity(ids["ball"], Transform)
        seen.append((e.time, ball.linear_velocity.copy(),
                     e.world.component_for_entity(ids["hand_r"], HandState).held))

    bench.run(bench.TABLE + bench.ball("ball", width, centre) + bench.hand("hand_r", "right"),
              tmp_path, {"right": feed}, 2.6, note, settle=0.0)
    gone = next(i for i, s in enumerate(seen) if s[0] > 2.0 and not s[2])
    after = seen[gone + 1][1]  # the first step free: gravity only since
    assert abs(after[0] - 0.3) < 0.05 and abs(after[1]) < 0.05


def test_penetration_and_jitter_of_a_pinched_ball_meet_their_goals(tmp_path: Path):
    deep, still = bench.held_ball(tmp_path)
    assert deep["contacts"] > 100 and deep["deepest_mm"] <= 1.6  # goal 2 mm
    assert still["ok"] == "yes" and still["jitter_rms_mm"] <= 0.3  # goal 0.5 mm


def test_a_finger_pushing_a_box_does_not_grasp_it_and_does_not_sink_in(tmp_path: Path):
    held: list[tuple[int, ...]] = []

    def watch(e: Any, ids: dict[str, int]) -> None:
        held.append(e.world.component_for_entity(ids["hand_r"], HandState).held)

    row = bench.pushed_box(tmp_path)
    assert row["contacts"] > 20 and row["deepest_mm"] <= 1.6
    scene = bench.TABLE + ('Object { ID "box" Position [0.1 0 0.8] PhysicalAttributes { '
                           'Mass 0.5 Geometry { Primitive "box" Size [0.1 0.1 0.1] } } }\n')
    from services.input.hand_pose import GESTURES, pose_hand

    def push(t: float) -> Any:
        x = float(np.interp(t, [0.0, 0.4, 2.0], [-0.22, -0.22, 0.05]))
        return pose_hand("right", (x, 0.0, bench.TOP + 0.04), (1, 0, 0, 0), GESTURES["point"],
                         timestamp=t)

    bench.run(scene + bench.hand("hand_r", "right", (-0.15, 0, 0.8)), tmp_path,
              {"right": push}, 2.0, watch, settle=0.0)
    assert len(held) > 100 and not any(held)  # one finger pressing is a push, however long


def test_a_cup_held_by_the_fingers_survives_a_3_hz_10_cm_shake(tmp_path: Path):
    row = bench.shake(tmp_path)
    assert row["ok"] == "yes" and row["held_share"] == 1.0


def test_handing_a_ball_over_moves_it_at_most_5_mm(tmp_path: Path):
    row = bench.hand_over(tmp_path)
    assert row["ok"] == "yes", row


def test_a_3_m_per_s_swipe_does_not_pass_through_a_5_mm_plate(tmp_path: Path):
    row = bench.swipe(tmp_path)
    assert row["farthest_centre_mm"] < -2.5  # no bone's centre reached the plate's far side


def test_finger_deviation_says_how_far_a_blocked_fingertip_is_from_its_tracked_one(
        tmp_path: Path):
    """The tracked pinch closes 2 cm inside a ball: the thumb's and index's tips stop on
    it, about a centimetre each from where they are tracked; the others are free."""
    width = 0.06
    centre = np.array([0.0, 0.0, bench.TOP + width / 2])

    def squeeze(t: float) -> Any:
        grip = float(np.interp(t, [0.3, 0.7], [width + 0.04, width - 0.02]))
        return pinch("right", centre, (0.0, 1.0, 0.0), width, grip, timestamp=t)

    seen: list[tuple[float, ...]] = []
    bench.run(bench.TABLE + bench.ball("ball", width, centre) + bench.hand("hand_r", "right"),
              tmp_path, {"right": squeeze}, 1.2, lambda e, ids: seen.append(
                  e.world.component_for_entity(ids["hand_r"], HandState).finger_deviation),
              settle=0.0)
    thumb, index, middle, ring, little = seen[-1]
    assert 0.005 < thumb < 0.04 and 0.005 < index < 0.04
    assert max(middle, ring, little) < 0.003


def test_fingers_on_a_backend_without_them_are_told_and_the_hand_is_a_palm(tmp_path: Path,
                                                                           caplog):
    """ODE and pymunk (a 2D hand: tests/hands/test_fingers2d.py) have fingers; the
    ballistic backend, without joints, says so and keeps a palm."""
    from engine import EngineConfig
    from engine.scene import instantiate
    from services.input import InputHub
    from systems import create_engine

    config = EngineConfig(backend="ballistic", fast=True, dt=1 / 120, content_dir=tmp_path,
                          debug=False)
    with caplog.at_level(logging.WARNING), create_engine(config) as engine:
        ids = instantiate(engine, spec_from_text(bench.hand("hand_r", "right"), tmp_path))
        engine.start()
        hub = engine.resource(InputHub)
        hub.clock = lambda: engine.time
        hub.inject(pinch("right", (0, 0, 1), (0, 1, 0), 0.06, 0.08))
        engine.run(seconds=0.1)
        assert engine.resource(Hands).rigs[ids["hand_r"]].fingers is None
    assert "Fingers 1 needs the ode or pymunk backend" in caplog.text


def test_a_recorded_hand_reads_back_the_same_and_a_short_one_is_refused():
    import json

    from services.input.hand_pose import pose_hand
    from services.input.record import event_from_record, event_record

    hand = pose_hand("right", (0.1, 0.2, 1.0), (1, 0, 0, 0), {"index": 0.5}, timestamp=1.5)
    line = json.loads(json.dumps(event_record(3, hand)))
    line.pop("frame")
    assert event_from_record(dict(line)) == hand
    line["radii"] = line["radii"][:25]
    with pytest.raises(ValueError, match="a list of 26"):
        event_from_record(line)


def test_a_hand_first_seen_as_a_fist_opens_flat(tmp_path: Path):
    """The chain's joint limits are anatomical, not counted from the first sample's pose
    (a joint's zero is where it was made): a hand first tracked as a fist opens fully."""
    from services.input.hand_pose import GESTURES, pose_hand

    gaps: list[float] = []

    def opening(t: float) -> Any:
        curls = {f: max(0.0, 1.0 - t) for f in GESTURES["fist"]}  # fist, opening over 1 s
        return pose_hand("right", (0, 0, 1), (1, 0, 0, 0), curls, timestamp=t)

    def note(e: Any, ids: dict[str, int]) -> None:
        if e.time > 1.3:
            tracked = np.asarray(opening(e.time).positions)[[5, 10, 15, 20, 25]]
            gaps.append(float(np.linalg.norm(bench.physical_tips(e, ids["hand_r"]) - tracked,
                                             axis=1).max()))

    bench.run(bench.hand("hand_r", "right"), tmp_path, {"right": opening}, 1.8, note, settle=0)
    assert gaps and max(gaps) < 0.006  # every fingertip within 6 mm of the open hand's
