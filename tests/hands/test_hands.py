"""Virtual hands against physics: tracking, pushing, grasping, weights, the 5.4 rule."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hand_helpers import G, Rig, between, ramp, waypoints

from components import Transform
from components.hand import HandMode
from engine import Phase
from engine.events import HandReleased
from engine.rotation import local_axis
from systems.hands import Hands

BACKENDS = ["ode", "pymunk"]
FLOOR = 'Object { ID "floor" PhysicalAttributes { Geometry { Primitive "plane" } } }\n'
TABLE = ('Object { ID "table" Position [0 0 0.725] Dynamic 0\n'
         '  PhysicalAttributes { Geometry { Primitive "box" Size [1.2 1.2 0.05] } } }\n')
CUP = ('Object { ID "cup" Position [0 0 0.8]\n'
       '  PhysicalAttributes { Mass 0.3 Geometry { Primitive "cylinder" Size [0.08 0.1] } } }\n')


def hand(name: str, x: float, z: float, extra: str = "") -> str:
    side = name[-1]
    return (f'Object {{ ID "{name}" Position [{x} 0 {z}]\n'
            f'  Hand {{ Tracker "{name}" Glove "glove_{side}" {extra} }} }}\n')


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("dt", [1 / 120, 1 / 240])
def test_a_free_hand_tracks_a_tracker_moving_at_1_m_per_s(tmp_path: Path, backend, dt):
    path = waypoints((0.0, (0, 0, 1)), (2.0, (2, 0, 1)))  # 1 m/s along X
    errors = []
    with Rig(hand("hand_r", 0, 1), tmp_path, backend, dt=dt, paths={"hand_r": path}) as rig:
        # after the frame's step the tracker (and the hand) are one step further on
        rig.every_frame(lambda e, h: errors.append(np.linalg.norm(
            rig.position("hand_r") - path(e.time + h))) if 0.5 < e.time < 1.9 else None)
        rig.run(2.0)
    assert max(errors) < 1e-3  # within a millimetre at a walking reach's speed


@pytest.mark.parametrize("backend", BACKENDS)
def test_pushing_a_box_slides_it(tmp_path: Path, backend):
    box = ('Object { ID "box" Position [0.3 0 0.1]\n'
           '  PhysicalAttributes { Mass 2 Geometry { Primitive "box" Size [0.2 0.2 0.2] } } }\n')
    path = ramp((0, 0, 0.1), (0.6, 0, 0.1), 0.2, 1.4)  # 0.5 m/s toward +X, through it
    with Rig(FLOOR + box + hand("hand_r", 0, 0.1), tmp_path, backend,
             paths={"hand_r": path}) as rig:
        rig.run(1.8)
        box_x, hand_x = rig.position("box")[0], rig.position("hand_r")[0]
    # pushed along at 0.5 m/s until the hand stopped at 0.6 (its face 0.045 m ahead of its
    # centre, the box's 0.1 behind its own), then sliding to rest on friction μ = 0.5
    assert hand_x == pytest.approx(0.6, abs=1e-3)
    assert box_x == pytest.approx(0.6 + 0.045 + 0.1 + 0.5**2 / (2 * 0.5 * G), abs=0.01)


def lift_cup(tmp_path: Path, backend: str, mode: str = "serial") -> dict[str, list]:
    """Lower onto the cup, grasp, lift 0.3 m, hold, let go at 2 s: per frame, the time, the
    cup's and hand's heights and the hand's mode."""
    path = waypoints((0.0, (0, 0, 0.9)), (0.4, (0, 0, 0.852)), (0.6, (0, 0, 0.852)),
                     (1.4, (0, 0, 1.152)), (2.0, (0, 0, 1.152)))
    seen: dict[str, list] = {"t": [], "cup": [], "hand": [], "mode": []}
    scene = TABLE + CUP + hand("hand_r", 0, 0.9)
    with Rig(scene, tmp_path, backend, mode=mode, paths={"hand_r": path},
             gloves={"glove_r": between(0.5, 2.0)}) as rig:
        def note(e, h):
            for key, value in (("t", e.time), ("cup", rig.position("cup")[2]),
                               ("hand", rig.position("hand_r")[2]),
                               ("mode", rig.state("hand_r").mode)):
                seen[key].append(value)

        rig.every_frame(note, after=("HandContactSystem",))
        rig.run(2.3)
    return seen


def at(seen: dict[str, list], key: str, t: float) -> object:
    return seen[key][int(np.searchsorted(seen["t"], t))]


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_grasp_lifts_a_cup_and_a_release_drops_it(tmp_path: Path, backend):
    s = lift_cup(tmp_path, backend)
    assert at(s, "mode", 0.45) == HandMode.CONTACT  # touching it: an open hand
    assert at(s, "mode", 0.55) == HandMode.GRASP
    # held, the cup rose with the hand, which reached its tracker (the cup's 0.3 kg is well
    # within the drive's 300 N); it had rested on the cup a little above its tracker
    assert at(s, "hand", 1.9) == pytest.approx(1.152, abs=1e-3)
    assert at(s, "cup", 1.9) - at(s, "cup", 0.45) == pytest.approx(
        at(s, "hand", 1.9) - at(s, "hand", 0.45), abs=2e-3)
    # let go: from then on it falls freely, its acceleration g on every step
    free = next(i for i, m in enumerate(s["mode"]) if i > 0 and m != HandMode.GRASP
                and s["mode"][i - 1] == HandMode.GRASP) + 1  # the first frame wholly free
    z = np.array(s["cup"][free:free + 13])
    h = s["t"][1] - s["t"][0]
    assert np.diff(z[1:], 2) / h**2 == pytest.approx(-G, rel=0.01)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize(("share", "holds"), [(0.85, False), (3.0, True)],
                         ids=["under its weight", "three times its weight"])
def test_a_grip_carries_the_cups_weight_and_breaks_beyond_break_force(
        tmp_path: Path, backend, share: float, holds: bool):
    """Held still, the grip pulls the cup up with its weight m g (measured by the backend);
    a BreakForce under that weight lets go as the lift begins, one over it holds through a
    smooth lift (at most 2.8 m/s² up: m (g + a) = 3.8 N)."""
    def path(t: float) -> np.ndarray:
        s = min(max((t - 0.6) / 0.8, 0.0), 1.0)
        return np.array([0.0, 0.0, (0.9 - 0.048 * min(t / 0.4, 1.0)) if t < 0.6
                         else 0.852 + 0.3 * s * s * (3 - 2 * s)])

    weight = 0.3 * G
    limit = share * weight
    scene = TABLE + CUP + hand("hand_r", 0, 0.9, f"BreakForce {limit}")
    with Rig(scene, tmp_path, backend, paths={"hand_r": path},
             gloves={"glove_r": between(0.5)}) as rig:
        released: list[float] = []
        rig.engine.events.subscribe(HandReleased, lambda e: released.append(
            rig.engine.time))
        rig.run(2.2)
        if holds:
            assert not released and rig.state("hand_r").held == (rig.ids["cup"],)
            # lifted by its top (0.05 m from its middle), under the hand's 0.015 m
            # half-thickness (less the few mm a soft contact gave under the press)
            assert rig.position("hand_r")[2] == pytest.approx(1.152, abs=2e-3)
            assert rig.position("hand_r")[2] - rig.position("cup")[2] == pytest.approx(
                0.065, abs=5e-3)
            joint = rig.engine.resource(Hands).rigs[rig.ids["hand_r"]].grasps[
                rig.ids["cup"]]
            force = rig.engine.physics.request(lambda b: b.joint_force(joint)).result()
            # the cup hangs on the hand: pulls it down by its weight
            assert force == pytest.approx([0, 0, -weight], abs=0.02 * weight)
        else:  # let go as it began to rise, well before the glove opened
            assert len(released) == 1 and 0.5 < released[0] < 0.8
            assert rig.position("cup")[2] == pytest.approx(0.8, abs=0.01)


def test_serial_and_threaded_runs_lift_alike(tmp_path: Path):
    serial = lift_cup(tmp_path, "ode", "serial")
    threaded = lift_cup(tmp_path, "ode", "threaded")
    assert at(threaded, "cup", 1.9) == pytest.approx(at(serial, "cup", 1.9), abs=0.01)
    assert HandMode.GRASP in threaded["mode"]


CRATE = ('Object { ID "crate" Position [0 0 0.25]\n'
         '  PhysicalAttributes { Mass 50 Geometry { Primitive "box" Size [0.6 0.4 0.5] } } }\n')


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_50_kg_crate_one_hand_cannot_lift_two_hands_can(tmp_path: Path, backend):
    """Each hand pushes at most 300 N; the crate weighs 490 N: one hand fails, two lift."""
    def lift(x: float) -> object:
        return waypoints((0.0, (x, 0, 0.6)), (0.5, (x, 0, 0.505)), (0.8, (x, 0, 0.505)),
                         (1.8, (x, 0, 0.705)), (3.0, (x, 0, 0.705)))

    gloves = {"glove_l": between(0.6), "glove_r": between(0.6)}
    one = FLOOR + CRATE + hand("hand_r", 0.2, 0.6)
    with Rig(one, tmp_path, backend, paths={"hand_r": lift(0.2)}, gloves=gloves) as rig:
        rig.run(3.0)
        assert rig.state("hand_r").mode == HandMode.GRASP
        assert rig.position("crate")[2] == pytest.approx(0.25, abs=0.01)  # it stays put
    two = FLOOR + CRATE + hand("hand_r", 0.2, 0.6) + hand("hand_l", -0.2, 0.6)
    with Rig(two, tmp_path, backend, paths={"hand_r": lift(0.2), "hand_l": lift(-0.2)},
             gloves=gloves) as rig:
        rig.run(3.0)
        assert rig.position("crate")[2] > 0.25 + 0.15  # up with both, a little behind


@pytest.mark.parametrize("backend", BACKENDS)
def test_two_hands_carry_a_plank_level(tmp_path: Path, backend):
    plank = ('Object { ID "plank" Position [0 0 0.025]\n'
             '  PhysicalAttributes { Mass 3 Geometry { Primitive "box" Size [1.2 0.2 0.05] } } }\n')

    def carry(x: float) -> object:
        return waypoints((0.0, (x, 0, 0.1)), (0.4, (x, 0, 0.062)), (0.6, (x, 0, 0.062)),
                         (1.6, (x, 0, 0.462)), (2.6, (x + 0.4, 0, 0.462)))

    scene = FLOOR + plank + hand("hand_r", 0.5, 0.1) + hand("hand_l", -0.5, 0.1)
    with Rig(scene, tmp_path, backend, paths={"hand_r": carry(0.5), "hand_l": carry(-0.5)},
             gloves={"glove_l": between(0.5), "glove_r": between(0.5)}) as rig:
        rig.run(2.6)
        t = rig.engine.world.component_for_entity(rig.ids["plank"], Transform)
        x_axis = local_axis(t.orientation, 0)
    assert t.position[2] == pytest.approx(0.462 - 0.025 - 0.015, abs=0.02)
    assert t.position[0] == pytest.approx(0.4, abs=0.02)
    tilt = math.degrees(math.asin(abs(x_axis[2])))
    assert tilt < 1.0  # carried level


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_hand_pushed_under_a_table_follows_the_rule_of_section_5_4(tmp_path: Path, backend):
    """D = 0.3 m: the table stops the hand; beyond D it passes through (collisions off) and
    comes back to the tracker; under 0.1 D it collides again; see-through exactly between
    0.1 D and 0.7 D. Then up again: the underside stops it, and it passes through again."""
    top = 0.75
    path = waypoints((0.0, (0, 0, 0.9)), (1.0, (0, 0, top - 0.5)), (2.5, (0, 0, top - 0.5)),
                     (3.5, (0, 0, 1.2)), (4.5, (0, 0, 1.2)))
    seen: list[tuple[float, float, bool, bool, float]] = []
    with Rig(TABLE + hand("hand_r", 0, 0.9), tmp_path, backend, paths={"hand_r": path}) as rig:
        def note(e, h):
            s = rig.state("hand_r")
            seen.append((e.time, s.deviation, s.colliding, rig.visual("hand_r").overlay,
                         rig.position("hand_r")[2]))

        rig.every_frame(note, Phase.PRE_PHYSICS, after=("HandDriveSystem",))
        rig.run(4.5)
    d_max = 0.3
    t, dev, colliding, overlay, z = (np.array(c) for c in zip(*seen, strict=True))
    assert np.array_equal(overlay, (dev >= 0.1 * d_max) & (dev <= 0.7 * d_max))
    assert overlay.any()
    off = np.flatnonzero(colliding[:-1] & ~colliding[1:]) + 1  # frames it stopped colliding
    on = np.flatnonzero(~colliding[:-1] & colliding[1:]) + 1
    assert len(off) == 2 and len(on) == 2  # through the top, then through the underside
    assert all(dev[i] > d_max for i in off)  # switched off only beyond D
    assert all(dev[i] < 0.1 * d_max for i in on)  # and on only within 0.1 D
    # the table held the hand on its top until then, and it went through afterwards
    blocked = (t > 0.4) & (t < t[off[0]])
    assert z[blocked].min() > top - 0.01
    assert z[(t > 2.0) & (t < 2.5)].max() < top - 0.4  # under the table, with its tracker
    assert z[(t > 3.0) & (t < t[off[1]])].max() < top - 0.05 + 0.001  # the underside held it
    assert colliding[-1] and z[-1] == pytest.approx(1.2, abs=1e-3)  # above, colliding again


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_lost_tracker_holds_the_hand_still_and_lets_go_after_a_second(tmp_path: Path,
                                                                        backend):
    path = waypoints((0.0, (0, 0, 0.9)), (0.4, (0, 0, 0.852)), (0.6, (0, 0, 0.852)),
                     (1.0, (0, 0, 1.0)))
    with Rig(TABLE + CUP + hand("hand_r", 0, 0.9), tmp_path, backend,
             paths={"hand_r": path}, gloves={"glove_r": between(0.5)}) as rig:
        rig.run(1.0)
        assert rig.state("hand_r").mode == HandMode.GRASP
        del rig.paths["hand_r"]  # the tracker goes silent
        rig.run(1.0)  # the input layer calls it lost after its timeout (0.5 s)
        assert not rig.state("hand_r").tracked
        held_at = rig.position("hand_r")
        rig.run(1.2)
        assert np.allclose(rig.position("hand_r"), held_at, atol=1e-3)  # held still
        assert rig.state("hand_r").held == ()  # and let go after a second


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_hand_pressing_a_cup_into_the_table_rests_on_it_still(tmp_path: Path, backend):
    """The tracker 13 mm inside the cup: the drive presses with its full 300 N through a
    0.3 kg cup into the table. The hand rests on the cup within a millimetre or so, and
    still (the solver runs the iterations hands need)."""
    path = waypoints((0.0, (0, 0, 0.9)), (0.4, (0, 0, 0.852)))
    with Rig(TABLE + CUP + hand("hand_r", 0, 0.9), tmp_path, backend,
             paths={"hand_r": path}) as rig:
        assert rig.engine.config.world.iterations >= 40
        rig.run(0.6)
        sunk = []
        rig.every_frame(lambda e, dt: sunk.append(
            rig.position("cup")[2] + 0.05 - (rig.position("hand_r")[2] - 0.015)))
        rig.run(0.3)
        assert rig.state("hand_r").mode == HandMode.CONTACT
        assert max(sunk) < 1.5e-3 and np.std(sunk) < 2e-4
