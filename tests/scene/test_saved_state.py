"""Saved states continue exactly: free motion, impacts, joints, sleep (issue 3, serial mode).

``--save-state`` at t, then running on, must match the run that never stopped
within 1e-6 m. Joints are re-created as at their first creation (from the
reference poses the file carries) and every body's auto-sleep state is saved.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from components import Transform
from engine.app import Engine, EngineConfig
from engine.rotation import euler_to_quat
from engine.scene import (
    SceneIds,
    SceneSpec,
    check,
    format_scene,
    instantiate,
    parse_text,
    spec_from_text,
    write,
    write_state,
)
from engine.scene.db import STRUCTURE, VECTOR, SceneDB
from systems import create_engine

pytest.importorskip("engine.physics.ode3d")

#: A bob on a world hinge; a body whose centre of mass is off its origin on a ball joint;
#: a bob on a ball joint to a body that turns on a world hinge.
PENDULUM = """\
World { TimeStep 0.01 }
Object { ID "anchor" Position [5 0 5] PhysicalAttributes { Geometry { Primitive "sphere" } } }
Object { ID "hung" Position [5 1 5] Velocity [0 0 2]
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.2] } } }
Joint { Type "Ball" Bodies ["anchor" "hung"] Anchor [5 0 5] }
Joint { Type "Hinge" Bodies ["anchor"] Axis [1 0 0] }
Object { ID "bob" Position [0 0 1] Velocity [0 2 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.2] } } }
Joint { ID "pivot" Type "Hinge" Bodies ["bob"] Anchor [0 0 2] Axis [1 0 0] }
Object { ID "dumbbell" Position [1 0 2] Orientation [0 30 0] AngularVelocity [0 0 90]
  PhysicalAttributes { Mass 2
    Geometry { Primitive "sphere" Size [0.2] Offset [0.5 0 0] }
    Geometry { Primitive "box" Size [0.1 0.1 0.3] Offset [0.1 0.1 -0.2] } } }
Joint { Type "Ball" Bodies ["dumbbell"] Anchor [1 0 2.2] }
"""

#: A double pendulum: a hinge to the world and a hinge between the two links.
CHAIN = """\
World { TimeStep 0.01 }
Object { ID "upper" Position [0.5 0 2]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [1 0.1 0.1] } } }
Object { ID "lower" Position [1.5 0 2] Orientation [0 0 20]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [1 0.1 0.1] } } }
Joint { Type "Hinge" Bodies ["upper"] Anchor [0 0 2] Axis [0 1 0] }
Joint { ID "elbow" Type "Hinge" Bodies ["upper" "lower"] Anchor [1 0 2] Axis [0 1 0] }
"""

#: A world slider against its limit; a carriage sliding on a swinging arm; a motor
#: lifting an arm to its limit; a universal, a hinge2 wheel and a fixed pair.
MECHANISMS = """\
World { TimeStep 0.01 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "slide" Position [0 0 3] Orientation [0 0 10] Velocity [0.5 0 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.2] } } }
Joint { Type "Slider" Bodies ["slide"] Axis [1 0 -1] Low -0.2 High 0.5 }
Object { ID "arm" Position [3 0 3]
  PhysicalAttributes { Mass 2 Geometry { Primitive "box" Size [1.2 0.1 0.1] } } }
Object { ID "carriage" Position [3.2 0 3.1] Orientation [10 0 0] Velocity [0 0 1]
  PhysicalAttributes { Mass 0.5 Geometry { Primitive "box" Size [0.2 0.2 0.1] } } }
Joint { Type "Hinge" Bodies ["arm"] Anchor [2.4 0 3] Axis [0 1 0] }
Joint { Type "Slider" Bodies ["carriage" "arm"] Axis [1 0 0] Low -0.3 High 0.3 }
Object { ID "lever" Position [6.5 0 3]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [1 0.1 0.1] } } }
Joint { ID "motor" Type "MotorizedHinge" Bodies ["lever"] Anchor [6 0 3] Axis [0 -1 0]
  Low -30 High 45 MotorVelocity 60 MotorMaxForce 20 }
Object { ID "yoke" Position [9 0 3] Velocity [0 1 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.2 0.2 0.6] } } }
Object { ID "fork" Position [9 0 2.4] Orientation [0 15 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.2 0.2 0.6] } } }
Joint { Type "Ball" Bodies ["yoke"] Anchor [9 0 3.3] }
Joint { Type "Universal" Bodies ["fork" "yoke"] Anchor [9 0 2.7] Axis [1 0 0] Axis2 [0 1 0] }
Object { ID "chassis" Position [12 0 0.6]
  PhysicalAttributes { Mass 5 Geometry { Primitive "box" Size [1 0.6 0.2] } } }
Object { ID "wheel" Position [12.5 0.4 0.3] Orientation [90 0 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "cylinder" Size [0.6 0.1] } } }
Joint { Type "Hinge2" Bodies ["wheel" "chassis"] Anchor [12.5 0.4 0.3] Axis [0 0 1]
  Axis2 [0 1 0] Low -20 High 20 MotorVelocity 200 MotorMaxForce 5 }
Object { ID "left" Position [15 0 2] Orientation [20 10 0] AngularVelocity [30 0 60]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.4] } } }
Object { ID "right" Position [15.5 0.1 2.2]
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.3] } } }
Joint { Type "Fixed" Bodies ["left" "right"] }
"""

#: Boxes that slide to rest before and around t = 2 s: at the save one sleeps, one is in
#: its quiet stretch, one still slides. A stack of crates that sleeps by about 1.2 s,
#: until a pebble lands on it at 1.9 s.
SETTLING = """\
World { TimeStep 0.01 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "slider1" Position [0 0 0.25] Velocity [8 0 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.5] } } }
Object { ID "slider2" Position [0 2 0.25] Velocity [6 0 0] AngularVelocity [0 0 40]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.5] } } }
Object { ID "slider3" Position [0 4 0.25] Velocity [10.4 0 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.5] } } }
Object { ID "base" Position [-3 0 0.5]
  PhysicalAttributes { Mass 500 Geometry { Primitive "box" } } }
Object { ID "middle" Position [-3 0.05 1.51]
  PhysicalAttributes { Mass 500 Geometry { Primitive "box" } } }
Object { ID "top" Position [-3 -0.05 2.6] Orientation [0 0 20]
  PhysicalAttributes { Mass 500 Geometry { Primitive "box" } } }
Object { ID "pebble" Position [-3.2 0.1 19.5]
  PhysicalAttributes { Mass 0.05 Geometry { Primitive "sphere" Size [0.2] } } }
"""



def engine_for(spec: SceneSpec) -> Engine:
    return create_engine(EngineConfig(backend=spec.backend, dt=spec.time_step, fast=True,
                               world=spec.world))


def run(text: str, seconds: float, folder: Path,
        edit: Callable[[SceneSpec], None] | None = None) -> tuple[np.ndarray, str]:
    """Positions of every object after ``seconds``, and the state saved then."""
    spec = spec_from_text(text, folder, np.random.default_rng(4), path=str(folder / "m.scene"))
    if edit is not None:
        edit(spec)
    with engine_for(spec) as engine:
        ids = instantiate(engine, spec)
        engine.run(seconds=seconds)
        pos = np.array([engine.world.component_for_entity(ids[e.id], Transform).position
                        for e in spec.entities])
        return pos, write_state(engine)


def resumed(text: str, legs: list[float], folder: Path) -> tuple[np.ndarray, list[str]]:
    """Run ``legs[0]`` s and save, load that and run ``legs[1]`` s and save, ...;
    the last positions and every state saved on the way."""
    saves = []
    for seconds in legs:
        pos, text = run(text, seconds, folder)
        saves.append(text)
    return pos, saves


def values(saved: str, key: str) -> list[list[float]]:
    """Every ``key`` in a saved state, as numbers, in file order."""
    db = parse_text(saved)
    found = [e.value for b in db.root.entries if b.value.kind == STRUCTURE
             for e in b.value.data.entries if e.key == key]
    return [[x.data for x in v.data] if v.kind == VECTOR else [v.data] for v in found]


MOTION = """\
World { TimeStep 0.01 AutoSleep 0 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object {
  ID "thrown"
  Position [0 0 10]
  Velocity [1 2 12]
  AngularVelocity [90 30 -45]
  PhysicalAttributes { Mass 2 Geometry { Primitive "box" Size [0.2 0.4 0.6] } }
}
Object {
  ID "slider"
  Position [5 0 0.25]
  Orientation [0 0 30]
  Velocity [randInterval(3, 4) 0 0]
  PhysicalAttributes { Mass 1 Geometry { Primitive "box" Size [0.5] } }
}
Object {
  ID "ball"
  Position [-3 0 1]
  Velocity [0 1 0]
  AngularVelocity [0 0 720]
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.4] } }
}
"""
def test_saved_state_continues_the_motion(tmp_path):
    """Tumbling flight, sliding and rolling on the ground: save at t=2 + 1 s matches 3 s."""
    straight, _ = run(MOTION, 3.0, tmp_path)
    _, saved = run(MOTION, 2.0, tmp_path)
    resumed, _ = run(saved, 1.0, tmp_path)
    np.testing.assert_allclose(resumed, straight, atol=1e-6, rtol=0)
    assert straight[1, 2] < 3 and straight[2, 0] > 6  # it really moved (and touched ground)


IMPACTS = """\
World { TimeStep 0.01 AutoSleep 0 }
Object { ID "ground" Dynamic 0 PhysicalAttributes { Geometry { Primitive "plane" } } }
Object { ID "crate" Position [0 0 3] AngularVelocity [200 100 0]
  PhysicalAttributes { Mass 2 Geometry { Primitive "box" Size [0.4 0.6 0.8] } } }
Object { ID "ball" Position [0.3 0 5] Velocity [0 0 -2]
  PhysicalAttributes { Mass 1 Geometry { Primitive "sphere" Size [0.5] } } }
Object { ID "base" Position [3 0 0.5] PhysicalAttributes { Geometry { Primitive "box" } } }
Object { ID "top" Position [3.2 0 1.6] PhysicalAttributes { Geometry { Primitive "box" } } }
"""


def test_saved_state_continues_through_impacts_and_stacking(tmp_path):
    """Saved before the bodies land and tumble: the solver's random state is saved too."""
    straight, _ = run(IMPACTS, 3.0, tmp_path)
    _, saved = run(IMPACTS, 0.5, tmp_path)
    assert "SolverSeed" in saved
    resumed, _ = run(saved, 2.5, tmp_path)
    np.testing.assert_allclose(resumed, straight, atol=1e-6, rtol=0)
    assert straight[1, 2] < 0.5 and straight[4, 2] < 1.5  # it landed; the top box toppled


def test_saved_state_is_a_valid_literal_scene(tmp_path):
    _, saved = run(MOTION, 0.5, tmp_path)
    db = parse_text(saved)
    assert db.find("Object[thrown]/Quaternion") is not None
    assert db.find("Object[slider]/Velocity").data[0].expr is None  # frozen
    assert db.find("World/Time").data == pytest.approx(0.5)


@pytest.mark.parametrize("scene", [PENDULUM, CHAIN, MECHANISMS],
                         ids=["pendulum", "chain", "mechanisms"])
def test_saved_jointed_state_continues_exactly(scene: str, tmp_path: Path) -> None:
    """Hinges (world and between bodies), ball, slider on its limits, motor on its limit,
    universal, hinge2 and fixed: saved at 2 s, 1 s more is the uninterrupted 3 s run."""
    straight, _ = run(scene, 3.0, tmp_path)
    start, _ = run(scene, 0.0, tmp_path)
    again, (saved, _) = resumed(scene, [2.0, 1.0], tmp_path)
    np.testing.assert_allclose(again, straight, atol=1e-6, rtol=0)
    assert np.abs(straight - start).max() > 0.2  # it really moved
    assert len(values(saved, "ReferencePose1")) == saved.count("Joint {")


def test_saved_jointed_state_continues_on_the_2d_backend_too(tmp_path: Path) -> None:
    """pymunk makes a saved joint at its reference poses as well (a double pendulum in
    the X–Z plane; without them it resumes 0.86 m off)."""
    scene = CHAIN.replace("TimeStep 0.01", 'TimeStep 0.01 Dynamics "pymunk"').replace(
        "Orientation [0 0 20]", "Orientation [0 20 0]")
    straight, _ = run(scene, 3.0, tmp_path)
    again, _ = resumed(scene, [2.0, 1.0], tmp_path)
    np.testing.assert_allclose(again, straight, atol=1e-6, rtol=0)


#: A pendulum whose mass sits off its one small shape, with inertia axes of its own and a
#: hinge spring; a cart on a slider spring that pulls at most 3 N, against its limits.
MASS_FRAMES_AND_SPRINGS = """\
World { TimeStep 0.01 AutoSleep 0 }
Object { ID "weighted" Position [0 0 2] Orientation [0 20 0]
  PhysicalAttributes { Mass 2 CenterOfMass [0 0 -0.4] Inertia [0.1 0.05 0.02]
    InertiaOrientation [0 0 30] Geometry { Primitive "sphere" Size [0.1] } } }
Joint { Type "Hinge" Bodies ["weighted"] Anchor [0 0 2] Axis [0 1 0]
  Spring { Stiffness 0.05 Damping 0.001 Target 10 } }
Object { ID "cart" Position [3 0 1] Velocity [0.5 0 0]
  PhysicalAttributes { Mass 1 Gravity 0 Geometry { Primitive "box" Size [0.2] } } }
Joint { Type "Slider" Bodies ["cart"] Axis [1 0 0] Low -0.3 High 0.3
  Spring { Stiffness 20 Target 0.1 MaxForce 3 } }
"""


@pytest.mark.parametrize("backend", ["ode", "pymunk"])
def test_a_saved_state_keeps_mass_frames_and_springs(backend: str, tmp_path: Path) -> None:
    """A given centre of mass and inertia and joint springs are written in the saved state
    and act after it as before: saved at 2 s, 1 s more is the uninterrupted 3 s run."""
    scene = MASS_FRAMES_AND_SPRINGS.replace("TimeStep 0.01", f'TimeStep 0.01 Dynamics '
                                                             f'"{backend}"')
    straight, _ = run(scene, 3.0, tmp_path)
    start, _ = run(scene, 0.0, tmp_path)
    again, (saved, _) = resumed(scene, [2.0, 1.0], tmp_path)
    np.testing.assert_allclose(again, straight, atol=1e-6, rtol=0)
    assert np.abs(straight - start).max() > 0.1  # it really moved
    db = parse_text(saved)
    assert [x.data for x in db.find("Object[weighted]/PhysicalAttributes/CenterOfMass").data
            ] == [0, 0, -0.4]
    springs = [e.value.data.get("Spring") for e in db.root.entries if e.key == "Joint"]
    assert [(s.get("Stiffness"), s.get("Target"), s.get("MaxForce")) for s in springs] == [
        (0.05, 10, None), (20, 0.1, 3)]


def _asleep(db: SceneDB, oid: str) -> bool:
    return db.find(f"Object[{oid}]/Asleep") is not None


def test_saved_sleeping_state_continues_exactly(tmp_path: Path) -> None:
    straight, _ = run(SETTLING, 3.0, tmp_path)
    again, (saved, end) = resumed(SETTLING, [2.0, 1.0], tmp_path)
    np.testing.assert_allclose(again, straight, atol=1e-6, rtol=0)
    at_save, at_end = parse_text(saved), parse_text(end)
    # at the save one slider sleeps, one is in its quiet stretch, one still slides; the
    # stack, asleep from about 1.2 s, was woken by the pebble at 1.9 s and settles again
    assert [_asleep(at_save, o) for o in ("slider1", "slider2", "slider3", "base")] == \
        [False, True, False, False]
    assert at_save.find("Object[slider1]/SleepTimer").data > 0
    assert len(at_save.find("Object[slider1]/SleepReference").data) == 6
    assert at_save.find("Object[slider3]/SleepTimer") is None
    assert at_save.find("Object[base]/SleepTimer") is not None
    assert all(_asleep(at_end, o) for o in ("slider1", "slider2", "slider3"))  # all by 3 s


def test_resaving_keeps_the_first_reference_poses(tmp_path: Path) -> None:
    straight, _ = run(MECHANISMS, 3.0, tmp_path)
    again, saves = resumed(MECHANISMS, [1.0, 1.0, 1.0], tmp_path)
    np.testing.assert_allclose(again, straight, atol=1e-6, rtol=0)
    first = values(saves[0], "ReferencePose1") + values(saves[0], "ReferencePose2")
    assert values(saves[2], "ReferencePose1") + values(saves[2], "ReferencePose2") == first
    assert first[0] == [0.0, 0.0, 3.0, *euler_to_quat((0.0, 0.0, 10.0))]  # "slide" at start
    assert values(saves[2], "Anchor")[:2] == values(saves[0], "Anchor")[:2]


def test_a_scene_without_reference_poses_loads_as_before(tmp_path: Path) -> None:
    """Joints made where their bodies are (no reference) and joints given the poses the
    bodies start at (what the factory fills in) are the same, bit for bit."""
    def no_reference(spec: SceneSpec) -> None:
        for js in spec.joints:
            js.joint.reference = None

    plain, _ = run(MECHANISMS, 1.0, tmp_path, no_reference)
    filled, _ = run(MECHANISMS, 1.0, tmp_path)
    assert np.array_equal(plain, filled)
    spec = spec_from_text(CHAIN, tmp_path)
    upper = next(c for c in spec.entities[0].components if isinstance(c, Transform))
    assert spec.joints[0].joint.reference == ((*upper.position, *upper.orientation), None)


def test_a_joint_made_elsewhere_keeps_its_reference_poses(tmp_path: Path) -> None:
    """A joint whose file gives the poses its bodies had: made as if they were there."""
    moved = CHAIN.replace('Position [0.5 0 2]', 'Position [0.5 0 2] Orientation [0 -30 0]')
    told = moved.replace('Axis [0 1 0] }', 'Axis [0 1 0] ReferencePose1 [0.5 0 2 1 0 0 0] }', 1)
    swinging, _ = run(told, 1.0, tmp_path)
    dropped, _ = run(moved, 1.0, tmp_path)
    # the hinge holds the link's end at the anchor it had at [0.5 0 2]: it is pulled back
    # to the pivot and swings from there; made where it is, it would hang from the tilt
    assert np.abs(swinging - dropped).max() > 0.05


def test_saved_state_passes_check_and_fmt_round_trips(tmp_path: Path) -> None:
    _, saved = run(MECHANISMS, 1.5, tmp_path)
    path = tmp_path / "state.scene"
    path.write_text(saved)
    assert [d for d in check(path) if d.is_error] == []
    canonical = format_scene(path)
    assert write(parse_text(canonical)) == canonical
    assert parse_text(canonical) == parse_text(saved)


def test_a_loaded_state_restores_each_bodys_sleep(tmp_path: Path) -> None:
    _, saved = run(SETTLING, 2.0, tmp_path)
    spec = spec_from_text(saved, tmp_path)
    with engine_for(spec) as engine:
        ids = instantiate(engine, spec)
        engine.run(frames=0)
        states = engine.physics.request(lambda b: b.sleep_states()).result()
        assert states[ids["slider2"]].asleep and not states[ids["slider1"]].asleep
        assert states[ids["slider1"]].timer == \
            parse_text(saved).find("Object[slider1]/SleepTimer").data
        assert SceneIds in engine.resources


def test_sleep_keys_are_checked_where_they_are_written(tmp_path: Path) -> None:
    def errors(text: str) -> list[tuple[int, int, str]]:
        path = tmp_path / "main.scene"
        path.write_text(text)
        return [(d.line, d.col, d.message) for d in check(path) if d.is_error]

    ((line, col, message),) = errors(
        'Object { ID "a"\n  SleepTimer -3 SleepReference [0 0 0 0 0 0] }\n')
    assert (line, col, message) == (2, 14, "SleepTimer must not be negative")
    ((line, col, message),) = errors('Object { ID "a"\n  SleepTimer 0.2 }\n')
    assert (line, col) == (2, 14) and "needs the SleepReference" in message
    ((line, col, message),) = errors('Object { ID "a"\n  SleepVelocity [1 2 3] }\n')
    assert (line, col) == (2, 17) and "6 numbers" in message
    ((line, col, message),) = errors('World {\n  SleepTime 0 }\n')
    assert (line, col, message) == (2, 13, "SleepTime must be more than 0, got 0")
